/* fuzz_frame.c: libFuzzer target for the frame decoder: arbitrary bytes, fed in arbitrary
 * splits, must never crash or leak; decoded envelopes are freed. The first byte picks the mode:
 *   clear   the bytes are the stream, as before the handshake ends;
 *   forged  the same bytes reach a decoder that opens sealed frames (a fixed key): the length
 *           checks and the refusal of frames whose tag does not authenticate;
 *   sealed  the bytes are read as (2-byte length, payload) records that the target seals with
 *           the matching sending key before the decoder sees them, so the fuzzer reaches
 *           opening, the counter's progress and the protobuf parser behind it with authentic
 *           frames. Authentic frames must always open; a third of the time one byte of the
 *           sealed stream is flipped, and then no frame from the flipped one on may decode. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "wire_frame.h"

enum { CLEAR, FORGED, SEALED };

/* Seals each record of in[0..n) as one frame; returns the malloc'd stream and its length, and
 * in ends[] (room for n / 2 entries) the offset just past each frame. */
static uint8_t *seal_records(pc_seal_dir *tx, const uint8_t *in, size_t n, size_t *out_len, size_t *ends,
                             size_t *frames) {
  uint8_t *out = malloc(n / 2 * (4 + PC_SEAL_TAG) + n + 1);
  size_t o = 0;
  *frames = 0;
  if (!out) return NULL;
  while (n >= 2) {
    size_t len = (size_t)in[0] << 8 | in[1];
    in += 2, n -= 2;
    if (len > n) len = n;
    uint8_t *f = out + o;
    f[0] = f[1] = 0, f[2] = (uint8_t)(len >> 8), f[3] = (uint8_t)len;
    memcpy(f + 4, in, len);
    size_t flen = 4 + len;
    pc_err e;
    if (pc_seal_frame(tx, f, &flen, &e) != 0) abort();
    o += flen;
    ends[(*frames)++] = o;
    in += len, n -= len;
  }
  *out_len = o;
  return out;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size == 0) return 0;
  int mode = data[0] % 3;
  size_t step = (size_t)data[0] / 3 % 7 + 1;
  pc_wire_decoder d;
  pc_wire_decoder_init(&d, 1 << 16);
  const uint8_t *stream = data + 1;
  size_t len = size - 1;
  uint8_t *sealed = NULL;
  size_t *ends = NULL, frames = 0, intact = SIZE_MAX, decoded = 0;
  bool flipped = false;
  if (mode != CLEAR) {
    uint8_t key[PC_AUTH_KEY], cn[PC_AUTH_NONCE], sn[PC_AUTH_NONCE];
    pc_seal_dir client_tx, client_rx, server_tx;
    memset(key, 1, sizeof key);
    memset(cn, 2, sizeof cn);
    memset(sn, 3, sizeof sn);
    if (pc_auth_init(NULL) != 0 || pc_seal_derive(key, false, cn, sn, &client_tx, &client_rx, NULL) != 0 ||
        pc_seal_derive(key, true, cn, sn, &server_tx, &d.open, NULL) != 0)
      abort();
    if (mode == SEALED) {
      if (!(ends = malloc((len / 2 + 1) * sizeof *ends)) ||
          !(sealed = seal_records(&client_tx, stream, len, &len, ends, &frames)))
        abort();
      if (len && data[0] % 9 >= 6) {
        size_t at = (size_t)data[len / 2 % size] * 131 % len;
        sealed[at] ^= 0x20;
        flipped = true;
        for (intact = 0; intact < frames && ends[intact] <= at; intact++) {}
      }
      stream = sealed;
    }
  }
  size_t off = 0;
  while (off < len) {
    size_t n = len - off < step ? len - off : step, used = 0;
    Pcbpt__Envelope *env = NULL;
    pc_err e;
    int r = pc_wire_decoder_push(&d, stream + off, n, &used, &env, &e);
    /* an authentic frame that does not open is a bug in sealing or in the decoder */
    if (r < 0 && mode == SEALED && !flipped && strstr(e.msg, "does not authenticate")) abort();
    if (r < 0) break;
    if (r == 1) {
      pcbpt__envelope__free_unpacked(env, NULL);
      if (++decoded > intact) abort(); /* a frame at or after the flipped byte was accepted */
    }
    off += used;
  }
  pc_wire_decoder_free(&d);
  free(sealed);
  free(ends);
  return 0;
}
