/* test_helpers_serialized.h: writes Mitsuba serialized mesh files for tests (the format of
 * common/scene/mesh_serialized.c), with one to a few shapes, single or double precision. */
#ifndef TEST_HELPERS_SERIALIZED_H
#define TEST_HELPERS_SERIALIZED_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

typedef struct th_ser_shape {
  uint64_t nv, nt;         /* counts written in the header (may lie, for hostile files) */
  const float *p, *n, *uv; /* nv*3, nv*3 or NULL, nv*2 or NULL */
  const uint32_t *idx;     /* nt*3 */
  uint32_t nv_data, nt_data; /* counts actually written */
  uint32_t extra_flags;    /* e.g. 0x10 face normals */
} th_ser_shape;

typedef struct th_buf {
  unsigned char *d;
  size_t n, cap;
} th_buf;

static inline void th_put(th_buf *b, const void *p, size_t n) {
  if (b->n + n > b->cap) {
    b->cap = (b->n + n) * 2 + 64;
    b->d = realloc(b->d, b->cap);
  }
  memcpy(b->d + b->n, p, n);
  b->n += n;
}

static inline void th_put_reals(th_buf *b, const float *v, size_t count, int dbl) {
  for (size_t i = 0; i < count; i++) {
    if (dbl) {
      double d = v[i];
      th_put(b, &d, 8);
    } else {
      th_put(b, &v[i], 4);
    }
  }
}

/* Returns 0 on success. version 3 or 4. */
static inline int th_write_serialized(const char *path, const th_ser_shape *shapes, int count, int version, int dbl) {
  th_buf file = {0};
  uint64_t *offsets = malloc((size_t)count * sizeof *offsets);
  for (int s = 0; s < count; s++) {
    const th_ser_shape *sh = &shapes[s];
    th_buf raw = {0};
    uint32_t flags = (dbl ? 0x2000u : 0x1000u) | (sh->n ? 1u : 0u) | (sh->uv ? 2u : 0u) | sh->extra_flags;
    th_put(&raw, &flags, 4);
    if (version == 4) th_put(&raw, "shape", 6);
    th_put(&raw, &sh->nv, 8);
    th_put(&raw, &sh->nt, 8);
    th_put_reals(&raw, sh->p, (size_t)sh->nv_data * 3, dbl);
    if (sh->n) th_put_reals(&raw, sh->n, (size_t)sh->nv_data * 3, dbl);
    if (sh->uv) th_put_reals(&raw, sh->uv, (size_t)sh->nv_data * 2, dbl);
    th_put(&raw, sh->idx, (size_t)sh->nt_data * 12);
    uLongf zn = compressBound(raw.n);
    unsigned char *z = malloc(zn);
    if (compress(z, &zn, raw.d, raw.n) != Z_OK) return -1;
    offsets[s] = file.n;
    uint16_t head[2] = {0x041C, (uint16_t)version};
    th_put(&file, head, 4);
    th_put(&file, z, zn);
    free(z);
    free(raw.d);
  }
  for (int s = 0; s < count; s++) {
    if (version == 4) th_put(&file, &offsets[s], 8);
    else {
      uint32_t o = (uint32_t)offsets[s];
      th_put(&file, &o, 4);
    }
  }
  free(offsets);
  uint32_t c = (uint32_t)count;
  th_put(&file, &c, 4);
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  int bad = fwrite(file.d, 1, file.n, f) != file.n;
  bad |= fclose(f) != 0;
  free(file.d);
  return bad ? -1 : 0;
}

#endif
