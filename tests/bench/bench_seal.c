/* bench_seal.c: benchmark (not a test) of the wire's sealing cost. Encodes 256 KiB upload
 * chunks (PC_WIRE_CHUNK, the size films and bundles travel in) and decodes them through the
 * frame decoder, once in the clear and once sealed (wire_seal.h), and prints the CPU time
 * (CLOCK_PROCESS_CPUTIME_ID, so other processes on the machine disturb it little) per MB of
 * payload for each, and the difference: the price of confidentiality per MB sent and received.
 * Usage: build/tests/bench_seal [MB]   (default 256) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "wire_frame.h"
#include "wire_seal.h"

static double cpu_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Encodes (and seals, when tx) then decodes (and opens, when d->open.on) `frames` chunks;
 * returns the CPU seconds of the sending and the receiving halves. */
static int run(size_t frames, uint8_t *data, pc_seal_dir *tx, pc_wire_decoder *d, double *send_s, double *recv_s) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__UploadChunk u = PCBPT__UPLOAD_CHUNK__INIT;
  u.data.data = data;
  u.data.len = PC_WIRE_CHUNK;
  env.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK;
  env.upload_chunk = &u;
  *send_s = *recv_s = 0;
  for (size_t i = 0; i < frames; i++) {
    pc_err e;
    uint8_t *b;
    size_t n, used;
    double t0 = cpu_s();
    u.index = (uint32_t)i;
    if (pc_wire_encode(&env, &b, &n, &e) != 0 || (tx && pc_seal_frame(tx, b, &n, &e) != 0)) {
      fprintf(stderr, "bench_seal: %s\n", e.msg);
      return 1;
    }
    double t1 = cpu_s();
    Pcbpt__Envelope *out = NULL;
    if (pc_wire_decoder_push(d, b, n, &used, &out, &e) != 1 || out->upload_chunk->index != i) {
      fprintf(stderr, "bench_seal: frame %zu did not decode: %s\n", i, e.msg);
      return 1;
    }
    pcbpt__envelope__free_unpacked(out, NULL);
    free(b);
    double t2 = cpu_s();
    *send_s += t1 - t0;
    *recv_s += t2 - t1;
  }
  return 0;
}

int main(int argc, char **argv) {
  long mb = argc > 1 ? strtol(argv[1], NULL, 10) : 256;
  if (mb < 1 || mb > 1 << 20) { fprintf(stderr, "usage: bench_seal [MB]\n"); return 2; }
  pc_err e;
  if (pc_auth_init(&e) != 0) { fprintf(stderr, "bench_seal: %s\n", e.msg); return 1; }
  size_t frames = (size_t)mb * (1u << 20) / PC_WIRE_CHUNK;
  uint8_t *data = malloc(PC_WIRE_CHUNK), key[PC_AUTH_KEY], cn[PC_AUTH_NONCE], sn[PC_AUTH_NONCE];
  if (!data) return 1;
  for (size_t i = 0; i < PC_WIRE_CHUNK; i++) data[i] = (uint8_t)(i * 2654435761u >> 13);
  pc_auth_nonce(key);
  pc_auth_nonce(cn);
  pc_auth_nonce(sn);
  pc_seal_dir ctx, crx, stx, srx;
  if (pc_seal_derive(key, false, cn, sn, &ctx, &crx, &e) != 0 || pc_seal_derive(key, true, cn, sn, &stx, &srx, &e) != 0) {
    fprintf(stderr, "bench_seal: %s\n", e.msg);
    return 1;
  }
  pc_wire_decoder clear, sealed;
  pc_wire_decoder_init(&clear, 0);
  pc_wire_decoder_init(&sealed, 0);
  sealed.open = srx;
  double cs, cr, ss, sr;
  /* a warm-up pass so the first measured one does not pay for page faults */
  if (run(frames / 8 + 1, data, NULL, &clear, &cs, &cr) || run(frames, data, NULL, &clear, &cs, &cr) ||
      run(frames, data, &ctx, &sealed, &ss, &sr))
    return 1;
  double total = (double)frames * PC_WIRE_CHUNK / (1 << 20);
  printf("%zu frames of %u KiB (%.0f MB), CPU ms per MB of payload:\n", frames, PC_WIRE_CHUNK >> 10, total);
  printf("  send (encode%s):      clear %.3f  sealed %.3f  sealing costs %.3f ms/MB (%.0f MB/s)\n", "+seal",
         1e3 * cs / total, 1e3 * ss / total, 1e3 * (ss - cs) / total, total / (ss - cs > 0 ? ss - cs : 1e-9));
  printf("  receive (decode+open): clear %.3f  sealed %.3f  opening costs %.3f ms/MB (%.0f MB/s)\n", 1e3 * cr / total,
         1e3 * sr / total, 1e3 * (sr - cr) / total, total / (sr - cr > 0 ? sr - cr : 1e-9));
  pc_wire_decoder_free(&clear);
  pc_wire_decoder_free(&sealed);
  pc_seal_wipe(&ctx);
  pc_seal_wipe(&crx);
  pc_seal_wipe(&stx);
  free(data);
  return 0;
}
