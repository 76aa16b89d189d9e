/* auth.c: token file loading and the challenge/response MACs. */
#include "auth.h"

#include <errno.h>
#include <fcntl.h>
#include <sodium.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int pc_auth_init(pc_err *e) {
  if (sodium_init() < 0) return pc_errf(e, PC_EIO, "auth: libsodium failed to initialise");
  return 0;
}

int pc_auth_load_token(const char *path, uint8_t key[PC_AUTH_KEY], pc_err *e) {
  /* a symlink is followed (Kubernetes mounts secrets as links): the checks below are on the
   * file opened, so a link cannot launder a group-readable token */
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return pc_errf(e, PC_EIO, "%s: cannot open token file: %s", path, strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0) {
    int err = errno;
    close(fd);
    return pc_errf(e, PC_EIO, "%s: stat: %s", path, strerror(err));
  }
  if (!S_ISREG(st.st_mode)) { close(fd); return pc_errf(e, PC_EINVAL, "%s: token file is not a regular file", path); }
  if (st.st_mode & (S_IRWXG | S_IRWXO)) {
    close(fd);
    return pc_errf(e, PC_EINVAL, "%s: token file is accessible by group or others (mode %03o); chmod 600 it",
                   path, (unsigned)(st.st_mode & 0777));
  }
  unsigned char buf[4097];
  size_t n = 0;
  for (;;) {
    ssize_t r = read(fd, buf + n, sizeof buf - n);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      int err = errno;
      close(fd);
      sodium_memzero(buf, sizeof buf);
      return pc_errf(e, PC_EIO, "%s: read: %s", path, strerror(err));
    }
    if (r == 0 || (n += (size_t)r) == sizeof buf) break;
  }
  close(fd);
  while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == '\r' || buf[n - 1] == ' ' || buf[n - 1] == '\t')) n--;
  if (n < 8 || n > 4096) {
    sodium_memzero(buf, sizeof buf);
    return pc_errf(e, PC_EINVAL, "%s: token must be 8 to 4096 bytes, found %zu", path, n);
  }
  static const unsigned char ctx[] = "pcbpt-token-v1";
  int rc = crypto_generichash(key, PC_AUTH_KEY, buf, n, ctx, sizeof ctx - 1);
  sodium_memzero(buf, sizeof buf);
  if (rc != 0) return pc_errf(e, PC_EIO, "%s: key derivation failed", path);
  return 0;
}

void pc_auth_nonce(uint8_t nonce[PC_AUTH_NONCE]) { randombytes_buf(nonce, PC_AUTH_NONCE); }

int pc_auth_hash(const uint8_t key[PC_AUTH_KEY], const char *label, const uint8_t *n1, const uint8_t *n2,
                 uint8_t out[PC_AUTH_MAC]) {
  crypto_generichash_state st;
  int rc = 0;
  if (crypto_generichash_init(&st, key, PC_AUTH_KEY, PC_AUTH_MAC) != 0 ||
      crypto_generichash_update(&st, (const unsigned char *)label, strlen(label)) != 0 ||
      crypto_generichash_update(&st, n1, PC_AUTH_NONCE) != 0 ||
      crypto_generichash_update(&st, n2, PC_AUTH_NONCE) != 0 ||
      crypto_generichash_final(&st, out, PC_AUTH_MAC) != 0)
    rc = PC_EIO;
  sodium_memzero(&st, sizeof st); /* the state holds the keyed hash's key */
  return rc;
}

int pc_auth_mac(const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t *n1, const uint8_t *n2,
                uint8_t mac[PC_AUTH_MAC]) {
  /* The direction label keeps a peer from reflecting the coordinator's proof back at it. */
  return pc_auth_hash(key, is_server ? "pcbpt-auth-server-v1" : "pcbpt-auth-client-v1", n1, n2, mac);
}

bool pc_auth_verify(const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t *n1, const uint8_t *n2,
                    const uint8_t *mac, size_t len) {
  if (len != PC_AUTH_MAC) return false;
  uint8_t want[PC_AUTH_MAC];
  if (pc_auth_mac(key, is_server, n1, n2, want) != 0) return false;
  bool ok = sodium_memcmp(want, mac, PC_AUTH_MAC) == 0;
  sodium_memzero(want, sizeof want);
  return ok;
}
