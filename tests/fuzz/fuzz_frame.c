/* fuzz_frame.c: libFuzzer target for the frame decoder: arbitrary bytes, fed in arbitrary
 * splits, must never crash or leak; decoded envelopes are freed. The first byte also picks
 * clear frames or sealed ones (a fixed key: the fuzzer reaches the length checks and the tag
 * refusal, not the plaintext parser, which the clear mode covers). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "wire_frame.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  pc_wire_decoder d;
  pc_wire_decoder_init(&d, 1 << 16);
  if (size && data[0] & 0x80) {
    uint8_t key[PC_AUTH_KEY], cn[PC_AUTH_NONCE], sn[PC_AUTH_NONCE];
    pc_seal_dir tx;
    memset(key, 1, sizeof key);
    memset(cn, 2, sizeof cn);
    memset(sn, 3, sizeof sn);
    if (pc_auth_init(NULL) != 0 || pc_seal_derive(key, true, cn, sn, &tx, &d.open, NULL) != 0) return 0;
  }
  size_t off = 0, step = size ? (size_t)data[0] % 7 + 1 : 1;
  while (off < size) {
    size_t n = size - off < step ? size - off : step, used = 0;
    Pcbpt__Envelope *env = NULL;
    pc_err e;
    int r = pc_wire_decoder_push(&d, data + off, n, &used, &env, &e);
    if (r < 0) break;
    if (r == 1) pcbpt__envelope__free_unpacked(env, NULL);
    off += used;
  }
  pc_wire_decoder_free(&d);
  return 0;
}
