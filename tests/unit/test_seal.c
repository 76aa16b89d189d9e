/* test_seal.c: sealed frames (wire_seal.h) through the frame decoder: round trips in both
 * directions and in any split, no plaintext on the wire, and refusal of a tampered byte anywhere
 * in the frame, a replayed, reordered or dropped frame, a frame keyed for the other direction,
 * another connection or another token, and the size limits with the tag's overhead. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "wire_frame.h"
#include "wire_seal.h"

typedef struct pair { pc_seal_dir ctx, crx, stx, srx; } pair;

static void keyed(pair *p, uint8_t token_byte, uint8_t nonce_byte) {
  uint8_t key[PC_AUTH_KEY], cn[PC_AUTH_NONCE], sn[PC_AUTH_NONCE];
  memset(key, token_byte, sizeof key);
  memset(cn, nonce_byte, sizeof cn);
  memset(sn, (uint8_t)(nonce_byte + 1), sizeof sn);
  pc_err e;
  assert_int_equal(pc_seal_derive(key, false, cn, sn, &p->ctx, &p->crx, &e), 0);
  assert_int_equal(pc_seal_derive(key, true, cn, sn, &p->stx, &p->srx, &e), 0);
}

static const char SECRET[] = "an-unpublished-scene-name-0123456789";

/* A sealed upload chunk whose data is SECRET repeated to `len` bytes, with its index. */
static void sealed_chunk(pc_seal_dir *tx, uint32_t index, size_t len, uint8_t **b, size_t *n) {
  uint8_t *data = malloc(len);
  for (size_t i = 0; i < len; i++) data[i] = (uint8_t)SECRET[i % (sizeof SECRET - 1)];
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__UploadChunk u = PCBPT__UPLOAD_CHUNK__INIT;
  u.index = index;
  u.data.data = data;
  u.data.len = len;
  env.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK;
  env.upload_chunk = &u;
  pc_err e;
  assert_int_equal(pc_wire_encode(&env, b, n, &e), 0);
  size_t plain = *n;
  assert_int_equal(pc_seal_frame(tx, *b, n, &e), 0);
  assert_int_equal(*n, plain + PC_SEAL_TAG);
  free(data);
}

/* Feeds b[0..n) in steps of `step` bytes; returns the decoder's first negative code, or the
 * number of frames decoded, checking each is upload chunk `*next_index` (then incremented). */
static int feed(pc_wire_decoder *d, const uint8_t *b, size_t n, size_t step, uint32_t *next_index, pc_err *e) {
  int frames = 0;
  size_t off = 0;
  while (off < n) {
    size_t k = n - off < step ? n - off : step, used;
    Pcbpt__Envelope *env;
    int r = pc_wire_decoder_push(d, b + off, k, &used, &env, e);
    if (r < 0) return r;
    off += used;
    if (r == 1) {
      assert_int_equal(env->msg_case, PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK);
      assert_int_equal(env->upload_chunk->index, *next_index);
      size_t k = env->upload_chunk->data.len < 8 ? env->upload_chunk->data.len : 8;
      assert_memory_equal(env->upload_chunk->data.data, SECRET, k);
      (*next_index)++;
      pcbpt__envelope__free_unpacked(env, NULL);
      frames++;
    }
  }
  return frames;
}

static void decoder_with(pc_wire_decoder *d, const pc_seal_dir *rx) {
  pc_wire_decoder_init(d, 0);
  d->open = *rx;
}

static void round_trip(void **st) {
  (void)st;
  pair p;
  keyed(&p, 7, 1);
  pc_wire_decoder srv, cli;
  decoder_with(&srv, &p.srx);
  decoder_with(&cli, &p.crx);
  uint32_t sidx = 0, cidx = 0;
  pc_err e;
  for (uint32_t i = 0; i < 20; i++) {
    uint8_t *b;
    size_t n;
    /* client to server, in odd splits, a frame's size growing to a few chunks' worth */
    sealed_chunk(&p.ctx, i, 1 + (size_t)i * 7919, &b, &n);
    assert_null(memmem(b, n, SECRET, 16)); /* nothing of the plaintext is on the wire */
    assert_int_equal(feed(&srv, b, n, 1 + i * 13, &sidx, &e), 1);
    free(b);
    sealed_chunk(&p.stx, i, 100, &b, &n);
    assert_int_equal(feed(&cli, b, n, n, &cidx, &e), 1);
    free(b);
  }
  assert_int_equal(p.ctx.counter, 20);
  assert_int_equal(srv.open.counter, 20);
  pc_wire_decoder_free(&srv);
  pc_wire_decoder_free(&cli);
  assert_false(srv.open.on);
}

static void tampered_byte(void **st) {
  (void)st;
  uint8_t *b;
  size_t n;
  pair p;
  keyed(&p, 7, 1);
  sealed_chunk(&p.ctx, 0, 300, &b, &n);
  /* every byte after the length prefix, and the prefix's low byte (the frame is then shorter,
   * or waits for more bytes than arrive) */
  for (size_t i = 3; i < n; i++) {
    uint8_t *t = malloc(n);
    memcpy(t, b, n);
    t[i] ^= (uint8_t)(1u << (i % 8));
    pc_wire_decoder d;
    decoder_with(&d, &p.srx);
    uint32_t idx = 0;
    pc_err e;
    int r = feed(&d, t, n, n, &idx, &e);
    assert_true(r <= 0);
    if (i >= 4) {
      assert_int_equal(r, PC_EPARSE);
      assert_non_null(strstr(e.msg, "does not authenticate"));
    }
    pc_wire_decoder_free(&d);
    free(t);
  }
  free(b);
}

static void replayed_reordered_dropped(void **st) {
  (void)st;
  pair p;
  keyed(&p, 7, 1);
  uint8_t *f[3];
  size_t n[3];
  for (uint32_t i = 0; i < 3; i++) sealed_chunk(&p.ctx, i, 64, &f[i], &n[i]);
  pc_err e;
  uint32_t idx = 0;
  pc_wire_decoder d;
  /* replay: frame 0 twice */
  decoder_with(&d, &p.srx);
  assert_int_equal(feed(&d, f[0], n[0], n[0], &idx, &e), 1);
  assert_int_equal(feed(&d, f[0], n[0], n[0], &idx, &e), PC_EPARSE);
  pc_wire_decoder_free(&d);
  /* reorder: frame 1 before frame 0 */
  decoder_with(&d, &p.srx);
  idx = 1;
  assert_int_equal(feed(&d, f[1], n[1], n[1], &idx, &e), PC_EPARSE);
  pc_wire_decoder_free(&d);
  /* drop: frame 0, then frame 2 */
  decoder_with(&d, &p.srx);
  idx = 0;
  assert_int_equal(feed(&d, f[0], n[0], n[0], &idx, &e), 1);
  assert_int_equal(feed(&d, f[2], n[2], n[2], &idx, &e), PC_EPARSE);
  pc_wire_decoder_free(&d);
  /* a clear decoder sees only noise: the sealed payload is not a valid envelope of chunk 0 */
  pc_wire_decoder_init(&d, 0);
  Pcbpt__Envelope *env = NULL;
  size_t used;
  int r = pc_wire_decoder_push(&d, f[0], n[0], &used, &env, &e);
  if (r == 1) {
    assert_false(env->msg_case == PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK && env->upload_chunk->data.len == 64);
    pcbpt__envelope__free_unpacked(env, NULL);
  }
  pc_wire_decoder_free(&d);
  for (int i = 0; i < 3; i++) free(f[i]);
}

static void wrong_keys(void **st) {
  (void)st;
  pair p, other_conn, other_token;
  keyed(&p, 7, 1);
  keyed(&other_conn, 7, 3);
  keyed(&other_token, 8, 1);
  uint8_t *b;
  size_t n;
  sealed_chunk(&p.ctx, 0, 64, &b, &n);
  const pc_seal_dir *wrong[] = {&p.crx /* reflected back to its sender */, &other_conn.srx, &other_token.srx};
  for (int i = 0; i < 3; i++) {
    pc_wire_decoder d;
    decoder_with(&d, wrong[i]);
    uint32_t idx = 0;
    pc_err e;
    assert_int_equal(feed(&d, b, n, n, &idx, &e), PC_EPARSE);
    pc_wire_decoder_free(&d);
  }
  /* the right key still opens it */
  pc_wire_decoder d;
  decoder_with(&d, &p.srx);
  uint32_t idx = 0;
  pc_err e;
  assert_int_equal(feed(&d, b, n, n, &idx, &e), 1);
  pc_wire_decoder_free(&d);
  free(b);
}

static void limits(void **st) {
  (void)st;
  pair p;
  keyed(&p, 7, 1);
  pc_err e;
  pc_wire_decoder d;
  size_t used;
  Pcbpt__Envelope *env;
  /* a frame whose plaintext is exactly PC_WIRE_MAX_FRAME bytes passes sealed */
  size_t data = PC_WIRE_MAX_FRAME - 16;
  uint8_t *b;
  size_t n;
  for (;;) {
    sealed_chunk(&p.ctx, 0, data, &b, &n);
    if (n - 4 - PC_SEAL_TAG == PC_WIRE_MAX_FRAME) break;
    assert_true(n - 4 - PC_SEAL_TAG < PC_WIRE_MAX_FRAME);
    free(b);
    p.ctx.counter--;
    data++;
  }
  decoder_with(&d, &p.srx);
  uint32_t idx = 0;
  assert_int_equal(feed(&d, b, n, 65536, &idx, &e), 1);
  pc_wire_decoder_free(&d);
  free(b);
  /* one byte more than the limit plus the tag is refused before any allocation */
  uint32_t over = PC_WIRE_MAX_FRAME + PC_SEAL_TAG + 1;
  uint8_t hdr[4] = {(uint8_t)(over >> 24), (uint8_t)(over >> 16), (uint8_t)(over >> 8), (uint8_t)over};
  decoder_with(&d, &p.srx);
  assert_int_equal(pc_wire_decoder_push(&d, hdr, 4, &used, &env, &e), PC_ELIMIT);
  pc_wire_decoder_free(&d);
  /* a sealed frame with no room for a tag */
  uint8_t tiny[4 + PC_SEAL_TAG] = {0, 0, 0, PC_SEAL_TAG};
  decoder_with(&d, &p.srx);
  assert_int_equal(pc_wire_decoder_push(&d, tiny, sizeof tiny, &used, &env, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "too short"));
  pc_wire_decoder_free(&d);
  /* the encoder refuses a plaintext over the limit, so no sealed frame can exceed it */
  Pcbpt__Envelope big = PCBPT__ENVELOPE__INIT;
  Pcbpt__UploadChunk u = PCBPT__UPLOAD_CHUNK__INIT;
  u.data.data = calloc(1, PC_WIRE_MAX_FRAME);
  u.data.len = PC_WIRE_MAX_FRAME;
  big.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK;
  big.upload_chunk = &u;
  assert_int_equal(pc_wire_encode(&big, &b, &n, &e), PC_ELIMIT);
  free(u.data.data);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(round_trip), cmocka_unit_test(tampered_byte), cmocka_unit_test(replayed_reordered_dropped),
    cmocka_unit_test(wrong_keys), cmocka_unit_test(limits),
  };
  if (pc_auth_init(NULL) != 0) return 1;
  return cmocka_run_group_tests(tests, NULL, NULL);
}
