/* worker.c: the farm worker: connects to the coordinator (reconnecting with backoff while it
 * is away), authenticates, takes iteration ranges, fetches and caches scene bundles by hash,
 * and streams deltas (sums + counts since the last acknowledged upload) in bounded chunks,
 * handed to the connection a few at a time as it drains.
 * A delta stays in memory until acknowledged and is re-sent after a reconnect; the
 * coordinator recognises re-sent iterations and never counts them twice. The next range is
 * asked for as soon as the last delta of a range is sent, so the render thread does not sit
 * idle while the coordinator checkpoints and acknowledges it. */
#include <errno.h>
#include <netdb.h>
#include <signal.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "auth.h"
#include "bundle.h"
#include "render_flags.h"
#include "wire_conn.h"
#include "wire_film.h"
#include "wire_log.h"
#include "wire_settings.h"
#include "wire_upload.h"
#include "worker.h"

struct pc_worker {
  uv_loop_t *loop, loop_storage;
  uv_timer_t retry, beat, pump;
  uv_async_t notify;
  uv_async_t stop;
  uv_signal_t sigint, sigterm;
  bool handle_signals, shutting_down;
  bool wrong_token;          /* the coordinator holds another token: retrying cannot help */
  pc_conn *conn;
  bool connected, challenged, authed, waiting_work;
  double backoff, last_upload, next_request;
  double upload_share; /* pc_worker_opts */
  char host[256];
  int port;
  char name[64], cache[1024];
  uint8_t key[PC_AUTH_KEY], cnonce[PC_AUTH_NONCE], snonce[PC_AUTH_NONCE];
  int threads;
  pc_wrender r;
  /* current range, as the loop sees it */
  bool busy, drop, stopping;
  uint64_t job, range, count;
  /* an upload being sent (in_next of its chunks handed to the current connection) or sent and
   * not yet acknowledged (re-sent whole after a reconnect). in_unwanted: a dropped range's, sent
   * to its end only because the coordinator takes an upload's chunks in order on a connection,
   * then freed (or freed with the connection). */
  uint8_t *inflight; size_t inflight_len, inflight_cap;
  uint32_t in_next; bool in_unwanted;
  uint64_t in_job, in_range, in_first, in_count, in_raw; bool in_final;
  pc_render_stats in_stats;
  /* a bundle being received */
  uint8_t *bun; size_t bun_len; uint8_t bun_hash[PC_BUNDLE_HASH]; bool bun_wait;
  Pcbpt__Assign *pending_assign;
};
typedef struct pc_worker worker;

static double now_s(void) { return (double)uv_hrtime() * 1e-9; }

/* Only once authenticated: the coordinator opens every frame after the AuthResponse as sealed,
 * and a range's messages belong to the connection it was assigned on anyway. */
static void send_env(worker *w, Pcbpt__Envelope *env) {
  if (w->conn && w->connected && w->authed) pc_conn_send(w->conn, env);
}

static void request_work(worker *w) {
  /* (an assignment waiting for its bundle is work in hand) */
  if (!w->authed || w->busy || w->waiting_work || w->bun_wait) return;
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__WorkRequest m = PCBPT__WORK_REQUEST__INIT;
  uv_mutex_lock(&w->r.mu);
  m.iterations_per_second = w->r.rate;
  m.upload_seconds = w->r.zip_seconds;
  uv_mutex_unlock(&w->r.mu);
  env.msg_case = PCBPT__ENVELOPE__MSG_WORK_REQUEST;
  env.work_request = &m;
  w->waiting_work = true;
  send_env(w, &env);
}

static void send_heartbeat(worker *w) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Heartbeat h = PCBPT__HEARTBEAT__INIT;
  uv_mutex_lock(&w->r.mu);
  h.iterations_per_second = w->r.rate;
  h.iterations_done = w->r.rendered;
  if (w->busy && w->r.rend) h.iteration_fraction = pc_renderer_progress(w->r.rend);
  uv_mutex_unlock(&w->r.mu);
  if (w->busy) { h.job_id = w->job; h.range_id = w->range; }
  env.msg_case = PCBPT__ENVELOPE__MSG_HEARTBEAT;
  env.heartbeat = &h;
  send_env(w, &env);
}

/* Hands the connection the upload's next chunks while fewer than PC_WORKER_SEND_WINDOW bytes
 * wait in its bulk queue, and the rest as it drains (on_drain): the frames of a whole upload,
 * queued at once, were a second copy of the compressed film for as long as it took to send. */
#define PC_WORKER_SEND_WINDOW (3 * (size_t)PC_WIRE_CHUNK)
static void pump(worker *w);

static uint32_t upload_chunks(const worker *w) {
  size_t n = (w->inflight_len + PC_WIRE_CHUNK - 1) / PC_WIRE_CHUNK;
  return n ? (uint32_t)n : 1;
}

static void free_inflight(worker *w) {
  uv_mutex_lock(&w->r.mu);
  pc_big_spare_keep(&w->r.spare, w->inflight, w->inflight_cap);
  uv_mutex_unlock(&w->r.mu);
  w->inflight = NULL;
  w->in_unwanted = false;
}

static void send_upload(worker *w) {
  if (!w->inflight || !w->conn || !w->authed) return;
  Pcbpt__RenderStats st = PCBPT__RENDER_STATS__INIT;
  st.rays = w->in_stats.rays;
  st.t_paths = w->in_stats.t_paths;
  st.t_lt = w->in_stats.t_lt;
  st.t_pmf = w->in_stats.t_pmf;
  st.t_connect = w->in_stats.t_connect;
  st.pmf_bytes = w->in_stats.pmf_bytes;
  st.t_total = w->in_stats.t_total;
  st.t_cpu = w->in_stats.t_cpu;
  uint32_t nchunks = upload_chunks(w);
  while (w->in_next < nchunks && w->conn->bulk_queued < PC_WORKER_SEND_WINDOW) {
    size_t off = (size_t)w->in_next * PC_WIRE_CHUNK;
    Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
    Pcbpt__UploadChunk u = PCBPT__UPLOAD_CHUNK__INIT;
    u.job_id = w->in_job;
    u.range_id = w->in_range;
    u.first = w->in_first;
    u.count = w->in_count;
    u.index = w->in_next;
    u.nchunks = nchunks;
    u.raw_size = w->in_raw;
    u.final = w->in_final;
    u.stats = &st;
    u.data.data = w->inflight + off;
    u.data.len = w->inflight_len - off < PC_WIRE_CHUNK ? w->inflight_len - off : PC_WIRE_CHUNK;
    env.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK;
    env.upload_chunk = &u;
    int r = pc_conn_send_bulk(w->conn, &env);
    if (r != 0) {
      /* a chunk that cannot be queued (out of memory) would leave the coordinator waiting for
       * it: the connection goes, and the upload is sent whole on the next one */
      pc_conn_close(w->conn, uv_strerror(r));
      return;
    }
    w->in_next++;
  }
  if (w->in_next == nchunks && w->in_unwanted) {
    free_inflight(w);
    pump(w);
  }
}

/* Sends the upload from its first chunk (a new one, or the last one again after a reconnect). */
static void send_inflight(worker *w) {
  if (!w->inflight || !w->authed) return;
  w->in_next = 0;
  w->last_upload = now_s();
  send_upload(w);
}

/* The upload is no longer waited for: freed, unless it is part sent (then sent to its end). */
static void forget_inflight(worker *w) {
  if (w->in_unwanted) return;
  if (w->in_next > 0 && w->in_next < upload_chunks(w)) {
    pc_wire_log("job %llu: range %llu's upload was dropped with %u of its %u chunks sent; sending the rest",
                (unsigned long long)w->in_job, (unsigned long long)w->in_range, w->in_next, upload_chunks(w));
    w->in_unwanted = true;
    return;
  }
  free_inflight(w);
}

static void on_drain(pc_conn *c) { send_upload(c->data); }

/* Halted with nothing rendered since the last upload: an upload of no iterations tells the
 * coordinator the range ends here, or it would wait for one that never comes. */
static void send_closing(worker *w) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__UploadChunk u = PCBPT__UPLOAD_CHUNK__INIT;
  u.job_id = w->job;
  u.range_id = w->range;
  uv_mutex_lock(&w->r.mu);
  u.first = w->r.pend_first;
  uv_mutex_unlock(&w->r.mu);
  u.nchunks = 1;
  u.final = true;
  env.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK;
  env.upload_chunk = &u;
  send_env(w, &env);
}

/* Tells the coordinator a range cannot be rendered here (it counts towards failing the job,
 * with this reason) and asks again only after a pause, so a failing worker does not spin. */
static void give_back(worker *w, uint64_t job, uint64_t range, const char *why) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__RangeFailed f = PCBPT__RANGE_FAILED__INIT;
  f.job_id = job;
  f.range_id = range;
  f.reason = (char *)why;
  env.msg_case = PCBPT__ENVELOPE__MSG_RANGE_FAILED;
  env.range_failed = &f;
  send_env(w, &env);
  w->next_request = now_s() + 0.5;
}

/* The render thread is idle and nothing of the range is left to take: ask for the next one
 * (a final delta may still wait for its acknowledgement). */
static void finish_range(worker *w) {
  w->busy = false;
  w->drop = w->stopping = false;
  request_work(w);
}

/* Seconds between uploads within a range (pc_worker_opts.upload_share), by what the last
 * upload took to compress or, before the first, by the film's size: a one-worker farm's
 * first range is its whole job (range_size.h), and its first upload would otherwise come
 * after PC_WIRE_UPLOAD_INTERVAL, at the cost of the probe it replaced. */
static double upload_interval(const worker *w, double zip_seconds, const pc_render_settings *set) {
  if (!(zip_seconds > 0))
    zip_seconds = PC_WIRE_ZIP_SECONDS_PER_BYTE * (double)pc_film_bytes(set->width, set->height, set->strategy_layers);
  double t = pc_wire_upload_spacing(zip_seconds, w->upload_share);
  return t < PC_WIRE_UPLOAD_INTERVAL ? PC_WIRE_UPLOAD_INTERVAL : t;
}

/* Takes the pending delta for upload when due; finishes the range when all is acknowledged. */
static void pump(worker *w) {
  uv_mutex_lock(&w->r.mu);
  /* an upload compressed for a range that ended without it (dropped) goes */
  if (w->r.zip_ready && (!w->busy || w->drop || w->r.zip_range != w->range)) {
    pc_big_spare_keep(&w->r.spare, w->r.zip, w->r.zip_cap);
    w->r.zip = NULL;
    w->r.zip_ready = false;
  }
  bool done = w->r.range_done, failed = w->r.failed;
  uint64_t pend = w->r.pend_count, rendered = w->r.rendered;
  double rate = w->r.rate, interval = upload_interval(w, w->r.zip_seconds, &w->r.set);
  uv_mutex_unlock(&w->r.mu);
  if (!w->busy) return;
  if (done && failed) {
    pc_wire_log("job %llu: render failed: %s; giving the range back", (unsigned long long)w->job, w->r.error);
    give_back(w, w->job, w->range, w->r.error);
    w->busy = false;
    w->drop = w->stopping = false;
    return;
  }
  if (w->drop) {
    if (done) finish_range(w);
    return;
  }
  if (w->inflight) return;
  uv_mutex_lock(&w->r.mu);
  bool zip = w->r.zip_ready;
  if (zip) {
    /* everything of the range is in it when the thread had finished and nothing is pending */
    bool all = done && w->r.pend_count == 0 && (rendered == w->count || w->stopping || atomic_load(&w->r.cancel));
    w->inflight = w->r.zip;
    w->inflight_len = w->r.zip_len;
    w->inflight_cap = w->r.zip_cap;
    w->in_first = w->r.zip_first;
    w->in_count = w->r.zip_count;
    w->in_stats = w->r.zip_stats;
    w->in_raw = w->r.zip_raw;
    w->r.zip = NULL;
    w->r.zip_ready = false;
    uv_mutex_unlock(&w->r.mu);
    w->in_job = w->job;
    w->in_range = w->range;
    w->in_final = all;
    send_inflight(w);
    if (all) finish_range(w);
    return;
  }
  uv_mutex_unlock(&w->r.mu);
  if (pend == 0) {
    if (done && w->stopping) send_closing(w);
    if (done) finish_range(w);
    return;
  }
  if (!w->authed) return;
  if (!done) {
    if (now_s() - w->last_upload < interval) return;
    /* the range's final upload is due within an interval anyway: every upload costs a whole
     * film on both sides whatever it holds, and this keeps a range of up to two intervals
     * to one upload (at most about two intervals of work unacknowledged) */
    if (rate > 0 && (double)(w->count - rendered) / rate < interval) return;
  }
  pc_wrender_take(&w->r);
}

static void on_notify(uv_async_t *a) { pump(a->data); }
static void on_pump(uv_timer_t *t) {
  worker *w = t->data;
  pump(w);
  if (!w->busy && now_s() >= w->next_request) request_work(w);
}

static void start_range(worker *w, const Pcbpt__Assign *a, const char *scene) {
  pc_render_settings s;
  pc_err e;
  char root[1200];
  /* the bundle's folder is the scene's root there, as the client's root folder was */
  int bad = pc_bundle_dir(w->cache, a->bundle_hash.data, root, sizeof root) != 0 ? pc_errf(&e, PC_ELIMIT, "cache path too long") : 0;
  if (bad || pc_wire_settings_from_proto(a->settings, &s, &e) != 0) {
    pc_wire_log("job %llu: cannot start range %llu: %s", (unsigned long long)a->job_id, (unsigned long long)a->range_id, e.msg);
    give_back(w, a->job_id, a->range_id, e.msg);
    return;
  }
  pc_wrender_assign(&w->r, a->job_id, a->range_id, a->first, a->count, &s, scene, root);
  w->busy = true;
  w->job = a->job_id;
  w->range = a->range_id;
  w->count = a->count;
  w->drop = w->stopping = false;
  w->last_upload = now_s();
}

static void on_assign(worker *w, Pcbpt__Envelope *env) {
  Pcbpt__Assign *a = env->assign;
  w->waiting_work = false;
  if (w->busy || a->bundle_hash.len != PC_BUNDLE_HASH || a->count == 0) {
    pc_conn_close(w->conn, "unexpected or malformed assignment");
    return;
  }
  char scene[1200];
  if (pc_bundle_lookup(w->cache, a->bundle_hash.data, scene, sizeof scene)) {
    start_range(w, a, scene);
    return;
  }
  /* keep the assignment until the bundle is here */
  env->msg_case = PCBPT__ENVELOPE__MSG__NOT_SET;
  env->assign = NULL;
  w->pending_assign = a;
  memcpy(w->bun_hash, a->bundle_hash.data, PC_BUNDLE_HASH);
  w->bun_len = 0;
  w->bun_wait = true;
  Pcbpt__Envelope req = PCBPT__ENVELOPE__INIT;
  Pcbpt__BundleRequest br = PCBPT__BUNDLE_REQUEST__INIT;
  br.hash.data = w->bun_hash;
  br.hash.len = PC_BUNDLE_HASH;
  req.msg_case = PCBPT__ENVELOPE__MSG_BUNDLE_REQUEST;
  req.bundle_request = &br;
  send_env(w, &req);
}

static void on_bundle_chunk(worker *w, const Pcbpt__BundleChunk *b) {
  if (!w->bun_wait || b->hash.len != PC_BUNDLE_HASH || memcmp(b->hash.data, w->bun_hash, PC_BUNDLE_HASH) ||
      b->offset != w->bun_len || b->total > PC_BUNDLE_MAX || b->offset + b->data.len > b->total) {
    pc_conn_close(w->conn, "bundle chunk does not continue the transfer");
    return;
  }
  if (b->offset == 0) {
    free(w->bun);
    w->bun = malloc(b->total ? b->total : 1);
    if (!w->bun) { pc_conn_close(w->conn, "out of memory for a bundle"); return; }
  }
  memcpy(w->bun + w->bun_len, b->data.data, b->data.len);
  w->bun_len += b->data.len;
  if (w->bun_len < b->total) return;
  char scene[1200];
  pc_err e;
  int rc = pc_bundle_unpack(w->bun, w->bun_len, w->bun_hash, w->cache, scene, sizeof scene, &e);
  free(w->bun);
  w->bun = NULL;
  w->bun_wait = false;
  Pcbpt__Assign *a = w->pending_assign;
  w->pending_assign = NULL;
  if (rc) {
    /* the range fails, not the connection: the job fails after a few such ranges with this
     * reason, where reconnecting would fetch the same bundle forever */
    char why[sizeof e.msg + 32];
    snprintf(why, sizeof why, "scene bundle refused: %s", e.msg);
    pc_wire_log("job %llu: %s", (unsigned long long)a->job_id, why);
    give_back(w, a->job_id, a->range_id, why);
  } else {
    start_range(w, a, scene);
  }
  pcbpt__assign__free_unpacked(a, NULL);
}

static void on_cancel(worker *w, const Pcbpt__Cancel *c) {
  if (w->bun_wait && w->pending_assign && w->pending_assign->job_id == c->job_id) {
    /* the range waits for its bundle: nothing to render or upload, only to forget */
    w->bun_wait = false;
    free(w->bun);
    w->bun = NULL;
    pcbpt__assign__free_unpacked(w->pending_assign, NULL);
    w->pending_assign = NULL;
    w->next_request = now_s() + 0.5;
    return;
  }
  /* an upload of a dropped range (this one or the last) is not waited for: nothing would
   * be uploaded after it */
  if (!c->upload_partial && w->inflight && w->in_job == c->job_id && (!c->range_id || c->range_id == w->in_range))
    forget_inflight(w);
  if (!w->busy || c->job_id != w->job || (c->range_id && c->range_id != w->range)) {
    pump(w);
    return;
  }
  atomic_store(&w->r.cancel, true);
  if (c->upload_partial) {
    w->stopping = true;
    pc_wire_log("job %llu: halted; uploading what is rendered", (unsigned long long)w->job);
  } else {
    w->drop = true;
    pc_wire_log("job %llu: range %llu cancelled", (unsigned long long)w->job, (unsigned long long)w->range);
  }
  pump(w);
}

static void on_ack(worker *w, const Pcbpt__UploadAck *a) {
  if (!w->inflight || a->range_id != w->in_range) return;
  if (a->refused && !(w->busy && w->in_range == w->range)) {
    pc_wire_log("job %llu: last upload for range %llu refused: %s", (unsigned long long)w->in_job,
                (unsigned long long)w->in_range, a->reason);
  } else if (a->refused) {
    pc_wire_log("job %llu: upload for range %llu refused: %s; dropping the range", (unsigned long long)w->job,
                (unsigned long long)w->range, a->reason);
    atomic_store(&w->r.cancel, true);
    w->drop = true;
  }
  free_inflight(w);
  pump(w);
}

static void schedule_reconnect(worker *w);
static void token_mismatch(worker *w, pc_conn *c);

static void on_msg(pc_conn *c, Pcbpt__Envelope *env) {
  worker *w = c->data;
  switch (env->msg_case) {
  case PCBPT__ENVELOPE__MSG_CHALLENGE: {
    Pcbpt__Challenge *ch = env->challenge;
    if (w->authed || ch->nonce.len != PC_AUTH_NONCE) {
      pc_conn_close(c, "malformed challenge");
      return;
    }
    if (!pc_auth_verify(w->key, true, w->cnonce, ch->nonce.data, ch->server_mac.data, ch->server_mac.len)) {
      token_mismatch(w, c);
      return;
    }
    uint8_t mac[PC_AUTH_MAC];
    if (pc_auth_mac(w->key, false, ch->nonce.data, w->cnonce, mac) != 0) { pc_conn_close(c, "auth: MAC failed"); return; }
    memcpy(w->snonce, ch->nonce.data, PC_AUTH_NONCE);
    w->challenged = true;
    Pcbpt__Envelope out = PCBPT__ENVELOPE__INIT;
    Pcbpt__AuthResponse ar = PCBPT__AUTH_RESPONSE__INIT;
    ar.mac.data = mac;
    ar.mac.len = PC_AUTH_MAC;
    out.msg_case = PCBPT__ENVELOPE__MSG_AUTH_RESPONSE;
    out.auth_response = &ar;
    pc_conn_send(c, &out);
    return;
  }
  case PCBPT__ENVELOPE__MSG_AUTH_RESULT:
    if (!env->auth_result->ok) { token_mismatch(w, c); return; }
    if (w->authed || !w->challenged) { pc_conn_close(c, "auth_result out of order"); return; }
    if (pc_conn_seal(c, w->key, false, w->cnonce, w->snonce) != 0) return;
    w->authed = true;
    w->backoff = 0.5;
    pc_wire_log("connected to %s:%d", w->host, w->port);
    send_heartbeat(w);
    if (w->inflight) send_inflight(w);
    if (!w->busy) request_work(w);
    else pump(w);
    return;
  case PCBPT__ENVELOPE__MSG_ERROR:
    pc_wire_log("coordinator: %s", env->error->reason);
    return;
  default:
    break;
  }
  if (!w->authed) { pc_conn_close(c, "unexpected message before authentication"); return; }
  switch (env->msg_case) {
  case PCBPT__ENVELOPE__MSG_ASSIGN: on_assign(w, env); return;
  case PCBPT__ENVELOPE__MSG_NO_WORK:
    /* asked again by the pump timer once retry_ms has passed */
    w->waiting_work = false;
    w->next_request = now_s() + (env->no_work->retry_ms > 10000 ? 10000 : env->no_work->retry_ms) / 1000.0;
    return;
  case PCBPT__ENVELOPE__MSG_WORK_AVAILABLE:
    if (!w->busy) {
      w->next_request = 0;
      request_work(w);
    }
    return;
  case PCBPT__ENVELOPE__MSG_BUNDLE_CHUNK: on_bundle_chunk(w, env->bundle_chunk); return;
  case PCBPT__ENVELOPE__MSG_CANCEL: on_cancel(w, env->cancel); return;
  case PCBPT__ENVELOPE__MSG_UPLOAD_ACK: on_ack(w, env->upload_ack); return;
  default:
    pc_conn_close(c, "unexpected message from the coordinator");
  }
}

static void on_closed(pc_conn *c) {
  worker *w = c->data;
  free(c);
  w->conn = NULL;
  /* no part of the upload is on a connection now; a dropped range's was sent only to finish
   * this connection's stream */
  w->in_next = 0;
  if (w->in_unwanted) free_inflight(w);
  if (w->shutting_down) return;
  w->connected = w->challenged = w->authed = w->waiting_work = false;
  if (w->bun_wait) {
    /* the range was never started: the coordinator takes it back */
    w->bun_wait = false;
    free(w->bun);
    w->bun = NULL;
    if (w->pending_assign) pcbpt__assign__free_unpacked(w->pending_assign, NULL);
    w->pending_assign = NULL;
  }
  schedule_reconnect(w);
}

static void on_connect(uv_connect_t *req, int status) {
  pc_conn *c = (pc_conn *)req->handle->data;
  worker *w = c->data;
  free(req);
  if (status < 0) {
    pc_wire_log("cannot connect to %s:%d: %s (retrying in %.1f s)", w->host, w->port, uv_strerror(status), w->backoff);
    pc_conn_close(c, NULL);
    return;
  }
  int r = pc_conn_start(c);
  if (r) { pc_conn_close(c, uv_strerror(r)); return; }
  w->connected = true;
  pc_auth_nonce(w->cnonce);
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Hello h = PCBPT__HELLO__INIT;
  h.protocol_version = PC_WIRE_PROTOCOL_VERSION;
  h.role = PCBPT__ROLE__ROLE_WORKER;
  h.name = w->name;
  h.threads = (uint32_t)w->threads;
  h.client_nonce.data = w->cnonce;
  h.client_nonce.len = PC_AUTH_NONCE;
  env.msg_case = PCBPT__ENVELOPE__MSG_HELLO;
  env.hello = &h;
  pc_conn_send(c, &env);
}

static void try_connect(uv_timer_t *t) {
  worker *w = t->data;
  struct addrinfo hints = {.ai_socktype = SOCK_STREAM, .ai_family = AF_UNSPEC}, *ai = NULL;
  char port[16];
  snprintf(port, sizeof port, "%d", w->port);
  int g = getaddrinfo(w->host, port, &hints, &ai);
  if (g != 0) {
    pc_wire_log("%s: %s (retrying)", w->host, gai_strerror(g));
    schedule_reconnect(w);
    return;
  }
  pc_conn *c = malloc(sizeof *c);
  uv_connect_t *req = malloc(sizeof *req);
  pc_conn_cbs cbs = {.on_msg = on_msg, .on_drain = on_drain, .on_closed = on_closed};
  int r = !c || !req ? UV_ENOMEM : pc_conn_init(w->loop, c, &cbs, w, PC_WIRE_MAX_FRAME);
  if (r) {
    free(c);
    free(req);
    freeaddrinfo(ai);
    pc_wire_log("connect: %s", uv_strerror(r));
    schedule_reconnect(w);
    return;
  }
  w->conn = c;
  r = uv_tcp_connect(req, &c->tcp, ai->ai_addr, on_connect);
  freeaddrinfo(ai);
  if (r) {
    free(req);
    pc_wire_log("connect: %s", uv_strerror(r));
    pc_conn_close(c, NULL);
  }
}

static void schedule_reconnect(worker *w) {
  double d = w->backoff;
  w->backoff = w->backoff * 2 > 10 ? 10 : w->backoff * 2;
  int r = uv_timer_start(&w->retry, try_connect, (uint64_t)(d * 1000), 0);
  if (r) pc_wire_log("reconnect timer: %s", uv_strerror(r));
}

static void on_beat(uv_timer_t *t) {
  worker *w = t->data;
  if (w->authed) send_heartbeat(w);
}

static void close_handle(uv_handle_t *h) {
  if (!uv_is_closing(h)) uv_close(h, NULL);
}

/* Closes every handle but `notify` (the render thread may still signal it; unreferenced, it
 * does not keep the loop alive) so the loop ends. */
static void shut_down(worker *w) {
  if (w->shutting_down) return;
  w->shutting_down = true;
  if (w->conn) pc_conn_close(w->conn, NULL);
  close_handle((uv_handle_t *)&w->retry);
  close_handle((uv_handle_t *)&w->beat);
  close_handle((uv_handle_t *)&w->pump);
  close_handle((uv_handle_t *)&w->stop);
  uv_unref((uv_handle_t *)&w->notify);
  if (w->handle_signals) {
    close_handle((uv_handle_t *)&w->sigint);
    close_handle((uv_handle_t *)&w->sigterm);
  }
}

static void walk_close(uv_handle_t *h, void *arg) {
  (void)arg;
  close_handle(h);
}

static void on_stop(uv_async_t *a) { shut_down(a->data); }

/* Neither side can tell which token is the wrong one, only that they differ; a worker with
 * the wrong token would fail the same way forever, so it stops and says so. */
static void token_mismatch(worker *w, pc_conn *c) {
  pc_wire_log("the coordinator at %s:%d holds a different token than this worker's --token-file: stopping", w->host, w->port);
  w->wrong_token = true;
  pc_conn_close(c, NULL);
  shut_down(w);
}

static void on_signal(uv_signal_t *s, int signum) {
  worker *w = s->data;
  pc_wire_log("signal %d: stopping", signum);
  shut_down(w);
}

int pc_worker_create(const pc_worker_opts *o, pc_worker **out, pc_err *e) {
  worker *w = calloc(1, sizeof *w);
  if (!w) return pc_errf(e, PC_ENOMEM, "worker: out of memory");
  snprintf(w->host, sizeof w->host, "%s", o->host);
  w->port = o->port;
  memcpy(w->key, o->key, PC_AUTH_KEY);
  w->threads = o->threads;
  w->handle_signals = o->handle_signals;
  w->upload_share = o->upload_share;
  snprintf(w->cache, sizeof w->cache, "%s", o->cache_dir);
  if (o->name) snprintf(w->name, sizeof w->name, "%s", o->name);
  else {
    char hostname[64] = "worker";
    if (gethostname(hostname, sizeof hostname - 1) != 0) snprintf(hostname, sizeof hostname, "worker");
    snprintf(w->name, sizeof w->name, "%.40s-%ld", hostname, (long)getpid()); /* fits: 40 + 1 + 20 < 64 */
  }
  if (mkdir(w->cache, 0700) != 0 && errno != EEXIST) {
    int rc = pc_errf(e, PC_EIO, "%s: %s", w->cache, strerror(errno));
    free(w);
    return rc;
  }
  w->backoff = 0.5;
  int r = uv_loop_init(&w->loop_storage);
  if (r) { free(w); return pc_errf(e, PC_EIO, "worker: loop: %s", uv_strerror(r)); }
  w->loop = &w->loop_storage;
  w->notify.data = w->stop.data = w->retry.data = w->beat.data = w->pump.data = w->sigint.data = w->sigterm.data = w;
  if ((r = uv_async_init(w->loop, &w->notify, on_notify)) != 0 || (r = uv_async_init(w->loop, &w->stop, on_stop)) != 0 ||
      (r = uv_timer_init(w->loop, &w->retry)) != 0 || (r = uv_timer_init(w->loop, &w->beat)) != 0 ||
      (r = uv_timer_init(w->loop, &w->pump)) != 0 || (r = uv_timer_start(&w->beat, on_beat, 1000, 1000)) != 0 ||
      (r = uv_timer_start(&w->pump, on_pump, 250, 250)) != 0 || (r = uv_timer_start(&w->retry, try_connect, 0, 0)) != 0)
    goto uv_fail;
  if (w->handle_signals &&
      ((r = uv_signal_init(w->loop, &w->sigint)) != 0 || (r = uv_signal_init(w->loop, &w->sigterm)) != 0 ||
       (r = uv_signal_start(&w->sigint, on_signal, SIGINT)) != 0 || (r = uv_signal_start(&w->sigterm, on_signal, SIGTERM)) != 0))
    goto uv_fail;
  if ((r = pc_wrender_start(&w->r, w->threads, o->max_film, &w->notify, e)) != 0) {
    shut_down(w);
    close_handle((uv_handle_t *)&w->notify);
    uv_run(w->loop, UV_RUN_DEFAULT);
    uv_loop_close(w->loop);
    free(w);
    return r;
  }
  *out = w;
  return 0;
uv_fail:
  pc_errf(e, PC_EIO, "worker: libuv initialisation failed: %s", uv_strerror(r));
  /* handles initialised so far are closed by walking the loop */
  uv_walk(w->loop, walk_close, NULL);
  uv_run(w->loop, UV_RUN_DEFAULT);
  uv_loop_close(w->loop);
  free(w);
  return PC_EIO;
}

int pc_worker_run(pc_worker *w, pc_err *e) {
  uv_run(w->loop, UV_RUN_DEFAULT);
  if (w->wrong_token)
    return pc_errf(e, PC_EINVAL, "the coordinator at %s:%d holds a different token than --token-file", w->host, w->port);
  return 0;
}

void pc_worker_stop(pc_worker *w) { uv_async_send(&w->stop); }

void pc_worker_destroy(pc_worker *w) {
  if (!w) return;
  shut_down(w);
  uv_run(w->loop, UV_RUN_DEFAULT);
  pc_wrender_stop(&w->r);
  close_handle((uv_handle_t *)&w->notify);
  uv_run(w->loop, UV_RUN_DEFAULT);
  if (uv_loop_close(w->loop) != 0) pc_wire_log("worker: loop still has open handles");
  free(w->inflight);
  free(w->bun);
  if (w->pending_assign) pcbpt__assign__free_unpacked(w->pending_assign, NULL);
  sodium_memzero(w->key, sizeof w->key);
  free(w);
}
