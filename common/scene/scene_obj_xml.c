/* scene_obj_xml.c: the materials of an OBJ shape as Mitsuba 0.6's obj plugin assigns them. A
 * mesh of the file (mesh_obj.c splits it at `g` and `usemtl`) gets, in this order of
 * precedence: the last of the shape's BSDF children that is unnamed or named after the
 * mesh's `usemtl` name (Mitsuba adds children in document order, each replacing the one
 * before on the meshes it names); else the material of that name in the file's `mtllib`, made
 * as Mitsuba's addMaterial makes it (below); else Mitsuba's default diffuse.
 *
 * A .mtl material: Kd, Ks (sRGB, as fromSRGB), map_Kd, map_Ks (bitmaps), Ns, illum, bump
 * (bitmap, gamma 1) and d or map_d (an opacity mask); everything else is ignored, as Mitsuba
 * does. illum 2 makes a phong (a diffuse when Ks or Ns is zero), 4, 6, 7 and 9 a smooth
 * dielectric, 5 and 8 a smooth aluminium conductor, anything else a diffuse of Kd (black when
 * Kd is not given); then a bump map wraps it, and a mask wraps that. Each is built as the
 * equivalent XML element and read by the ordinary BSDF reader, so every check applies. */
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "file_read.h"
#include "parse.h"
#include "scene_xml_ctx.h"

#define MTL_MAX_FILE ((size_t)64 << 20)
#define MTL_MAX_MATERIALS 65536
#define MTL_MAX_NAME 4096

typedef struct mtl_entry {
  char *name;
  int line;
  float kd[3], ks[3], ns, d;
  bool has_kd, has_ks;
  char *map_kd, *map_ks, *bump, *map_d;
  int illum;
  int material; /* made on first use; -1 until then */
} mtl_entry;

struct pc_sx_mtl {
  char *display; /* the library's name below the root, for messages */
  char *objdir;  /* the OBJ file's folder as written in the scene ("" for the scene's), with '/' */
  int n, cap;
  mtl_entry *e;
};

void pc_sx_mtl_free(pc_sx_mtl *lib) {
  if (!lib) return;
  for (int i = 0; i < lib->n; i++) {
    mtl_entry *m = &lib->e[i];
    free(m->name);
    free(m->map_kd);
    free(m->map_ks);
    free(m->bump);
    free(m->map_d);
  }
  free(lib->e);
  free(lib->display);
  free(lib->objdir);
  free(lib);
}

static bool is_space(char ch) { return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f'; }

/* [s, end) without the whitespace around it, malloc'd. */
static char *trimmed(const char *s, const char *end) {
  while (s < end && is_space(*s)) s++;
  while (end > s && is_space(end[-1])) end--;
  return (size_t)(end - s) <= MTL_MAX_NAME ? strndup(s, (size_t)(end - s)) : NULL;
}

/* The next whitespace-separated token of [*s, end), malloc'd; NULL at the end of the line. */
static char *token(const char **s, const char *end) {
  const char *t = *s;
  while (t < end && is_space(*t)) t++;
  const char *u = t;
  while (u < end && !is_space(*u)) u++;
  *s = u;
  return u > t ? trimmed(t, u) : NULL;
}

static int numbers(pc_sx *c, const pc_sx_mtl *lib, int line, const char *key, const char *s, const char *end, float *out,
                   int count) {
  for (int i = 0; i < count; i++) {
    char *t = token(&s, end);
    double v;
    bool ok = t && pc_parse_f64(t, -FLT_MAX, FLT_MAX, &v);
    free(t);
    if (!ok)
      return pc_errf(c->e, PC_EPARSE, "%s:%d: '%s' needs %d finite number%s", lib->display, line, key, count, count > 1 ? "s" : "");
    out[i] = (float)v;
  }
  return 0;
}

static int parse_line(pc_sx *c, pc_sx_mtl *lib, int line, const char *s, const char *end) {
  const char *rest = s;
  char *key = token(&rest, end);
  if (!key || key[0] == '#') {
    free(key);
    return 0;
  }
  int rc = 0;
  mtl_entry *m = lib->n ? &lib->e[lib->n - 1] : NULL;
  if (strcmp(key, "newmtl") == 0) {
    if (lib->n >= MTL_MAX_MATERIALS) rc = pc_errf(c->e, PC_ELIMIT, "%s:%d: more than %d materials", lib->display, line, MTL_MAX_MATERIALS);
    else if (!(rc = pc_sx_grow(c, (void **)&lib->e, &lib->cap, lib->n + 1, sizeof *lib->e))) {
      m = &lib->e[lib->n];
      memset(m, 0, sizeof *m);
      m->line = line;
      m->material = -1;
      m->d = 1.f;
      if (!(m->name = trimmed(rest, end))) rc = pc_errf(c->e, PC_ELIMIT, "%s:%d: material name too long or out of memory", lib->display, line);
      else lib->n++;
    }
  } else if (!m) {
    /* Mitsuba keeps what comes before the first newmtl for a material named "": never used */
  } else if (strcmp(key, "Kd") == 0 || strcmp(key, "Ks") == 0) {
    bool kd = key[1] == 'd';
    if (!(rc = numbers(c, lib, line, key, rest, end, kd ? m->kd : m->ks, 3))) *(kd ? &m->has_kd : &m->has_ks) = true;
  } else if (strcmp(key, "Ns") == 0) {
    rc = numbers(c, lib, line, key, rest, end, &m->ns, 1);
  } else if (strcmp(key, "d") == 0) {
    rc = numbers(c, lib, line, key, rest, end, &m->d, 1);
    if (!rc && !(m->d >= 0.f && m->d <= 1.f)) rc = pc_errf(c->e, PC_EINVAL, "%s:%d: 'd' must lie in [0, 1]", lib->display, line);
  } else if (strcmp(key, "illum") == 0) {
    float v;
    if (!(rc = numbers(c, lib, line, key, rest, end, &v, 1))) {
      if (v != (float)(int)v) rc = pc_errf(c->e, PC_EPARSE, "%s:%d: 'illum' must be an integer", lib->display, line);
      m->illum = (int)v;
    }
  } else if (strcmp(key, "map_Kd") == 0 || strcmp(key, "map_Ks") == 0 || strcmp(key, "bump") == 0 ||
             strcmp(key, "map_d") == 0) {
    /* Mitsuba reads the first word: a map given with options is looked for under the option's name */
    char **slot = key[0] == 'b' ? &m->bump : strcmp(key, "map_d") == 0 ? &m->map_d : key[5] == 'd' ? &m->map_kd : &m->map_ks;
    free(*slot);
    if (!(*slot = token(&rest, end))) rc = pc_errf(c->e, PC_EPARSE, "%s:%d: '%s' needs a file name", lib->display, line, key);
    else
      for (char *p = *slot; *p; p++)
        if (*p == '\\') *p = '/'; /* files written on Windows, as Mitsuba */
  }
  free(key);
  return rc;
}

/* The folder of `rel` with its trailing '/', or "" (malloc'd). */
static char *folder_of(const char *rel) {
  const char *slash = strrchr(rel, '/');
  size_t len = slash ? (size_t)(slash - rel + 1) : 0;
  char *out = malloc(len + 1);
  if (out) {
    memcpy(out, rel, len);
    out[len] = 0;
  }
  return out;
}

/* The first of `candidates` (NULL-terminated, relative to the scene's folder) that exists inside
 * the scene's folder, strdup'd into *out; *out NULL when none does. */
static int first_existing(pc_sx *c, const pc_xml_node *n, const char *what, const char *const *candidates, char **out) {
  *out = NULL;
  for (const char *const *p = candidates; *p; p++) {
    if (!**p) continue;
    char *real;
    int rc = pc_sx_resolve(c, n, what, *p, &real);
    if (rc == PC_ENOMEM) return rc;
    if (rc) continue;
    free(real);
    if (!(*out = strdup(*p))) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
    return 0;
  }
  return 0;
}

static char *joined(const char *a, const char *b) {
  size_t la = strlen(a), lb = strlen(b);
  char *out = malloc(la + lb + 1);
  if (out) {
    memcpy(out, a, la);
    memcpy(out + la, b, lb + 1);
  }
  return out;
}

int pc_sx_mtl_load(pc_sx *c, const pc_xml_node *shape, const char *obj_rel, const char *mtllib, int line,
                   pc_sx_mtl **out) {
  *out = NULL;
  pc_sx_mtl *lib = calloc(1, sizeof *lib);
  if (!lib || !(lib->objdir = folder_of(obj_rel))) {
    free(lib);
    return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  }
  /* Mitsuba looks in the OBJ's folder first, then in the scene's */
  char *in_dir = joined(lib->objdir, mtllib), *rel = NULL;
  const char *cand[] = {in_dir ? in_dir : "", mtllib, NULL};
  int rc = in_dir ? first_existing(c, shape, "shape 'obj'", cand, &rel) : pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  free(in_dir);
  if (!rc && !rel) {
    pc_sx_mtl_free(lib);
    return pc_sx_warn(c, shape, "shape 'obj': cannot find its material library '%s' (%s line %d); its meshes get the shape's BSDFs "
                      "or the default, as in Mitsuba", mtllib, obj_rel, line);
  }
  char *path = NULL, *buf = NULL;
  size_t len = 0;
  if (!rc) rc = pc_sx_resolve(c, shape, "shape 'obj'", rel, &path);
  if (!rc && !(lib->display = strdup(rel))) rc = pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  if (!rc && (rc = pc_file_read(path, MTL_MAX_FILE, &buf, &len, c->e))) rc = pc_sx_wrap(c, shape, "shape 'obj'", rc);
  free(rel);
  free(path);
  if (!rc && memchr(buf, 0, len)) rc = pc_errf(c->e, PC_EPARSE, "%s: NUL byte in a text file", lib->display);
  const char *s = buf, *end = buf + len;
  for (int ln = 1; !rc && s < end; ln++) {
    const char *eol = memchr(s, '\n', (size_t)(end - s));
    if (!eol) eol = end;
    rc = parse_line(c, lib, ln, s, eol);
    s = eol + 1;
  }
  free(buf);
  if (rc) {
    pc_sx_mtl_free(lib);
    return rc;
  }
  *out = lib;
  return 0;
}

/* Generated XML elements: one allocation failure makes the whole tree NULL. */
typedef struct xb {
  bool oom;
  int line;
} xb;

/* Adds child as the last child of parent. */
static void append(pc_xml_node *parent, pc_xml_node *child) {
  pc_xml_node **p = &parent->first;
  while (*p) p = &(*p)->next;
  *p = child;
}

static pc_xml_node *el(xb *b, pc_xml_node *parent, const char *name, const char *a1, const char *v1, const char *a2,
                       const char *v2) {
  pc_xml_node *n = calloc(1, sizeof *n);
  int na = a2 ? 2 : a1 ? 1 : 0;
  if (n) {
    n->name = strdup(name);
    n->line = b->line;
    n->attrs = na ? calloc((size_t)(2 * na), sizeof *n->attrs) : NULL;
    n->nattrs = na;
    const char *kv[4] = {a1, v1, a2, v2};
    for (int i = 0; i < 2 * na && n->attrs; i++) n->attrs[i] = strdup(kv[i]);
  }
  bool ok = n && n->name && (!na || n->attrs);
  for (int i = 0; ok && i < 2 * na; i++) ok = n->attrs[i] != NULL;
  if (!ok) {
    b->oom = true;
    pc_xml_free(n);
    return NULL;
  }
  if (parent) append(parent, n);
  return n;
}

static void number_el(xb *b, pc_xml_node *parent, const char *kind, const char *name, const float *v, int count) {
  char text[96];
  if (count == 3) snprintf(text, sizeof text, "%.9g %.9g %.9g", (double)v[0], (double)v[1], (double)v[2]);
  else snprintf(text, sizeof text, "%.9g", (double)v[0]);
  el(b, parent, kind, "name", name, "value", text);
}

/* Where a map of the library is (*rel, relative to the scene's folder), or *rel NULL with a
 * warning where Mitsuba cannot find it either (it then uses a black constant). */
static int find_map(pc_sx *c, const pc_sx_mtl *lib, const mtl_entry *m, const pc_xml_node *at, const char *file, char **rel) {
  /* Mitsuba: the name as written, in the OBJ's folder or the scene's, then its last part */
  const char *base = strrchr(file, '/');
  base = base ? base + 1 : file;
  char *a = joined(lib->objdir, file), *d = joined(lib->objdir, base);
  const char *cand[] = {a ? a : "", file, d ? d : "", base, NULL};
  int rc = a && d ? first_existing(c, at, "bsdf", cand, rel) : pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  free(a);
  free(d);
  if (!rc && !*rel) rc = pc_sx_warn(c, at, "material '%s': cannot find the texture '%s'; black instead, as in Mitsuba", m->name, file);
  return rc;
}

/* A bitmap texture of `rel` named `name` (NULL: unnamed), gamma 1 where `linear`. */
static void bitmap_el(xb *b, pc_xml_node *parent, const char *name, const char *rel, bool linear) {
  pc_xml_node *t = el(b, parent, "texture", "type", "bitmap", name ? "name" : NULL, name);
  if (!t) return;
  el(b, t, "string", "name", "filename", "value", rel);
  if (linear) el(b, t, "float", "name", "gamma", "value", "1");
}

/* A map as the parameter `name`: its bitmap, or black where it cannot be found. */
static int map_el(pc_sx *c, xb *b, const pc_sx_mtl *lib, const mtl_entry *m, pc_xml_node *parent, const char *name,
                  const char *file) {
  char *rel;
  int rc = find_map(c, lib, m, parent, file, &rel);
  if (rc) return rc;
  static const float black = 0.f;
  if (rel) bitmap_el(b, parent, name, rel, false);
  else number_el(b, parent, "spectrum", name, &black, 1);
  free(rel);
  return 0;
}

static int colour_el(pc_sx *c, xb *b, const pc_sx_mtl *lib, const mtl_entry *m, pc_xml_node *parent, const char *name,
                     const char *map, bool has, const float *rgb) {
  if (map) return map_el(c, b, lib, m, parent, name, map);
  static const float zero[3] = {0, 0, 0};
  number_el(b, parent, "srgb", name, has ? rgb : zero, 3);
  return 0;
}

/* Mitsuba's addMaterial as an element tree. */
static int material_tree(pc_sx *c, xb *b, const pc_sx_mtl *lib, const mtl_entry *m, pc_xml_node **out) {
  *out = NULL;
  int model = m->illum, rc = 0;
  /* Mitsuba tests the specular texture's maximum; a map counts as non-zero here */
  bool ks_zero = !m->map_ks && (!m->has_ks || (m->ks[0] == 0 && m->ks[1] == 0 && m->ks[2] == 0));
  if (model == 2 && (ks_zero || m->ns == 0)) model = 1;
  pc_xml_node *bsdf;
  if (model == 2) {
    bsdf = el(b, NULL, "bsdf", "type", "phong", NULL, NULL);
    if (bsdf && !(rc = colour_el(c, b, lib, m, bsdf, "diffuseReflectance", m->map_kd, m->has_kd, m->kd)) &&
        !(rc = colour_el(c, b, lib, m, bsdf, "specularReflectance", m->map_ks, m->has_ks, m->ks)))
      number_el(b, bsdf, "float", "exponent", &m->ns, 1);
  } else if (model == 4 || model == 6 || model == 7 || model == 9) {
    bsdf = el(b, NULL, "bsdf", "type", "dielectric", NULL, NULL);
  } else if (model == 5 || model == 8) {
    bsdf = el(b, NULL, "bsdf", "type", "conductor", NULL, NULL);
    if (bsdf) el(b, bsdf, "string", "name", "material", "value", "Al");
  } else {
    bsdf = el(b, NULL, "bsdf", "type", "diffuse", NULL, NULL);
    if (bsdf) rc = colour_el(c, b, lib, m, bsdf, "reflectance", m->map_kd, m->has_kd, m->kd);
  }
  char *bump = NULL;
  /* a bump map Mitsuba cannot find is a constant: no bump at all */
  if (!rc && bsdf && m->bump && !(rc = find_map(c, lib, m, bsdf, m->bump, &bump)) && bump) {
    pc_xml_node *w = el(b, NULL, "bsdf", "type", "bumpmap", NULL, NULL);
    if (w) {
      bitmap_el(b, w, NULL, bump, true);
      append(w, bsdf);
      bsdf = w;
    }
  }
  free(bump);
  if (!rc && bsdf && (m->map_d || m->d != 1.f)) {
    pc_xml_node *w = el(b, NULL, "bsdf", "type", "mask", NULL, NULL);
    if (w) {
      if (m->map_d) rc = map_el(c, b, lib, m, w, "opacity", m->map_d);
      else number_el(b, w, "spectrum", "opacity", &m->d, 1);
      append(w, bsdf);
      bsdf = w;
    }
  }
  if (rc || b->oom) {
    pc_xml_free(bsdf);
    return rc ? rc : pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  }
  *out = bsdf;
  return 0;
}

int pc_sx_mtl_material(pc_sx *c, pc_sx_mtl *lib, const char *name, int *index) {
  *index = -1;
  if (!lib) return 0;
  mtl_entry *m = NULL;
  /* Mitsuba's map keeps the last material of a name */
  for (int i = lib->n - 1; i >= 0 && !m; i--)
    if (strcmp(lib->e[i].name, name) == 0) m = &lib->e[i];
  if (!m) return 0;
  if (m->material < 0) {
    /* messages name the library and the material's line */
    const char *file = c->file;
    c->file = lib->display;
    xb b = {false, m->line};
    pc_xml_node *tree;
    int rc = material_tree(c, &b, lib, m, &tree);
    if (!rc) rc = pc_sx_bsdf(c, tree, &m->material);
    pc_xml_free(tree);
    c->file = file;
    if (rc) return rc;
  }
  *index = m->material;
  return 0;
}
