/* scene_include.c: Mitsuba's <include filename="..."/>: another scene file whose <scene>
 * children take the include's place. The path is relative to the including file and must stay
 * inside the scene's root folder; a file that includes itself (directly or not) is refused. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_xml_ctx.h"

#define MAX_INCLUDED_FILES 256

static void mark_file(pc_xml_node *n, const char *file) {
  for (; n; n = n->next) {
    n->file = file;
    mark_file(n->first, file); /* recursion bounded by PC_XML_MAX_DEPTH */
  }
}

int pc_sx_include_open(pc_sx *c, const pc_xml_node *n, pc_xml_node **root) {
  static const char *const allowed[] = {"filename", NULL};
  *root = NULL;
  int rc = pc_xml_check_attrs(c->file, n, allowed, c->e);
  if (rc) return rc;
  if (n->first) return pc_errf(c->e, PC_EPARSE, "%s:%d: <include> must be empty", c->file, n->line);
  const char *rel = pc_xml_attr(n, "filename");
  if (!rel || !*rel) return pc_errf(c->e, PC_EPARSE, "%s:%d: <include> needs a filename", c->file, n->line);
  if (rel[0] == '/')
    return pc_errf(c->e, PC_EINVAL, "%s:%d: <include>: absolute path '%s' (paths are relative to the including file)", c->file,
                   n->line, rel);
  if (c->incl_depth >= (int)(sizeof c->incl_stack / sizeof c->incl_stack[0]))
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: <include>: nested more than %d deep", c->file, n->line, c->incl_depth);
  if (c->nnames >= MAX_INCLUDED_FILES)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: <include>: more than %d included files", c->file, n->line, MAX_INCLUDED_FILES);
  /* Relative to the including file (its real path is on top of the stack). */
  const char *cur = c->incl_stack[c->incl_depth - 1];
  const char *slash = strrchr(cur, '/');
  char joined[PATH_MAX], real[PATH_MAX];
  if ((size_t)snprintf(joined, sizeof joined, "%.*s/%s", (int)(slash - cur), cur, rel) >= sizeof joined)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: <include>: path too long", c->file, n->line);
  if (!realpath(joined, real))
    return pc_errf(c->e, PC_EIO, "%s:%d: <include>: cannot find '%s': %s", c->file, n->line, rel, strerror(errno));
  size_t dl = strlen(c->dir);
  if (!(strcmp(c->dir, "/") == 0 || (strncmp(real, c->dir, dl) == 0 && real[dl] == '/')))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: <include>: '%s' lies outside the scene's folder %s (see --scene-root)", c->file,
                   n->line, rel, c->dir);
  for (int i = 0; i < c->incl_depth; i++)
    if (strcmp(c->incl_stack[i], real) == 0)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: <include>: '%s' includes itself (an include loop)", c->file, n->line, rel);
  /* Messages name it as the including file's folder plus the relative path. */
  const char *ds = strrchr(c->file, '/');
  char display[PATH_MAX];
  if (ds) snprintf(display, sizeof display, "%.*s/%s", (int)(ds - c->file), c->file, rel);
  else snprintf(display, sizeof display, "%s", rel);
  int r = pc_sx_grow(c, (void **)&c->names, &c->cap_names, c->nnames + 1, sizeof *c->names);
  if (r) return r;
  char *name = strdup(display), *stacked = strdup(real);
  if (!name || !stacked) {
    free(name);
    free(stacked);
    return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  }
  c->names[c->nnames++] = name;
  char below[PATH_MAX];
  if ((rc = pc_sx_name_below(c, n, c->incl_names[c->incl_depth - 1], rel, below)) || (rc = pc_sx_note_file(c, real, below))) {
    free(stacked);
    return rc;
  }
  pc_xml_node *t = NULL;
  if ((rc = pc_xml_parse(real, name, &t, c->e))) {
    free(stacked);
    return rc;
  }
  if (strcmp(t->name, "scene") != 0 || !pc_xml_attr(t, "version")) {
    rc = pc_errf(c->e, PC_EPARSE, "%s:%d: an included file's root must be <scene version=...>", name, t->line);
    pc_xml_free(t);
    free(stacked);
    return rc;
  }
  mark_file(t->first, name);
  if (!(c->incl_names[c->incl_depth] = strdup(below))) {
    pc_xml_free(t);
    free(stacked);
    return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  }
  c->incl_stack[c->incl_depth++] = stacked;
  *root = t;
  return 0;
}

void pc_sx_include_close(pc_sx *c) {
  free(c->incl_names[c->incl_depth - 1]);
  free((char *)c->incl_stack[--c->incl_depth]);
}
