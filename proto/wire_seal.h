/* wire_seal.h: confidentiality and integrity of a connection's frames once the handshake
 * (auth.h) has succeeded. Each direction of each connection gets its own key, derived from the
 * token key and both handshake nonces; every frame after AuthResult(ok) is sealed with
 * XChaCha20-Poly1305 under that key and a per-direction frame counter as the nonce, with the
 * frame's 4-byte length prefix as associated data.
 *
 * Why a counter-nonce AEAD and not crypto_secretstream: the handshake already gives both sides
 * fresh, shared, per-connection material, so a deterministic counter needs no extra header to be
 * exchanged (no extra round trip, nothing to pipeline across the switch), and a frame that is
 * replayed, reordered, dropped or sent back in the other direction fails its tag because the
 * receiver's counter or key does not match. secretstream would add the same guarantees plus a
 * header per direction and tags for rekeying and end-of-stream that the framing (TCP + the
 * connection's own close) does not need. Both seal and open work in place, so a 256 KiB upload
 * chunk is never copied for the cipher. There is no forward secrecy: whoever learns the token
 * and recorded a connection's handshake can decrypt it (an ephemeral X25519 exchange in
 * Hello/Challenge would fix that). */
#ifndef PC_WIRE_SEAL_H
#define PC_WIRE_SEAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "auth.h"
#include "error.h"

#define PC_SEAL_KEY 32
#define PC_SEAL_TAG 16u   /* bytes a sealed frame's payload grows by */

/* One direction of one connection: off until keyed. */
typedef struct pc_seal_dir {
  uint8_t key[PC_SEAL_KEY];
  uint64_t counter;   /* frames sealed (or opened) so far in this direction */
  bool on;
} pc_seal_dir;

/* Derives the sending (tx) and receiving (rx) keys of the coordinator (is_server) or of the
 * connecting side from the token key and the handshake's client and server nonces, and turns
 * both on with their counters at zero. */
int pc_seal_derive(const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t client_nonce[PC_AUTH_NONCE],
                   const uint8_t server_nonce[PC_AUTH_NONCE], pc_seal_dir *tx, pc_seal_dir *rx, pc_err *e);
/* Seals a frame in place: frame[0..*len) is a 4-byte length prefix and its payload, and the
 * buffer has PC_SEAL_TAG bytes of room after it. Rewrites the prefix and grows *len. */
int pc_seal_frame(pc_seal_dir *tx, uint8_t *frame, size_t *len, pc_err *e);
/* Opens a received payload of n bytes in place, hdr being its length prefix as received; on
 * success *plain_len = n - PC_SEAL_TAG bytes of plaintext are at payload. Any failure means
 * the frame was forged, altered, replayed, reordered or keyed for the other direction. */
int pc_seal_open(pc_seal_dir *rx, const uint8_t hdr[4], uint8_t *payload, size_t n, size_t *plain_len, pc_err *e);
void pc_seal_wipe(pc_seal_dir *d);

#endif
