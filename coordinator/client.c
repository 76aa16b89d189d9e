/* client.c: blocking client connections (submit, status, wait, cancel, fetch ...). */
#include "client.h"

#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "auth.h"
#include "bundle.h"
#include "wire_conn.h"
#include "wire_settings.h"

int pc_client_send(pc_client *cl, const Pcbpt__Envelope *env, pc_err *e) {
  uint8_t *buf;
  size_t n;
  int rc = pc_wire_encode(env, &buf, &n, e);
  if (rc) return rc;
  if (cl->seal_tx.on && (rc = pc_seal_frame(&cl->seal_tx, buf, &n, e)) != 0) { free(buf); return rc; }
  size_t off = 0;
  while (off < n) {
    ssize_t w = send(cl->fd, buf + off, n - off, MSG_NOSIGNAL);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0) { free(buf); return pc_errf(e, PC_EIO, "send: %s", strerror(errno)); }
    off += (size_t)w;
  }
  free(buf);
  return 0;
}

int pc_client_recv(pc_client *cl, double timeout_s, Pcbpt__Envelope **out, pc_err *e) {
  uint8_t buf[65536];
  for (;;) {
    struct pollfd pfd = {.fd = cl->fd, .events = POLLIN};
    int pr = poll(&pfd, 1, (int)(timeout_s * 1000));
    if (pr < 0 && errno == EINTR) continue;
    if (pr < 0) return pc_errf(e, PC_EIO, "poll: %s", strerror(errno));
    if (pr == 0) return pc_errf(e, PC_EIO, "no answer from the coordinator within %.0f s", timeout_s);
    /* read at most up to the end of the current frame so no bytes are lost between calls */
    size_t want = 4 - (cl->dec.hdr_have < 4 ? cl->dec.hdr_have : 4);
    if (cl->dec.hdr_have == 4) want = cl->dec.len - cl->dec.have;
    if (want > sizeof buf) want = sizeof buf;
    ssize_t r = recv(cl->fd, buf, want ? want : 1, 0);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return pc_errf(e, PC_EIO, "recv: %s", strerror(errno));
    if (r == 0) return pc_errf(e, PC_EIO, "the coordinator closed the connection");
    size_t used;
    int d = pc_wire_decoder_push(&cl->dec, buf, (size_t)r, &used, out, e);
    if (d < 0) return d;
    if (d == 1) {
      if ((*out)->msg_case == PCBPT__ENVELOPE__MSG_ERROR) {
        int rc = pc_errf(e, PC_EINVAL, "coordinator: %s", (*out)->error->reason);
        pcbpt__envelope__free_unpacked(*out, NULL);
        *out = NULL;
        return rc;
      }
      return 0;
    }
  }
}

void pc_client_close(pc_client *cl) {
  if (cl->fd >= 0) close(cl->fd);
  cl->fd = -1;
  pc_wire_decoder_free(&cl->dec);
  pc_seal_wipe(&cl->seal_tx);
}

int pc_client_connect(const char *hostport, const char *token_file, pc_client *cl, pc_err *e) {
  return pc_client_connect_as(hostport, token_file, PCBPT__ROLE__ROLE_CLIENT, cl, e);
}

int pc_client_connect_as(const char *hostport, const char *token_file, Pcbpt__Role role, pc_client *cl, pc_err *e) {
  char host[256], portstr[16];
  int port;
  uint8_t key[PC_AUTH_KEY];
  cl->fd = -1;
  pc_wire_decoder_init(&cl->dec, 0);
  memset(&cl->seal_tx, 0, sizeof cl->seal_tx);
  if (pc_wire_parse_hostport(hostport, host, sizeof host, &port, 7878) != 0) return pc_errf(e, PC_EINVAL, "--host: expected HOST[:PORT], got '%s'", hostport);
  int rc = pc_auth_init(e);
  if (!rc) rc = pc_auth_load_token(token_file, key, e);
  if (rc) return rc;
  snprintf(portstr, sizeof portstr, "%d", port);
  struct addrinfo hints = {.ai_socktype = SOCK_STREAM}, *ai = NULL;
  int g = getaddrinfo(host, portstr, &hints, &ai);
  if (g != 0) return pc_errf(e, PC_EIO, "%s: %s", host, gai_strerror(g));
  for (struct addrinfo *a = ai; a; a = a->ai_next) {
    int fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    if (connect(fd, a->ai_addr, a->ai_addrlen) == 0) { cl->fd = fd; break; }
    close(fd);
  }
  freeaddrinfo(ai);
  if (cl->fd < 0) return pc_errf(e, PC_EIO, "cannot connect to %s:%d: %s", host, port, strerror(errno));
  /* Requests are small and each waits for its answer: with Nagle's algorithm one sent while
   * the coordinator has not yet acknowledged the previous bytes (a bundle's last chunk) waits
   * for its delayed ACK, 40 ms on Linux (measured: a render's submit reached the coordinator
   * 37 ms after it was sent). */
  int one = 1;
  if (setsockopt(cl->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) != 0) {
    rc = pc_errf(e, PC_EIO, "%s:%d: cannot set TCP_NODELAY: %s", host, port, strerror(errno));
    close(cl->fd);
    cl->fd = -1;
    return rc;
  }
  uint8_t cn[PC_AUTH_NONCE], sn[PC_AUTH_NONCE], mac[PC_AUTH_MAC];
  pc_auth_nonce(cn);
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Hello h = PCBPT__HELLO__INIT;
  h.protocol_version = PC_WIRE_PROTOCOL_VERSION;
  h.role = role;
  h.name = role == PCBPT__ROLE__ROLE_CLIENT ? "client" : "test-worker";
  h.client_nonce.data = cn;
  h.client_nonce.len = PC_AUTH_NONCE;
  env.msg_case = PCBPT__ENVELOPE__MSG_HELLO;
  env.hello = &h;
  Pcbpt__Envelope *in = NULL;
  if ((rc = pc_client_send(cl, &env, e)) != 0 || (rc = pc_client_recv(cl, 30, &in, e)) != 0) goto fail;
  if (in->msg_case != PCBPT__ENVELOPE__MSG_CHALLENGE || in->challenge->nonce.len != PC_AUTH_NONCE ||
      !pc_auth_verify(key, true, cn, in->challenge->nonce.data, in->challenge->server_mac.data, in->challenge->server_mac.len)) {
    rc = in->msg_case == PCBPT__ENVELOPE__MSG_CHALLENGE && in->challenge->nonce.len == PC_AUTH_NONCE
             ? pc_errf(e, PC_EINVAL, "authentication failed: the coordinator at %s holds a different token than %s", hostport, token_file)
             : pc_errf(e, PC_EINVAL, "the coordinator at %s sent no valid challenge", hostport);
    goto fail;
  }
  if ((rc = pc_auth_mac(key, false, in->challenge->nonce.data, cn, mac)) != 0) goto fail;
  memcpy(sn, in->challenge->nonce.data, PC_AUTH_NONCE);
  pcbpt__envelope__free_unpacked(in, NULL);
  in = NULL;
  Pcbpt__AuthResponse ar = PCBPT__AUTH_RESPONSE__INIT;
  ar.mac.data = mac;
  ar.mac.len = PC_AUTH_MAC;
  env.msg_case = PCBPT__ENVELOPE__MSG_AUTH_RESPONSE;
  env.auth_response = &ar;
  if ((rc = pc_client_send(cl, &env, e)) != 0 || (rc = pc_client_recv(cl, 30, &in, e)) != 0) goto fail;
  if (in->msg_case != PCBPT__ENVELOPE__MSG_AUTH_RESULT || !in->auth_result->ok) {
    rc = pc_errf(e, PC_EINVAL, "authentication refused: %s",
                 in->msg_case == PCBPT__ENVELOPE__MSG_AUTH_RESULT ? in->auth_result->reason : "unexpected reply");
    goto fail;
  }
  pcbpt__envelope__free_unpacked(in, NULL);
  in = NULL;
  /* pc_client_recv read nothing past AuthResult, so the next byte is the first sealed frame */
  if ((rc = pc_seal_derive(key, false, cn, sn, &cl->seal_tx, &cl->dec.open, e)) != 0) goto fail;
  sodium_memzero(key, sizeof key);
  return 0;
fail:
  if (in) pcbpt__envelope__free_unpacked(in, NULL);
  sodium_memzero(key, sizeof key);
  pc_client_close(cl);
  return rc;
}

int pc_client_send_bundle(pc_client *cl, const uint8_t *blob, size_t n, const uint8_t *hash, pc_err *e) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__BundleChunk bc = PCBPT__BUNDLE_CHUNK__INIT;
  bc.hash.data = (uint8_t *)hash;
  bc.hash.len = PC_BUNDLE_HASH;
  bc.total = n;
  env.msg_case = PCBPT__ENVELOPE__MSG_BUNDLE_CHUNK;
  env.bundle_chunk = &bc;
  int rc = 0;
  for (size_t off = 0; off < n && !rc; off += PC_WIRE_CHUNK) {
    bc.offset = off;
    bc.data.data = (uint8_t *)blob + off;
    bc.data.len = n - off < PC_WIRE_CHUNK ? n - off : PC_WIRE_CHUNK;
    rc = pc_client_send(cl, &env, e);
  }
  return rc;
}

int pc_client_fetch(pc_client *cl, uint64_t job, const char *out, uint64_t *bytes, pc_err *e) {
  return pc_client_fetch_snapshot(cl, job, 0, out, bytes, e);
}

int pc_client_fetch_snapshot(pc_client *cl, uint64_t job, uint32_t snapshot, const char *out, uint64_t *bytes, pc_err *e) {
  char tmp[4096];
  snprintf(tmp, sizeof tmp, "%s.part.%ld", out, (long)getpid());
  FILE *f = fopen(tmp, "wb");
  if (!f) return pc_errf(e, PC_EIO, "%s: cannot create: %s", tmp, strerror(errno));
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT, *in = NULL;
  Pcbpt__FetchRequest fr = PCBPT__FETCH_REQUEST__INIT;
  fr.job_id = job;
  fr.snapshot = snapshot;
  env.msg_case = PCBPT__ENVELOPE__MSG_FETCH_REQUEST;
  env.fetch_request = &fr;
  uint64_t got = 0, total = 1;
  int rc = pc_client_send(cl, &env, e);
  while (!rc && got < total) {
    if ((rc = pc_client_recv(cl, 60, &in, e)) != 0) break;
    if (in->msg_case != PCBPT__ENVELOPE__MSG_FETCH_CHUNK || in->fetch_chunk->offset != got) rc = pc_errf(e, PC_EPARSE, "unexpected reply");
    else {
      total = in->fetch_chunk->total;
      if (fwrite(in->fetch_chunk->data.data, 1, in->fetch_chunk->data.len, f) != in->fetch_chunk->data.len) rc = pc_errf(e, PC_EIO, "%s: write failed", tmp);
      got += in->fetch_chunk->data.len;
    }
    pcbpt__envelope__free_unpacked(in, NULL);
  }
  if (fclose(f) != 0 && !rc) rc = pc_errf(e, PC_EIO, "%s: write failed", tmp);
  if (!rc && rename(tmp, out) != 0) rc = pc_errf(e, PC_EIO, "%s: cannot rename into place: %s", out, strerror(errno));
  if (rc) unlink(tmp);
  *bytes = got;
  return rc;
}

int pc_client_submit(pc_client *cl, const Pcbpt__Submit *sub, uint64_t *job, pc_err *e) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT, *in = NULL;
  env.msg_case = PCBPT__ENVELOPE__MSG_SUBMIT;
  env.submit = (Pcbpt__Submit *)sub;
  int rc = pc_client_send(cl, &env, e);
  if (!rc) rc = pc_client_recv(cl, 60, &in, e);
  if (rc) return rc;
  if (in->msg_case != PCBPT__ENVELOPE__MSG_SUBMIT_REPLY) rc = pc_errf(e, PC_EPARSE, "unexpected reply to submit");
  else *job = in->submit_reply->job_id;
  pcbpt__envelope__free_unpacked(in, NULL);
  return rc;
}

int pc_client_submit_request(pc_client *cl, const char *name, const uint8_t *hash, const pc_render_request *req,
                             const char *auto_report, uint64_t prior_group, double prior_amount, int priority,
                             uint64_t *job, pc_err *e) {
  Pcbpt__Settings ps;
  pc_wire_settings_buf psb;
  pc_wire_settings_to_proto(&req->set, &ps, &psb);
  ps.halt_noise = req->halt_noise;
  ps.auto_report = (char *)auto_report;
  ps.prior_group = prior_amount > 0 ? prior_group : 0;
  ps.prior_amount = prior_amount > 0 ? prior_amount : 0;
  Pcbpt__Submit sub = PCBPT__SUBMIT__INIT;
  sub.name = (char *)name;
  sub.bundle_hash.data = (uint8_t *)hash;
  sub.bundle_hash.len = PC_BUNDLE_HASH;
  sub.settings = &ps;
  sub.halt_iterations = req->spp;
  sub.halt_seconds = req->seconds;
  sub.priority = priority;
  return pc_client_submit(cl, &sub, job, e);
}

int pc_client_status(pc_client *cl, uint64_t job, Pcbpt__Envelope **out, pc_err *e) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__StatusRequest sr = PCBPT__STATUS_REQUEST__INIT;
  sr.job_id = job;
  env.msg_case = PCBPT__ENVELOPE__MSG_STATUS_REQUEST;
  env.status_request = &sr;
  int rc = pc_client_send(cl, &env, e);
  if (!rc) rc = pc_client_recv(cl, 30, out, e);
  if (rc) return rc;
  if ((*out)->msg_case != PCBPT__ENVELOPE__MSG_STATUS_REPLY) {
    pcbpt__envelope__free_unpacked(*out, NULL);
    *out = NULL;
    return pc_errf(e, PC_EPARSE, "unexpected reply to a status request");
  }
  return 0;
}
