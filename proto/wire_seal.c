/* wire_seal.c: per-direction key derivation and in-place XChaCha20-Poly1305 sealing of frames. */
#include "wire_seal.h"

#include <sodium.h>
#include <string.h>

_Static_assert(PC_SEAL_TAG == crypto_aead_xchacha20poly1305_ietf_ABYTES, "tag size");
_Static_assert(PC_SEAL_KEY == crypto_aead_xchacha20poly1305_ietf_KEYBYTES, "key size");
_Static_assert(PC_SEAL_KEY == PC_AUTH_MAC, "keys are pc_auth_hash outputs");

int pc_seal_derive(const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t client_nonce[PC_AUTH_NONCE],
                   const uint8_t server_nonce[PC_AUTH_NONCE], pc_seal_dir *tx, pc_seal_dir *rx, pc_err *e) {
  /* labels unlike auth.c's, so no key equals a MAC that travelled in the clear */
  static const char c2s[] = "pcbpt-seal-client-to-server-v3", s2c[] = "pcbpt-seal-server-to-client-v3";
  memset(tx, 0, sizeof *tx);
  memset(rx, 0, sizeof *rx);
  if (pc_auth_hash(key, is_server ? s2c : c2s, client_nonce, server_nonce, tx->key) != 0 ||
      pc_auth_hash(key, is_server ? c2s : s2c, client_nonce, server_nonce, rx->key) != 0) {
    pc_seal_wipe(tx);
    pc_seal_wipe(rx);
    return pc_errf(e, PC_EIO, "seal: key derivation failed");
  }
  tx->on = rx->on = true;
  return 0;
}

static void counter_nonce(uint64_t counter, uint8_t nonce[crypto_aead_xchacha20poly1305_ietf_NPUBBYTES]) {
  memset(nonce, 0, crypto_aead_xchacha20poly1305_ietf_NPUBBYTES);
  for (int i = 0; i < 8; i++) nonce[i] = (uint8_t)(counter >> (8 * i));
}

int pc_seal_frame(pc_seal_dir *tx, uint8_t *frame, size_t *len, pc_err *e) {
  if (*len < 4) return pc_errf(e, PC_EINVAL, "seal: a frame without its length prefix");
  size_t n = *len - 4, sealed = n + PC_SEAL_TAG;
  if (sealed > UINT32_MAX) return pc_errf(e, PC_ELIMIT, "seal: a %zu-byte frame does not fit a length prefix", n);
  if (tx->counter == UINT64_MAX) return pc_errf(e, PC_ELIMIT, "seal: frame counter exhausted; reconnect");
  frame[0] = (uint8_t)(sealed >> 24); frame[1] = (uint8_t)(sealed >> 16); frame[2] = (uint8_t)(sealed >> 8);
  frame[3] = (uint8_t)sealed;
  uint8_t nonce[crypto_aead_xchacha20poly1305_ietf_NPUBBYTES];
  counter_nonce(tx->counter, nonce);
  if (crypto_aead_xchacha20poly1305_ietf_encrypt_detached(frame + 4, frame + 4 + n, NULL, frame + 4, n, frame, 4,
                                                          NULL, nonce, tx->key) != 0)
    return pc_errf(e, PC_EIO, "seal: encryption failed");
  tx->counter++;
  *len = 4 + sealed;
  return 0;
}

int pc_seal_open(pc_seal_dir *rx, const uint8_t hdr[4], uint8_t *payload, size_t n, size_t *plain_len, pc_err *e) {
  if (n <= PC_SEAL_TAG) return pc_errf(e, PC_EPARSE, "seal: a %zu-byte frame is too short to be sealed", n);
  if (rx->counter == UINT64_MAX) return pc_errf(e, PC_ELIMIT, "seal: frame counter exhausted");
  uint8_t nonce[crypto_aead_xchacha20poly1305_ietf_NPUBBYTES];
  counter_nonce(rx->counter, nonce);
  size_t m = n - PC_SEAL_TAG;
  if (crypto_aead_xchacha20poly1305_ietf_decrypt_detached(payload, NULL, payload, m, payload + m, hdr, 4, nonce,
                                                          rx->key) != 0)
    return pc_errf(e, PC_EPARSE, "seal: frame %llu does not authenticate (forged, altered, replayed or out of order)",
                   (unsigned long long)rx->counter);
  rx->counter++;
  *plain_len = m;
  return 0;
}

void pc_seal_wipe(pc_seal_dir *d) { sodium_memzero(d, sizeof *d); }
