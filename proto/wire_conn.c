/* wire_conn.c: framed libuv TCP connections with a control lane and a bulk lane. */
#include "wire_conn.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "parse.h"
#include "wire_log.h"

struct pc_conn_frame {
  pc_conn_frame *next;
  uint8_t *buf;
  size_t len;
};

typedef struct write_req {
  uv_write_t req;
  uint8_t *buf;
  bool bulk;
} write_req;

int pc_conn_init(uv_loop_t *loop, pc_conn *c, const pc_conn_cbs *cbs, void *data, size_t max_frame) {
  memset(c, 0, sizeof *c);
  c->cbs = *cbs;
  c->data = data;
  pc_wire_decoder_init(&c->dec, max_frame);
  snprintf(c->peer, sizeof c->peer, "?");
  int r = uv_tcp_init(loop, &c->tcp);
  if (r) return r;
  c->tcp.data = c;
  return 0;
}

static void alloc_cb(uv_handle_t *h, size_t suggested, uv_buf_t *buf) {
  (void)h;
  size_t n = suggested < 65536 ? suggested : 65536;
  buf->base = malloc(n);
  buf->len = buf->base ? n : 0;
}

static void read_cb(uv_stream_t *s, ssize_t nread, const uv_buf_t *buf) {
  pc_conn *c = s->data;
  if (nread < 0) {
    free(buf->base);
    pc_conn_close(c, nread == UV_EOF ? "peer closed the connection" : uv_strerror((int)nread));
    return;
  }
  size_t off = 0;
  while (!c->closing && off < (size_t)nread) {
    size_t used = 0;
    Pcbpt__Envelope *env = NULL;
    pc_err e = {0};
    int r = pc_wire_decoder_push(&c->dec, (const uint8_t *)buf->base + off, (size_t)nread - off, &used, &env, &e);
    off += used;
    if (r < 0) { pc_conn_close(c, e.msg); break; }
    if (r == 1) {
      c->cbs.on_msg(c, env);
      pcbpt__envelope__free_unpacked(env, NULL);
    }
  }
  free(buf->base);
}

int pc_conn_start(pc_conn *c) {
  struct sockaddr_storage ss;
  int len = sizeof ss;
  if (uv_tcp_getpeername(&c->tcp, (struct sockaddr *)&ss, &len) == 0) {
    char ip[48] = "?";
    int port = 0;
    if (ss.ss_family == AF_INET) {
      uv_ip4_name((struct sockaddr_in *)&ss, ip, sizeof ip);
      port = ntohs(((struct sockaddr_in *)&ss)->sin_port);
    } else if (ss.ss_family == AF_INET6) {
      uv_ip6_name((struct sockaddr_in6 *)&ss, ip, sizeof ip);
      port = ntohs(((struct sockaddr_in6 *)&ss)->sin6_port);
    }
    snprintf(c->peer, sizeof c->peer, "%s:%d", ip, port);
  }
  int r = uv_tcp_nodelay(&c->tcp, 1);
  if (r) return r;
  return uv_read_start((uv_stream_t *)&c->tcp, alloc_cb, read_cb);
}

int pc_conn_pause(pc_conn *c, bool paused) {
  if (c->closing) return 0;
  return paused ? uv_read_stop((uv_stream_t *)&c->tcp) : uv_read_start((uv_stream_t *)&c->tcp, alloc_cb, read_cb);
}

static void write_bulk_next(pc_conn *c);

static void write_cb(uv_write_t *req, int status) {
  write_req *w = (write_req *)req;
  pc_conn *c = req->handle->data;
  free(w->buf);
  bool bulk = w->bulk;
  free(w);
  if (status < 0) { pc_conn_close(c, uv_strerror(status)); return; }
  if (bulk) {
    c->bulk_writing = false;
    write_bulk_next(c);
  }
}

static int write_frame(pc_conn *c, uint8_t *buf, size_t len, bool bulk) {
  pc_err e;
  if (c->seal_tx.on && pc_seal_frame(&c->seal_tx, buf, &len, &e) != 0) {
    pc_wire_log("%s: cannot send: %s", c->peer, e.msg);
    free(buf);
    return UV_EINVAL;
  }
  write_req *w = malloc(sizeof *w);
  if (!w) { free(buf); return UV_ENOMEM; }
  w->buf = buf;
  w->bulk = bulk;
  uv_buf_t b = uv_buf_init((char *)buf, (unsigned)len);
  int r = uv_write(&w->req, (uv_stream_t *)&c->tcp, &b, 1, write_cb);
  if (r) { free(buf); free(w); }
  return r;
}

static void write_bulk_next(pc_conn *c) {
  if (c->closing || c->bulk_writing) return;
  pc_conn_frame *f = c->bulk_head;
  if (!f) {
    if (c->cbs.on_drain) c->cbs.on_drain(c);
    return;
  }
  c->bulk_head = f->next;
  if (!c->bulk_head) c->bulk_tail = NULL;
  c->bulk_queued -= f->len;
  c->bulk_writing = true;
  int r = write_frame(c, f->buf, f->len, true);
  free(f);
  if (r) { c->bulk_writing = false; pc_conn_close(c, uv_strerror(r)); }
}

int pc_conn_send(pc_conn *c, const Pcbpt__Envelope *env) {
  if (c->closing) return UV_ECANCELED;
  uint8_t *buf;
  size_t len;
  pc_err e;
  if (pc_wire_encode(env, &buf, &len, &e) != 0) {
    pc_wire_log("%s: cannot send: %s", c->peer, e.msg);
    return UV_EINVAL;
  }
  int r = write_frame(c, buf, len, false);
  if (r) pc_conn_close(c, uv_strerror(r));
  return r;
}

int pc_conn_seal(pc_conn *c, const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t client_nonce[PC_AUTH_NONCE],
                 const uint8_t server_nonce[PC_AUTH_NONCE]) {
  pc_err e;
  if (pc_seal_derive(key, is_server, client_nonce, server_nonce, &c->seal_tx, &c->dec.open, &e) != 0) {
    pc_conn_close(c, e.msg);
    return UV_EINVAL;
  }
  return 0;
}

int pc_conn_send_bulk(pc_conn *c, const Pcbpt__Envelope *env) {
  if (c->closing) return UV_ECANCELED;
  pc_conn_frame *f = malloc(sizeof *f);
  pc_err e;
  if (!f) return UV_ENOMEM;
  if (pc_wire_encode(env, &f->buf, &f->len, &e) != 0) {
    pc_wire_log("%s: cannot send: %s", c->peer, e.msg);
    free(f);
    return UV_EINVAL;
  }
  f->next = NULL;
  if (c->bulk_tail) c->bulk_tail->next = f;
  else c->bulk_head = f;
  c->bulk_tail = f;
  c->bulk_queued += f->len;
  if (!c->bulk_writing) {
    /* write the first chunk directly; on_drain fires only after a real write completes */
    c->bulk_head = f->next;
    if (!c->bulk_head) c->bulk_tail = NULL;
    c->bulk_queued -= f->len;
    c->bulk_writing = true;
    int r = write_frame(c, f->buf, f->len, true);
    free(f);
    if (r) { c->bulk_writing = false; pc_conn_close(c, uv_strerror(r)); return r; }
  }
  return 0;
}

static void closed_cb(uv_handle_t *h) {
  pc_conn *c = h->data;
  while (c->bulk_head) {
    pc_conn_frame *f = c->bulk_head;
    c->bulk_head = f->next;
    free(f->buf);
    free(f);
  }
  c->bulk_tail = NULL;
  pc_wire_decoder_free(&c->dec);
  pc_seal_wipe(&c->seal_tx);
  if (c->cbs.on_closed) c->cbs.on_closed(c);
}

void pc_conn_close(pc_conn *c, const char *reason) {
  if (c->closing) return;
  c->closing = true;
  if (reason) pc_wire_log("%s: closing: %s", c->peer, reason);
  uv_close((uv_handle_t *)&c->tcp, closed_cb);
}

int pc_wire_parse_hostport(const char *s, char *host, size_t hn, int *port, int default_port) {
  const char *colon = strrchr(s, ':');
  size_t len = colon ? (size_t)(colon - s) : strlen(s);
  if (len == 0 || len >= hn) return PC_EINVAL;
  memcpy(host, s, len);
  host[len] = 0;
  long long p = default_port;
  if (colon && !pc_parse_i64(colon + 1, 0, 65535, &p)) return PC_EINVAL;
  *port = (int)p;
  return 0;
}

