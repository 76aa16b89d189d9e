/* wire_film.c: film (de)serialization and zstd wrapping for uploads and checkpoints. */
#include "wire_film.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#define MAGIC "PCFILM01"
#define HEAD (8 + 4 * 3 + 8)
#define LAYER_HEAD (16 + 4 + 8)

static void put32(uint8_t *p, uint32_t v) { for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i)); }
static void put64(uint8_t *p, uint64_t v) { for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i)); }
static uint32_t get32(const uint8_t *p) { uint32_t v = 0; for (int i = 3; i >= 0; i--) v = v << 8 | p[i]; return v; }
static uint64_t get64(const uint8_t *p) { uint64_t v = 0; for (int i = 7; i >= 0; i--) v = v << 8 | p[i]; return v; }

size_t pc_wire_film_size(const pc_film *f) {
  size_t px = (size_t)f->w * (size_t)f->h * 3;
  return HEAD + (size_t)f->nlayers * (LAYER_HEAD + px * 8);
}

int pc_wire_film_pack(const pc_film *f, uint8_t **out, size_t *n, pc_err *e) {
  size_t total = pc_wire_film_size(f), px = (size_t)f->w * (size_t)f->h * 3;
  uint8_t *b = malloc(total), *p = b;
  if (!b) return pc_errf(e, PC_ENOMEM, "film: out of memory packing %zu bytes", total);
  memcpy(p, MAGIC, 8); p += 8;
  put32(p, (uint32_t)f->w); put32(p + 4, (uint32_t)f->h); put32(p + 8, (uint32_t)f->nlayers); p += 12;
  put64(p, f->dropped_nonfinite); p += 8;
  for (int l = 0; l < f->nlayers; l++) {
    memset(p, 0, 16);
    memcpy(p, f->layers[l].name, strnlen(f->layers[l].name, 16));
    put32(p + 16, (uint32_t)f->layers[l].norm);
    put64(p + 20, f->layers[l].count);
    p += LAYER_HEAD;
  }
  for (int l = 0; l < f->nlayers; l++)
    for (size_t i = 0; i < px; i++) {
      uint64_t bits;
      memcpy(&bits, &f->layers[l].sum[i], 8);
      put64(p, bits);
      p += 8;
    }
  *out = b;
  *n = total;
  return 0;
}

int pc_wire_film_unpack(const uint8_t *buf, size_t n, pc_film *into, pc_err *e) {
  if (n < HEAD || memcmp(buf, MAGIC, 8) != 0) return pc_errf(e, PC_EPARSE, "film: not a serialized film (bad magic or %zu bytes)", n);
  uint32_t w = get32(buf + 8), h = get32(buf + 12), nl = get32(buf + 16);
  if ((int)w != into->w || (int)h != into->h)
    return pc_errf(e, PC_EINVAL, "film: resolution %ux%u, the job has %dx%d", w, h, into->w, into->h);
  if ((int)nl != into->nlayers) return pc_errf(e, PC_EINVAL, "film: %u layers, the job has %d", nl, into->nlayers);
  if (n != pc_wire_film_size(into)) return pc_errf(e, PC_EINVAL, "film: %zu bytes, expected %zu", n, pc_wire_film_size(into));
  const uint8_t *p = buf + HEAD;
  for (int l = 0; l < into->nlayers; l++, p += LAYER_HEAD) {
    char name[17] = {0};
    memcpy(name, p, 16);
    if (strncmp(name, into->layers[l].name, 16) != 0 || get32(p + 16) != (uint32_t)into->layers[l].norm)
      return pc_errf(e, PC_EINVAL, "film: layer %d is '%s', the job has '%s'", l, name, into->layers[l].name);
  }
  size_t px = (size_t)w * h * 3;
  const uint8_t *d = p;
  for (size_t i = 0; i < px * nl; i++) {
    uint64_t bits = get64(d + 8 * i);
    double v;
    memcpy(&v, &bits, 8);
    if (!isfinite(v)) return pc_errf(e, PC_ENUMERIC, "film: non-finite sum in layer %zu at pixel %zu", i / px, (i % px) / 3);
  }
  into->dropped_nonfinite = get64(buf + 20);
  p = buf + HEAD;
  for (int l = 0; l < into->nlayers; l++, p += LAYER_HEAD) into->layers[l].count = get64(p + 20);
  for (int l = 0; l < into->nlayers; l++)
    for (size_t i = 0; i < px; i++, d += 8) {
      uint64_t bits = get64(d);
      memcpy(&into->layers[l].sum[i], &bits, 8);
    }
  return 0;
}

int pc_wire_compress(const uint8_t *in, size_t n, uint8_t **out, size_t *outn, pc_err *e) {
  size_t cap = ZSTD_compressBound(n);
  uint8_t *b = malloc(cap ? cap : 1);
  if (!b) return pc_errf(e, PC_ENOMEM, "zstd: out of memory for %zu bytes", cap);
  size_t r = ZSTD_compress(b, cap, in, n, 3);
  if (ZSTD_isError(r)) {
    free(b);
    return pc_errf(e, PC_EIO, "zstd: compress failed: %s", ZSTD_getErrorName(r));
  }
  *out = b;
  *outn = r;
  return 0;
}

int pc_wire_decompress(const uint8_t *in, size_t n, size_t expect, size_t limit, uint8_t **out, pc_err *e) {
  unsigned long long cs = ZSTD_getFrameContentSize(in, n);
  if (cs == ZSTD_CONTENTSIZE_ERROR || cs == ZSTD_CONTENTSIZE_UNKNOWN)
    return pc_errf(e, PC_EPARSE, "zstd: not a zstd frame with a known size");
  if (cs != expect || cs > limit)
    return pc_errf(e, PC_EINVAL, "zstd: content size %llu, expected %zu (limit %zu)", cs, expect, limit);
  uint8_t *b = malloc(expect ? expect : 1);
  if (!b) return pc_errf(e, PC_ENOMEM, "zstd: out of memory for %zu bytes", expect);
  size_t r = ZSTD_decompress(b, expect, in, n);
  if (ZSTD_isError(r) || r != expect) {
    free(b);
    return pc_errf(e, PC_EPARSE, "zstd: decompress failed: %s", ZSTD_isError(r) ? ZSTD_getErrorName(r) : "short output");
  }
  *out = b;
  return 0;
}
