/* wire_film.c: film (de)serialization and zstd wrapping for uploads and checkpoints.
 * Format PCFILM02 stores each layer's sums in blocks of PLANE_BLOCK doubles, each block as
 * eight byte planes (byte 0 of every value, then byte 1, ...): the sign/exponent and high
 * mantissa planes of nearby pixels repeat, so zstd at a fast level packs them ~20% smaller
 * and ~3x faster than interleaved doubles. PCFILM01 (plain little-endian doubles) is still
 * read, so checkpoints of older coordinators load, and so is a checkpoint without the film's
 * last layer, beauty_sq (written before it existed): it loads with beauty_sq empty, and the
 * job's error estimate says it cannot tell (film.h). Uploads must be whole. */
#include "wire_film.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#define MAGIC_V1 "PCFILM01"
#define MAGIC_V2 "PCFILM02"
#define HEAD (8 + 4 * 3 + 8)
#define LAYER_HEAD (16 + 4 + 8)
#define PLANE_BLOCK 2048
/* Fast: films are compressed on the render machines for every upload and on the
 * coordinator for every checkpoint; higher levels cost several times the CPU for a few
 * per cent of size. */
#define ZSTD_LEVEL 1

static void put32(uint8_t *p, uint32_t v) { for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i)); }
static void put64(uint8_t *p, uint64_t v) { for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i)); }
static uint32_t get32(const uint8_t *p) { uint32_t v = 0; for (int i = 3; i >= 0; i--) v = v << 8 | p[i]; return v; }
static uint64_t get64(const uint8_t *p) { uint64_t v = 0; for (int i = 7; i >= 0; i--) v = v << 8 | p[i]; return v; }

static size_t size_of(const pc_film *f, int nlayers) {
  size_t px = (size_t)f->w * (size_t)f->h * 3;
  return HEAD + (size_t)nlayers * (LAYER_HEAD + px * 8);
}

size_t pc_wire_film_size(const pc_film *f) { return size_of(f, f->nlayers); }

/* Layers a serialized film of `like`'s shape may hold: all, or (old checkpoints) all but a
 * last beauty_sq. */
static int short_layers(const pc_film *like) {
  int q = pc_film_square_layer(like);
  return q >= 0 && q == like->nlayers - 1 ? like->nlayers - 1 : like->nlayers;
}

/* Plane by plane, so the loops vectorize. */
static void put_block(uint8_t *d, const double *v, size_t m) {
  uint64_t bits[PLANE_BLOCK];
  memcpy(bits, v, 8 * m);
  for (int b = 0; b < 8; b++, d += m)
    for (size_t i = 0; i < m; i++) d[i] = (uint8_t)(bits[i] >> (8 * b));
}

/* Values [0, m) of a block: byte planes (v2) or interleaved (v1). */
static void get_block(const uint8_t *d, bool planes, size_t m, double *v) {
  uint64_t bits[PLANE_BLOCK];
  if (planes) {
    for (size_t i = 0; i < m; i++) bits[i] = d[i];
    for (int b = 1; b < 8; b++) {
      const uint8_t *q = d + (size_t)b * m;
      for (size_t i = 0; i < m; i++) bits[i] |= (uint64_t)q[i] << (8 * b);
    }
  } else {
    for (size_t i = 0; i < m; i++) bits[i] = get64(d + 8 * i);
  }
  memcpy(v, bits, 8 * m);
}

/* The first value of a block whose biased binary exponent exceeds max_exp, or m. NaN and
 * infinities have the largest exponent (0x7ff), so every bound refuses them; in byte planes
 * the exponent is in planes 7 and 6 alone. */
static size_t first_over(const uint8_t *d, bool planes, size_t m, unsigned max_exp) {
  if (!planes) {
    double v[PLANE_BLOCK];
    get_block(d, false, m, v);
    for (size_t i = 0; i < m; i++) {
      uint64_t bits;
      memcpy(&bits, &v[i], 8);
      if ((unsigned)(bits >> 52 & 0x7ff) > max_exp) return i;
    }
    return m;
  }
  const uint8_t *hi = d + 7 * m, *lo = d + 6 * m;
  int bad = 0;
  for (size_t i = 0; i < m; i++) bad |= ((unsigned)(hi[i] & 0x7f) << 4 | lo[i] >> 4) > max_exp;
  if (!bad) return m;
  for (size_t i = 0; i < m; i++)
    if (((unsigned)(hi[i] & 0x7f) << 4 | lo[i] >> 4) > max_exp) return i;
  return m;
}

void pc_wire_film_pack_to(const pc_film *f, uint8_t *out) {
  size_t px = (size_t)f->w * (size_t)f->h * 3;
  uint8_t *p = out;
  memcpy(p, MAGIC_V2, 8); p += 8;
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
    for (size_t k = 0; k < px; k += PLANE_BLOCK) {
      size_t m = px - k < PLANE_BLOCK ? px - k : PLANE_BLOCK;
      put_block(p, f->layers[l].sum + k, m);
      p += 8 * m;
    }
}

int pc_wire_film_pack(const pc_film *f, uint8_t **out, size_t *n, pc_err *e) {
  size_t total = pc_wire_film_size(f);
  uint8_t *b = malloc(total);
  if (!b) return pc_errf(e, PC_ENOMEM, "film: out of memory packing %zu bytes", total);
  pc_wire_film_pack_to(f, b);
  *out = b;
  *n = total;
  return 0;
}

/* Checks a serialized film's header against the shape of `like`; *planes tells the format,
 * *nl how many of like's layers it holds (all, or with `whole` false maybe all but beauty_sq). */
static int check_header(const uint8_t *buf, size_t n, const pc_film *like, bool whole, bool *planes, int *nlp,
                        pc_err *e) {
  bool v1 = n >= HEAD && memcmp(buf, MAGIC_V1, 8) == 0, v2 = n >= HEAD && memcmp(buf, MAGIC_V2, 8) == 0;
  if (!v1 && !v2) return pc_errf(e, PC_EPARSE, "film: not a serialized film (bad magic or %zu bytes)", n);
  uint32_t w = get32(buf + 8), h = get32(buf + 12), nl = get32(buf + 16);
  if ((int)w != like->w || (int)h != like->h)
    return pc_errf(e, PC_EINVAL, "film: resolution %ux%u, the job has %dx%d", w, h, like->w, like->h);
  if ((int)nl != like->nlayers && (whole || (int)nl != short_layers(like)))
    return pc_errf(e, PC_EINVAL, "film: %u layers, the job has %d", nl, like->nlayers);
  if (n != size_of(like, (int)nl)) return pc_errf(e, PC_EINVAL, "film: %zu bytes, expected %zu", n, size_of(like, (int)nl));
  const uint8_t *p = buf + HEAD;
  for (int l = 0; l < (int)nl; l++, p += LAYER_HEAD) {
    char name[17] = {0};
    memcpy(name, p, 16);
    if (strncmp(name, like->layers[l].name, 16) != 0 || get32(p + 16) != (uint32_t)like->layers[l].norm)
      return pc_errf(e, PC_EINVAL, "film: layer %d is '%s', the job has '%s'", l, name, like->layers[l].name);
  }
  *planes = v2;
  *nlp = (int)nl;
  return 0;
}

/* The header checks, then that every sum is finite and, for a delta (bounded), under
 * 2^PC_WIRE_SAMPLE_LOG2 per sample of its layer (2^(2 PC_WIRE_SAMPLE_LOG2) for beauty_sq, whose
 * samples are squares; a biased exponent of at most 1023 + that + the bit length of the count
 * - 1), before anything is read into a film. A delta holds every layer; a checkpoint may be
 * one written before beauty_sq (*nl tells). */
static int check(const uint8_t *buf, size_t n, const pc_film *like, bool bounded, bool *planes, int *nl, pc_err *e) {
  int rc = check_header(buf, n, like, bounded, planes, nl, e);
  if (rc) return rc;
  size_t px = (size_t)like->w * (size_t)like->h * 3;
  const uint8_t *d = buf + HEAD + (size_t)*nl * LAYER_HEAD;
  for (int l = 0; l < *nl; l++) {
    uint64_t count = get64(buf + HEAD + (size_t)l * LAYER_HEAD + 20);
    unsigned bits = 0, sample_log2 = like->layers[l].norm == PC_NORM_SQUARE ? 2 * PC_WIRE_SAMPLE_LOG2 : PC_WIRE_SAMPLE_LOG2;
    while (bits < 64 && count >> bits) bits++;
    unsigned max_exp = bounded ? 1023 + sample_log2 + bits - 1 : 0x7fe;
    for (size_t k = 0; k < px; k += PLANE_BLOCK) {
      size_t m = px - k < PLANE_BLOCK ? px - k : PLANE_BLOCK;
      size_t i = first_over(d, *planes, m, max_exp);
      if (i < m && first_over(d, *planes, m, 0x7fe) == i)
        return pc_errf(e, PC_ENUMERIC, "film: non-finite sum in layer %d at pixel %zu", l, (k + i) / 3);
      if (i < m)
        return pc_errf(e, PC_ENUMERIC, "film: a sum in layer %d at pixel %zu is beyond any radiance for %llu samples", l,
                       (k + i) / 3, (unsigned long long)count);
      d += 8 * m;
    }
  }
  return 0;
}

/* Sets (add = false) or adds the serialized film into `into` once it passed check() and
 * judge, so `into` is unchanged on error. */
static int apply(const uint8_t *buf, size_t n, pc_film *into, bool add, pc_wire_counts_judge judge, void *user,
                 pc_err *e) {
  bool planes = false;
  int nl = 0;
  int rc = check(buf, n, into, add, &planes, &nl, e);
  if (rc) return rc;
  if (judge) {
    uint64_t counts[PC_FILM_MAX_LAYERS];
    for (int l = 0; l < into->nlayers; l++) counts[l] = get64(buf + HEAD + (size_t)l * LAYER_HEAD + 20);
    if ((rc = judge(user, counts, e)) != 0) return rc;
  }
  size_t px = (size_t)into->w * (size_t)into->h * 3;
  const uint8_t *d = buf + HEAD + (size_t)nl * LAYER_HEAD;
  double v[PLANE_BLOCK];
  uint64_t dropped = get64(buf + 20);
  into->dropped_nonfinite = add ? into->dropped_nonfinite + dropped : dropped;
  const uint8_t *p = buf + HEAD;
  for (int l = 0; l < nl; l++, p += LAYER_HEAD) into->layers[l].count = (add ? into->layers[l].count : 0) + get64(p + 20);
  for (int l = nl; l < into->nlayers; l++) { /* an old checkpoint's missing beauty_sq (set only) */
    into->layers[l].count = 0;
    if (into->layers[l].sum) memset(into->layers[l].sum, 0, px * sizeof(double));
  }
  for (int l = 0; l < nl; l++)
    for (size_t k = 0; k < px; k += PLANE_BLOCK) {
      size_t m = px - k < PLANE_BLOCK ? px - k : PLANE_BLOCK;
      double *s = into->layers[l].sum + k;
      get_block(d, planes, m, add ? v : s);
      d += 8 * m;
      if (add)
        for (size_t i = 0; i < m; i++) s[i] += v[i];
    }
  return 0;
}

int pc_wire_film_unpack(const uint8_t *buf, size_t n, pc_film *into, pc_err *e) {
  return apply(buf, n, into, false, NULL, NULL, e);
}
int pc_wire_film_add(const uint8_t *buf, size_t n, pc_film *into, pc_wire_counts_judge judge, void *user, pc_err *e) {
  return apply(buf, n, into, true, judge, user, e);
}

int pc_wire_film_load(const uint8_t *z, size_t zn, pc_film *into, pc_err *e) {
  unsigned long long cs = ZSTD_getFrameContentSize(z, zn);
  size_t whole = pc_wire_film_size(into), old = size_of(into, short_layers(into));
  size_t want = cs == (unsigned long long)old ? old : whole;
  uint8_t *raw = NULL;
  int rc = pc_wire_decompress(z, zn, want, whole, &raw, e);
  if (!rc) rc = pc_wire_film_unpack(raw, want, into, e);
  free(raw);
  return rc;
}

int pc_wire_compress(const uint8_t *in, size_t n, uint8_t **out, size_t *outn, pc_err *e) {
  size_t cap = ZSTD_compressBound(n);
  uint8_t *b = malloc(cap ? cap : 1);
  if (!b) return pc_errf(e, PC_ENOMEM, "zstd: out of memory for %zu bytes", cap);
  size_t r = ZSTD_compress(b, cap, in, n, ZSTD_LEVEL);
  if (ZSTD_isError(r)) {
    free(b);
    return pc_errf(e, PC_EIO, "zstd: compress failed: %s", ZSTD_getErrorName(r));
  }
  *out = b;
  *outn = r;
  return 0;
}

int pc_wire_decompress_to(const uint8_t *in, size_t n, uint8_t *out, size_t expect, pc_err *e) {
  unsigned long long cs = ZSTD_getFrameContentSize(in, n);
  if (cs == ZSTD_CONTENTSIZE_ERROR || cs == ZSTD_CONTENTSIZE_UNKNOWN)
    return pc_errf(e, PC_EPARSE, "zstd: not a zstd frame with a known size");
  if (cs != expect) return pc_errf(e, PC_EINVAL, "zstd: content size %llu, expected %zu", cs, expect);
  size_t r = ZSTD_decompress(out, expect, in, n);
  if (ZSTD_isError(r) || r != expect)
    return pc_errf(e, PC_EPARSE, "zstd: decompress failed: %s", ZSTD_isError(r) ? ZSTD_getErrorName(r) : "short output");
  return 0;
}

int pc_wire_decompress(const uint8_t *in, size_t n, size_t expect, size_t limit, uint8_t **out, pc_err *e) {
  if (expect > limit) return pc_errf(e, PC_EINVAL, "zstd: content size %zu over the limit %zu", expect, limit);
  uint8_t *b = malloc(expect ? expect : 1);
  if (!b) return pc_errf(e, PC_ENOMEM, "zstd: out of memory for %zu bytes", expect);
  int rc = pc_wire_decompress_to(in, n, b, expect, e);
  if (rc) {
    free(b);
    return rc;
  }
  *out = b;
  return 0;
}
