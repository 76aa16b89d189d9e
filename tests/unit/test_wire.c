/* test_wire.c: frame encoding/decoding (split reads, limits, garbage), film packing with its
 * refusals, zstd wrapping, and the render settings' round trip. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "irec.h"
#include "wire_film.h"
#include "wire_frame.h"
#include "wire_settings.h"

static void encode_hello(uint8_t **b, size_t *n) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Hello h = PCBPT__HELLO__INIT;
  h.protocol_version = PC_WIRE_PROTOCOL_VERSION;
  h.role = PCBPT__ROLE__ROLE_WORKER;
  h.name = "w1";
  env.msg_case = PCBPT__ENVELOPE__MSG_HELLO;
  env.hello = &h;
  pc_err e;
  assert_int_equal(pc_wire_encode(&env, b, n, &e), 0);
}

static void byte_by_byte(void **st) {
  (void)st;
  uint8_t *b;
  size_t n;
  encode_hello(&b, &n);
  /* two frames back to back, fed one byte at a time */
  uint8_t *two = malloc(2 * n);
  memcpy(two, b, n);
  memcpy(two + n, b, n);
  pc_wire_decoder d;
  pc_wire_decoder_init(&d, 0);
  int frames = 0;
  for (size_t i = 0; i < 2 * n; i++) {
    size_t used;
    Pcbpt__Envelope *env;
    pc_err e;
    int r = pc_wire_decoder_push(&d, two + i, 1, &used, &env, &e);
    assert_true(r >= 0);
    assert_int_equal(used, 1);
    if (r == 1) {
      assert_int_equal(env->msg_case, PCBPT__ENVELOPE__MSG_HELLO);
      assert_string_equal(env->hello->name, "w1");
      pcbpt__envelope__free_unpacked(env, NULL);
      frames++;
    }
  }
  assert_int_equal(frames, 2);
  pc_wire_decoder_free(&d);
  free(two);
  free(b);
}

static void whole_buffer(void **st) {
  (void)st;
  uint8_t *b;
  size_t n;
  encode_hello(&b, &n);
  uint8_t *two = malloc(2 * n);
  memcpy(two, b, n);
  memcpy(two + n, b, n);
  pc_wire_decoder d;
  pc_wire_decoder_init(&d, 0);
  size_t off = 0, used;
  int frames = 0;
  Pcbpt__Envelope *env;
  pc_err e;
  while (off < 2 * n) {
    int r = pc_wire_decoder_push(&d, two + off, 2 * n - off, &used, &env, &e);
    assert_true(r >= 0);
    off += used;
    if (r == 1) { frames++; pcbpt__envelope__free_unpacked(env, NULL); }
  }
  assert_int_equal(frames, 2);
  pc_wire_decoder_free(&d);
  free(two);
  free(b);
}

static int push_all(const uint8_t *b, size_t n, pc_err *e) {
  pc_wire_decoder d;
  pc_wire_decoder_init(&d, 0);
  size_t off = 0, used;
  Pcbpt__Envelope *env;
  int r = 0;
  while (off < n && (r = pc_wire_decoder_push(&d, b + off, n - off, &used, &env, e)) >= 0) {
    off += used;
    if (r == 1) pcbpt__envelope__free_unpacked(env, NULL);
  }
  pc_wire_decoder_free(&d);
  return r;
}

static void refusals(void **st) {
  (void)st;
  pc_err e;
  uint8_t big[4] = {0x00, 0x10, 0x00, 0x01}; /* 1 MiB + 1 */
  assert_int_equal(push_all(big, 4, &e), PC_ELIMIT);
  assert_non_null(strstr(e.msg, "exceeds"));
  uint8_t empty[4] = {0, 0, 0, 0};
  assert_int_equal(push_all(empty, 4, &e), PC_EPARSE);
  uint8_t garbage[] = {0, 0, 0, 6, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff};
  assert_int_equal(push_all(garbage, sizeof garbage, &e), PC_EPARSE);
  uint8_t noset[] = {0, 0, 0, 2, 0x78, 0x01}; /* unknown field 15 varint: no message set */
  assert_int_equal(push_all(noset, sizeof noset, &e), PC_EPARSE);
  /* a truncated frame is simply incomplete: no error, nothing decoded */
  uint8_t *b;
  size_t n;
  encode_hello(&b, &n);
  assert_int_equal(push_all(b, n - 1, &e), 0);
  free(b);
}

static void make_film(pc_film *f, int w, int h) {
  memset(f, 0, sizeof *f);
  f->w = w; f->h = h; f->nlayers = 2;
  strcpy(f->layers[0].name, "pt");
  f->layers[0].norm = PC_NORM_EYE;
  strcpy(f->layers[1].name, "lt");
  f->layers[1].norm = PC_NORM_LIGHT;
  for (int l = 0; l < 2; l++) f->layers[l].sum = calloc((size_t)w * h * 3, sizeof(double));
}
static void free_film(pc_film *f) {
  for (int l = 0; l < f->nlayers; l++) free(f->layers[l].sum);
  pc_trace_free(&f->trace);
}

static void film_roundtrip(void **st) {
  (void)st;
  pc_film a, b, c;
  make_film(&a, 4, 3);
  make_film(&b, 4, 3);
  make_film(&c, 3, 4);
  for (int i = 0; i < 36; i++) { a.layers[0].sum[i] = i * 0.5; a.layers[1].sum[i] = -i; }
  a.layers[0].count = 7;
  a.layers[1].count = 7 * 12;
  a.dropped_nonfinite = 3;
  uint8_t *buf, *z, *back;
  size_t n, zn;
  pc_err e;
  assert_int_equal(pc_wire_film_pack(&a, &buf, &n, &e), 0);
  assert_int_equal(pc_wire_compress(buf, n, &z, &zn, &e), 0);
  assert_int_equal(pc_wire_decompress(z, zn, n + 1, n + 1, &back, &e), PC_EINVAL);
  assert_int_equal(pc_wire_decompress(z, zn, n, n, &back, &e), 0);
  assert_memory_equal(buf, back, n);
  assert_int_equal(pc_wire_film_unpack(back, n, &b, &e), 0);
  assert_int_equal(b.layers[0].count, 7);
  assert_int_equal(b.layers[1].count, 84);
  assert_int_equal(b.dropped_nonfinite, 3);
  assert_true(b.layers[0].sum[35] == 17.5);
  /* wrong resolution */
  assert_int_equal(pc_wire_film_unpack(back, n, &c, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "resolution"));
  /* a NaN is refused and leaves the target untouched */
  a.layers[1].sum[5] = 0.0 / 0.0;
  free(buf);
  assert_int_equal(pc_wire_film_pack(&a, &buf, &n, &e), 0);
  b.layers[1].count = 1;
  assert_int_equal(pc_wire_film_unpack(buf, n, &b, &e), PC_ENUMERIC);
  assert_int_equal(b.layers[1].count, 1);
  /* truncated */
  assert_int_equal(pc_wire_film_unpack(buf, n - 8, &b, &e), PC_EINVAL);
  free(buf); free(z); free(back);
  free_film(&a); free_film(&b); free_film(&c);
}

/* Films larger than the streaming windows (decompression 256 KiB, staging 1 MiB): compressed
 * without a serialized copy, merged and loaded through two passes; every refusal, found
 * anywhere in the stream, leaves the target as it was. */
static bool films_equal(const pc_film *a, const pc_film *b) {
  size_t n = (size_t)a->w * a->h * 3;
  for (int l = 0; l < a->nlayers; l++)
    if (a->layers[l].count != b->layers[l].count || memcmp(a->layers[l].sum, b->layers[l].sum, n * sizeof(double)))
      return false;
  return a->dropped_nonfinite == b->dropped_nonfinite;
}
static void film_streamed(void **st) {
  (void)st;
  pc_film a, b, before;
  int w = 300, h = 200;
  size_t n = (size_t)w * h * 3;
  make_film(&a, w, h);
  make_film(&b, w, h);
  make_film(&before, w, h);
  for (size_t i = 0; i < n; i++) { a.layers[0].sum[i] = (double)(i % 977) * 0.25; a.layers[1].sum[i] = 1.0 / (double)(i + 1); }
  a.layers[0].count = 5;
  a.layers[1].count = 5 * 64;
  a.dropped_nonfinite = 2;
  pc_err e;
  uint8_t *z, *raw, *back;
  size_t zn, rn;
  assert_int_equal(pc_wire_film_zip(&a, 1, &z, &zn, &e), 0);
  assert_int_equal(pc_wire_film_pack(&a, &raw, &rn, &e), 0);
  assert_true(rn > ((size_t)1 << 20) && zn < rn);
  /* the same bytes as packing, then compressing */
  assert_int_equal(pc_wire_decompress(z, zn, rn, rn, &back, &e), 0);
  assert_memory_equal(raw, back, rn);
  /* set, then add */
  assert_int_equal(pc_wire_film_load(z, zn, &b, &e), 0);
  assert_true(films_equal(&a, &b));
  /* compressed on zstd's threads too (a worker's uploads): the same film */
  pc_film t;
  make_film(&t, w, h);
  uint8_t *zt;
  size_t ztn;
  assert_int_equal(pc_wire_film_zip(&a, 3, &zt, &ztn, &e), 0);
  assert_int_equal(pc_wire_film_load(zt, ztn, &t, &e), 0);
  assert_true(films_equal(&a, &t));
  free(zt);
  free_film(&t);
  /* into a kept buffer: the same bytes; the buffer is kept while it holds the worst case,
   * and one too small is replaced */
  uint8_t *kept = NULL;
  size_t cap = 0, kn;
  assert_int_equal(pc_wire_film_zip_reuse(&a, 1, &kept, &cap, &kn, &e), 0);
  assert_true(kn == zn && cap >= kn);
  assert_memory_equal(kept, z, zn);
  uint8_t *first = kept;
  memset(kept, 0xa5, kn);
  assert_int_equal(pc_wire_film_zip_reuse(&a, 1, &kept, &cap, &kn, &e), 0);
  assert_ptr_equal(kept, first);
  assert_true(kn == zn);
  assert_memory_equal(kept, z, zn);
  free(kept);
  kept = malloc(16);
  cap = 16;
  assert_int_equal(pc_wire_film_zip_reuse(&a, 1, &kept, &cap, &kn, &e), 0);
  assert_true(kn == zn && cap >= kn);
  assert_memory_equal(kept, z, zn);
  free(kept);
  assert_int_equal(pc_wire_film_add_z(z, zn, &b, NULL, NULL, &e), 0);
  assert_int_equal(b.layers[0].count, 10);
  assert_true(b.layers[0].sum[n - 1] == 2 * a.layers[0].sum[n - 1] && b.dropped_nonfinite == 4);
  for (int l = 0; l < 2; l++) memcpy(before.layers[l].sum, b.layers[l].sum, n * sizeof(double)), before.layers[l].count = b.layers[l].count;
  before.dropped_nonfinite = b.dropped_nonfinite;
  /* truncated, and with a byte after the frame */
  assert_int_not_equal(pc_wire_film_add_z(z, zn - 1, &b, NULL, NULL, &e), 0);
  uint8_t *longer = malloc(zn + 1);
  memcpy(longer, z, zn);
  longer[zn] = 0;
  assert_int_equal(pc_wire_film_add_z(longer, zn + 1, &b, NULL, NULL, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "after the frame"));
  assert_true(films_equal(&b, &before));
  /* a NaN in the last block, far past the first window, refuses the whole upload */
  a.layers[1].sum[n - 1] = 0.0 / 0.0;
  free(z);
  assert_int_equal(pc_wire_film_zip(&a, 1, &z, &zn, &e), 0);
  assert_int_equal(pc_wire_film_add_z(z, zn, &b, NULL, NULL, &e), PC_ENUMERIC);
  assert_true(films_equal(&b, &before));
  /* not a zstd frame */
  assert_int_equal(pc_wire_film_add_z(raw, rn, &b, NULL, NULL, &e), PC_EPARSE);
  assert_true(films_equal(&b, &before));
  free(z); free(raw); free(back); free(longer);
  free_film(&a); free_film(&b); free_film(&before);
}

/* A counts judge that notes what it was shown and answers `answer`. */
typedef struct seen_counts {
  uint64_t counts[2];
  int answer;
} seen_counts;

static int record_counts(void *user, const pc_wire_film_counts *c, pc_err *e) {
  seen_counts *s = user;
  memcpy(s->counts, c->counts, sizeof s->counts);
  return s->answer ? pc_errf(e, s->answer, "counts refused") : 0;
}

/* A film serialized as older coordinators wrote it (PCFILM01: interleaved doubles), as in
 * their checkpoints: it still loads. */
static void film_v1_and_add(void **st) {
  (void)st;
  pc_film a, b;
  make_film(&a, 4, 3);
  make_film(&b, 4, 3);
  size_t px = 36, n = 28 + 2 * 28 + 2 * px * 8;
  uint8_t *v1 = calloc(1, n), *p = v1;
  memcpy(p, "PCFILM01", 8);
  p[8] = 4; p[12] = 3; p[16] = 2; p[20] = 5; /* w, h, layers, dropped (little-endian) */
  p += 28;
  const char *names[] = {"pt", "lt"};
  for (int l = 0; l < 2; l++, p += 28) {
    memcpy(p, names[l], strlen(names[l]));
    p[16] = (uint8_t)(l == 0 ? PC_NORM_EYE : PC_NORM_LIGHT);
    p[20] = (uint8_t)(l == 0 ? 2 : 24);
  }
  for (int l = 0; l < 2; l++)
    for (size_t i = 0; i < px; i++, p += 8) {
      double v = l == 0 ? 0.25 * (double)i : -1.0 - (double)i;
      memcpy(p, &v, 8); /* the test machine is little-endian like the format */
    }
  pc_err e;
  /* the judge sees the counts before anything is added, and its refusal leaves b as it was */
  seen_counts seen = {{0, 0}, PC_EINVAL};
  assert_int_equal(pc_wire_film_add(v1, n, &b, record_counts, &seen, &e), PC_EINVAL);
  assert_int_equal(seen.counts[0], 2);
  assert_int_equal(seen.counts[1], 24);
  assert_true(b.layers[0].sum[35] == 0.0 && b.layers[0].count == 0 && b.dropped_nonfinite == 0);
  assert_int_equal(pc_wire_film_unpack(v1, n, &a, &e), 0);
  assert_true(a.layers[0].sum[35] == 8.75 && a.layers[1].sum[35] == -36.0);
  assert_int_equal(a.dropped_nonfinite, 5);
  /* adding a film packed now (byte planes) to it: sums, counts and drops add */
  uint8_t *v2;
  size_t n2;
  assert_int_equal(pc_wire_film_pack(&a, &v2, &n2, &e), 0);
  assert_int_equal(n2, n + 8); /* PCFILM03's header holds the trace's count and blocks; no record */
  assert_memory_not_equal(v1, v2, n);
  assert_int_equal(pc_wire_film_add(v2, n2, &a, NULL, NULL, &e), 0);
  assert_true(a.layers[0].sum[35] == 17.5 && a.layers[1].sum[0] == -2.0);
  assert_int_equal(a.layers[0].count, 4);
  assert_int_equal(a.layers[1].count, 48);
  assert_int_equal(a.dropped_nonfinite, 10);
  /* a non-finite value anywhere refuses the whole add, leaving the target as it was */
  double inf = 1.0 / 0.0;
  memcpy(v1 + 28 + 56 + (px + 7) * 8, &inf, 8);
  seen = (seen_counts){{0, 0}, 0};
  assert_int_equal(pc_wire_film_add(v1, n, &a, record_counts, &seen, &e), PC_ENUMERIC);
  assert_int_equal(seen.counts[0], 0); /* refused for the value before its counts were judged */
  assert_non_null(strstr(e.msg, "layer 1"));
  assert_true(a.layers[0].sum[35] == 17.5);
  assert_int_equal(a.layers[0].count, 4);
  free(v1); free(v2);
  free_film(&a); free_film(&b);
}

typedef struct seen_trace {
  uint32_t n, first, last;
} seen_trace;
static int record_trace(void *user, const pc_wire_film_counts *c, pc_err *e) {
  seen_trace *s = user;
  s->n = c->ntraced;
  s->first = c->ntraced ? c->traced[0] : 0;
  s->last = c->ntraced ? c->traced[c->ntraced - 1] : 0;
  return pc_errf(e, PC_EINVAL, "trace refused");
}

static bool traces_equal(const pc_film *a, const pc_film *b) {
  int nb = pc_trace_blocks(a->w, a->h);
  return a->trace.n == b->trace.n && memcmp(a->trace.iteration, b->trace.iteration, a->trace.n * sizeof(uint32_t)) == 0 &&
         memcmp(a->trace.block, b->trace.block, (size_t)a->trace.n * nb * sizeof(float)) == 0;
}

/* The trace travels with the film: after the layers, across the compressor's staging buffer
 * (a 300x200 film's layers fill it past 1 MiB, its 4096 records another ~1 MiB), in its order;
 * a record that is not finite, an iteration traced twice or past the bound, or one the target
 * traces already, refuses the whole film; the judge sees the traced iterations. */
static void film_trace_travels(void **st) {
  (void)st;
  pc_film a, b, c;
  int w = 300, h = 200, nb = pc_trace_blocks(w, h);
  make_film(&a, w, h);
  make_film(&b, w, h);
  make_film(&c, w, h);
  assert_int_equal(nb, 64);
  a.layers[0].count = PC_TRACE_ITERATIONS;
  a.layers[1].count = PC_TRACE_ITERATIONS;
  pc_err e;
  assert_int_equal(pc_trace_reserve(&a.trace, PC_TRACE_ITERATIONS, nb, &e), 0);
  float blk[PC_TRACE_MAX_BLOCKS];
  for (uint32_t k = 0; k < PC_TRACE_ITERATIONS; k++) {
    for (int i = 0; i < nb; i++) blk[i] = (float)k * 0.5f + (float)i;
    pc_trace_put(&a.trace, nb, PC_TRACE_ITERATIONS - 1 - k, blk);
  }
  uint8_t *z, *raw, *back;
  size_t zn, rn;
  assert_int_equal(pc_wire_film_zip(&a, 1, &z, &zn, &e), 0);
  assert_int_equal(pc_wire_film_pack(&a, &raw, &rn, &e), 0);
  assert_int_equal(rn, pc_wire_film_size_traced(&a, PC_TRACE_ITERATIONS));
  assert_int_equal(pc_wire_decompress(z, zn, rn, rn, &back, &e), 0);
  assert_memory_equal(raw, back, rn);
  assert_int_equal(pc_wire_film_load(z, zn, &b, &e), 0);
  assert_true(traces_equal(&a, &b));
  /* merging the same iterations again is refused, b unchanged */
  assert_int_equal(pc_wire_film_add_z(z, zn, &b, NULL, NULL, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "traced already"));
  assert_true(traces_equal(&a, &b) && b.layers[0].count == PC_TRACE_ITERATIONS);
  /* the judge sees them, in order; its refusal leaves c without a trace */
  seen_trace seen = {0};
  assert_int_equal(pc_wire_film_add_z(z, zn, &c, record_trace, &seen, &e), PC_EINVAL);
  assert_true(seen.n == PC_TRACE_ITERATIONS && seen.first == PC_TRACE_ITERATIONS - 1 && seen.last == 0);
  assert_true(c.trace.n == 0 && c.layers[0].count == 0);
  assert_int_equal(pc_wire_film_add_z(z, zn, &c, NULL, NULL, &e), 0);
  assert_true(traces_equal(&a, &c));
  /* broken records, in the raw bytes: each refuses the whole add */
  size_t rs = 4 + 4 * (size_t)nb, last = rn - rs;
  uint8_t keep[4];
  memcpy(keep, raw + last, 4);
  uint32_t bad_it = PC_TRACE_ITERATIONS; /* past the bound */
  memcpy(raw + last, &bad_it, 4);
  pc_film_clear(&c);
  assert_int_equal(pc_wire_film_add(raw, rn, &c, NULL, NULL, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "only the first"));
  memcpy(raw + last, raw + last - rs, 4); /* the iteration before it, twice */
  assert_int_equal(pc_wire_film_add(raw, rn, &c, NULL, NULL, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "traced twice"));
  memcpy(raw + last, keep, 4);
  float nan = 0.0f / 0.0f;
  memcpy(raw + last + 4 + 4 * 7, &nan, 4);
  assert_int_equal(pc_wire_film_add(raw, rn, &c, NULL, NULL, &e), PC_ENUMERIC);
  assert_true(c.trace.n == 0 && c.layers[0].count == 0);
  free(z); free(raw); free(back);
  free_film(&a); free_film(&b); free_film(&c);
}

/* Several byte-plane blocks and a short last one: every value comes back bit for bit. */
static void film_blocks(void **st) {
  (void)st;
  pc_film a, b;
  make_film(&a, 50, 50); /* 7500 values a layer: 3 blocks of 2048 and one of 1356 */
  make_film(&b, 50, 50);
  for (int l = 0; l < 2; l++)
    for (int i = 0; i < 7500; i++) a.layers[l].sum[i] = (l ? -1.0 : 1.0) * (double)i * 1.000001 / 7.0 + 1e-300 * i;
  uint8_t *buf;
  size_t n;
  pc_err e;
  assert_int_equal(pc_wire_film_pack(&a, &buf, &n, &e), 0);
  assert_int_equal(pc_wire_film_unpack(buf, n, &b, &e), 0);
  assert_memory_equal(a.layers[0].sum, b.layers[0].sum, 7500 * sizeof(double));
  assert_memory_equal(a.layers[1].sum, b.layers[1].sum, 7500 * sizeof(double));
  assert_int_equal(pc_wire_film_add(buf, n, &b, NULL, NULL, &e), 0);
  assert_true(b.layers[1].sum[7499] == 2 * a.layers[1].sum[7499] && b.layers[0].sum[4100] == 2 * a.layers[0].sum[4100]);
  free(buf);
  free_film(&a); free_film(&b);
}

/* A checkpoint of a coordinator from before beauty_sq and beauty_max (two layers short), or
 * before beauty_max alone (one short), loads with the missing layers empty, so the job says it
 * cannot tell its error or its largest iterations; an upload short of a layer is refused. */
static void film_without_per_iteration(void **st) {
  (void)st;
  pc_err e = {0};
  pc_film old, now;
  assert_int_equal(pc_film_init(&now, 3, 2, 0, &e), 0);
  int q = pc_film_square_layer(&now), mx = pc_film_max_layer(&now);
  assert_int_equal(q, now.nlayers - 2);
  assert_int_equal(mx, now.nlayers - 1);
  for (int missing = 2; missing >= 1; missing--) {
    assert_int_equal(pc_film_init(&old, 3, 2, 0, &e), 0);
    for (int l = old.nlayers - missing; l < old.nlayers; l++) free(old.layers[l].sum);
    old.nlayers -= missing; /* the old coordinator's film: the same layers but the last */
    for (int l = 0; l < old.nlayers; l++) {
      old.layers[l].count = l == PC_LAYER_LT ? 30 : 5;
      for (int i = 0; i < 18; i++) old.layers[l].sum[i] = l + 0.25 * i;
    }
    for (int i = 0; i < 18; i++) now.layers[q].sum[i] = now.layers[mx].sum[i] = 9.0;
    now.layers[q].count = now.layers[mx].count = 4;
    uint8_t *raw, *z;
    size_t n, zn;
    assert_int_equal(pc_wire_film_pack(&old, &raw, &n, &e), 0);
    assert_true(n < pc_wire_film_size(&now));
    assert_int_not_equal(pc_wire_film_add(raw, n, &now, NULL, NULL, &e), 0);
    assert_int_equal(now.layers[q].count, 4);
    assert_int_equal(pc_wire_compress(raw, n, &z, &zn, &e), 0);
    assert_int_equal(pc_wire_film_load(z, zn, &now, &e), 0);
    assert_int_equal(now.layers[PC_LAYER_LT].count, 30);
    assert_true(now.layers[PC_LAYER_INNER].sum[17] == 3 + 0.25 * 17);
    assert_int_equal(now.layers[q].count, missing == 2 ? 0 : 5);
    assert_true(now.layers[q].sum[5] == (missing == 2 ? 0.0 : q + 0.25 * 5));
    assert_int_equal(now.layers[mx].count, 0);
    assert_true(now.layers[mx].sum[5] == 0.0);
    assert_false(pc_film_max_complete(&now));
    double est;
    assert_int_equal(pc_film_relmse_estimate(&now, &est), missing == 1);
    free(raw);
    free(z);
    pc_film_free(&old);
  }
  /* a film three layers short is no checkpoint of this job */
  assert_int_equal(pc_film_init(&old, 3, 2, 0, &e), 0);
  for (int l = old.nlayers - 3; l < old.nlayers; l++) free(old.layers[l].sum);
  old.nlayers -= 3;
  uint8_t *raw, *z;
  size_t n, zn;
  assert_int_equal(pc_wire_film_pack(&old, &raw, &n, &e), 0);
  assert_int_equal(pc_wire_compress(raw, n, &z, &zn, &e), 0);
  assert_int_equal(pc_wire_film_load(z, zn, &now, &e), PC_EINVAL);
  free(raw);
  free(z);
  pc_film_free(&old);
  pc_film_free(&now);
}

/* The checkpoint round trip keeps beauty_sq and beauty_max bit for bit; uploads merge
 * beauty_max by max, in either order, and everything else by sum. */
static void film_max_roundtrip(void **st) {
  (void)st;
  pc_err e = {0};
  pc_film a, b, ab, ba, back;
  assert_int_equal(pc_film_init(&a, 50, 50, 0, &e), 0);
  assert_int_equal(pc_film_init(&b, 50, 50, 0, &e), 0);
  int q = pc_film_square_layer(&a), mx = pc_film_max_layer(&a);
  for (int l = 0; l < a.nlayers; l++) {
    a.layers[l].count = l == PC_LAYER_LT ? 6 : 3;
    b.layers[l].count = l == PC_LAYER_LT ? 10 : 5;
  }
  for (int i = 0; i < 7500; i++) {
    a.layers[PC_LAYER_PT].sum[i] = i / 7.0;
    b.layers[PC_LAYER_PT].sum[i] = i / 3.0;
    a.layers[q].sum[i] = (double)(float)(i / 5.0);
    a.layers[mx].sum[i] = (double)(float)((i * 37 % 101) / 9.0);
    b.layers[mx].sum[i] = (double)(float)((i * 53 % 103) / 9.0);
  }
  uint8_t *za, *zb;
  size_t zan, zbn;
  assert_int_equal(pc_wire_film_zip(&a, 1, &za, &zan, &e), 0);
  assert_int_equal(pc_wire_film_zip(&b, 1, &zb, &zbn, &e), 0);
  assert_int_equal(pc_film_init(&ab, 50, 50, 0, &e), 0);
  assert_int_equal(pc_film_init(&ba, 50, 50, 0, &e), 0);
  assert_int_equal(pc_film_init(&back, 50, 50, 0, &e), 0);
  assert_int_equal(pc_wire_film_add_z(za, zan, &ab, NULL, NULL, &e), 0);
  assert_int_equal(pc_wire_film_add_z(zb, zbn, &ab, NULL, NULL, &e), 0);
  assert_int_equal(pc_wire_film_add_z(zb, zbn, &ba, NULL, NULL, &e), 0);
  assert_int_equal(pc_wire_film_add_z(za, zan, &ba, NULL, NULL, &e), 0);
  assert_memory_equal(ab.layers[mx].sum, ba.layers[mx].sum, 7500 * sizeof(double));
  for (int i = 0; i < 7500; i++) {
    assert_true(ab.layers[mx].sum[i] == fmax(a.layers[mx].sum[i], b.layers[mx].sum[i]));
    assert_true(ab.layers[PC_LAYER_PT].sum[i] == a.layers[PC_LAYER_PT].sum[i] + b.layers[PC_LAYER_PT].sum[i]);
  }
  assert_int_equal(ab.layers[mx].count, 8);
  assert_true(pc_film_max_complete(&ab));
  /* a checkpoint of the merged film loads back whole */
  uint8_t *zc;
  size_t zcn;
  assert_int_equal(pc_wire_film_zip(&ab, 1, &zc, &zcn, &e), 0);
  assert_int_equal(pc_wire_film_load(zc, zcn, &back, &e), 0);
  for (int l = 0; l < ab.nlayers; l++) {
    assert_int_equal(back.layers[l].count, ab.layers[l].count);
    assert_memory_equal(back.layers[l].sum, ab.layers[l].sum, 7500 * sizeof(double));
  }
  /* and a worker's further upload merges into it by max */
  assert_int_equal(pc_wire_film_add_z(za, zan, &back, NULL, NULL, &e), 0);
  assert_memory_equal(back.layers[mx].sum, ab.layers[mx].sum, 7500 * sizeof(double));
  assert_int_equal(back.layers[mx].count, 11);
  free(za);
  free(zb);
  free(zc);
  pc_film_free(&a);
  pc_film_free(&b);
  pc_film_free(&ab);
  pc_film_free(&ba);
  pc_film_free(&back);
}

/* A delta's sums are bounded per sample of their layer (2^64 each): 1.7e308 in one sample is
 * refused, even though finite (two such add to +inf); a sum near the bound for its count is
 * taken; a checkpoint (unpack) is only checked for finiteness. (Issue 10, failure 6.) */
static void film_bounds(void **st) {
  (void)st;
  pc_film a, b;
  make_film(&a, 50, 50);
  make_film(&b, 50, 50);
  a.layers[0].count = 1;
  a.layers[1].count = 1000;
  a.layers[0].sum[4100] = 1.7e308;
  uint8_t *buf;
  size_t n;
  pc_err e;
  assert_int_equal(pc_wire_film_pack(&a, &buf, &n, &e), 0);
  assert_int_equal(pc_wire_film_add(buf, n, &b, NULL, NULL, &e), PC_ENUMERIC);
  assert_non_null(strstr(e.msg, "beyond any radiance for 1 samples"));
  assert_true(b.layers[0].sum[4100] == 0 && b.layers[0].count == 0);
  assert_int_equal(pc_wire_film_unpack(buf, n, &b, &e), 0);
  free(buf);
  a.layers[0].sum[4100] = 1.5e19;   /* < 2^64 for 1 sample */
  a.layers[1].sum[7499] = -1.5e22;  /* < 1000 * 2^64 */
  assert_int_equal(pc_wire_film_pack(&a, &buf, &n, &e), 0);
  free_film(&b);
  make_film(&b, 50, 50);
  assert_int_equal(pc_wire_film_add(buf, n, &b, NULL, NULL, &e), 0);
  free(buf);
  a.layers[1].sum[7499] = -1e30;    /* > 1024 * 2^64 */
  assert_int_equal(pc_wire_film_pack(&a, &buf, &n, &e), 0);
  assert_int_equal(pc_wire_film_add(buf, n, &b, NULL, NULL, &e), PC_ENUMERIC);
  assert_non_null(strstr(e.msg, "layer 1 at pixel 2499"));
  free(buf);
  free_film(&a); free_film(&b);
  /* beauty_sq's samples are squares: bounded by 2^128 per iteration, not 2^64 */
  pc_film c, d;
  assert_int_equal(pc_film_init(&c, 4, 4, 0, &e), 0);
  assert_int_equal(pc_film_init(&d, 4, 4, 0, &e), 0);
  int q = pc_film_square_layer(&c);
  for (int l = 0; l < c.nlayers; l++) c.layers[l].count = 1;
  c.layers[PC_LAYER_PT].sum[3] = 1e19;
  c.layers[q].sum[3] = 1e38;
  assert_int_equal(pc_wire_film_pack(&c, &buf, &n, &e), 0);
  assert_int_equal(pc_wire_film_add(buf, n, &d, NULL, NULL, &e), 0);
  free(buf);
  c.layers[q].sum[3] = 1e39;
  assert_int_equal(pc_wire_film_pack(&c, &buf, &n, &e), 0);
  assert_int_equal(pc_wire_film_add(buf, n, &d, NULL, NULL, &e), PC_ENUMERIC);
  free(buf);
  pc_film_free(&c);
  pc_film_free(&d);
}

/* The MIS mode and count reach a worker as the client set them; a count out of range or an
 * unknown mode is refused there, not rendered. */
static void settings_mis_roundtrip(void **st) {
  (void)st;
  pc_render_settings s, back;
  pc_render_settings_default(&s);
  s.method = PC_METHOD_PCBPT;
  s.mis_mode = PC_MIS_COUNT;
  s.mis_count = 3.5f;
  Pcbpt__Settings p;
  pc_wire_settings_buf buf;
  pc_err e = {0};
  pc_wire_settings_to_proto(&s, &p, &buf);
  assert_int_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
  assert_int_equal(back.mis_mode, PC_MIS_COUNT);
  assert_true(back.mis_count == 3.5f);
  s.mis_mode = PC_MIS_STANDARD;
  pc_wire_settings_to_proto(&s, &p, &buf);
  assert_int_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
  assert_int_equal(back.mis_mode, PC_MIS_STANDARD);
  p.mis_mode = PC_MIS_COUNT;
  p.mis_count = 0.5f;
  assert_int_not_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
  p.mis_count = 2.f;
  p.mis_mode = PC_MIS_COUNT + 1;
  assert_int_not_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
}

/* The connection rates (--pcbpt-rate, --pcbpt-unseen-rate) reach a worker as set; 0 (settings
 * from before the field) reads as 1, and a rate outside (0, 1] is refused. */
static void settings_rate_roundtrip(void **st) {
  (void)st;
  for (int unseen = 0; unseen < 2; unseen++) {
    pc_render_settings s, back;
    pc_render_settings_default(&s);
    s.method = PC_METHOD_PCBPT;
    *(unseen ? &s.pcbpt_unseen_rate : &s.pcbpt_rate) = 0.25f;
    Pcbpt__Settings p;
    pc_wire_settings_buf buf;
    pc_err e = {0};
    pc_wire_settings_to_proto(&s, &p, &buf);
    float *wire = unseen ? &p.pcbpt_unseen_rate : &p.pcbpt_rate;
    const float *got = unseen ? &back.pcbpt_unseen_rate : &back.pcbpt_rate;
    assert_int_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
    assert_true(*got == 0.25f);
    *wire = 0.f;
    assert_int_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
    assert_true(*got == 1.f);
    const float bad[] = {1.5f, -0.5f, NAN};
    for (int i = 0; i < 3; i++) {
      *wire = bad[i];
      assert_int_not_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
    }
  }
}

/* The dark-vertex rule (--pcbpt-dark-seen, --pcbpt-dark-candidates, --pcbpt-dark-mix) reaches
 * a worker as set. Settings from before the fields (all 0) render as they did, with no dark
 * vertex; a 0 count or mix reads as the default; values out of range are refused. */
static void settings_dark_roundtrip(void **st) {
  (void)st;
  pc_render_settings s, back, def;
  pc_render_settings_default(&s);
  pc_render_settings_default(&def);
  s.method = PC_METHOD_PCBPT;
  s.pcbpt_dark_seen = 0.25f;
  s.pcbpt_dark_candidates = 5;
  s.pcbpt_dark_mix = 0.7f;
  Pcbpt__Settings p;
  pc_wire_settings_buf buf;
  pc_err e = {0};
  pc_wire_settings_to_proto(&s, &p, &buf);
  assert_int_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
  assert_true(back.pcbpt_dark_seen == 0.25f && back.pcbpt_dark_candidates == 5 && back.pcbpt_dark_mix == 0.7f);
  p.pcbpt_dark_seen = 0.f;
  p.pcbpt_dark_candidates = 0;
  p.pcbpt_dark_mix = 0.f;
  assert_int_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
  assert_true(back.pcbpt_dark_seen == 0.f);
  assert_true(back.pcbpt_dark_candidates == def.pcbpt_dark_candidates && back.pcbpt_dark_mix == def.pcbpt_dark_mix);
  const float bad_seen[] = {1.5f, -0.5f, NAN}, bad_mix[] = {1.5f, -0.5f, NAN};
  const uint32_t bad_count[] = {PC_IREC_MAX_CANDIDATES + 1, 1025, UINT32_MAX};
  for (int i = 0; i < 3; i++) {
    pc_wire_settings_to_proto(&s, &p, &buf);
    p.pcbpt_dark_seen = bad_seen[i];
    assert_int_not_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
    pc_wire_settings_to_proto(&s, &p, &buf);
    p.pcbpt_dark_mix = bad_mix[i];
    assert_int_not_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
    pc_wire_settings_to_proto(&s, &p, &buf);
    p.pcbpt_dark_candidates = bad_count[i];
    assert_int_not_equal(pc_wire_settings_from_proto(&p, &back, &e), 0);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(byte_by_byte), cmocka_unit_test(whole_buffer), cmocka_unit_test(refusals),
    cmocka_unit_test(film_roundtrip), cmocka_unit_test(film_v1_and_add), cmocka_unit_test(film_trace_travels), cmocka_unit_test(film_blocks),
    cmocka_unit_test(film_without_per_iteration), cmocka_unit_test(film_max_roundtrip), cmocka_unit_test(film_bounds), cmocka_unit_test(film_streamed),
    cmocka_unit_test(settings_mis_roundtrip), cmocka_unit_test(settings_rate_roundtrip),
    cmocka_unit_test(settings_dark_roundtrip),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
