/* wire_conn.h: one framed, authenticated-or-not TCP connection on a libuv loop. Incoming
 * bytes go through the incremental decoder; a decode error closes this connection only, with
 * the reason logged. Outgoing frames are either control (written at once) or bulk (uploads,
 * bundles: written one chunk at a time), so a heartbeat, cancel or ack waits behind at most
 * one bulk chunk. After the handshake both directions are sealed (pc_conn_seal); a frame is
 * sealed when it is handed to the socket, so the counters follow the order on the wire. */
#ifndef PC_WIRE_CONN_H
#define PC_WIRE_CONN_H

#include <stdbool.h>
#include <uv.h>

#include "wire_frame.h"

typedef struct pc_conn pc_conn;
typedef struct pc_conn_frame pc_conn_frame;

typedef struct pc_conn_cbs {
  void (*on_msg)(pc_conn *c, Pcbpt__Envelope *env); /* env is freed after the call */
  void (*on_drain)(pc_conn *c);                     /* bulk queue became empty (may be NULL) */
  void (*on_closed)(pc_conn *c);                    /* handle closed: the owner may free c */
} pc_conn_cbs;

struct pc_conn {
  uv_tcp_t tcp;
  pc_wire_decoder dec;  /* holds the receiving direction's seal */
  pc_seal_dir seal_tx;
  pc_conn_cbs cbs;
  void *data;
  pc_conn_frame *bulk_head, *bulk_tail;
  bool bulk_writing;
  bool closing;
  size_t bulk_queued;   /* bytes waiting in the bulk queue */
  char peer[64];
};

int pc_conn_init(uv_loop_t *loop, pc_conn *c, const pc_conn_cbs *cbs, void *data, size_t max_frame);
/* Records the peer address and starts reading. */
int pc_conn_start(pc_conn *c);
int pc_conn_send(pc_conn *c, const Pcbpt__Envelope *env);
/* Seals every frame from now on in both directions (pc_seal_derive). Call it exactly where the
 * handshake ends: the coordinator right after sending AuthResult(ok), the connecting side on
 * receiving it (from on_msg, so the next frame in the same read is already opened). */
int pc_conn_seal(pc_conn *c, const uint8_t key[PC_AUTH_KEY], bool is_server, const uint8_t client_nonce[PC_AUTH_NONCE],
                 const uint8_t server_nonce[PC_AUTH_NONCE]);
int pc_conn_send_bulk(pc_conn *c, const Pcbpt__Envelope *env);
/* Stops (paused true) or resumes reading: back-pressure while the reader cannot take more. */
int pc_conn_pause(pc_conn *c, bool paused);
/* Logs "peer: closing: reason" (when reason is non-NULL) and closes; idempotent. */
void pc_conn_close(pc_conn *c, const char *reason);

/* "HOST[:PORT]" into host and port (default_port when absent). */
int pc_wire_parse_hostport(const char *s, char *host, size_t hn, int *port, int default_port);

#endif
