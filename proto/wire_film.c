/* wire_film.c: film (de)serialization and zstd wrapping for uploads and checkpoints.
 * Format PCFILM02 stores each layer's sums in blocks of PLANE_BLOCK doubles, each block as
 * eight byte planes (byte 0 of every value, then byte 1, ...): the sign/exponent and high
 * mantissa planes of nearby pixels repeat, so zstd at a fast level packs them ~20% smaller
 * and ~3x faster than interleaved doubles. PCFILM01 (plain little-endian doubles) is still
 * read, so checkpoints of older coordinators load, and so is a checkpoint without the film's
 * last layers, beauty_sq and beauty_max, or beauty_max alone (written before they existed): it
 * loads with them empty, and the job's error estimate and largest iterations say they cannot
 * tell (film.h). Uploads must be whole. beauty_max merges by max, every other layer by sum.
 * PCFILM03 adds the film's trace (film_trace.h): its record count and blocks per record in the
 * header, the records (iteration, then its block means as floats) after the last layer; a
 * film of an older format loads with no trace. */
#include "wire_film.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "big_alloc.h"

#define MAGIC_V1 "PCFILM01"
#define MAGIC_V2 "PCFILM02"
#define MAGIC_V3 "PCFILM03"
#define HEAD (8 + 4 * 3 + 8)
#define HEAD3 (HEAD + 4 + 4)
#define LAYER_HEAD (16 + 4 + 8)
#define PLANE_BLOCK 2048
/* Fast: films are compressed on the render machines for every upload (while the render pool
 * waits) and on the coordinator for every checkpoint, and every upload is decompressed twice
 * (checked, then added); higher levels cost several times the CPU for a few per cent of size.
 * The first of zstd's fast levels (-1) against level 1, on a worker's upload of cornell-box
 * 512x512 BDPT (37.8 MB; `zstd -b`): 2.7% larger (19.70 MB against 19.18), compressed 2.15x and
 * decompressed 1.8x faster (1311 and 3294 MB/s against 609 and 1815 on one core). */
#define ZSTD_LEVEL (-1)

static void put32(uint8_t *p, uint32_t v) { for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i)); }
static void put64(uint8_t *p, uint64_t v) { for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i)); }
static uint32_t get32(const uint8_t *p) { uint32_t v = 0; for (int i = 3; i >= 0; i--) v = v << 8 | p[i]; return v; }
static uint64_t get64(const uint8_t *p) { uint64_t v = 0; for (int i = 7; i >= 0; i--) v = v << 8 | p[i]; return v; }

static size_t record_size(const pc_film *f) { return 4 + 4 * (size_t)pc_trace_blocks(f->w, f->h); }

/* A serialized film of f's shape: nlayers of its layers and, when v3, ntrace trace records. */
static size_t size_of(const pc_film *f, int nlayers, bool v3, uint32_t ntrace) {
  size_t px = (size_t)f->w * (size_t)f->h * 3;
  return (v3 ? HEAD3 : HEAD) + (size_t)nlayers * (LAYER_HEAD + px * 8) + (v3 ? ntrace * record_size(f) : 0);
}

size_t pc_wire_film_size(const pc_film *f) { return size_of(f, f->nlayers, true, f->trace.n); }
size_t pc_wire_film_size_traced(const pc_film *like, uint32_t ntrace) { return size_of(like, like->nlayers, true, ntrace); }

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

/* The header: magic, shape, dropped samples, trace records and blocks per record, then each
 * layer's name, norm and count. */
static size_t put_header(const pc_film *f, uint8_t *p) {
  uint8_t *start = p;
  memcpy(p, MAGIC_V3, 8); p += 8;
  put32(p, (uint32_t)f->w); put32(p + 4, (uint32_t)f->h); put32(p + 8, (uint32_t)f->nlayers); p += 12;
  put64(p, f->dropped_nonfinite); p += 8;
  put32(p, f->trace.n); put32(p + 4, (uint32_t)pc_trace_blocks(f->w, f->h)); p += 8;
  for (int l = 0; l < f->nlayers; l++, p += LAYER_HEAD) {
    memset(p, 0, 16);
    memcpy(p, f->layers[l].name, strnlen(f->layers[l].name, 16));
    put32(p + 16, (uint32_t)f->layers[l].norm);
    put64(p + 20, f->layers[l].count);
  }
  return (size_t)(p - start);
}

/* Trace record k: its iteration, then its block means (float bits, little-endian). */
static void put_record(const pc_film *f, uint32_t k, uint8_t *p) {
  int nb = pc_trace_blocks(f->w, f->h);
  put32(p, f->trace.iteration[k]);
  for (int b = 0; b < nb; b++) {
    uint32_t bits;
    memcpy(&bits, &f->trace.block[(size_t)k * (size_t)nb + (size_t)b], 4);
    put32(p + 4 + 4 * (size_t)b, bits);
  }
}

void pc_wire_film_pack_to(const pc_film *f, uint8_t *out) {
  size_t px = (size_t)f->w * (size_t)f->h * 3;
  uint8_t *p = out + put_header(f, out);
  for (int l = 0; l < f->nlayers; l++)
    for (size_t k = 0; k < px; k += PLANE_BLOCK) {
      size_t m = px - k < PLANE_BLOCK ? px - k : PLANE_BLOCK;
      put_block(p, f->layers[l].sum + k, m);
      p += 8 * m;
    }
  for (uint32_t k = 0; k < f->trace.n; k++, p += record_size(f)) put_record(f, k, p);
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

/* A serialized film read front to back, from memory or from a zstd frame decompressed
 * through a window of WINDOW bytes, so a film of any size is checked and merged without a
 * whole second copy of it. Reads are of at most a block (8 * PLANE_BLOCK bytes) or the
 * header. */
#define WINDOW ((size_t)256 << 10)
/* Our frames use level 1's window (2^19 for films); anything wider is not ours. */
#define WINDOW_LOG_MAX 24
typedef struct film_src {
  const uint8_t *data;   /* raw bytes, or a zstd frame (dctx set) */
  size_t n;
  size_t total;          /* the serialized film's size */
  size_t pos;            /* raw: bytes read */
  ZSTD_DCtx *dctx;
  ZSTD_inBuffer in;
  uint8_t *win;          /* decompressed, not yet read: win[lo, hi) */
  size_t lo, hi;
  bool ended;            /* the frame is complete */
} film_src;

static void src_raw(film_src *s, const uint8_t *buf, size_t n) { *s = (film_src){.data = buf, .n = n, .total = n}; }

static int src_zstd(film_src *s, const uint8_t *z, size_t zn, pc_err *e) {
  *s = (film_src){.data = z, .n = zn};
  unsigned long long cs = ZSTD_getFrameContentSize(z, zn);
  if (cs == ZSTD_CONTENTSIZE_ERROR || cs == ZSTD_CONTENTSIZE_UNKNOWN)
    return pc_errf(e, PC_EPARSE, "zstd: not a zstd frame with a known size");
  if (cs > PC_WIRE_FILM_MAX) return pc_errf(e, PC_EINVAL, "zstd: content size %llu over the limit", cs);
  s->total = (size_t)cs;
  s->dctx = ZSTD_createDCtx();
  s->win = malloc(WINDOW);
  if (!s->dctx || !s->win) return pc_errf(e, PC_ENOMEM, "zstd: out of memory for a decompression stream");
  if (ZSTD_isError(ZSTD_DCtx_setParameter(s->dctx, ZSTD_d_windowLogMax, WINDOW_LOG_MAX)))
    return pc_errf(e, PC_EIO, "zstd: cannot bound the window");
  s->in = (ZSTD_inBuffer){z, zn, 0};
  return 0;
}

static void src_free(film_src *s) {
  ZSTD_freeDCtx(s->dctx);
  free(s->win);
}

/* Back to the first byte, for a second pass over the same bytes. */
static void src_rewind(film_src *s) {
  s->pos = s->lo = s->hi = 0;
  s->ended = false;
  if (s->dctx) {
    ZSTD_DCtx_reset(s->dctx, ZSTD_reset_session_only);
    s->in.pos = 0;
  }
}

/* The next n bytes, or NULL (e set) when the film ends before them. */
static const uint8_t *src_read(film_src *s, size_t n, pc_err *e) {
  if (!s->dctx) {
    if (n > s->n - s->pos) { pc_errf(e, PC_EINVAL, "film: %zu bytes, expected more", s->n); return NULL; }
    s->pos += n;
    return s->data + s->pos - n;
  }
  if (s->hi - s->lo < n) {
    memmove(s->win, s->win + s->lo, s->hi - s->lo);
    s->hi -= s->lo;
    s->lo = 0;
    while (s->hi < n && !s->ended) {
      ZSTD_outBuffer out = {s->win, WINDOW, s->hi};
      size_t r = ZSTD_decompressStream(s->dctx, &out, &s->in);
      if (ZSTD_isError(r)) { pc_errf(e, PC_EPARSE, "zstd: decompress failed: %s", ZSTD_getErrorName(r)); return NULL; }
      if (r == 0) s->ended = true;
      else if (out.pos == s->hi && s->in.pos == s->in.size) break; /* truncated frame */
      s->hi = out.pos;
    }
    if (s->hi < n) { pc_errf(e, PC_EPARSE, "zstd: the frame ends inside the film"); return NULL; }
  }
  s->lo += n;
  return s->win + s->lo - n;
}

/* After the last byte: nothing may follow (no data in the frame, no bytes after it). */
static int src_end(film_src *s, pc_err *e) {
  if (!s->dctx) return s->pos == s->n ? 0 : pc_errf(e, PC_EINVAL, "film: %zu bytes, expected %zu", s->n, s->pos);
  uint8_t extra;
  while (!s->ended && s->lo == s->hi) {
    ZSTD_outBuffer out = {&extra, 1, 0};
    size_t r = ZSTD_decompressStream(s->dctx, &out, &s->in);
    if (ZSTD_isError(r)) return pc_errf(e, PC_EPARSE, "zstd: decompress failed: %s", ZSTD_getErrorName(r));
    if (out.pos) s->hi = s->lo + 1;
    else if (r == 0) s->ended = true;
    else if (s->in.pos == s->in.size) return pc_errf(e, PC_EPARSE, "zstd: truncated frame");
  }
  if (s->lo != s->hi) return pc_errf(e, PC_EPARSE, "zstd: more data than the film");
  if (s->in.pos != s->in.size) return pc_errf(e, PC_EPARSE, "zstd: %zu bytes after the frame", s->in.size - s->in.pos);
  return 0;
}

/* What a serialized film's header says beyond its counts. */
typedef struct film_head {
  bool planes;     /* sums as byte planes (v2, v3) */
  int nl;          /* of like's layers it holds */
  uint32_t ntrace; /* trace records after the layers (v3) */
  uint64_t dropped;
} film_head;

/* Reads and checks a serialized film's header against the shape of `like`: the layers it holds
 * (all, or with `whole` false maybe all but the per-iteration layers at the end), counts[]. */
static int read_header(film_src *s, const pc_film *like, bool whole, film_head *hd, uint64_t *counts, pc_err *e) {
  const uint8_t *buf = s->total >= HEAD ? src_read(s, HEAD, e) : NULL;
  if (!buf && s->total >= HEAD) return e->code;
  bool v1 = buf && memcmp(buf, MAGIC_V1, 8) == 0, v2 = buf && memcmp(buf, MAGIC_V2, 8) == 0,
       v3 = buf && memcmp(buf, MAGIC_V3, 8) == 0;
  if (!v1 && !v2 && !v3) return pc_errf(e, PC_EPARSE, "film: not a serialized film (bad magic or %zu bytes)", s->total);
  uint32_t w = get32(buf + 8), h = get32(buf + 12), nl = get32(buf + 16);
  hd->dropped = get64(buf + 20);
  hd->ntrace = 0;
  if ((int)w != like->w || (int)h != like->h)
    return pc_errf(e, PC_EINVAL, "film: resolution %ux%u, the job has %dx%d", w, h, like->w, like->h);
  if ((int)nl != like->nlayers && (whole || (int)nl < pc_film_per_iteration_first(like) || (int)nl > like->nlayers))
    return pc_errf(e, PC_EINVAL, "film: %u layers, the job has %d", nl, like->nlayers);
  if (v3) {
    const uint8_t *t = s->total >= HEAD3 ? src_read(s, HEAD3 - HEAD, e) : NULL;
    if (!t) return s->total >= HEAD3 ? e->code : pc_errf(e, PC_EINVAL, "film: %zu bytes, expected more", s->total);
    hd->ntrace = get32(t);
    uint32_t nb = get32(t + 4);
    if (hd->ntrace > PC_TRACE_ITERATIONS)
      return pc_errf(e, PC_ELIMIT, "film: %u traced iterations, at most %u", hd->ntrace, PC_TRACE_ITERATIONS);
    if (nb != (uint32_t)pc_trace_blocks(like->w, like->h))
      return pc_errf(e, PC_EINVAL, "film: %u trace blocks, a %dx%d film has %d", nb, like->w, like->h,
                     pc_trace_blocks(like->w, like->h));
  }
  size_t want = size_of(like, (int)nl, v3, hd->ntrace);
  if (s->total != want) return pc_errf(e, PC_EINVAL, "film: %zu bytes, expected %zu", s->total, want);
  const uint8_t *p = src_read(s, (size_t)nl * LAYER_HEAD, e);
  if (!p) return e->code;
  for (int l = 0; l < (int)nl; l++, p += LAYER_HEAD) {
    char name[17] = {0};
    memcpy(name, p, 16);
    if (strncmp(name, like->layers[l].name, 16) != 0 || get32(p + 16) != (uint32_t)like->layers[l].norm)
      return pc_errf(e, PC_EINVAL, "film: layer %d is '%s', the job has '%s'", l, name, like->layers[l].name);
    counts[l] = get64(p + 20);
  }
  hd->planes = v2 || v3;
  hd->nl = (int)nl;
  return 0;
}

/* The next trace record: its iteration and (into `block`, may be NULL) its block means. */
static int read_record(film_src *s, const pc_film *like, uint32_t *it, float *block, pc_err *e) {
  int nb = pc_trace_blocks(like->w, like->h);
  const uint8_t *p = src_read(s, record_size(like), e);
  if (!p) return e->code;
  *it = get32(p);
  for (int b = 0; b < nb; b++) {
    uint32_t bits = get32(p + 4 + 4 * (size_t)b);
    float v;
    memcpy(&v, &bits, 4);
    if (!isfinite(v)) return pc_errf(e, PC_ENUMERIC, "film: non-finite trace value of iteration %u", *it);
    if (block) block[b] = v;
  }
  return 0;
}

/* The first pass: the header, then that every sum is finite and, for a delta (bounded), under
 * 2^PC_WIRE_SAMPLE_LOG2 per sample of its layer (2^(2 PC_WIRE_SAMPLE_LOG2) for beauty_sq, whose
 * samples are squares; a biased exponent of at most 1023 + that + the bit length of the count
 * - 1; a maximum is under the same bound as a sum), before anything is read into a film. A
 * delta holds every layer; a checkpoint may be one written before beauty_sq or beauty_max (*nl
 * tells). */
static int check(film_src *s, const pc_film *like, bool bounded, film_head *hd, uint64_t *counts, uint32_t *traced,
                 pc_err *e) {
  int rc = read_header(s, like, bounded, hd, counts, e);
  if (rc) return rc;
  size_t px = (size_t)like->w * (size_t)like->h * 3;
  bool planes = hd->planes;
  int *nl = &hd->nl;
  for (int l = 0; l < *nl; l++) {
    unsigned bits = 0, sample_log2 = like->layers[l].norm == PC_NORM_SQUARE ? 2 * PC_WIRE_SAMPLE_LOG2 : PC_WIRE_SAMPLE_LOG2;
    while (bits < 64 && counts[l] >> bits) bits++;
    unsigned max_exp = bounded ? 1023 + sample_log2 + bits - 1 : 0x7fe;
    for (size_t k = 0; k < px; k += PLANE_BLOCK) {
      size_t m = px - k < PLANE_BLOCK ? px - k : PLANE_BLOCK;
      const uint8_t *d = src_read(s, 8 * m, e);
      if (!d) return e->code;
      size_t i = first_over(d, planes, m, max_exp);
      if (i < m && first_over(d, planes, m, 0x7fe) == i)
        return pc_errf(e, PC_ENUMERIC, "film: non-finite sum in layer %d at pixel %zu", l, (k + i) / 3);
      if (i < m)
        return pc_errf(e, PC_ENUMERIC, "film: a sum in layer %d at pixel %zu is beyond any radiance for %llu samples", l,
                       (k + i) / 3, (unsigned long long)counts[l]);
    }
  }
  /* the trace: every iteration once, below the bound, and (merging) not in `like` already */
  uint64_t seen[PC_TRACE_ITERATIONS / 64] = {0};
  for (uint32_t k = 0; k < hd->ntrace; k++) {
    uint32_t it;
    if ((rc = read_record(s, like, &it, NULL, e)) != 0) return rc;
    if (it >= PC_TRACE_ITERATIONS)
      return pc_errf(e, PC_EINVAL, "film: traced iteration %u, only the first %u are", it, PC_TRACE_ITERATIONS);
    if (seen[it / 64] >> (it % 64) & 1u) return pc_errf(e, PC_EINVAL, "film: iteration %u traced twice", it);
    if (bounded && pc_trace_has(&like->trace, it))
      return pc_errf(e, PC_EINVAL, "film: iteration %u is traced already", it);
    seen[it / 64] |= (uint64_t)1 << (it % 64);
    traced[k] = it;
  }
  return src_end(s, e);
}

/* Sets (add = false) or adds the serialized film into `into` once a first pass over it
 * passed check() and judge, so `into` is unchanged on error; the second pass reads the same
 * bytes again. */
static int apply(film_src *s, pc_film *into, bool add, pc_wire_counts_judge judge, void *user, pc_err *e) {
  film_head hd = {0};
  uint64_t counts[PC_FILM_MAX_LAYERS];
  uint32_t *traced = malloc(PC_TRACE_ITERATIONS * sizeof *traced);
  if (!traced) return pc_errf(e, PC_ENOMEM, "film: out of memory for a trace");
  int rc = check(s, into, add, &hd, counts, traced, e);
  if (!rc && judge) rc = judge(user, &(pc_wire_film_counts){counts, traced, hd.ntrace}, e);
  free(traced);
  int nb = pc_trace_blocks(into->w, into->h);
  /* room for the trace before anything changes */
  if (!rc) rc = pc_trace_reserve(&into->trace, (add ? into->trace.n : 0) + hd.ntrace, nb, e);
  if (rc) return rc;
  src_rewind(s);
  if ((rc = read_header(s, into, add, &hd, counts, e)) != 0) return rc;
  int nl = hd.nl;
  bool planes = hd.planes;
  size_t px = (size_t)into->w * (size_t)into->h * 3;
  double v[PLANE_BLOCK];
  into->dropped_nonfinite = add ? into->dropped_nonfinite + hd.dropped : hd.dropped;
  for (int l = 0; l < nl; l++) into->layers[l].count = (add ? into->layers[l].count : 0) + counts[l];
  for (int l = nl; l < into->nlayers; l++) { /* an old checkpoint's missing beauty_sq, beauty_max (set only) */
    into->layers[l].count = 0;
    if (into->layers[l].sum) memset(into->layers[l].sum, 0, px * sizeof(double));
  }
  for (int l = 0; l < nl; l++)
    for (size_t k = 0; k < px; k += PLANE_BLOCK) {
      size_t m = px - k < PLANE_BLOCK ? px - k : PLANE_BLOCK;
      double *sum = into->layers[l].sum + k;
      /* the first pass read these bytes: only a failing allocator could stop this one */
      const uint8_t *d = src_read(s, 8 * m, e);
      if (!d) return e->code;
      get_block(d, planes, m, add ? v : sum);
      if (add && into->layers[l].norm == PC_NORM_MAX)
        for (size_t i = 0; i < m; i++) sum[i] = v[i] > sum[i] ? v[i] : sum[i];
      else if (add)
        for (size_t i = 0; i < m; i++) sum[i] += v[i];
    }
  if (!add) pc_trace_clear(&into->trace);
  float block[PC_TRACE_MAX_BLOCKS];
  for (uint32_t k = 0; k < hd.ntrace; k++) {
    uint32_t it;
    if ((rc = read_record(s, into, &it, block, e)) != 0) return rc;
    pc_trace_put(&into->trace, nb, it, block);
  }
  return 0;
}

int pc_wire_film_unpack(const uint8_t *buf, size_t n, pc_film *into, pc_err *e) {
  film_src s;
  src_raw(&s, buf, n);
  return apply(&s, into, false, NULL, NULL, e);
}
int pc_wire_film_add(const uint8_t *buf, size_t n, pc_film *into, pc_wire_counts_judge judge, void *user, pc_err *e) {
  film_src s;
  src_raw(&s, buf, n);
  return apply(&s, into, true, judge, user, e);
}

int pc_wire_film_add_z(const uint8_t *z, size_t zn, pc_film *into, pc_wire_counts_judge judge, void *user, pc_err *e) {
  film_src s;
  int rc = src_zstd(&s, z, zn, e);
  if (!rc) rc = apply(&s, into, true, judge, user, e);
  src_free(&s);
  return rc;
}

int pc_wire_film_load(const uint8_t *z, size_t zn, pc_film *into, pc_err *e) {
  film_src s;
  int rc = src_zstd(&s, z, zn, e);
  if (!rc) rc = apply(&s, into, false, NULL, NULL, e);
  src_free(&s);
  return rc;
}

/* Packs blocks into a staging buffer of about STAGE bytes and compresses it into the sink as
 * it fills, so the serialized film never exists whole. */
#define STAGE ((size_t)1 << 20)
int pc_wire_film_compress(const pc_film *f, int threads, pc_wire_sink sink, void *user, size_t *zn, pc_err *e) {
  size_t px = (size_t)f->w * (size_t)f->h * 3, head = HEAD + (size_t)f->nlayers * LAYER_HEAD;
  size_t cap = STAGE > head ? STAGE : head, outcap = ZSTD_CStreamOutSize();
  ZSTD_CCtx *cc = ZSTD_createCCtx();
  uint8_t *stage = malloc(cap), *out = malloc(outcap);
  int rc = 0;
  if (!cc || !stage || !out) rc = pc_errf(e, PC_ENOMEM, "zstd: out of memory for a compression stream");
  if (!rc && (ZSTD_isError(ZSTD_CCtx_setParameter(cc, ZSTD_c_compressionLevel, ZSTD_LEVEL)) ||
              ZSTD_isError(ZSTD_CCtx_setPledgedSrcSize(cc, pc_wire_film_size(f)))))
    rc = pc_errf(e, PC_EIO, "zstd: cannot set up the compression stream");
  if (!rc && threads > 1) (void)ZSTD_CCtx_setParameter(cc, ZSTD_c_nbWorkers, threads); /* refused: one thread */
  size_t fill = rc ? 0 : put_header(f, stage), total = 0, rs = record_size(f);
  int l = 0;
  size_t k = 0;
  uint32_t r = 0;
  while (!rc) {
    /* stage blocks, then trace records, until the next would not fit, or the film is done */
    while (l < f->nlayers) {
      size_t m = px - k < PLANE_BLOCK ? px - k : PLANE_BLOCK;
      if (fill + 8 * m > cap) break;
      put_block(stage + fill, f->layers[l].sum + k, m);
      fill += 8 * m;
      if ((k += m) >= px) k = 0, l++;
    }
    for (; l == f->nlayers && r < f->trace.n && fill + rs <= cap; r++, fill += rs) put_record(f, r, stage + fill);
    bool last = l == f->nlayers && r == f->trace.n;
    ZSTD_inBuffer in = {stage, fill, 0};
    size_t left;
    do {
      ZSTD_outBuffer o = {out, outcap, 0};
      left = ZSTD_compressStream2(cc, &o, &in, last ? ZSTD_e_end : ZSTD_e_continue);
      if (ZSTD_isError(left)) { rc = pc_errf(e, PC_EIO, "zstd: compress failed: %s", ZSTD_getErrorName(left)); break; }
      if (o.pos && (rc = sink(user, out, o.pos, e)) != 0) break;
      total += o.pos;
    } while (last ? left != 0 : in.pos < in.size);
    fill = 0;
    if (last) break;
  }
  ZSTD_freeCCtx(cc);
  free(stage);
  free(out);
  if (!rc && zn) *zn = total;
  return rc;
}

typedef struct grow_buf { uint8_t *p; size_t n, cap; } grow_buf;
static int grow_sink(void *user, const uint8_t *p, size_t n, pc_err *e) {
  grow_buf *b = user;
  if (n > b->cap - b->n) {
    size_t cap = b->cap ? b->cap : (size_t)1 << 16;
    while (n > cap - b->n) cap *= 2;
    uint8_t *q = realloc(b->p, cap);
    if (!q) return pc_errf(e, PC_ENOMEM, "zstd: out of memory for %zu compressed bytes", cap);
    b->p = q;
    b->cap = cap;
  }
  memcpy(b->p + b->n, p, n);
  b->n += n;
  return 0;
}

int pc_wire_film_zip_reuse(const pc_film *f, int threads, uint8_t **buf, size_t *cap, size_t *outn, pc_err *e) {
  /* Room for the worst case at once: grown by doubling, the buffer was copied at every step
   * and each new one faulted in page by page (a tenth of a 16-spp render's page faults).
   * Pages the output does not reach are never touched. */
  size_t bound = ZSTD_compressBound(pc_wire_film_size(f));
  if (!ZSTD_isError(bound) && *cap < bound) {
    uint8_t *p = pc_big_alloc(bound);
    if (p) {
      free(*buf);
      *buf = p;
      *cap = bound;
    }
  }
  grow_buf b = {*buf, 0, *cap};
  int rc = pc_wire_film_compress(f, threads, grow_sink, &b, NULL, e);
  *buf = b.p; /* grow_sink may have moved it */
  *cap = b.cap;
  *outn = rc ? 0 : b.n;
  return rc;
}

int pc_wire_film_zip(const pc_film *f, int threads, uint8_t **out, size_t *outn, pc_err *e) {
  uint8_t *buf = NULL;
  size_t cap = 0;
  int rc = pc_wire_film_zip_reuse(f, threads, &buf, &cap, outn, e);
  if (rc) {
    free(buf);
    return rc;
  }
  *out = buf;
  return 0;
}

int pc_wire_compress(const uint8_t *in, size_t n, uint8_t **out, size_t *outn, pc_err *e) {
  size_t cap = ZSTD_compressBound(n);
  uint8_t *b = pc_big_alloc(cap);
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

static int decompress_to(const uint8_t *in, size_t n, uint8_t *out, size_t expect, pc_err *e) {
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
  uint8_t *b = pc_big_alloc(expect);
  if (!b) return pc_errf(e, PC_ENOMEM, "zstd: out of memory for %zu bytes", expect);
  int rc = decompress_to(in, n, b, expect, e);
  if (rc) {
    free(b);
    return rc;
  }
  *out = b;
  return 0;
}
