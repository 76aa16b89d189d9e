/* fuzz_film.c: libFuzzer target for the film decoder that every upload and checkpoint goes
 * through (wire_film.h): whatever the bytes, no crash, no leak, and a refused film leaves the
 * target film exactly as it was (sums, counts, dropped samples and trace). The first byte picks
 * the mode:
 *   raw      the rest is the serialized film;
 *   edited   the rest is a list of (offset, value) edits, 3 bytes each, applied to a valid
 *            serialized film with a trace (so the fuzzer reaches every check past the header
 *            without having to find a header first), and the last byte's low bits cut or
 *            extend it;
 *   zstd     the edited film, compressed, through the streamed decoder (pc_wire_film_add_z,
 *            pc_wire_film_load).
 * The target film already traces one of the valid film's iterations in half the runs, so the
 * refusal of an iteration traced twice is reached too. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "wire_film.h"

enum { RAW, EDITED, ZSTD, NMODES };
enum { W = 9, H = 7, TRACED = 5 };

static uint8_t *valid;
static size_t nvalid;

/* A film of 3 iterations with a few non-zero sums and 5 traced iterations, serialized. */
static void make_valid(void) {
  pc_film f;
  pc_err e;
  if (pc_film_init(&f, W, H, 1, &e)) abort();
  for (int l = 0; l < f.nlayers; l++) {
    f.layers[l].count = f.layers[l].norm == PC_NORM_LIGHT ? 3 * W * H : 3;
    for (int k = 0; k < 3 * W * H; k += 7) f.layers[l].sum[k] = 0.25 * (k + l);
  }
  int nb = pc_trace_blocks(W, H);
  float block[PC_TRACE_MAX_BLOCKS];
  for (int k = 0; k < nb; k++) block[k] = 0.5f * (float)k;
  if (pc_trace_reserve(&f.trace, TRACED, nb, &e)) abort();
  for (uint32_t i = 0; i < TRACED; i++) pc_trace_put(&f.trace, nb, 10 + 3 * i, block);
  if (pc_wire_film_pack(&f, &valid, &nvalid, &e)) abort();
  pc_film_free(&f);
}

/* What a refused add must leave as it was. */
static bool same(const pc_film *a, const pc_film *b) {
  if (a->dropped_nonfinite != b->dropped_nonfinite || a->trace.n != b->trace.n) return false;
  for (int l = 0; l < a->nlayers; l++)
    if (a->layers[l].count != b->layers[l].count ||
        memcmp(a->layers[l].sum, b->layers[l].sum, sizeof(double) * 3 * W * H) != 0)
      return false;
  int nb = pc_trace_blocks(W, H);
  return a->trace.n == 0 || (memcmp(a->trace.iteration, b->trace.iteration, a->trace.n * sizeof(uint32_t)) == 0 &&
                             memcmp(a->trace.block, b->trace.block, a->trace.n * (size_t)nb * sizeof(float)) == 0);
}

static void target(pc_film *into, bool preset) {
  pc_err e;
  if (pc_film_init(into, W, H, 1, &e)) abort();
  into->layers[0].sum[4] = 1.5;
  into->layers[0].count = 1;
  if (preset) {
    int nb = pc_trace_blocks(W, H);
    float block[PC_TRACE_MAX_BLOCKS] = {0};
    if (pc_trace_reserve(&into->trace, 1, nb, &e)) abort();
    pc_trace_put(&into->trace, nb, 13, block); /* one of the valid film's */
  }
}

/* Adds buf into a fresh target and checks a refusal changed nothing; then sets another. */
static void decode(const uint8_t *buf, size_t n, bool z, bool preset) {
  pc_film into, before, set;
  target(&into, preset);
  target(&before, preset);
  pc_err e;
  int rc = z ? pc_wire_film_add_z(buf, n, &into, NULL, NULL, &e) : pc_wire_film_add(buf, n, &into, NULL, NULL, &e);
  if (rc && !same(&into, &before)) abort();
  target(&set, false);
  rc = z ? pc_wire_film_load(buf, n, &set, &e) : pc_wire_film_unpack(buf, n, &set, &e);
  (void)rc;
  pc_film_free(&into);
  pc_film_free(&before);
  pc_film_free(&set);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (!valid) make_valid();
  if (size < 1) return 0;
  int mode = data[0] % NMODES;
  bool preset = data[0] / NMODES % 2;
  data++, size--;
  if (mode == RAW) {
    decode(data, size, false, preset);
    return 0;
  }
  /* the last byte, when there is one past the edits, cuts or extends the film by up to 15 */
  int resize = size % 3 ? (int)(data[size - 1] & 31) - 15 : 0;
  size_t n = nvalid + (resize > 0 ? (size_t)resize : 0);
  if (resize < 0) n = nvalid - (size_t)-resize;
  uint8_t *buf = calloc(n, 1);
  if (!buf) return 0;
  memcpy(buf, valid, n < nvalid ? n : nvalid);
  for (size_t i = 0; i + 3 <= size; i += 3) buf[((size_t)data[i] << 8 | data[i + 1]) % n] = data[i + 2];
  if (mode == EDITED) {
    decode(buf, n, false, preset);
  } else {
    uint8_t *z;
    size_t zn;
    pc_err e;
    if (!pc_wire_compress(buf, n, &z, &zn, &e)) {
      decode(z, zn, true, preset);
      free(z);
    }
  }
  free(buf);
  return 0;
}
