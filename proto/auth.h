/* auth.h: the farm's shared-secret authentication. The secret comes from a token file that
 * only its owner may read; on the wire each side proves knowledge of it with a keyed BLAKE2b
 * MAC over both sides' fresh nonces (libsodium), so the secret never travels and a recorded
 * exchange cannot be replayed. MACs are compared in constant time. */
#ifndef PC_AUTH_H
#define PC_AUTH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"

#define PC_AUTH_KEY 32
#define PC_AUTH_NONCE 32
#define PC_AUTH_MAC 32

/* Initialises libsodium (idempotent). */
int pc_auth_init(pc_err *e);
/* Reads the token file: a regular file with no group/other permission bits, 8..4096 bytes
 * (trailing whitespace ignored). Derives the MAC key; the token itself is wiped. */
int pc_auth_load_token(const char *path, uint8_t key[PC_AUTH_KEY], pc_err *e);
void pc_auth_nonce(uint8_t nonce[PC_AUTH_NONCE]);
/* Keyed BLAKE2b-256 of (label || n1 || n2), each nonce PC_AUTH_NONCE bytes: the MACs below and
 * the connection keys (wire_seal.c) differ by their labels. */
int pc_auth_hash(const uint8_t key[PC_AUTH_KEY], const char *label, const uint8_t *n1, const uint8_t *n2,
                 uint8_t out[PC_AUTH_MAC]);
/* MAC of the client (is_server false) or the coordinator over (first nonce || second nonce). */
int pc_auth_mac(const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t *n1, const uint8_t *n2,
                uint8_t mac[PC_AUTH_MAC]);
/* Constant-time check of a received MAC of `len` bytes. */
bool pc_auth_verify(const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t *n1, const uint8_t *n2,
                    const uint8_t *mac, size_t len);

#endif
