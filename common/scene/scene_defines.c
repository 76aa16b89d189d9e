/* scene_defines.c: the -D name=value parameters of a scene, in a flat bounded buffer. */
#include <stdio.h>
#include <string.h>

#include "scene.h"

int pc_scene_defines_add(pc_scene_defines *d, const char *nv, pc_err *e) {
  const char *eq = strchr(nv, '=');
  if (!eq || eq == nv) return pc_errf(e, PC_EINVAL, "-D %.60s: expected name=value", nv);
  size_t nl = (size_t)(eq - nv), vl = strlen(eq + 1);
  for (size_t i = 0; i < nl; i++) {
    char ch = nv[i];
    if (!(ch == '_' || (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9')))
      return pc_errf(e, PC_EINVAL, "-D %.60s: the name must be letters, digits and _", nv);
  }
  /* Substitution is one pass, so a value naming its own parameter would stay "$name" for ever
   * (Mitsuba would loop or leave it); say so instead of failing later on a strange value. */
  const char *p = eq + 1;
  while ((p = strchr(p, '$'))) {
    if (strncmp(p + 1, nv, nl) == 0) return pc_errf(e, PC_EINVAL, "-D %.60s: '$%.*s' expands to itself", nv, (int)nl, nv);
    p++;
  }
  /* A later -D of the same name replaces the earlier one. */
  pc_scene_defines keep = {0};
  for (int i = 0; i < d->n; i++) {
    const char *n, *v;
    pc_scene_defines_get(d, i, &n, &v);
    if (strlen(n) == nl && strncmp(n, nv, nl) == 0) continue;
    size_t a = strlen(n) + 1, b = strlen(v) + 1;
    memcpy(keep.buf + keep.used, n, a);
    memcpy(keep.buf + keep.used + a, v, b);
    keep.used += (int)(a + b);
    keep.n++;
  }
  if (keep.n >= PC_SCENE_MAX_DEFINES) return pc_errf(e, PC_ELIMIT, "-D: more than %d parameters", PC_SCENE_MAX_DEFINES);
  if ((size_t)keep.used + nl + vl + 2 > sizeof keep.buf)
    return pc_errf(e, PC_ELIMIT, "-D: parameters longer than %d bytes in all", PC_SCENE_DEFINES_BYTES);
  memcpy(keep.buf + keep.used, nv, nl);
  keep.buf[keep.used + nl] = 0;
  memcpy(keep.buf + keep.used + nl + 1, eq + 1, vl + 1);
  keep.used += (int)(nl + vl + 2);
  keep.n++;
  *d = keep;
  return 0;
}

void pc_scene_defines_get(const pc_scene_defines *d, int i, const char **name, const char **value) {
  const char *p = d->buf;
  for (int k = 0; k < i; k++) {
    p += strlen(p) + 1;
    p += strlen(p) + 1;
  }
  *name = p;
  *value = p + strlen(p) + 1;
}

int pc_scene_defines_text(const pc_scene_defines *d, char *buf, size_t size) {
  bool taken[PC_SCENE_MAX_DEFINES] = {false};
  size_t len = 0;
  if (size) buf[0] = 0;
  for (int k = 0; k < d->n; k++) {
    int first = -1;
    const char *fn = NULL, *fv = NULL;
    for (int i = 0; i < d->n; i++) {
      const char *n, *v;
      pc_scene_defines_get(d, i, &n, &v);
      if (!taken[i] && (first < 0 || strcmp(n, fn) < 0)) {
        first = i;
        fn = n;
        fv = v;
      }
    }
    taken[first] = true;
    int w = snprintf(len < size ? buf + len : NULL, len < size ? size - len : 0, "%s%s=%s", k ? " " : "", fn, fv);
    if (w < 0) return w;
    len += (size_t)w;
  }
  return (int)len;
}
