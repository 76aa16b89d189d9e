/* wire_frame.c: length-prefixed protobuf frames: encoding and the incremental decoder. */
#include "wire_frame.h"

#include <stdlib.h>
#include <string.h>

void pc_wire_decoder_init(pc_wire_decoder *d, size_t max_frame) {
  memset(d, 0, sizeof *d);
  d->max = max_frame && max_frame <= PC_WIRE_MAX_FRAME ? max_frame : PC_WIRE_MAX_FRAME;
}

void pc_wire_decoder_free(pc_wire_decoder *d) {
  pc_seal_wipe(&d->open);
  free(d->buf);
  d->buf = NULL;
  d->hdr_have = d->len = d->have = 0;
}

int pc_wire_decoder_push(pc_wire_decoder *d, const uint8_t *data, size_t n, size_t *used,
                         Pcbpt__Envelope **out, pc_err *e) {
  size_t i = 0;
  *out = NULL;
  while (d->hdr_have < 4 && i < n) d->hdr[d->hdr_have++] = data[i++];
  if (d->hdr_have < 4) { *used = i; return 0; }
  if (!d->buf) {
    uint32_t len = (uint32_t)d->hdr[0] << 24 | (uint32_t)d->hdr[1] << 16 | (uint32_t)d->hdr[2] << 8 | d->hdr[3];
    if (len == 0) { *used = i; return pc_errf(e, PC_EPARSE, "wire: empty frame"); }
    size_t limit = d->max + (d->open.on ? PC_SEAL_TAG : 0);
    if (len > limit) {
      *used = i;
      return pc_errf(e, PC_ELIMIT, "wire: frame of %u bytes exceeds the limit of %zu", len, limit);
    }
    d->buf = malloc(len);
    if (!d->buf) { *used = i; return pc_errf(e, PC_ENOMEM, "wire: out of memory for a %u-byte frame", len); }
    d->len = len;
    d->have = 0;
  }
  size_t take = n - i < d->len - d->have ? n - i : d->len - d->have;
  memcpy(d->buf + d->have, data + i, take);
  d->have += take;
  i += take;
  *used = i;
  if (d->have < d->len) return 0;
  size_t len = d->len;
  int rc = d->open.on ? pc_seal_open(&d->open, d->hdr, d->buf, d->len, &len, e) : 0;
  Pcbpt__Envelope *env = rc ? NULL : pcbpt__envelope__unpack(NULL, len, d->buf);
  free(d->buf);
  d->buf = NULL;
  d->hdr_have = d->len = d->have = 0;
  if (rc) return rc;
  if (!env) return pc_errf(e, PC_EPARSE, "wire: malformed %zu-byte frame (protobuf decode failed)", len);
  if (env->msg_case == PCBPT__ENVELOPE__MSG__NOT_SET) {
    pcbpt__envelope__free_unpacked(env, NULL);
    return pc_errf(e, PC_EPARSE, "wire: frame carries no message");
  }
  *out = env;
  return 1;
}

int pc_wire_encode(const Pcbpt__Envelope *env, uint8_t **out, size_t *outlen, pc_err *e) {
  size_t len = pcbpt__envelope__get_packed_size(env);
  if (len == 0 || len > PC_WIRE_MAX_FRAME)
    return pc_errf(e, PC_ELIMIT, "wire: %s message of %zu bytes does not fit a frame",
                   pc_wire_msg_name(env->msg_case), len);
  uint8_t *b = malloc(4 + len + PC_SEAL_TAG);
  if (!b) return pc_errf(e, PC_ENOMEM, "wire: out of memory encoding a frame");
  b[0] = (uint8_t)(len >> 24); b[1] = (uint8_t)(len >> 16); b[2] = (uint8_t)(len >> 8); b[3] = (uint8_t)len;
  size_t packed = pcbpt__envelope__pack(env, b + 4);
  if (packed != len) {
    free(b);
    return pc_errf(e, PC_EINVAL, "wire: protobuf packed %zu bytes, expected %zu", packed, len);
  }
  *out = b;
  *outlen = 4 + len;
  return 0;
}

const char *pc_wire_msg_name(int msg_case) {
  static const char *const names[] = {
    "none", "hello", "challenge", "auth_response", "auth_result", "work_request", "no_work",
    "assign", "cancel", "heartbeat", "bundle_request", "bundle_chunk", "upload_chunk",
    "upload_ack", "submit", "submit_reply", "status_request", "status_reply", "cancel_request",
    "fetch_request", "fetch_chunk", "error", "range_failed", "work_available"};
  if (msg_case < 0 || (size_t)msg_case >= sizeof names / sizeof names[0]) return "unknown";
  return names[msg_case];
}
