/* scene_warn.c: the loader's warnings. Mitsuba warns about parameters it does not use and goes
 * on; so does pcbpt for settings that do not change what it computes. Each distinct warning is
 * handed once per scene to the caller's sink (the loader never prints), or is the error itself
 * under --strict. Also the list of files a scene read, which bundles ship. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "scene_xml_ctx.h"

#define MAX_WARNINGS 1024

int pc_sx_warn(pc_sx *c, const pc_xml_node *n, const char *fmt, ...) {
  char msg[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (c->opts->strict)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s (an error under --strict)", c->file, n->line, msg);
  for (int i = 0; i < c->nwarned; i++)
    if (strcmp(c->warned[i], msg) == 0) return 0;
  if (c->nwarned >= MAX_WARNINGS) return 0; /* a hostile file cannot grow this without bound */
  int rc = pc_sx_grow(c, (void **)&c->warned, &c->cap_warned, c->nwarned + 1, sizeof *c->warned);
  if (rc) return rc;
  if (!(c->warned[c->nwarned] = strdup(msg))) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  c->nwarned++;
  if (c->opts->warn) {
    char line[700];
    snprintf(line, sizeof line, "%s:%d: warning: %s", c->file, n->line, msg);
    c->opts->warn(c->opts->warn_ud, line);
  }
  return 0;
}

int pc_sx_note_file(pc_sx *c, const char *real, const char *name) {
  pc_scene *s = c->s;
  for (int i = 0; i < s->nfiles; i++)
    if (strcmp(s->file_names[i], name) == 0) return 0;
  /* sized before it is read: a scene too large to ship (a 2 GB mesh) is refused unread */
  struct stat st;
  if (c->opts->max_file_bytes && stat(real, &st) == 0 && st.st_size > 0) {
    c->file_bytes += (unsigned long long)st.st_size;
    if (c->file_bytes > c->opts->max_file_bytes)
      return pc_errf(c->e, PC_ELIMIT, "%s: the scene and its files exceed %zu bytes (at '%s')", c->main_file,
                     c->opts->max_file_bytes, real);
  }
  char **f = realloc(s->files, (size_t)(s->nfiles + 1) * sizeof *f);
  if (!f) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  s->files = f;
  char **fn = realloc(s->file_names, (size_t)(s->nfiles + 1) * sizeof *fn);
  if (!fn) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  s->file_names = fn;
  char *r = strdup(real), *nm = strdup(name);
  if (!r || !nm) {
    free(r);
    free(nm);
    return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  }
  s->files[s->nfiles] = r;
  s->file_names[s->nfiles++] = nm;
  return 0;
}
