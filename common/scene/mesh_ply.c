/* mesh_ply.c: the PLY reader (ascii and binary_little_endian). Uses x,y,z, optional
 * nx,ny,nz and texture coordinates (u,v / s,t / texture_u,texture_v / texture_s,texture_t)
 * of `vertex`, and the index list (vertex_indices or vertex_index) of `face`, polygons
 * fan-triangulated; every other element and property is skipped by its declared type. Counts
 * are checked against the size of the data before anything is allocated. */
#include <stdlib.h>
#include <string.h>

#include "big_alloc.h"
#include "file_read.h"
#include "mesh.h"

#define PLY_MAX_FILE ((size_t)2 << 30)
#define PLY_MAX_HEADER (64 << 10)
#define PLY_MAX_ELEMS 32
#define PLY_MAX_PROPS 64
#define PLY_MAX_NAME 64

typedef enum { T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 } ply_type;
static const int type_size[] = {1, 1, 2, 2, 4, 4, 4, 8};

enum { R_NONE, R_X, R_Y, R_Z, R_NX, R_NY, R_NZ, R_U, R_V, R_INDICES };

typedef struct ply_prop {
  char name[PLY_MAX_NAME];
  ply_type type, count_type;
  int is_list, role;
} ply_prop;

typedef struct ply_elem {
  char name[PLY_MAX_NAME];
  uint64_t count;
  ply_prop props[PLY_MAX_PROPS];
  int nprops;
} ply_elem;

typedef struct ply_reader {
  const char *path;
  int binary;
  const unsigned char *s, *end;
  int line;          /* ascii: current line */
  uint64_t elem_i;   /* index of the element instance being read, for messages */
  const char *elem_name;
  pc_err *e;
} ply_reader;

static int type_from_name(const char *s, ply_type *t) {
  static const struct { const char *n; ply_type t; } tab[] = {
      {"char", T_I8},    {"int8", T_I8},     {"uchar", T_U8},    {"uint8", T_U8},
      {"short", T_I16},  {"int16", T_I16},   {"ushort", T_U16},  {"uint16", T_U16},
      {"int", T_I32},    {"int32", T_I32},   {"uint", T_U32},    {"uint32", T_U32},
      {"float", T_F32},  {"float32", T_F32}, {"double", T_F64},  {"float64", T_F64},
  };
  for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
    if (strcmp(s, tab[i].n) == 0) {
      *t = tab[i].t;
      return 1;
    }
  return 0;
}

static int where_err(ply_reader *r, int code, const char *what) {
  if (r->binary)
    return pc_errf(r->e, code, "%s: %s %llu: %s", r->path, r->elem_name, (unsigned long long)r->elem_i, what);
  return pc_errf(r->e, code, "%s:%d: %s %llu: %s", r->path, r->line, r->elem_name, (unsigned long long)r->elem_i, what);
}

static int read_value(ply_reader *r, ply_type t, double *out) {
  if (r->binary) {
    int n = type_size[t];
    if (r->end - r->s < n) return where_err(r, PC_EPARSE, "file is truncated");
    uint64_t u = 0;
    for (int i = n - 1; i >= 0; i--) u = (u << 8) | r->s[i];
    r->s += n;
    switch (t) {
    case T_I8: *out = (int8_t)u; break;
    case T_U8: *out = (uint8_t)u; break;
    case T_I16: *out = (int16_t)u; break;
    case T_U16: *out = (uint16_t)u; break;
    case T_I32: *out = (int32_t)u; break;
    case T_U32: *out = (uint32_t)u; break;
    case T_F32: { uint32_t b = (uint32_t)u; float f; memcpy(&f, &b, 4); *out = f; break; }
    case T_F64: { double d; memcpy(&d, &u, 8); *out = d; break; }
    }
    if (!isfinite(*out)) return where_err(r, PC_ENUMERIC, "non-finite value");
    return 0;
  }
  while (r->s < r->end && (*r->s == ' ' || *r->s == '\t' || *r->s == '\r' || *r->s == '\n')) {
    if (*r->s == '\n') r->line++;
    r->s++;
  }
  char buf[64];
  size_t len = 0;
  while (r->s < r->end && !(*r->s == ' ' || *r->s == '\t' || *r->s == '\r' || *r->s == '\n')) {
    if (len + 1 >= sizeof buf) return where_err(r, PC_EPARSE, "malformed number");
    buf[len++] = (char)*r->s++;
  }
  if (len == 0) return where_err(r, PC_EPARSE, "file is truncated");
  buf[len] = 0;
  char *endp;
  double d = strtod(buf, &endp);
  if (*endp) return where_err(r, PC_EPARSE, "malformed number");
  if (!isfinite(d)) return where_err(r, PC_ENUMERIC, "non-finite value");
  if (t != T_F32 && t != T_F64 && d != floor(d)) return where_err(r, PC_EPARSE, "non-integer value of an integer property");
  *out = d;
  return 0;
}

static int read_count(ply_reader *r, ply_type t, uint32_t *out) {
  double d;
  int rc = read_value(r, t, &d);
  if (rc) return rc;
  if (t == T_F32 || t == T_F64 || d < 0 || d != floor(d))
    return where_err(r, PC_EPARSE, "invalid list length");
  /* Every item takes at least one byte, so a list longer than the rest of the file is bogus. */
  if (d > (double)(r->end - r->s)) return where_err(r, PC_EPARSE, "list longer than the rest of the file");
  *out = (uint32_t)d;
  return 0;
}

/* Reads one header line into buf (NUL-terminated, \r stripped); returns 0 at the end. */
static int header_line(const char **s, const char *end, char *buf, size_t cap) {
  const char *eol = memchr(*s, '\n', (size_t)(end - *s));
  if (!eol) return 0;
  size_t len = (size_t)(eol - *s);
  if (len && (*s)[len - 1] == '\r') len--;
  if (len >= cap) len = cap - 1;
  memcpy(buf, *s, len);
  buf[len] = 0;
  *s = eol + 1;
  return 1;
}

static int parse_header(const char *path, const char *buf, size_t n, ply_elem *elems, int *nelems,
                        int *binary, size_t *data_off, pc_err *e) {
  const char *s = buf, *end = buf + (n < PLY_MAX_HEADER ? n : PLY_MAX_HEADER);
  char line[512];
  int ln = 0, have_format = 0;
  *nelems = 0;
  for (;;) {
    if (!header_line(&s, end, line, sizeof line))
      return pc_errf(e, PC_EPARSE, "%s: header without end_header (or longer than %d bytes)", path, PLY_MAX_HEADER);
    ln++;
    char *save = NULL;
    char *kw = strtok_r(line, " \t", &save);
    if (ln == 1) {
      if (!kw || strcmp(kw, "ply") != 0 || strtok_r(NULL, " \t", &save))
        return pc_errf(e, PC_EPARSE, "%s:1: not a PLY file", path);
      continue;
    }
    if (!kw) return pc_errf(e, PC_EPARSE, "%s:%d: empty header line", path, ln);
    if (strcmp(kw, "comment") == 0 || strcmp(kw, "obj_info") == 0) continue;
    if (strcmp(kw, "end_header") == 0) break;
    char *a = strtok_r(NULL, " \t", &save), *b = strtok_r(NULL, " \t", &save);
    char *c = strtok_r(NULL, " \t", &save), *d = strtok_r(NULL, " \t", &save);
    char *x = strtok_r(NULL, " \t", &save);
    if (strcmp(kw, "format") == 0) {
      if (have_format || !a || !b || c) return pc_errf(e, PC_EPARSE, "%s:%d: malformed format line", path, ln);
      if (strcmp(b, "1.0") != 0) return pc_errf(e, PC_EUNSUPPORTED, "%s:%d: PLY version '%s' unsupported", path, ln, b);
      if (strcmp(a, "ascii") == 0) *binary = 0;
      else if (strcmp(a, "binary_little_endian") == 0) *binary = 1;
      else return pc_errf(e, PC_EUNSUPPORTED, "%s:%d: PLY format '%s' unsupported (ascii or binary_little_endian)", path, ln, a);
      have_format = 1;
    } else if (strcmp(kw, "element") == 0) {
      if (!a || !b || c) return pc_errf(e, PC_EPARSE, "%s:%d: malformed element line", path, ln);
      if (*nelems == PLY_MAX_ELEMS) return pc_errf(e, PC_ELIMIT, "%s:%d: more than %d elements", path, ln, PLY_MAX_ELEMS);
      if (strlen(a) >= PLY_MAX_NAME) return pc_errf(e, PC_ELIMIT, "%s:%d: element name too long", path, ln);
      char *endp;
      unsigned long long cnt = strtoull(b, &endp, 10);
      if (*endp || *b == '-' || cnt > UINT32_MAX)
        return pc_errf(e, PC_EPARSE, "%s:%d: invalid element count '%s'", path, ln, b);
      ply_elem *el = &elems[(*nelems)++];
      memset(el, 0, sizeof *el);
      strcpy(el->name, a);
      el->count = cnt;
    } else if (strcmp(kw, "property") == 0) {
      if (*nelems == 0) return pc_errf(e, PC_EPARSE, "%s:%d: property before any element", path, ln);
      ply_elem *el = &elems[*nelems - 1];
      if (el->nprops == PLY_MAX_PROPS) return pc_errf(e, PC_ELIMIT, "%s:%d: more than %d properties", path, ln, PLY_MAX_PROPS);
      ply_prop *p = &el->props[el->nprops];
      memset(p, 0, sizeof *p);
      const char *name;
      if (a && strcmp(a, "list") == 0) {
        if (!b || !c || !d || x || !type_from_name(b, &p->count_type) || !type_from_name(c, &p->type))
          return pc_errf(e, PC_EPARSE, "%s:%d: malformed list property", path, ln);
        p->is_list = 1;
        name = d;
      } else {
        if (!a || !b || c || !type_from_name(a, &p->type))
          return pc_errf(e, PC_EPARSE, "%s:%d: malformed property", path, ln);
        name = b;
      }
      if (strlen(name) >= PLY_MAX_NAME) return pc_errf(e, PC_ELIMIT, "%s:%d: property name too long", path, ln);
      strcpy(p->name, name);
      el->nprops++;
    } else {
      return pc_errf(e, PC_EPARSE, "%s:%d: unknown header keyword '%.32s'", path, ln, kw);
    }
  }
  if (!have_format) return pc_errf(e, PC_EPARSE, "%s: no format line", path);
  *data_off = (size_t)(s - buf);
  return 0;
}

static int assign_roles(const char *path, ply_elem *el, int *vert_has, pc_err *e) {
  static const struct { const char *n; int role; } vtab[] = {
      {"x", R_X}, {"y", R_Y}, {"z", R_Z}, {"nx", R_NX}, {"ny", R_NY}, {"nz", R_NZ},
      {"u", R_U}, {"v", R_V}, {"s", R_U}, {"t", R_V}, {"texture_u", R_U}, {"texture_v", R_V},
      {"texture_s", R_U}, {"texture_t", R_V},
  };
  int is_vertex = strcmp(el->name, "vertex") == 0, is_face = strcmp(el->name, "face") == 0;
  for (int i = 0; i < el->nprops; i++) {
    ply_prop *p = &el->props[i];
    if (is_vertex)
      for (size_t k = 0; k < sizeof vtab / sizeof vtab[0]; k++)
        if (strcmp(p->name, vtab[k].n) == 0) p->role = vtab[k].role;
    if (is_face && (strcmp(p->name, "vertex_indices") == 0 || strcmp(p->name, "vertex_index") == 0))
      p->role = R_INDICES;
    if (p->role == R_NONE) continue;
    if ((p->role == R_INDICES) != (p->is_list != 0))
      return pc_errf(e, PC_EPARSE, "%s: property '%s' of '%s' has the wrong kind (list or scalar)", path, p->name, el->name);
    if (p->role == R_INDICES && (p->type == T_F32 || p->type == T_F64 || p->count_type == T_F32 || p->count_type == T_F64))
      return pc_errf(e, PC_EPARSE, "%s: face indices must be integers", path);
    if (vert_has[p->role]) return pc_errf(e, PC_EPARSE, "%s: property '%s' given twice", path, p->name);
    vert_has[p->role] = 1;
  }
  return 0;
}

/* Least number of bytes the data section must hold for what the header declares. */
static uint64_t min_data_size(const ply_elem *elems, int nelems, int binary) {
  uint64_t total = 0;
  for (int i = 0; i < nelems; i++) {
    uint64_t row = 0;
    for (int k = 0; k < elems[i].nprops; k++) {
      const ply_prop *p = &elems[i].props[k];
      row += binary ? (uint64_t)type_size[p->is_list ? p->count_type : p->type] : 2;
    }
    total += row * elems[i].count;
  }
  return binary ? total : (total > 0 ? total - 1 : 0);
}

int pc_mesh_load_ply(const char *path, pc_mesh *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  char *buf;
  size_t n;
  int rc = pc_file_read(path, PLY_MAX_FILE, &buf, &n, e);
  if (rc) return rc;
  ply_elem *elems = malloc(PLY_MAX_ELEMS * sizeof *elems);
  if (!elems) {
    free(buf);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  }
  int nelems = 0, binary = 0, has[R_INDICES + 1] = {0};
  size_t off = 0;
  uint64_t nv = 0, nf = 0;
  int vert_el = -1, face_el = -1;
  rc = parse_header(path, buf, n, elems, &nelems, &binary, &off, e);
  for (int i = 0; !rc && i < nelems; i++) {
    if (strcmp(elems[i].name, "vertex") == 0 || strcmp(elems[i].name, "face") == 0) {
      int *slot = elems[i].name[0] == 'v' ? &vert_el : &face_el;
      if (*slot >= 0) rc = pc_errf(e, PC_EPARSE, "%s: element '%s' declared twice", path, elems[i].name);
      *slot = i;
    }
    if (!rc) rc = assign_roles(path, &elems[i], has, e);
  }
  if (!rc) {
    if (vert_el < 0 || face_el < 0) rc = pc_errf(e, PC_EPARSE, "%s: needs both a vertex and a face element", path);
    else if (!has[R_X] || !has[R_Y] || !has[R_Z]) rc = pc_errf(e, PC_EPARSE, "%s: vertex element lacks x, y or z", path);
    else if (has[R_NX] + has[R_NY] + has[R_NZ] != 0 && has[R_NX] + has[R_NY] + has[R_NZ] != 3)
      rc = pc_errf(e, PC_EPARSE, "%s: vertex element has only some of nx, ny, nz", path);
    else if (has[R_U] != has[R_V]) rc = pc_errf(e, PC_EPARSE, "%s: vertex element has only one texture coordinate", path);
    else if (!has[R_INDICES]) rc = pc_errf(e, PC_EPARSE, "%s: face element lacks vertex_indices", path);
  }
  if (!rc) {
    nv = elems[vert_el].count;
    nf = elems[face_el].count;
    if (nv > PC_MESH_MAX_VERTICES || nf > PC_MESH_MAX_TRIANGLES)
      rc = pc_errf(e, PC_ELIMIT, "%s: header declares %llu vertices and %llu faces (limits %u, %u)", path,
                   (unsigned long long)nv, (unsigned long long)nf, PC_MESH_MAX_VERTICES, PC_MESH_MAX_TRIANGLES);
    else if (nv == 0 || nf == 0) rc = pc_errf(e, PC_EINVAL, "%s: no vertices or no faces", path);
    else if (min_data_size(elems, nelems, binary) > n - off)
      rc = pc_errf(e, PC_EPARSE, "%s: file is truncated: the header declares at least %llu bytes of data, the file has %zu",
                   path, (unsigned long long)min_data_size(elems, nelems, binary), n - off);
  }
  pc_mesh m = {0};
  uint32_t cap_tris = 0;
  if (!rc) {
    m.nverts = (uint32_t)nv;
    m.p = pc_big_alloc(nv * sizeof *m.p);
    m.n = has[R_NX] ? pc_big_alloc(nv * sizeof *m.n) : NULL;
    m.uv = has[R_U] ? pc_big_alloc(nv * sizeof *m.uv) : NULL;
    cap_tris = (uint32_t)nf;
    m.idx = pc_big_alloc(3 * (size_t)cap_tris * sizeof *m.idx);
    if (!m.p || !m.idx || (has[R_NX] && !m.n) || (has[R_U] && !m.uv)) rc = pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  }
  ply_reader r = {.path = path, .binary = binary, .s = (const unsigned char *)buf + off,
                  .end = (const unsigned char *)buf + n, .line = 0, .e = e};
  if (!binary) {
    for (const char *c = buf; c < buf + off; c++) r.line += *c == '\n';
    r.line++;
  }
  for (int ei = 0; !rc && ei < nelems; ei++) {
    ply_elem *el = &elems[ei];
    r.elem_name = el->name;
    for (uint64_t i = 0; !rc && i < el->count && el->nprops > 0; i++) {
      r.elem_i = i;
      double vals[R_INDICES] = {0};
      for (int k = 0; !rc && k < el->nprops; k++) {
        ply_prop *p = &el->props[k];
        if (!p->is_list) {
          double d;
          if ((rc = read_value(&r, p->type, &d))) break;
          if (p->role != R_NONE) vals[p->role] = d;
          continue;
        }
        uint32_t cnt = 0;
        if ((rc = read_count(&r, p->count_type, &cnt))) break;
        if (p->role != R_INDICES) {
          for (uint32_t j = 0; !rc && j < cnt; j++) rc = read_value(&r, p->type, &(double){0});
          continue;
        }
        if (cnt < 3) { rc = where_err(&r, PC_EPARSE, "face with fewer than 3 vertices"); break; }
        uint32_t first = 0, prev = 0;
        for (uint32_t j = 0; j < cnt; j++) {
          double d;
          if ((rc = read_value(&r, p->type, &d))) break;
          if (d < 0 || d >= (double)nv) { rc = where_err(&r, PC_EINVAL, "vertex index out of range"); break; }
          uint32_t vi = (uint32_t)d;
          if (j == 0) first = vi;
          if (j >= 2) {
            if (m.ntris >= PC_MESH_MAX_TRIANGLES) { rc = where_err(&r, PC_ELIMIT, "too many triangles"); break; }
            if (m.ntris == cap_tris) {
              uint64_t nc = (uint64_t)cap_tris * 2;
              if (nc > PC_MESH_MAX_TRIANGLES) nc = PC_MESH_MAX_TRIANGLES;
              uint32_t *q = realloc(m.idx, 3 * (size_t)nc * sizeof *q);
              if (!q) { rc = pc_errf(e, PC_ENOMEM, "%s: out of memory", path); break; }
              m.idx = q;
              cap_tris = (uint32_t)nc;
            }
            uint32_t *t = &m.idx[3 * m.ntris++];
            t[0] = first;
            t[1] = prev;
            t[2] = vi;
          }
          prev = vi;
        }
      }
      if (rc || ei != vert_el) continue;
      m.p[i] = v3((float)vals[R_X], (float)vals[R_Y], (float)vals[R_Z]);
      if (!v3_is_finite(m.p[i])) { rc = where_err(&r, PC_ENUMERIC, "position out of float range"); break; }
      if (m.n) {
        vec3 nn = v3((float)vals[R_NX], (float)vals[R_NY], (float)vals[R_NZ]);
        float l = v3_len(nn);
        if (!(l > 0) || !isfinite(l)) { rc = where_err(&r, PC_EINVAL, "zero-length normal"); break; }
        m.n[i] = v3_scale(nn, 1.f / l);
      }
      if (m.uv) {
        m.uv[i] = (vec2){(float)vals[R_U], (float)vals[R_V]};
        if (!isfinite(m.uv[i].x) || !isfinite(m.uv[i].y)) { rc = where_err(&r, PC_ENUMERIC, "texture coordinate out of float range"); break; }
      }
    }
  }
  free(buf);
  free(elems);
  if (rc) {
    pc_mesh_free(&m);
    return rc;
  }
  *out = m;
  return 0;
}
