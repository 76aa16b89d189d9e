/* mesh_obj.c: the Wavefront OBJ reader. Reads v, vn, vt and f (polygons fan-triangulated,
 * indices positive or negative, forms v, v/vt, v//vn, v/vt/vn) and splits the faces into meshes
 * as Mitsuba 0.6's obj plugin does: a new mesh at every `g` and every `usemtl` that follows
 * faces (unless collapsed), each mesh with the `usemtl` name in force and its own vertices
 * (equal (v, vt, vn) triples merged within the mesh). The last `mtllib` is kept for the caller;
 * objects and smoothing groups (o, s) are ignored, as Mitsuba does. Faces of one mesh must
 * agree on having normals and texture coordinates: a mesh that mixes them is refused rather
 * than given invented values. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "big_alloc.h"
#include "file_read.h"
#include "mesh.h"

#define OBJ_MAX_FILE ((size_t)2 << 30)
#define OBJ_MAX_LINE (1 << 20)
#define OBJ_MAX_NAME 4096

typedef struct obj_key { uint32_t v, vt, vn; } obj_key;

typedef struct obj_state {
  const char *path;
  int line;
  vec3 *v, *vn;
  vec2 *vt;
  uint32_t nv, nvn, nvt;    /* read so far */
  uint32_t tv, tvn, tvt;    /* totals in the file (first pass) */
  /* output vertices and their keys */
  vec3 *p, *n;
  vec2 *uv;
  obj_key *keys;
  uint32_t nverts, cap_verts;
  uint32_t *idx;
  uint32_t ntris, cap_tris;
  /* hash from key to output vertex */
  uint32_t *table;
  uint32_t table_size;
  int has_vt, has_vn; /* -1 unknown, else whether faces carry them */
  /* the meshes so far, the usemtl name in force, and Mitsuba's count of meshes made */
  bool collapse;
  int shape_index;
  pc_obj *out;
  int cap_meshes, made;
  char *material;
  pc_err *e;
} obj_state;

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

static const char *skip_space(const char *s, const char *end) {
  while (s < end && is_space(*s)) s++;
  return s;
}

/* Next whitespace-separated token in [s, end); returns its length, 0 at end of line. */
static size_t next_token(const char **s, const char *end) {
  *s = skip_space(*s, end);
  const char *t = *s;
  while (t < end && !is_space(*t)) t++;
  return (size_t)(t - *s);
}

static int parse_float_tok(obj_state *st, const char *tok, size_t len, float *out) {
  char buf[64];
  if (len == 0 || len >= sizeof buf)
    return pc_errf(st->e, PC_EPARSE, "%s:%d: malformed number", st->path, st->line);
  memcpy(buf, tok, len);
  buf[len] = 0;
  char *endp;
  errno = 0;
  float f = strtof(buf, &endp);
  if (*endp != 0) return pc_errf(st->e, PC_EPARSE, "%s:%d: malformed number '%s'", st->path, st->line, buf);
  if (!isfinite(f)) return pc_errf(st->e, PC_ENUMERIC, "%s:%d: non-finite number '%s'", st->path, st->line, buf);
  *out = f;
  return 0;
}

/* Reads between min and max floats from the rest of the line. */
static int parse_floats(obj_state *st, const char *s, const char *end, float *out, int min, int max, int *count) {
  int n = 0;
  for (;;) {
    size_t len = next_token(&s, end);
    if (len == 0) break;
    if (n == max) return pc_errf(st->e, PC_EPARSE, "%s:%d: too many numbers (at most %d)", st->path, st->line, max);
    int rc = parse_float_tok(st, s, len, &out[n++]);
    if (rc) return rc;
    s += len;
  }
  if (n < min) return pc_errf(st->e, PC_EPARSE, "%s:%d: expected at least %d numbers", st->path, st->line, min);
  *count = n;
  return 0;
}

static uint32_t hash_key(obj_key k) {
  uint64_t h = (uint64_t)k.v * 0x9E3779B97F4A7C15ull ^ (uint64_t)k.vt * 0xC2B2AE3D27D4EB4Full ^
               (uint64_t)k.vn * 0x165667B19E3779F9ull;
  h ^= h >> 29;
  return (uint32_t)(h ^ (h >> 32));
}

static int table_rehash(obj_state *st, uint32_t size) {
  uint32_t *t = malloc((size_t)size * sizeof *t);
  if (!t) return pc_errf(st->e, PC_ENOMEM, "%s: out of memory", st->path);
  memset(t, 0xff, (size_t)size * sizeof *t);
  for (uint32_t i = 0; i < st->nverts; i++) {
    uint32_t h = hash_key(st->keys[i]) & (size - 1);
    while (t[h] != UINT32_MAX) h = (h + 1) & (size - 1);
    t[h] = i;
  }
  free(st->table);
  st->table = t;
  st->table_size = size;
  return 0;
}

static int grow(void **p, uint32_t *cap, uint32_t need, size_t elem, obj_state *st) {
  if (need <= *cap) return 0;
  uint64_t c = *cap ? *cap : 64;
  while (c < need) c *= 2;
  void *q = realloc(*p, (size_t)c * elem);
  if (!q) return pc_errf(st->e, PC_ENOMEM, "%s: out of memory", st->path);
  *p = q;
  *cap = (uint32_t)(c > UINT32_MAX ? UINT32_MAX : c);
  return 0;
}

static int vertex_for(obj_state *st, obj_key k, uint32_t *out) {
  uint32_t h = hash_key(k) & (st->table_size - 1);
  while (st->table[h] != UINT32_MAX) {
    obj_key o = st->keys[st->table[h]];
    if (o.v == k.v && o.vt == k.vt && o.vn == k.vn) {
      *out = st->table[h];
      return 0;
    }
    h = (h + 1) & (st->table_size - 1);
  }
  if (st->nverts >= PC_MESH_MAX_VERTICES)
    return pc_errf(st->e, PC_ELIMIT, "%s:%d: more than %u vertices", st->path, st->line, PC_MESH_MAX_VERTICES);
  uint32_t cap = st->cap_verts;
  int rc = grow((void **)&st->keys, &cap, st->nverts + 1, sizeof *st->keys, st);
  if (!rc) { cap = st->cap_verts; rc = grow((void **)&st->p, &cap, st->nverts + 1, sizeof *st->p, st); }
  if (!rc && st->has_vn) { cap = st->cap_verts; rc = grow((void **)&st->n, &cap, st->nverts + 1, sizeof *st->n, st); }
  if (!rc && st->has_vt) { cap = st->cap_verts; rc = grow((void **)&st->uv, &cap, st->nverts + 1, sizeof *st->uv, st); }
  if (rc) return rc;
  st->cap_verts = cap;
  uint32_t i = st->nverts++;
  st->keys[i] = k;
  st->p[i] = st->v[k.v];
  if (st->has_vn) st->n[i] = st->vn[k.vn];
  if (st->has_vt) st->uv[i] = st->vt[k.vt];
  st->table[h] = i;
  *out = i;
  if ((uint64_t)st->nverts * 2 > st->table_size) return table_rehash(st, st->table_size * 2);
  return 0;
}

/* Parses one index of a face vertex; `read` is how many of that kind are defined so far
 * (negative indices are relative to it) and `total` how many the file defines. */
static int parse_index(obj_state *st, const char **s, const char *end, uint32_t read, uint32_t total,
                       const char *what, uint32_t *out) {
  const char *t = *s;
  int neg = 0;
  if (t < end && *t == '-') { neg = 1; t++; }
  uint64_t v = 0;
  const char *d = t;
  while (t < end && *t >= '0' && *t <= '9') {
    v = v * 10 + (uint64_t)(*t - '0');
    if (v > UINT32_MAX) return pc_errf(st->e, PC_EINVAL, "%s:%d: %s index out of range", st->path, st->line, what);
    t++;
  }
  if (t == d) return pc_errf(st->e, PC_EPARSE, "%s:%d: malformed face %s index", st->path, st->line, what);
  *s = t;
  if (v == 0) return pc_errf(st->e, PC_EINVAL, "%s:%d: %s index 0 is invalid (OBJ counts from 1)", st->path, st->line, what);
  if (neg) {
    if (v > read) return pc_errf(st->e, PC_EINVAL, "%s:%d: %s index -%llu out of range (%u defined so far)", st->path, st->line, what, (unsigned long long)v, read);
    *out = read - (uint32_t)v;
  } else {
    if (v > total) return pc_errf(st->e, PC_EINVAL, "%s:%d: %s index %llu out of range (%u in the file)", st->path, st->line, what, (unsigned long long)v, total);
    *out = (uint32_t)v - 1;
  }
  return 0;
}

static int parse_face(obj_state *st, const char *s, const char *end) {
  uint32_t first = 0, prev = 0;
  int count = 0;
  for (;;) {
    size_t len = next_token(&s, end);
    if (len == 0) break;
    const char *t = s, *tend = s + len;
    s += len;
    obj_key k = {0, UINT32_MAX, UINT32_MAX};
    int rc = parse_index(st, &t, tend, st->nv, st->tv, "vertex", &k.v);
    if (rc) return rc;
    int with_vt = 0, with_vn = 0;
    if (t < tend && *t == '/') {
      t++;
      if (t < tend && *t != '/') {
        if ((rc = parse_index(st, &t, tend, st->nvt, st->tvt, "texture coordinate", &k.vt))) return rc;
        with_vt = 1;
      }
      if (t < tend && *t == '/') {
        t++;
        if ((rc = parse_index(st, &t, tend, st->nvn, st->tvn, "normal", &k.vn))) return rc;
        with_vn = 1;
      }
    }
    if (t != tend) return pc_errf(st->e, PC_EPARSE, "%s:%d: malformed face vertex", st->path, st->line);
    if (st->has_vt < 0) {
      st->has_vt = with_vt;
      st->has_vn = with_vn;
    } else if (st->has_vt != with_vt || st->has_vn != with_vn) {
      return pc_errf(st->e, PC_EUNSUPPORTED,
                     "%s:%d: faces mix vertices with and without %s (unsupported: every face must "
                     "give the same kinds of indices)", st->path, st->line,
                     st->has_vt != with_vt ? "texture coordinates" : "normals");
    }
    uint32_t vi = 0;
    if ((rc = vertex_for(st, k, &vi))) return rc;
    if (count == 0) first = vi;
    if (count >= 2) {
      if (st->ntris >= PC_MESH_MAX_TRIANGLES)
        return pc_errf(st->e, PC_ELIMIT, "%s:%d: more than %u triangles", st->path, st->line, PC_MESH_MAX_TRIANGLES);
      if ((rc = grow((void **)&st->idx, &st->cap_tris, 3 * (st->ntris + 1), sizeof *st->idx, st))) return rc;
      uint32_t *tri = &st->idx[3 * st->ntris++];
      tri[0] = first;
      tri[1] = prev;
      tri[2] = vi;
    }
    prev = vi;
    count++;
  }
  if (count < 3) return pc_errf(st->e, PC_EPARSE, "%s:%d: face with fewer than 3 vertices", st->path, st->line);
  return 0;
}

static int keyword_is(const char *s, size_t len, const char *kw) {
  return len == strlen(kw) && memcmp(s, kw, len) == 0;
}

/* First pass: how many v, vt and vn the file defines, so storage is allocated once and
 * positive indices can refer forward. */
static int count_pass(obj_state *st, const char *buf, size_t n) {
  uint64_t tv = 0, tvt = 0, tvn = 0;
  const char *s = buf, *end = buf + n;
  while (s < end) {
    const char *eol = memchr(s, '\n', (size_t)(end - s));
    if (!eol) eol = end;
    const char *k = s;
    size_t len = next_token(&k, eol);
    if (keyword_is(k, len, "v")) tv++;
    else if (keyword_is(k, len, "vt")) tvt++;
    else if (keyword_is(k, len, "vn")) tvn++;
    s = eol + 1;
  }
  if (tv > PC_MESH_MAX_VERTICES || tvt > PC_MESH_MAX_VERTICES || tvn > PC_MESH_MAX_VERTICES)
    return pc_errf(st->e, PC_ELIMIT, "%s: more than %u vertices, normals or texture coordinates", st->path, PC_MESH_MAX_VERTICES);
  st->tv = (uint32_t)tv;
  st->tvt = (uint32_t)tvt;
  st->tvn = (uint32_t)tvn;
  st->v = pc_big_alloc(tv * sizeof *st->v);
  st->vt = pc_big_alloc(tvt * sizeof *st->vt);
  st->vn = pc_big_alloc(tvn * sizeof *st->vn);
  if (!st->v || !st->vt || !st->vn) return pc_errf(st->e, PC_ENOMEM, "%s: out of memory", st->path);
  return 0;
}

/* The rest of a statement's line, trimmed, as Mitsuba reads usemtl and mtllib names. */
static int rest_of_line(obj_state *st, const char *s, const char *eol, char **out) {
  s = skip_space(s, eol);
  while (eol > s && is_space(eol[-1])) eol--;
  size_t len = (size_t)(eol - s);
  if (len > OBJ_MAX_NAME) return pc_errf(st->e, PC_ELIMIT, "%s:%d: name longer than %d bytes", st->path, st->line, OBJ_MAX_NAME);
  *out = malloc(len + 1);
  if (!*out) return pc_errf(st->e, PC_ENOMEM, "%s: out of memory", st->path);
  memcpy(*out, s, len);
  (*out)[len] = 0;
  return 0;
}

/* Ends the mesh being read (if it has faces) as Mitsuba's createMesh does, keeping it if
 * shape_index selects it. Mitsuba numbers a mesh ended by `g` or `usemtl` by its count of
 * meshes before it, but tests the last one against that count minus one: a shapeIndex of the
 * second-to-last mesh also selects the last, and on a file of one mesh shapeIndex 0 selects
 * nothing. Kept as Mitsuba renders it. */
static int flush(obj_state *st, bool last) {
  if (st->ntris == 0) return 0;
  int index = last ? st->made - 1 : st->made;
  if (!last) st->made++;
  else if (st->made == 0) st->made = 1; /* the count of meshes read, for "no faces" */
  bool keep = st->shape_index < 0 || index == st->shape_index;
  if (keep) {
    if (st->out->n >= PC_OBJ_MAX_MESHES)
      return pc_errf(st->e, PC_ELIMIT, "%s:%d: more than %d meshes (groups or materials)", st->path, st->line, PC_OBJ_MAX_MESHES);
    if (st->out->n == st->cap_meshes) {
      int cap = st->cap_meshes ? 2 * st->cap_meshes : 4;
      void *q = realloc(st->out->meshes, (size_t)cap * sizeof *st->out->meshes);
      if (!q) return pc_errf(st->e, PC_ENOMEM, "%s: out of memory", st->path);
      st->out->meshes = q;
      st->cap_meshes = cap;
    }
    pc_obj_mesh *m = &st->out->meshes[st->out->n];
    memset(m, 0, sizeof *m);
    m->material = strdup(st->material ? st->material : "");
    if (!m->material) return pc_errf(st->e, PC_ENOMEM, "%s: out of memory", st->path);
    m->mesh = (pc_mesh){.nverts = st->nverts, .ntris = st->ntris, .p = st->p, .n = st->n, .uv = st->uv, .idx = st->idx};
    st->out->n++;
  } else {
    free(st->p);
    free(st->n);
    free(st->uv);
    free(st->idx);
  }
  st->p = st->n = NULL;
  st->uv = NULL;
  st->idx = NULL;
  st->nverts = st->cap_verts = st->ntris = st->cap_tris = 0;
  st->has_vt = st->has_vn = -1;
  return last ? 0 : table_rehash(st, 1024);
}

static int parse_line(obj_state *st, const char *s, const char *eol) {
  const char *k = s;
  size_t len = next_token(&k, eol);
  if (len == 0 || *k == '#') return 0;
  const char *rest = k + len;
  float f[7];
  int cnt, rc;
  if (keyword_is(k, len, "v")) {
    if ((rc = parse_floats(st, rest, eol, f, 3, 7, &cnt))) return rc;
    if (cnt == 5) return pc_errf(st->e, PC_EPARSE, "%s:%d: vertex with 5 numbers", st->path, st->line);
    st->v[st->nv++] = v3(f[0], f[1], f[2]); /* w or vertex colours are ignored */
  } else if (keyword_is(k, len, "vt")) {
    if ((rc = parse_floats(st, rest, eol, f, 1, 3, &cnt))) return rc;
    st->vt[st->nvt++] = (vec2){f[0], cnt > 1 ? f[1] : 0.f};
  } else if (keyword_is(k, len, "vn")) {
    if ((rc = parse_floats(st, rest, eol, f, 3, 3, &cnt))) return rc;
    vec3 n = v3(f[0], f[1], f[2]);
    float l = v3_len(n);
    if (!(l > 0) || !isfinite(l)) return pc_errf(st->e, PC_EINVAL, "%s:%d: zero-length normal", st->path, st->line);
    st->vn[st->nvn++] = v3_scale(n, 1.f / l);
  } else if (keyword_is(k, len, "f")) {
    return parse_face(st, rest, eol);
  } else if (keyword_is(k, len, "g")) {
    if (!st->collapse) return flush(st, false);
  } else if (keyword_is(k, len, "usemtl") || keyword_is(k, len, "mtllib")) {
    char *name;
    if ((rc = rest_of_line(st, rest, eol, &name))) return rc;
    if (k[0] == 'm') {
      free(st->out->mtllib);
      st->out->mtllib = name;
      st->out->mtllib_line = st->line;
      return 0;
    }
    if (!st->collapse && (rc = flush(st, false))) {
      free(name);
      return rc;
    }
    free(st->material);
    st->material = name;
  } else if (!(keyword_is(k, len, "o") || keyword_is(k, len, "s"))) {
    return pc_errf(st->e, PC_EUNSUPPORTED, "%s:%d: unsupported OBJ statement '%.*s'", st->path, st->line,
                   (int)(len > 32 ? 32 : len), k);
  }
  return 0;
}

void pc_obj_free(pc_obj *o) {
  for (int i = 0; i < o->n; i++) {
    pc_mesh_free(&o->meshes[i].mesh);
    free(o->meshes[i].material);
  }
  free(o->meshes);
  free(o->mtllib);
  memset(o, 0, sizeof *o);
}

int pc_obj_load(const char *path, bool collapse, int shape_index, pc_obj *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  char *buf;
  size_t n;
  int rc = pc_file_read(path, OBJ_MAX_FILE, &buf, &n, e);
  if (rc) return rc;
  obj_state st = {.path = path, .e = e, .has_vt = -1, .has_vn = -1, .collapse = collapse, .shape_index = shape_index,
                  .out = out};
  rc = count_pass(&st, buf, n);
  if (!rc) rc = table_rehash(&st, 1024);
  const char *s = buf, *end = buf + n;
  while (!rc && s < end) {
    st.line++;
    const char *eol = memchr(s, '\n', (size_t)(end - s));
    if (!eol) eol = end;
    if (eol - s > OBJ_MAX_LINE) {
      rc = pc_errf(e, PC_ELIMIT, "%s:%d: line longer than %d bytes", path, st.line, OBJ_MAX_LINE);
      break;
    }
    if (memchr(s, 0, (size_t)(eol - s))) {
      rc = pc_errf(e, PC_EPARSE, "%s:%d: NUL byte in a text file", path, st.line);
      break;
    }
    rc = parse_line(&st, s, eol);
    s = eol + 1;
  }
  if (!rc) rc = flush(&st, true);
  if (!rc && st.made == 0) rc = pc_errf(e, PC_EINVAL, "%s: no faces", path);
  free(buf);
  free(st.v);
  free(st.vt);
  free(st.vn);
  free(st.keys);
  free(st.table);
  free(st.p);
  free(st.n);
  free(st.uv);
  free(st.idx);
  free(st.material);
  if (rc) pc_obj_free(out);
  return rc;
}

int pc_mesh_load_obj(const char *path, pc_mesh *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  pc_obj o;
  int rc = pc_obj_load(path, true, -1, &o, e);
  if (rc) return rc;
  *out = o.meshes[0].mesh;
  o.meshes[0].mesh = (pc_mesh){0};
  pc_obj_free(&o);
  return 0;
}
