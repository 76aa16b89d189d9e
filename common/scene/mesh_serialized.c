/* mesh_serialized.c: Mitsuba's `serialized` mesh files: one or more shapes, each a 0x041C
 * header and version (3 or 4) followed by a zlib stream of flags, (v4) a name, vertex and
 * triangle counts, positions, optional normals, texture coordinates and colours (single or
 * double precision), and uint32 triangle indices; a dictionary of shape offsets and the shape
 * count end the file. Every count is checked against the mesh limits before anything is
 * allocated, so a hostile header costs one line, not memory. */
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "big_alloc.h"
#include "file_read.h"
#include "mesh.h"

#define SER_MAX_FILE ((size_t)2 << 30)
#define SER_MAX_NAME 4096

enum { HAS_NORMALS = 0x1, HAS_TEXCOORDS = 0x2, HAS_COLORS = 0x8, FACE_NORMALS = 0x10, SINGLE = 0x1000, DOUBLE = 0x2000 };

static uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t le64(const unsigned char *p) { return (uint64_t)le32(p) | (uint64_t)le32(p + 4) << 32; }

typedef struct zin {
  z_stream z;
  const char *path;
  pc_err *e;
} zin;

/* Inflates exactly len bytes into dst. */
static int zread(zin *r, void *dst, size_t len) {
  r->z.next_out = dst;
  while (len > 0) {
    uInt chunk = len > (1u << 30) ? (1u << 30) : (uInt)len;
    r->z.avail_out = chunk;
    int zr = inflate(&r->z, Z_NO_FLUSH);
    size_t got = chunk - r->z.avail_out;
    len -= got;
    if (len == 0) break;
    if (zr == Z_STREAM_END || (zr == Z_BUF_ERROR && r->z.avail_in == 0))
      return pc_errf(r->e, PC_EPARSE, "%s: the compressed shape data ends early", r->path);
    if (zr != Z_OK && zr != Z_BUF_ERROR)
      return pc_errf(r->e, PC_EPARSE, "%s: corrupt compressed shape data (%s)", r->path, r->z.msg ? r->z.msg : "zlib error");
  }
  return 0;
}

/* Reads n tuples of k reals (float or double in the file) into out as floats. */
static int read_reals(zin *r, bool dbl, float *out, size_t count) {
  if (!dbl) return zread(r, out, count * sizeof(float)); /* little-endian IEEE, as on every supported host */
  enum { BLOCK = 4096 };
  double tmp[BLOCK];
  for (size_t i = 0; i < count; i += BLOCK) {
    size_t m = count - i < BLOCK ? count - i : BLOCK;
    int rc = zread(r, tmp, m * sizeof(double));
    if (rc) return rc;
    for (size_t j = 0; j < m; j++) out[i + j] = (float)tmp[j];
  }
  return 0;
}

static int load(const char *path, const unsigned char *buf, size_t n, int index, pc_mesh *m, bool *face_normals, pc_err *e) {
  if (n < 8) return pc_errf(e, PC_EPARSE, "%s: too short for a serialized mesh", path);
  uint16_t magic = (uint16_t)(buf[0] | buf[1] << 8), version = (uint16_t)(buf[2] | buf[3] << 8);
  if (magic != 0x041C) return pc_errf(e, PC_EPARSE, "%s: not a Mitsuba serialized mesh (bad header)", path);
  if (version != 3 && version != 4) return pc_errf(e, PC_EUNSUPPORTED, "%s: serialized mesh version %u (3 or 4 expected)", path, version);
  uint32_t count = le32(buf + n - 4);
  size_t esize = version == 4 ? 8 : 4;
  if (count == 0 || (uint64_t)count * esize + 4 > n - 4)
    return pc_errf(e, PC_EPARSE, "%s: bad shape dictionary (%u shapes)", path, count);
  if (index < 0 || (uint32_t)index >= count)
    return pc_errf(e, PC_EINVAL, "%s: shapeIndex %d out of range (the file holds %u shapes)", path, index, count);
  const unsigned char *dict = buf + n - 4 - (size_t)count * esize;
  uint64_t off = version == 4 ? le64(dict + (size_t)index * 8) : le32(dict + (size_t)index * 4);
  if (off > (uint64_t)(dict - buf) - 4 || le32(buf + off) != (0x041Cu | (uint32_t)version << 16))
    return pc_errf(e, PC_EPARSE, "%s: shape %d: bad offset in the dictionary", path, index);
  zin r = {.path = path, .e = e};
  if (inflateInit(&r.z) != Z_OK) return pc_errf(e, PC_ENOMEM, "%s: cannot start zlib", path);
  size_t avail = (size_t)(dict - buf) - (size_t)off - 4;
  r.z.next_in = (Bytef *)(buf + off + 4);
  r.z.avail_in = avail > UINT32_MAX ? UINT32_MAX : (uInt)avail;
  unsigned char head[16];
  int rc = zread(&r, head, 4);
  uint32_t flags = rc ? 0 : le32(head);
  if (!rc && version == 4) { /* the shape's name: skipped, bounded */
    char ch = 1;
    int len = 0;
    while (!rc && ch && len++ <= SER_MAX_NAME) rc = zread(&r, &ch, 1);
    if (!rc && ch) rc = pc_errf(e, PC_EPARSE, "%s: shape %d: name longer than %d bytes", path, index, SER_MAX_NAME);
  }
  if (!rc) rc = zread(&r, head, 16);
  uint64_t nv = rc ? 0 : le64(head), nt = rc ? 0 : le64(head + 8);
  if (!rc && (flags & SINGLE) && (flags & DOUBLE))
    rc = pc_errf(e, PC_EPARSE, "%s: shape %d: both single and double precision flags", path, index);
  if (!rc && (nv == 0 || nt == 0 || nv > PC_MESH_MAX_VERTICES || nt > PC_MESH_MAX_TRIANGLES))
    rc = pc_errf(e, nv == 0 || nt == 0 ? PC_EPARSE : PC_ELIMIT,
                 "%s: shape %d claims %llu vertices and %llu triangles (limits %u and %u)", path, index,
                 (unsigned long long)nv, (unsigned long long)nt, PC_MESH_MAX_VERTICES, PC_MESH_MAX_TRIANGLES);
  bool dbl = flags & DOUBLE;
  if (!rc) {
    m->nverts = (uint32_t)nv;
    m->ntris = (uint32_t)nt;
    m->p = pc_big_alloc(nv * sizeof *m->p);
    m->idx = pc_big_alloc(nt * 3 * sizeof *m->idx);
    if (flags & HAS_NORMALS) m->n = pc_big_alloc(nv * sizeof *m->n);
    if (flags & HAS_TEXCOORDS) m->uv = pc_big_alloc(nv * sizeof *m->uv);
    if (!m->p || !m->idx || ((flags & HAS_NORMALS) && !m->n) || ((flags & HAS_TEXCOORDS) && !m->uv))
      rc = pc_errf(e, PC_ENOMEM, "%s: out of memory for %llu vertices", path, (unsigned long long)nv);
  }
  if (!rc) rc = read_reals(&r, dbl, &m->p[0].x, nv * 3);
  if (!rc && m->n) rc = read_reals(&r, dbl, &m->n[0].x, nv * 3);
  if (!rc && m->uv) rc = read_reals(&r, dbl, &m->uv[0].x, nv * 2);
  if (!rc && (flags & HAS_COLORS)) {
    float skip[3 * 256];
    for (uint64_t i = 0; !rc && i < nv; i += 256) rc = read_reals(&r, dbl, skip, (nv - i < 256 ? nv - i : 256) * 3);
  }
  if (!rc) rc = zread(&r, m->idx, nt * 3 * sizeof(uint32_t));
  for (uint64_t i = 0; !rc && i < nt * 3; i++)
    if (m->idx[i] >= nv)
      rc = pc_errf(e, PC_EPARSE, "%s: shape %d: triangle %llu refers to vertex %u of %llu", path, index,
                   (unsigned long long)(i / 3), m->idx[i], (unsigned long long)nv);
  inflateEnd(&r.z);
  *face_normals = flags & FACE_NORMALS;
  return rc;
}

int pc_mesh_load_serialized(const char *path, int shape_index, pc_mesh *out, bool *face_normals, pc_err *e) {
  memset(out, 0, sizeof *out);
  *face_normals = false;
  char *buf;
  size_t n;
  int rc = pc_file_read(path, SER_MAX_FILE, &buf, &n, e);
  if (rc) return rc;
  rc = load(path, (const unsigned char *)buf, n, shape_index, out, face_normals, e);
  free(buf);
  if (rc) pc_mesh_free(out);
  return rc;
}
