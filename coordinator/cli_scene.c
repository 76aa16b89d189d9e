/* cli_scene.c: how the verbs that render (render, submit, study) load the scene a request
 * names: the request's -D, --strict and --scene-root, the loader's warnings on stderr, and the
 * scene's own defaults for what the flags left open; plus the bundle a farm job ships. */
#include <stdio.h>
#include <stdlib.h>

#include "bundle.h"
#include "cli_scene.h"

static void warn_stderr(void *ud, const char *line) { fprintf(stderr, "pcbpt-coord %s: %s\n", (const char *)ud, line); }

int pc_cli_load_scene(const char *verb, pc_render_request *req, const char *path, pc_scene *s, pc_err *e) {
  pc_scene_load_opts o;
  pc_render_request_load_opts(req, &o);
  o.warn = warn_stderr;
  o.warn_ud = (void *)verb;
  o.max_file_bytes = PC_BUNDLE_MAX; /* every verb that loads a scene ships it as a bundle */
  int rc = pc_scene_load_with(path, &o, s, e);
  if (rc) return rc;
  pc_render_request_apply_scene(req, s);
  if (req->spp == 0 && req->seconds == 0 && req->halt_noise == 0) req->spp = 64;
  return 0;
}

void pc_cli_warn_method(const char *verb, const char *path, pc_method m, const pc_render_request *req) {
  if (m == PC_METHOD_PT && !req->pt_complete)
    fprintf(stderr,
            "pcbpt-coord %s: warning: %s: pt never samples the light a point or spot light sends through a delta"
            " material (glass, a mirror, a smooth plastic coat, a mask's holes), so its image lacks it; bdpt and"
            " pcbpt render it\n",
            verb, path);
}

int pc_cli_scene_bundle(const pc_scene *s, uint8_t **blob, size_t *n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e) {
  return pc_bundle_create((const char *const *)s->files, (const char *const *)s->file_names, s->nfiles, blob, n, hash, e);
}
