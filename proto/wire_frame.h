/* wire_frame.h: the farm's framing: a 4-byte big-endian length, then one protobuf Envelope
 * (proto/pcbpt.proto), sealed (wire_seal.h) once the handshake is done. The decoder is
 * incremental (bytes arrive in any split across reads) and refuses empty, oversized, malformed
 * and (when sealed) unauthentic frames; every frame is untrusted input. */
#ifndef PC_WIRE_FRAME_H
#define PC_WIRE_FRAME_H

#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "pcbpt.pb-c.h"
#include "wire_seal.h"
#include "wire_upload.h"

#define PC_WIRE_PROTOCOL_VERSION 7u   /* 2: films as byte planes (PCFILM02); 3: films end with beauty_sq;
                                        * 4: sealed frames (wire_seal.h); 5: films end with beauty_max;
                                        * 6: Settings carry pcbpt_candidate_visibility (a worker
                                        * ignoring it would render another estimator); 7: films
                                        * carry their iteration trace (PCFILM03, film_trace.h) */
#define PC_WIRE_MAX_FRAME (1u << 20)   /* hard limit on one frame's plaintext payload */
#define PC_WIRE_CHUNK (256u << 10)     /* bulk payload bytes per frame; well under the limit */

typedef struct pc_wire_decoder {
  uint8_t hdr[4];
  size_t hdr_have;
  uint8_t *buf;     /* payload being assembled, allocated once the length is known */
  size_t len, have;
  size_t max;       /* plaintext limit for this decoder (PC_WIRE_MAX_FRAME unless lowered) */
  pc_seal_dir open; /* when on, every frame is sealed and opened before it is parsed */
} pc_wire_decoder;

void pc_wire_decoder_init(pc_wire_decoder *d, size_t max_frame);
void pc_wire_decoder_free(pc_wire_decoder *d);

/* Consumes bytes from data[0..n). Returns 1 with *out set (free with
 * pcbpt__envelope__free_unpacked) when a frame completed, 0 when all n bytes were consumed
 * without completing one, or a negative code (the connection must be dropped). *used says how
 * many bytes were consumed; call again with the rest. */
int pc_wire_decoder_push(pc_wire_decoder *d, const uint8_t *data, size_t n, size_t *used,
                         Pcbpt__Envelope **out, pc_err *e);

/* Encodes env as one frame (length prefix included) into a malloc'd buffer with PC_SEAL_TAG
 * bytes of room after it, so pc_seal_frame can seal it in place. */
int pc_wire_encode(const Pcbpt__Envelope *env, uint8_t **out, size_t *outlen, pc_err *e);

/* Name of an envelope's message kind, for log lines. */
const char *pc_wire_msg_name(int msg_case);

#endif
