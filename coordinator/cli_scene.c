/* cli_scene.c: how the verbs that render (render, submit, study) load the scene a request
 * names: the request's -D, --strict and --scene-root, the loader's warnings on stderr, and the
 * scene's own defaults for what the flags left open; plus the bundle a farm job ships. */
#include <stdio.h>
#include <stdlib.h>

#include "big_alloc.h"
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
  /* the job carries the -D values the scene uses (the loader warned of the others), so that its
   * image's pcbpt.defines is what it was rendered with */
  req->set.defines = s->defines_used;
  pc_render_request_apply_scene(req, s);
  if (req->spp == 0 && req->seconds == 0 && req->halt_noise == 0) req->spp = 64;
  return 0;
}

void pc_cli_warn_method(const char *verb, const char *path, pc_method m, const pc_render_request *req) {
  if (m == PC_METHOD_PT && !req->pt_complete)
    fprintf(stderr,
            "pcbpt-coord %s: warning: %s: pt never samples the light a point, spot or directional light sends through a delta"
            " material (glass, a mirror, a smooth plastic coat, a mask's holes), so its image lacks it; bdpt and"
            " pcbpt render it where it lands on a surface seen other than through a delta material (seen through"
            " one, no method samples it, nor does Mitsuba)\n",
            verb, path);
  if (m == PC_METHOD_LT && !req->lt_complete)
    fprintf(stderr,
            "pcbpt-coord %s: warning: %s: lt never sees a delta material from the camera (glass, a mirror, a smooth"
            " plastic coat, a mask's holes), so its image lacks what is seen in or through one; pt, bdpt and pcbpt"
            " render it\n",
            verb, path);
}

void pc_cli_warn_backs(const char *verb, pc_scene *s) {
  /* The probe's BVH (Embree's quickest build, under 128 bytes a triangle) must not be what
     exhausts a client that only submits: past a quarter of the memory, the scene goes unchecked. */
  double tris = 0;
  for (int i = 0; i < s->nshapes; i++) tris += s->shapes[i].mesh.ntris;
  if (128.0 * tris > 0.25 * (double)pc_big_memory_limit()) {
    fprintf(stderr, "pcbpt-coord %s: warning: %s: %.0f triangles, too many to check here for surfaces seen from behind\n",
            verb, s->path, tris);
    return;
  }
  pc_scene_backs b;
  pc_err e = {0};
  if (pc_scene_probe_backs(s, 64, &b, &e) != PC_OK) {
    /* the probe only advises: a scene Embree cannot build fails on the workers with the reason */
    fprintf(stderr, "pcbpt-coord %s: warning: %s: not checked for surfaces seen from behind: %s\n", verb, s->path, e.msg);
    return;
  }
  /* Mitsuba's path tracer starts its camera rays at nearClip and ends them at farClip; its
     light tracing does not see past those surfaces, so there is no one image to match */
  if (b.nearer + b.farther > 0)
    fprintf(stderr,
            "pcbpt-coord %s: warning: %s: %.1f%% of the image is nearer than the sensor's nearClip (%g) and %.1f%% beyond"
            " its farClip (%g): pcbpt renders those surfaces, which Mitsuba's path tracer clips away\n",
            verb, s->path, 100.0 * b.nearer / b.rays, (double)s->camera.near_clip, 100.0 * b.farther / b.rays,
            (double)s->camera.far_clip);
  if (b.rays == 0 || b.backs * 100 < b.rays) return;
  char named[PC_SCENE_BACKS_NAMED * 320] = "";
  size_t used = 0;
  int named_hits = 0;
  for (int k = 0; k < b.nshapes && used < sizeof named; k++) {
    const pc_shape *sh = &s->shapes[b.shape[k]];
    /* a shape of an included file is named with its file */
    bool included = sh->xml_file > 0 && sh->xml_file <= s->nxml_includes;
    double pct = 100.0 * b.count[k] / b.rays;
    char share[16] = "under 1%";
    if (pct >= 1) snprintf(share, sizeof share, "%.0f%%", pct);
    int n = snprintf(named + used, sizeof named - used, "%s%s%sline %d (%s)", k ? ", " : "",
                     included ? s->xml_includes[sh->xml_file - 1] : "", included ? " " : "", sh->xml_line, share);
    if (n < 0) break;
    used += (size_t)n;
    named_hits += b.count[k];
  }
  fprintf(stderr,
          "pcbpt-coord %s: warning: %s: %.0f%% of the image is the back of one-sided materials, black as in Mitsuba"
          " 0.6 (they reflect only on the side their normals face): the %s at %s%s; if light is meant to reach"
          " that side, wrap their bsdf in twosided or set flipNormals\n",
          verb, s->path, 100.0 * b.backs / b.rays, b.nshapes > 1 ? "shapes" : "shape", named,
          b.backs > named_hits ? " and others" : "");
}

int pc_cli_scene_bundle(const pc_scene *s, uint8_t **blob, size_t *n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e) {
  return pc_bundle_create((const char *const *)s->files, (const char *const *)s->file_names, s->nfiles, blob, n, hash, e);
}
