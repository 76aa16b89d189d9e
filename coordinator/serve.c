/* serve.c: `pcbpt-coord serve`: the coordinator's libuv loop: accepting connections, the
 * hello/challenge/response handshake, dispatching each peer's messages by role, assembling
 * uploads and bundles, liveness, and the periodic tick that drives checkpoints and halting.
 * Any protocol violation closes that peer's connection with a logged reason only. */
#include <errno.h>
#include <fcntl.h>
#include <malloc.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "big_alloc.h"
#include "coord.h"
#include "render_flags.h"
#include "serve.h"
#include "verbs.h"
#include "wire_film.h"
#include "wire_log.h"
#include "wire_settings.h"

#define HANDSHAKE_TIMEOUT 10.0
#define MAX_BUFFERED ((size_t)64 << 20)
/* Before authentication a peer may only say hello and answer the challenge (a few hundred
 * bytes): its frames are bounded by HANDSHAKE_MAX_FRAME and at most MAX_HANDSHAKES such
 * peers are connected at once, so strangers cannot make the coordinator hold memory. */
#define HANDSHAKE_MAX_FRAME 4096
#define MAX_HANDSHAKES 128

double pc_coord_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static const char *const state_names[] = {"queued", "running", "stopping", "done", "failed", "cancelled"};
const char *pc_job_state_name(pc_job_state s) { return state_names[s]; }
int pc_job_state_parse(const char *s, pc_job_state *out) {
  for (int i = 0; i < 6; i++)
    if (s && strcmp(s, state_names[i]) == 0) { *out = (pc_job_state)i; return 0; }
  return PC_EINVAL;
}

pc_job *pc_coord_job(pc_coord *c, uint64_t id) {
  for (pc_job *j = c->jobs; j; j = j->next)
    if (j->id == id) return j;
  return NULL;
}

void pc_peer_ref(pc_peer *p) { p->refs++; }
void pc_peer_unref(pc_peer *p) {
  if (--p->refs == 0) free(p);
}

void pc_coord_buffered(pc_coord *c, long long n, bool merged) {
  c->buffered = n < 0 && (size_t)-n > c->buffered ? 0 : (size_t)((long long)c->buffered + n);
  if (merged && n < 0) c->merging = (size_t)-n > c->merging ? 0 : c->merging - (size_t)-n;
  /* with no merge left to free memory, paused peers resume (and elect a new leader) */
  if (n >= 0 || (c->buffered > c->max_buffered && c->merging > 0)) return;
  for (pc_peer *p = c->peers; p; p = p->next) {
    if (!p->paused) continue;
    p->paused = false;
    int r = pc_conn_pause(&p->conn, false);
    if (r) pc_conn_close(&p->conn, uv_strerror(r));
  }
}

/* Drops the upload being assembled (after a refusal or when the peer goes); its buffer is
 * freed, so an idle peer holds no upload memory. */
static void upload_reset(pc_peer *p) {
  pc_coord_buffered(p->coord, -(long long)p->up_len, false);
  free(p->up_buf);
  p->up_buf = NULL;
  p->up_len = p->up_cap = 0;
  p->up_next = 0;
}

void pc_peer_send_ack(pc_peer *p, uint64_t range_id, uint64_t acked_end, const char *refused) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__UploadAck a = PCBPT__UPLOAD_ACK__INIT;
  a.range_id = range_id;
  a.acked_end = acked_end;
  a.refused = refused != NULL;
  a.reason = (char *)(refused ? refused : "");
  env.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_ACK;
  env.upload_ack = &a;
  pc_conn_send(&p->conn, &env);
}

void pc_peer_send_cancel(pc_peer *p, uint64_t job, uint64_t range, bool upload_partial) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Cancel m = PCBPT__CANCEL__INIT;
  m.job_id = job;
  m.range_id = range;
  m.upload_partial = upload_partial;
  env.msg_case = PCBPT__ENVELOPE__MSG_CANCEL;
  env.cancel = &m;
  pc_conn_send(&p->conn, &env);
}

static void send_error(pc_peer *p, const char *reason) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Error m = PCBPT__ERROR__INIT;
  m.reason = (char *)reason;
  env.msg_case = PCBPT__ENVELOPE__MSG_ERROR;
  env.error = &m;
  pc_conn_send(&p->conn, &env);
}

/* Logs, tells the peer why, and drops it. */
static void drop(pc_peer *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void drop(pc_peer *p, const char *fmt, ...) {
  char why[400];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(why, sizeof why, fmt, ap);
  va_end(ap);
  send_error(p, why);
  pc_conn_close(&p->conn, why);
}

/* ---- handshake ---- */

static void on_hello(pc_peer *p, const Pcbpt__Hello *h) {
  pc_coord *c = p->coord;
  if (h->protocol_version != PC_WIRE_PROTOCOL_VERSION) {
    drop(p, "protocol version %u, this coordinator speaks %u", h->protocol_version, PC_WIRE_PROTOCOL_VERSION);
    return;
  }
  if (h->role != PCBPT__ROLE__ROLE_WORKER && h->role != PCBPT__ROLE__ROLE_CLIENT) { drop(p, "hello without a valid role"); return; }
  if (h->client_nonce.len != PC_AUTH_NONCE) { drop(p, "hello with a %zu-byte nonce", h->client_nonce.len); return; }
  p->role = h->role;
  p->threads = h->threads;
  snprintf(p->name, sizeof p->name, "%s", h->name && *h->name ? h->name : p->conn.peer);
  for (char *s = p->name; *s; s++)
    if ((unsigned char)*s < 0x20 || *s == 0x7f) *s = '?';
  memcpy(p->client_nonce, h->client_nonce.data, PC_AUTH_NONCE);
  pc_auth_nonce(p->nonce);
  uint8_t mac[PC_AUTH_MAC];
  if (pc_auth_mac(c->key, true, p->client_nonce, p->nonce, mac) != 0) { drop(p, "auth: MAC failed"); return; }
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Challenge ch = PCBPT__CHALLENGE__INIT;
  ch.nonce.data = p->nonce;
  ch.nonce.len = PC_AUTH_NONCE;
  ch.server_mac.data = mac;
  ch.server_mac.len = PC_AUTH_MAC;
  env.msg_case = PCBPT__ENVELOPE__MSG_CHALLENGE;
  env.challenge = &ch;
  p->hello_seen = true;
  pc_conn_send(&p->conn, &env);
}

static void on_auth(pc_peer *p, const Pcbpt__AuthResponse *a) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__AuthResult r = PCBPT__AUTH_RESULT__INIT;
  env.msg_case = PCBPT__ENVELOPE__MSG_AUTH_RESULT;
  env.auth_result = &r;
  if (!pc_auth_verify(p->coord->key, false, p->nonce, p->client_nonce, a->mac.data, a->mac.len)) {
    r.reason = "authentication failed (wrong token)";
    pc_conn_send(&p->conn, &env);
    pc_conn_close(&p->conn, "authentication failed (wrong token)");
    return;
  }
  p->authed = true;
  p->conn.dec.max = PC_WIRE_MAX_FRAME; /* the handshake's bound is lifted for the peer's work */
  r.ok = true;
  r.reason = "";
  pc_conn_send(&p->conn, &env);
  /* the last clear frame: the peer sends nothing more until it has read it */
  if (pc_conn_seal(&p->conn, p->coord->key, true, p->client_nonce, p->nonce) != 0) return;
  if (p->role == PCBPT__ROLE__ROLE_WORKER)
    pc_wire_log("%s: worker '%s' joined (%u threads)", p->conn.peer, p->name, p->threads);
}

/* ---- worker messages ---- */

static void on_heartbeat(pc_peer *p, const Pcbpt__Heartbeat *h) {
  pc_coord *c = p->coord;
  if (h->iterations_per_second >= 0 && h->iterations_per_second < 1e9) p->rate = h->iterations_per_second;
  double frac = h->iteration_fraction >= 0 && h->iteration_fraction < 1 ? h->iteration_fraction : 0;
  if (h->range_id && h->range_id == p->hb_range && (h->iterations_done != p->hb_done || frac != p->hb_frac))
    p->hb_advanced = p->last_seen;
  p->hb_range = h->range_id;
  p->hb_done = h->iterations_done;
  p->hb_frac = frac;
  p->hb_time = p->last_seen;
  if (!h->range_id) return;
  p->rate_job = h->job_id; /* a busy worker's rate is measured on the job it renders */
  pc_job *j = pc_coord_job(c, h->job_id);
  pc_range *r = j && (j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING) ? pc_sched_find_range(j, h->range_id) : NULL;
  if (r && r->owner == p) return;
  if (r && !r->owner && !r->final && !r->revoked && r->acked < r->count) {
    r->owner = p;
    r->orphan_since = 0;
    r->progress_at = p->last_seen; /* (measured_at stays 0: no measure across a re-attach) */
    pc_wire_log("job %llu: range %llu re-attached to %s", (unsigned long long)j->id, (unsigned long long)r->id, p->name);
    if (j->state == PC_JOB_STOPPING) pc_peer_send_cancel(p, j->id, r->id, true);
    return;
  }
  pc_peer_send_cancel(p, h->job_id, h->range_id, false);
}

static void on_range_failed(pc_peer *p, const Pcbpt__RangeFailed *f) {
  pc_coord *c = p->coord;
  pc_job *j = pc_coord_job(c, f->job_id);
  pc_range *r = j ? pc_sched_find_range(j, f->range_id) : NULL;
  if (!r || r->owner != p) return;
  char why[300];
  snprintf(why, sizeof why, "%s", f->reason ? f->reason : "");
  for (char *s = why; *s; s++)
    if ((unsigned char)*s < 0x20 || *s == 0x7f) *s = '?';
  pc_job_range_failed(c, j, r, p->name, why);
}

static void stream_next(pc_peer *p) {
  pc_stream_out *o = &p->out;
  if (o->fd < 0) return;
  uint8_t buf[PC_WIRE_CHUNK];
  size_t want = o->total - o->off < sizeof buf ? (size_t)(o->total - o->off) : sizeof buf;
  ssize_t n = want ? pread(o->fd, buf, want, (off_t)o->off) : 0;
  if (n < 0 || (size_t)n != want) {
    close(o->fd);
    o->fd = -1;
    drop(p, "reading a file to send failed: %s", n < 0 ? strerror(errno) : "short read");
    return;
  }
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__BundleChunk bc = PCBPT__BUNDLE_CHUNK__INIT;
  Pcbpt__FetchChunk fc = PCBPT__FETCH_CHUNK__INIT;
  if (o->is_bundle) {
    bc.hash.data = o->hash;
    bc.hash.len = PC_BUNDLE_HASH;
    bc.offset = o->off;
    bc.total = o->total;
    bc.data.data = buf;
    bc.data.len = (size_t)n;
    env.msg_case = PCBPT__ENVELOPE__MSG_BUNDLE_CHUNK;
    env.bundle_chunk = &bc;
  } else {
    fc.offset = o->off;
    fc.total = o->total;
    fc.data.data = buf;
    fc.data.len = (size_t)n;
    env.msg_case = PCBPT__ENVELOPE__MSG_FETCH_CHUNK;
    env.fetch_chunk = &fc;
  }
  o->off += (uint64_t)n;
  if (o->off >= o->total) {
    close(o->fd);
    o->fd = -1;
  }
  pc_conn_send_bulk(&p->conn, &env);
}

static void on_drain(pc_conn *conn) { stream_next(conn->data); }

static int stream_file(pc_peer *p, const char *path, bool is_bundle, const uint8_t *hash) {
  if (p->out.fd >= 0) return PC_EINVAL;
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  struct stat st;
  if (fd < 0) return PC_EIO;
  if (fstat(fd, &st) != 0) { close(fd); return PC_EIO; }
  p->out.fd = fd;
  p->out.off = 0;
  p->out.total = (uint64_t)st.st_size;
  p->out.is_bundle = is_bundle;
  if (hash) memcpy(p->out.hash, hash, PC_BUNDLE_HASH);
  stream_next(p);
  return 0;
}

static void on_bundle_request(pc_peer *p, const Pcbpt__BundleRequest *b) {
  char hex[2 * PC_BUNDLE_HASH + 1], path[600];
  if (b->hash.len != PC_BUNDLE_HASH) { drop(p, "bundle request with a %zu-byte hash", b->hash.len); return; }
  pc_bundle_hex(b->hash.data, hex);
  snprintf(path, sizeof path, "%s/bundles/%s", p->coord->data_dir, hex);
  if (p->out.fd >= 0) { drop(p, "bundle %.16s... requested while a transfer is running", hex); return; }
  if (stream_file(p, path, true, b->hash.data) == 0) return;
  /* gone from the data dir: no worker can render the jobs on it (dropping the worker would
   * only have it ask again) */
  char why[200];
  snprintf(why, sizeof why, "scene bundle %.16s... cannot be read from the data dir: %s", hex, strerror(errno));
  for (pc_job *j = p->coord->jobs; j; j = j->next)
    if ((j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING) && memcmp(j->bundle, b->hash.data, PC_BUNDLE_HASH) == 0)
      pc_job_fail(p->coord, j, why);
}

/* Over max_buffered, uploads being assembled are paused, except one while no merge is
 * pending: the one furthest along (ties to the first in the list), so it completes and its
 * merge frees memory. Pausing them all deadlocks once uploads outgrow max_buffered /
 * (their number): a 4K film's are ~40 MB each. */
static bool upload_leader(const pc_coord *c, const pc_peer *p) {
  if (c->merging > 0) return false;
  for (const pc_peer *q = c->peers; q; q = q->next)
    if (q != p && !q->paused && q->up_len > p->up_len) return false;
  for (const pc_peer *q = c->peers; q && q != p; q = q->next)
    if (!q->paused && q->up_len == p->up_len && q->up_len > 0) return false;
  return true;
}

static void on_upload(pc_peer *p, const Pcbpt__UploadChunk *u) {
  pc_coord *c = p->coord;
  if (u->index != p->up_next || u->nchunks == 0 || u->index >= u->nchunks) {
    drop(p, "upload chunk %u/%u out of order (expected %u)", u->index, u->nchunks, p->up_next);
    return;
  }
  pc_job *j = pc_coord_job(c, u->job_id);
  if (u->index == 0) {
    upload_reset(p);
    p->up_job = u->job_id;
    p->up_range = u->range_id;
    p->up_first = u->first;
    p->up_count = u->count;
    p->up_raw = u->raw_size;
    p->up_nchunks = u->nchunks;
    p->up_final = u->final;
    memset(&p->up_stats, 0, sizeof p->up_stats);
    if (u->stats) {
      const Pcbpt__RenderStats *s = u->stats;
      /* informational only, but never let a peer put NaN or nonsense into a header */
      bool ok = s->t_paths >= 0 && s->t_paths < 1e9 && s->t_lt >= 0 && s->t_lt < 1e9 && s->t_pmf >= 0 && s->t_pmf < 1e9 &&
                s->t_connect >= 0 && s->t_connect < 1e9 && s->t_total >= 0 && s->t_total < 1e9 &&
                (s->t_cpu == -1.0 || (s->t_cpu >= 0 && s->t_cpu < 1e9));
      if (ok) {
        p->up_stats.rays = s->rays;
        p->up_stats.t_paths = s->t_paths;
        p->up_stats.t_lt = s->t_lt;
        p->up_stats.t_pmf = s->t_pmf;
        p->up_stats.t_connect = s->t_connect;
        p->up_stats.pmf_bytes = s->pmf_bytes;
        p->up_stats.t_total = s->t_total;
        p->up_stats.t_cpu = s->t_cpu;
      }
    }
  } else if (u->job_id != p->up_job || u->range_id != p->up_range || u->first != p->up_first ||
             u->count != p->up_count || u->raw_size != p->up_raw || u->nchunks != p->up_nchunks) {
    drop(p, "upload chunk %u does not match the upload it continues", u->index);
    return;
  }
  /* bound what one peer can make the coordinator hold: one compressed film of the job */
  size_t limit = j && j->upload_limit ? j->upload_limit : PC_WIRE_CHUNK;
  if (p->up_len + u->data.len > limit) {
    drop(p, "upload for job %llu exceeds %zu bytes", (unsigned long long)u->job_id, limit);
    return;
  }
  if (p->up_len + u->data.len > p->up_cap) {
    /* The first chunk sizes the buffer for the whole upload as announced (within the limit),
     * so it is neither copied as it grows nor faulted in 4 KiB page by page. */
    size_t whole = (size_t)u->nchunks * PC_WIRE_CHUNK;
    size_t cap = p->up_cap ? p->up_cap : (whole < limit ? whole : limit);
    while (cap < p->up_len + u->data.len) cap *= 2;
    if (!p->up_buf) {
      /* the last merged upload's buffer: its written pages are kept, also where it has to grow */
      p->up_buf = pc_big_spare_take(&c->spare_up, &p->up_cap);
      if (cap < p->up_cap) cap = p->up_cap;
    }
    uint8_t *nb = cap == p->up_cap ? p->up_buf : p->up_buf ? realloc(p->up_buf, cap) : pc_big_alloc(cap);
    if (!nb) { drop(p, "out of memory for an upload"); return; }
    p->up_buf = nb;
    p->up_cap = cap;
  }
  if (u->data.len) memcpy(p->up_buf + p->up_len, u->data.data, u->data.len);
  p->up_len += u->data.len;
  pc_coord_buffered(c, (long long)u->data.len, false);
  p->up_next = u->index + 1;
  if (p->up_next < p->up_nchunks) {
    if (c->buffered > c->max_buffered && !p->paused && !upload_leader(c, p)) {
      int r = pc_conn_pause(&p->conn, true);
      if (r) { drop(p, "pause: %s", uv_strerror(r)); return; }
      p->paused = true;
    }
    return;
  }
  p->up_next = 0;
  if (p->up_count == 0) {
    /* a halted worker with nothing rendered since its last upload: the range ends at what is
     * merged, now rather than when the stopping job gives up waiting for it */
    pc_range *r = j && (j->state == PC_JOB_STOPPING || j->state == PC_JOB_RUNNING) ? pc_sched_find_range(j, p->up_range) : NULL;
    if (p->up_final && r && r->owner == p && !r->merging && !r->final && (j->state == PC_JOB_STOPPING || r->stop_asked)) {
      r->final = true;
      j->dirty = true;
    }
    upload_reset(p);
    return;
  }

  const char *refuse = NULL;
  char why[200];
  pc_range *r = NULL;
  if (!j || !j->film_ready || (j->state != PC_JOB_RUNNING && j->state != PC_JOB_STOPPING)) refuse = "job is not running";
  else if (!(r = pc_sched_find_range(j, p->up_range))) refuse = "range is closed or unknown";
  else if (r->owner && r->owner != p) refuse = "range was handed to another worker";
  else if (!r->owner && r->revoked) refuse = "range was taken back (no upload in time)";
  else if (r->merging) refuse = "an upload for this range is still being merged";
  /* in the range, without an overflow of first + count */
  if (!refuse && (p->up_count == 0 || p->up_first < r->first || p->up_first - r->first > r->count ||
                  p->up_count > r->count - (p->up_first - r->first)))
    refuse = "iterations outside the range";
  uint64_t end = p->up_first + p->up_count;
  if (refuse) {
    pc_wire_log("job %llu: refused upload from %s for range %llu: %s", (unsigned long long)p->up_job, p->conn.peer,
                (unsigned long long)p->up_range, refuse);
    pc_peer_send_ack(p, p->up_range, 0, refuse);
    upload_reset(p);
    return;
  }
  if (!r->owner) { r->owner = p; r->orphan_since = 0; }
  if (end <= r->first + r->merged) {
    upload_reset(p);
    /* a re-sent upload already counted: acknowledge, never add twice */
    if (end <= r->first + r->acked) pc_peer_send_ack(p, r->id, r->first + r->acked, NULL);
    else {
      pc_pending_ack *a = calloc(1, sizeof *a);
      if (a) {
        a->peer = p;
        pc_peer_ref(p);
        a->range_id = r->id;
        a->acked_end = r->first + r->merged;
        a->next = j->acks;
        j->acks = a;
      }
    }
    return;
  }
  if (p->up_first != r->first + r->merged) {
    snprintf(why, sizeof why, "upload starts at iteration %llu, the range continues at %llu",
             (unsigned long long)p->up_first, (unsigned long long)(r->first + r->merged));
    pc_wire_log("job %llu: refused upload from %s: %s", (unsigned long long)j->id, p->conn.peer, why);
    pc_peer_send_ack(p, r->id, 0, why);
    upload_reset(p);
    return;
  }
  /* worker-seconds halt study jobs: a delta cannot have taken longer than the time since the
   * range was handed out or last uploaded (plus the time the upload took to come) */
  double since = pc_coord_now() - r->measured_at;
  if (r->measured_at > 0 && p->up_stats.t_total > since + 1) p->up_stats.t_total = since + 1;
  pc_sched_progress(j, r, p, p->up_count);
  /* the bytes stay accounted in c->buffered, and now in c->merging, until the merge frees them */
  uint8_t *buf = p->up_buf;
  size_t len = p->up_len, cap = p->up_cap;
  c->merging += len;
  p->up_buf = NULL;
  p->up_len = p->up_cap = 0;
  pc_job_merge(c, j, p, r, buf, len, cap, p->up_raw, p->up_first, p->up_count, p->up_final, &p->up_stats);
}

/* ---- client messages ---- */

static void on_bundle_chunk(pc_peer *p, const Pcbpt__BundleChunk *b) {
  pc_coord *c = p->coord;
  if (b->hash.len != PC_BUNDLE_HASH || b->total == 0 || b->total > PC_BUNDLE_MAX || b->offset != p->bun_off ||
      b->offset + b->data.len > b->total || (b->offset > 0 && (b->total != p->bun_total || memcmp(b->hash.data, p->bun_hash, PC_BUNDLE_HASH)))) {
    drop(p, "bundle chunk at %llu does not continue the transfer", (unsigned long long)b->offset);
    return;
  }
  if (b->offset == 0) {
    char dir[512];
    snprintf(dir, sizeof dir, "%s/bundles", c->data_dir);
    if (mkdir(dir, 0700) != 0 && errno != EEXIST) { drop(p, "%s: %s", dir, strerror(errno)); return; }
    snprintf(p->bun_tmp, sizeof p->bun_tmp, "%s/.upload.%08x%08x", dir, randombytes_random(), randombytes_random());
    p->bun_fd = open(p->bun_tmp, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (p->bun_fd < 0) { drop(p, "%s: %s", p->bun_tmp, strerror(errno)); return; }
    p->bun_total = b->total;
    memcpy(p->bun_hash, b->hash.data, PC_BUNDLE_HASH);
  }
  size_t done = 0;
  while (done < b->data.len) {
    ssize_t w = write(p->bun_fd, b->data.data + done, b->data.len - done);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0) { drop(p, "%s: %s", p->bun_tmp, strerror(errno)); return; }
    done += (size_t)w;
  }
  p->bun_off += b->data.len;
  if (p->bun_off < p->bun_total) return;
  /* complete: verify the content against its address before anyone can use it */
  int fd = p->bun_fd;
  p->bun_fd = -1;
  p->bun_off = 0;
  uint8_t *blob = pc_big_alloc(p->bun_total);
  int ok = blob && fsync(fd) == 0 && pread(fd, blob, p->bun_total, 0) == (ssize_t)p->bun_total;
  close(fd);
  uint8_t got[PC_BUNDLE_HASH];
  pc_err e;
  char hex[2 * PC_BUNDLE_HASH + 1], final[600];
  pc_bundle_hex(p->bun_hash, hex);
  if (!ok || pc_bundle_hash(blob, p->bun_total, got, &e) != 0 || sodium_memcmp(got, p->bun_hash, PC_BUNDLE_HASH) != 0) {
    free(blob);
    unlink(p->bun_tmp);
    p->bun_tmp[0] = 0;
    drop(p, "refused scene bundle %.16s...: content hash does not match", hex);
    return;
  }
  free(blob);
  snprintf(final, sizeof final, "%s/bundles/%s", c->data_dir, hex);
  if (rename(p->bun_tmp, final) != 0) { drop(p, "%s: %s", final, strerror(errno)); return; }
  p->bun_tmp[0] = 0;
}

static void on_submit(pc_peer *p, const Pcbpt__Submit *s) {
  pc_coord *c = p->coord;
  pc_err e = {0};
  char hex[2 * PC_BUNDLE_HASH + 1], path[600];
  if (s->bundle_hash.len != PC_BUNDLE_HASH) { send_error(p, "submit: missing bundle hash"); return; }
  pc_bundle_hex(s->bundle_hash.data, hex);
  snprintf(path, sizeof path, "%s/bundles/%s", c->data_dir, hex);
  pc_job *j = calloc(1, sizeof *j);
  if (!j) { send_error(p, "submit: out of memory"); return; }
  j->light_per_iter = -1;
  if (access(path, R_OK) != 0) pc_errf(&e, PC_EINVAL, "submit: scene bundle %.16s... was not uploaded", hex);
  else if (pc_wire_settings_from_proto(s->settings, &j->set, &e) != 0) {}
  else if (j->set.width < 1 || j->set.height < 1) pc_errf(&e, PC_EINVAL, "submit: film size missing");
  else if (c->max_film && pc_film_bytes(j->set.width, j->set.height, j->set.strategy_layers) > c->max_film)
    pc_errf(&e, PC_ELIMIT, "submit: the film of a %dx%d job takes %zu MB on the coordinator, more than its %zu MB (its memory, or --max-film-mb)",
            j->set.width, j->set.height, pc_big_mb(pc_film_bytes(j->set.width, j->set.height, j->set.strategy_layers)),
            pc_big_mb(c->max_film));
  else if (s->halt_iterations == 0 && !(s->halt_seconds > 0) && !(s->settings->halt_noise > 0) &&
           !(s->settings->halt_worker_seconds > 0))
    pc_errf(&e, PC_EINVAL, "submit: needs --spp, --time or --halt-noise");
  else if (!(s->settings->halt_worker_seconds >= 0 && s->settings->halt_worker_seconds < 1e9))
    pc_errf(&e, PC_EINVAL, "submit: bad worker-seconds budget");
  else if (s->settings->snapshots > PC_JOB_MAX_SNAPSHOTS || (s->settings->snapshots && !(s->settings->halt_worker_seconds > 0)))
    pc_errf(&e, PC_EINVAL, "submit: snapshots need a worker-seconds budget and are at most %d", PC_JOB_MAX_SNAPSHOTS);
  else if (!(s->halt_seconds >= 0 && s->halt_seconds < 1e9)) pc_errf(&e, PC_EINVAL, "submit: bad --time");
  else if (!(s->settings->halt_noise >= 0 && s->settings->halt_noise <= 1e6)) pc_errf(&e, PC_EINVAL, "submit: bad --halt-noise");
  else if (!(s->settings->prior_amount >= 0 && s->settings->prior_amount < 1e12))
    pc_errf(&e, PC_EINVAL, "submit: bad prior_amount %g", s->settings->prior_amount);
  else if (s->settings->prior_group && !(s->settings->prior_amount > 0))
    pc_errf(&e, PC_EINVAL, "submit: a prior_group needs a prior_amount");
  if (e.code) {
    pc_wire_log("%s: %s", p->conn.peer, e.msg);
    send_error(p, e.msg);
    free(j);
    return;
  }
  memcpy(j->bundle, s->bundle_hash.data, PC_BUNDLE_HASH);
  snprintf(j->name, sizeof j->name, "%s", s->name ? s->name : "");
  for (char *q = j->name; *q; q++)
    if ((unsigned char)*q < 0x20 || *q == 0x7f) *q = '?';
  j->settings_len = pcbpt__settings__get_packed_size(s->settings);
  j->settings_blob = malloc(j->settings_len + 1);
  if (!j->settings_blob) { free(j); send_error(p, "submit: out of memory"); return; }
  pcbpt__settings__pack(s->settings, j->settings_blob);
  j->halt_iterations = s->halt_iterations;
  j->halt_seconds = s->halt_seconds;
  pc_job_take_stored_settings(j, s->settings);
  j->relmse_est = -1;
  j->priority = s->priority;
  j->state = PC_JOB_QUEUED;
  if (pc_store_insert_job(c, j, &e) != 0) {
    pc_wire_log("%s", e.msg);
    send_error(p, e.msg);
    pc_job_free(j);
    return;
  }
  pc_job **tail = &c->jobs;
  while (*tail) tail = &(*tail)->next;
  *tail = j;
  pc_sched_nudge(c);
  pc_wire_log("job %llu: submitted by %s: '%s' %s %dx%d, %llu iterations, %.1f s", (unsigned long long)j->id, p->name,
              j->name, pc_method_name(j->set.method), j->set.width, j->set.height,
              (unsigned long long)j->halt_iterations, j->halt_seconds);
  if (j->auto_report[0]) pc_wire_log("job %llu: --method auto %s", (unsigned long long)j->id, j->auto_report);
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__SubmitReply r = PCBPT__SUBMIT_REPLY__INIT;
  r.job_id = j->id;
  env.msg_case = PCBPT__ENVELOPE__MSG_SUBMIT_REPLY;
  env.submit_reply = &r;
  pc_conn_send(&p->conn, &env);
}

static void send_status(pc_peer *p, uint64_t only) {
  pc_coord *c = p->coord;
  int nj = 0, nw = 0;
  for (pc_job *j = c->jobs; j; j = j->next) nj++;
  for (pc_peer *q = c->peers; q; q = q->next) nw++;
  Pcbpt__JobStatus *js = calloc((size_t)nj + 1, sizeof *js);
  Pcbpt__JobStatus **jp = calloc((size_t)nj + 1, sizeof *jp);
  Pcbpt__WorkerStatus *ws = calloc((size_t)nw + 1, sizeof *ws);
  Pcbpt__WorkerStatus **wp = calloc((size_t)nw + 1, sizeof *wp);
  char(*images)[600] = calloc((size_t)nj + 1, sizeof *images);
  if (!js || !jp || !ws || !wp || !images) { send_error(p, "status: out of memory"); goto done; }
  Pcbpt__StatusReply rep = PCBPT__STATUS_REPLY__INIT;
  size_t k = 0;
  for (pc_job *j = c->jobs; j; j = j->next) {
    if (only && j->id != only) continue;
    Pcbpt__JobStatus *s = &js[k];
    pcbpt__job_status__init(s);
    s->job_id = j->id;
    s->name = j->name;
    s->state = (char *)pc_job_state_name(j->state);
    s->method = (char *)pc_method_name(j->set.method);
    s->iterations_done = j->done;
    s->halt_iterations = j->halt_iterations;
    s->halt_seconds = j->halt_seconds;
    s->halt_noise = j->halt_noise;
    s->relmse_estimate = j->relmse_est;
    s->auto_report = j->auto_report;
    s->worker_seconds = j->stats_merged.t_total;
    s->cpu_seconds = j->stats_merged.t_cpu;
    s->snapshots = j->snaps_taken;
    s->ranges_rerun = j->ranges_rerun;
    s->elapsed = j->elapsed;
    s->iterations_rendered = j->done;
    for (pc_range *r = j->ranges; r && (j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING); r = r->next) {
      /* done counts what is committed (acked); past that, what is merged or merging, or what
       * the owner's heartbeats report (they stop with its last upload) */
      uint64_t got = r->merged + r->in_merge;
      if (r->owner && r->owner->hb_range == r->id && r->owner->hb_done > got) got = r->owner->hb_done;
      if (got > r->count) got = r->count;
      if (got > r->acked) s->iterations_rendered += got - r->acked;
      /* a worker may own two ranges for a moment (the next one starts before the last is acked) */
      bool seen = false;
      for (pc_range *q = j->ranges; q != r && !seen; q = q->next) seen = q->owner == r->owner;
      if (r->owner && !seen) { s->workers++; s->iterations_per_second += r->owner->rate; }
    }
    if (j->state == PC_JOB_RUNNING) {
      double eta_i = j->halt_iterations && s->iterations_per_second > 0
                         ? (double)(j->halt_iterations - (j->done < j->halt_iterations ? j->done : j->halt_iterations)) / s->iterations_per_second
                         : -1;
      double eta_t = j->halt_seconds > 0 ? j->halt_seconds - j->elapsed : -1;
      s->eta_seconds = eta_i >= 0 && (eta_t < 0 || eta_i < eta_t) ? eta_i : eta_t;
    }
    s->error = j->storage_error[0] ? j->storage_error : j->error;
    pc_job_path(c, j, "image.exr", images[k], sizeof images[k]);
    s->image = access(images[k], R_OK) == 0 ? images[k] : "";
    jp[k] = s;
    k++;
  }
  rep.n_jobs = k;
  rep.jobs = jp;
  k = 0;
  for (pc_peer *q = c->peers; q; q = q->next) {
    if (!q->authed || q->role != PCBPT__ROLE__ROLE_WORKER) continue;
    Pcbpt__WorkerStatus *w = &ws[k];
    pcbpt__worker_status__init(w);
    w->name = q->name;
    w->threads = q->threads;
    w->iterations_per_second = q->rate;
    w->address = q->conn.peer;
    for (pc_job *j = c->jobs; j; j = j->next)
      for (pc_range *r = j->ranges; r && (j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING); r = r->next)
        if (r->owner == q) { w->job_id = j->id; w->range_id = r->id; }
    wp[k++] = w;
  }
  rep.n_workers = k;
  rep.workers = wp;
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  env.msg_case = PCBPT__ENVELOPE__MSG_STATUS_REPLY;
  env.status_reply = &rep;
  pc_conn_send(&p->conn, &env);
done:
  free(js); free(jp); free(ws); free(wp); free(images);
}

static void on_fetch(pc_peer *p, uint64_t id, uint32_t snapshot) {
  pc_job *j = pc_coord_job(p->coord, id);
  char path[600], leaf[40];
  if (!j) { send_error(p, "fetch: no such job"); return; }
  if (snapshot > j->snaps_taken) {
    snprintf(leaf, sizeof leaf, "fetch: job %llu has %u snapshots", (unsigned long long)j->id, j->snaps_taken);
    send_error(p, leaf);
    return;
  }
  if (snapshot) snprintf(leaf, sizeof leaf, "snap.%u.exr", snapshot);
  pc_job_path(p->coord, j, snapshot ? leaf : "image.exr", path, sizeof path);
  if (stream_file(p, path, false, NULL) != 0) {
    char why[120];
    snprintf(why, sizeof why, "fetch: job %llu is %s and has no image%s", (unsigned long long)j->id, pc_job_state_name(j->state),
             j->state == PC_JOB_RUNNING || j->state == PC_JOB_QUEUED || j->state == PC_JOB_STOPPING ? " yet" : "");
    send_error(p, why);
  }
}

/* ---- dispatch ---- */

static void on_msg(pc_conn *conn, Pcbpt__Envelope *env) {
  pc_peer *p = conn->data;
  p->last_seen = pc_coord_now();
  int kind = env->msg_case;
  if (!p->hello_seen) {
    if (kind != PCBPT__ENVELOPE__MSG_HELLO) { drop(p, "expected hello, got %s", pc_wire_msg_name(kind)); return; }
    on_hello(p, env->hello);
    return;
  }
  if (!p->authed) {
    if (kind != PCBPT__ENVELOPE__MSG_AUTH_RESPONSE) { drop(p, "expected auth_response, got %s", pc_wire_msg_name(kind)); return; }
    on_auth(p, env->auth_response);
    return;
  }
  if (p->role == PCBPT__ROLE__ROLE_WORKER) {
    switch (kind) {
    case PCBPT__ENVELOPE__MSG_WORK_REQUEST: {
      double rate = env->work_request->iterations_per_second, up = env->work_request->upload_seconds;
      if (rate > 0 && rate < 1e9) p->rate = rate;
      if (up >= 0 && up < 1e6) p->upload_s = up; /* range_size caps what it earns */
      pc_sched_request(p->coord, p);
      return;
    }
    case PCBPT__ENVELOPE__MSG_HEARTBEAT: on_heartbeat(p, env->heartbeat); return;
    case PCBPT__ENVELOPE__MSG_RANGE_FAILED: on_range_failed(p, env->range_failed); return;
    case PCBPT__ENVELOPE__MSG_BUNDLE_REQUEST: on_bundle_request(p, env->bundle_request); return;
    case PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK: on_upload(p, env->upload_chunk); return;
    default: break;
    }
  } else {
    switch (kind) {
    case PCBPT__ENVELOPE__MSG_BUNDLE_CHUNK: on_bundle_chunk(p, env->bundle_chunk); return;
    case PCBPT__ENVELOPE__MSG_SUBMIT: on_submit(p, env->submit); return;
    case PCBPT__ENVELOPE__MSG_STATUS_REQUEST: send_status(p, env->status_request->job_id); return;
    case PCBPT__ENVELOPE__MSG_CANCEL_REQUEST: {
      pc_job *j = pc_coord_job(p->coord, env->cancel_request->job_id);
      if (!j) { send_error(p, "cancel: no such job"); return; }
      bool ended = j->state == PC_JOB_DONE || j->state == PC_JOB_FAILED || j->state == PC_JOB_CANCELLED;
      if (ended && !env->cancel_request->finish) { /* (finishing an ended job is a no-op: a race) */
        char why[80];
        snprintf(why, sizeof why, "cancel: job %llu is %s already", (unsigned long long)j->id, pc_job_state_name(j->state));
        send_error(p, why);
        return;
      }
      if (env->cancel_request->finish) pc_job_halt(p->coord, j);
      else pc_job_cancel(p->coord, j);
      send_status(p, j->id);
      return;
    }
    case PCBPT__ENVELOPE__MSG_FETCH_REQUEST: on_fetch(p, env->fetch_request->job_id, env->fetch_request->snapshot); return;
    default: break;
    }
  }
  drop(p, "unexpected %s from a %s", pc_wire_msg_name(kind), p->role == PCBPT__ROLE__ROLE_WORKER ? "worker" : "client");
}

static void on_closed(pc_conn *conn) {
  pc_peer *p = conn->data;
  pc_coord *c = p->coord;
  p->closed = true;
  for (pc_peer **pp = &c->peers; *pp; pp = &(*pp)->next)
    if (*pp == p) { *pp = p->next; break; }
  if (p->authed && p->role == PCBPT__ROLE__ROLE_WORKER) {
    pc_wire_log("%s: worker '%s' left", conn->peer, p->name);
    pc_sched_peer_gone(c, p);
  }
  upload_reset(p);
  if (p->bun_fd >= 0) close(p->bun_fd);
  if (p->bun_tmp[0]) unlink(p->bun_tmp);
  if (p->out.fd >= 0) close(p->out.fd);
  /* a burst of peers (or an upload) freed: give the memory back at the next tick */
  c->trim_due = true;
  pc_peer_unref(p);
}

static void on_connection(uv_stream_t *server, int status) {
  pc_coord *c = server->data;
  if (status < 0) { pc_wire_log("accept: %s", uv_strerror(status)); return; }
  int handshakes = 0;
  for (pc_peer *q = c->peers; q; q = q->next) handshakes += !q->authed && !q->conn.closing;
  pc_peer *p = calloc(1, sizeof *p);
  if (!p) { pc_wire_log("accept: out of memory"); return; }
  pc_conn_cbs cbs = {.on_msg = on_msg, .on_drain = on_drain, .on_closed = on_closed};
  int r = pc_conn_init(c->loop, &p->conn, &cbs, p, HANDSHAKE_MAX_FRAME);
  if (r) { pc_wire_log("accept: %s", uv_strerror(r)); free(p); return; }
  p->coord = c;
  p->refs = 1;
  p->bun_fd = -1;
  p->out.fd = -1;
  p->connected = p->last_seen = pc_coord_now();
  p->next = c->peers;
  c->peers = p;
  if ((r = uv_accept(server, (uv_stream_t *)&p->conn.tcp)) != 0 || (r = pc_conn_start(&p->conn)) != 0) {
    pc_conn_close(&p->conn, uv_strerror(r));
  } else if (handshakes >= MAX_HANDSHAKES) {
    double now = pc_coord_now();
    if (now - c->last_refusal_log > 10) {
      pc_wire_log("%s: refused: %d connections are authenticating already (logged once per 10 s)", p->conn.peer, handshakes);
      c->last_refusal_log = now;
    }
    pc_conn_close(&p->conn, NULL);
  }
}

/* The loop did not run for `by` seconds (the process was stopped, or the machine slept):
 * nothing was read in that time, so the peers' silence is ours. Every time a timeout is
 * judged from moves forward by as much, and the peers' pending input is read before it is
 * judged again. */
static void loop_stalled(pc_coord *c, double by) {
  pc_wire_log("the loop did not run for %.1f s: timeouts restart from now", by);
  for (pc_peer *p = c->peers; p; p = p->next) {
    p->connected += by;
    p->last_seen += by;
    p->hb_time += by;
    p->hb_advanced += by;
  }
  for (pc_job *j = c->jobs; j; j = j->next) {
    if (j->stopping_since > 0) j->stopping_since += by;
    for (pc_range *r = j->ranges; r; r = r->next) {
      if (r->orphan_since > 1) r->orphan_since += by; /* 1: free at once */
      if (r->progress_at > 0) r->progress_at += by;
      if (r->measured_at > 0) r->measured_at += by;
    }
  }
}

static void on_tick(uv_timer_t *t) {
  pc_coord *c = t->data;
  double now = pc_coord_now(), dt = now - c->last_tick;
  c->last_tick = now;
  if (dt > 1.0 + 2e-3 * c->tick_ms) loop_stalled(c, dt - 1e-3 * c->tick_ms);
  for (pc_peer *p = c->peers; p; p = p->next) {
    if (p->conn.closing || p->paused) continue; /* a paused peer is silent because we do not read */
    if (!p->authed && now - p->connected > HANDSHAKE_TIMEOUT) pc_conn_close(&p->conn, "no authentication within 10 s");
    else if (p->authed && p->role == PCBPT__ROLE__ROLE_WORKER && now - p->last_seen > c->heartbeat_timeout) {
      char why[80];
      snprintf(why, sizeof why, "no heartbeat for %.0f s", now - p->last_seen);
      pc_conn_close(&p->conn, why);
    }
  }
  bool running = false;
  for (pc_job *j = c->jobs; j; j = j->next) {
    pc_sched_check_progress(c, j);
    pc_job_tick(c, j, dt);
    running = running || j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING;
  }
  if (!running) pc_big_spare_free(&c->spare_up);
  if (c->trim_due) {
    c->trim_due = false;
    malloc_trim(0);
  }
}

static void close_handle(uv_handle_t *h) {
  if (h->loop && !uv_is_closing(h)) uv_close(h, NULL);
}

static void on_wake(uv_async_t *a) {
  pc_coord *c = a->data;
  if (!c->stopping) return;
  close_handle((uv_handle_t *)&c->listener);
  close_handle((uv_handle_t *)&c->tick);
  close_handle((uv_handle_t *)&c->wake);
  close_handle((uv_handle_t *)&c->sigint);
  close_handle((uv_handle_t *)&c->sigterm);
  for (pc_peer *p = c->peers; p; p = p->next) pc_conn_close(&p->conn, NULL);
}

void pc_coord_stop(pc_coord *c) {
  c->stopping = true;
  uv_async_send(&c->wake);
}

static void on_signal(uv_signal_t *s, int signum) {
  pc_coord *c = s->data;
  pc_wire_log("signal %d: stopping (the store and checkpoints are consistent)", signum);
  uv_stop(c->loop);
}

int pc_coord_start(pc_coord *c, uv_loop_t *loop, const char *host, int port, const char *data_dir,
                   const uint8_t key[PC_AUTH_KEY], pc_err *e) {
  c->loop = loop;
  memcpy(c->key, key, PC_AUTH_KEY);
  if (!c->orphan_grace) c->orphan_grace = 3;
  if (!c->heartbeat_timeout) c->heartbeat_timeout = 10;
  if (!c->range_seconds) c->range_seconds = 3;
  if (!c->ckpt_interval) c->ckpt_interval = 1;
  if (!c->exr_interval) c->exr_interval = 10;
  if (!c->tick_ms) c->tick_ms = 250;
  if (!c->progress_timeout) c->progress_timeout = 60;
  if (!c->max_buffered) c->max_buffered = MAX_BUFFERED;
  if (!c->max_film) c->max_film = pc_big_memory_limit();
  if ((size_t)snprintf(c->data_dir, sizeof c->data_dir, "%s", data_dir) >= sizeof c->data_dir)
    return pc_errf(e, PC_ELIMIT, "--data-dir: path too long");
  if (mkdir(data_dir, 0700) != 0 && errno != EEXIST) return pc_errf(e, PC_EIO, "%s: %s", data_dir, strerror(errno));
  int rc = pc_store_open(c, e);
  if (rc) return rc;
  if ((rc = pc_store_load(c, e)) != 0) return rc;
  for (pc_job *j = c->jobs; j; j = j->next) {
    if (j->state != PC_JOB_RUNNING && j->state != PC_JOB_STOPPING) continue;
    pc_err je;
    Pcbpt__Settings *s = pcbpt__settings__unpack(NULL, j->settings_len, j->settings_blob);
    if (s) pc_job_take_stored_settings(j, s);
    if (!s || pc_wire_settings_from_proto(s, &j->set, &je) != 0 || pc_job_activate(c, j, &je) != 0)
      pc_job_fail(c, j, s ? je.msg : "stored settings do not decode");
    else
      pc_wire_log("job %llu: resumed at %llu acknowledged iterations", (unsigned long long)j->id, (unsigned long long)j->done);
    if (j->state == PC_JOB_STOPPING) j->stopping_since = pc_coord_now();
    if (s) pcbpt__settings__free_unpacked(s, NULL);
  }
  for (pc_job *j = c->jobs; j; j = j->next) {
    if (j->state != PC_JOB_QUEUED) continue;
    pc_err je;
    Pcbpt__Settings *s = pcbpt__settings__unpack(NULL, j->settings_len, j->settings_blob);
    if (s) pc_job_take_stored_settings(j, s);
    if (!s || pc_wire_settings_from_proto(s, &j->set, &je) != 0) pc_job_fail(c, j, "stored settings do not decode");
    if (s) pcbpt__settings__free_unpacked(s, NULL);
  }
  struct sockaddr_storage addr;
  if (uv_ip4_addr(host, port, (struct sockaddr_in *)&addr) != 0 && uv_ip6_addr(host, port, (struct sockaddr_in6 *)&addr) != 0)
    return pc_errf(e, PC_EINVAL, "--listen: '%s' is not an IP address", host);
  int r;
  if ((r = uv_tcp_init(loop, &c->listener)) != 0) return pc_errf(e, PC_EIO, "listen: %s", uv_strerror(r));
  c->listener.data = c;
  if ((r = uv_tcp_bind(&c->listener, (struct sockaddr *)&addr, 0)) != 0 ||
      (r = uv_listen((uv_stream_t *)&c->listener, 128, on_connection)) != 0)
    return pc_errf(e, PC_EIO, "listen on %s:%d: %s", host, port, uv_strerror(r));
  struct sockaddr_storage bound;
  int blen = sizeof bound;
  if ((r = uv_tcp_getsockname(&c->listener, (struct sockaddr *)&bound, &blen)) != 0) return pc_errf(e, PC_EIO, "getsockname: %s", uv_strerror(r));
  c->bound_port = ntohs(bound.ss_family == AF_INET ? ((struct sockaddr_in *)&bound)->sin_port : ((struct sockaddr_in6 *)&bound)->sin6_port);
  if ((r = uv_timer_init(loop, &c->tick)) != 0) return pc_errf(e, PC_EIO, "timer: %s", uv_strerror(r));
  c->tick.data = c;
  c->last_tick = pc_coord_now();
  if ((r = uv_timer_start(&c->tick, on_tick, (uint64_t)c->tick_ms, (uint64_t)c->tick_ms)) != 0) return pc_errf(e, PC_EIO, "timer: %s", uv_strerror(r));
  if ((r = uv_async_init(loop, &c->wake, on_wake)) != 0) return pc_errf(e, PC_EIO, "async: %s", uv_strerror(r));
  c->wake.data = c;
  return 0;
}

void pc_coord_free(pc_coord *c) {
  while (c->jobs) {
    pc_job *j = c->jobs;
    c->jobs = j->next;
    pc_job_free(j);
  }
  pc_prior_free_all(c);
  pc_big_spare_free(&c->spare_up);
  pc_store_close(c);
  sodium_memzero(c->key, sizeof c->key);
}

static const char serve_help[] =
    "usage: pcbpt-coord serve --listen HOST:PORT --data-dir DIR --token-file F [options]\n"
    "Runs the coordinator: a job store in DIR, workers and clients authenticated with the token.\n"
    "  --orphan-grace S       seconds a vanished worker's range waits before reassignment (3)\n"
    "  --heartbeat-timeout S  drop a worker silent for S seconds (10)\n"
    "  --range-seconds S      target seconds of work per range (3)\n"
    "  --exr-interval S       seconds between image writes of a running job (10)\n"
    "  --progress-timeout S   seconds a worker not yet measured on a job may hold a range without\n"
    "                         uploading (60); a measured one gets 3 upload intervals of its rate.\n"
    "                         An overdue worker is asked to upload what it has and stop; one that\n"
    "                         ignores that loses the range to others\n"
    "  --max-buffered-mb N    upload bytes held before senders are paused (64); one upload\n"
    "                         always proceeds, so a film's upload may exceed it\n"
    "  --max-film-mb N        largest job film a submit may ask for (default: the machine's\n"
    "                         memory); a larger job is refused at submit\n"
    "  --port-file F          write the bound port to F (for --listen HOST:0)\n";

int pc_cmd_serve(int argc, char **argv) {
  const char *listen = NULL, *dir = NULL, *token = NULL, *port_file = NULL;
  pc_coord c;
  memset(&c, 0, sizeof c);
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    double *num = strcmp(a, "--orphan-grace") == 0 ? &c.orphan_grace
                  : strcmp(a, "--heartbeat-timeout") == 0 ? &c.heartbeat_timeout
                  : strcmp(a, "--range-seconds") == 0 ? &c.range_seconds
                  : strcmp(a, "--exr-interval") == 0 ? &c.exr_interval
                  : strcmp(a, "--progress-timeout") == 0 ? &c.progress_timeout : NULL;
    if (strcmp(a, "--help") == 0) { fputs(serve_help, stdout); return 0; }
    if (i + 1 >= argc) { fprintf(stderr, "pcbpt-coord serve: %s needs a value (see --help)\n", a); return 2; }
    if (num) {
      if (!pc_parse_f64(argv[++i], 0.01, 1e6, num)) { fprintf(stderr, "pcbpt-coord serve: %s: expected seconds\n", a); return 2; }
    } else if (strcmp(a, "--listen") == 0) listen = argv[++i];
    else if (strcmp(a, "--data-dir") == 0) dir = argv[++i];
    else if (strcmp(a, "--token-file") == 0) token = argv[++i];
    else if (strcmp(a, "--port-file") == 0) port_file = argv[++i];
    else if (strcmp(a, "--max-buffered-mb") == 0) {
      double mb;
      if (!pc_parse_f64(argv[++i], 0.25, 1 << 20, &mb)) {
        fprintf(stderr, "pcbpt-coord serve: --max-buffered-mb: expected megabytes in [0.25, 1048576]\n");
        return 2;
      }
      c.max_buffered = (size_t)(mb * 1048576);
    } else if (strcmp(a, "--max-film-mb") == 0) {
      double mb;
      if (!pc_parse_f64(argv[++i], 1, 1 << 30, &mb)) {
        fprintf(stderr, "pcbpt-coord serve: --max-film-mb: expected megabytes in [1, 2^30]\n");
        return 2;
      }
      c.max_film = (size_t)(mb * 1048576);
    } else { fprintf(stderr, "pcbpt-coord serve: unknown argument '%s' (see --help)\n", a); return 2; }
  }
  if (!listen || !dir || !token) { fprintf(stderr, "pcbpt-coord serve: --listen, --data-dir and --token-file are required\n"); return 2; }
  char host[256];
  int port;
  if (pc_wire_parse_hostport(listen, host, sizeof host, &port, 7878) != 0) { fprintf(stderr, "pcbpt-coord serve: --listen: expected HOST:PORT\n"); return 2; }
  pc_err e = {0};
  uint8_t key[PC_AUTH_KEY];
  if (pc_auth_init(&e) != 0 || pc_auth_load_token(token, key, &e) != 0) { fprintf(stderr, "pcbpt-coord serve: %s\n", e.msg); return 1; }
  uv_loop_t *loop = uv_default_loop();
  if (pc_coord_start(&c, loop, host, port, dir, key, &e) != 0) {
    sodium_memzero(key, sizeof key);
    fprintf(stderr, "pcbpt-coord serve: %s\n", e.msg);
    pc_coord_free(&c);
    return 1;
  }
  sodium_memzero(key, sizeof key);
  c.sigint.data = c.sigterm.data = &c;
  if (uv_signal_init(loop, &c.sigint) != 0 || uv_signal_init(loop, &c.sigterm) != 0 || uv_signal_start(&c.sigint, on_signal, SIGINT) != 0 || uv_signal_start(&c.sigterm, on_signal, SIGTERM) != 0)
    pc_wire_log("cannot install signal handlers");
  if (port_file) {
    FILE *f = fopen(port_file, "w");
    if (!f || fprintf(f, "%d\n", c.bound_port) < 0 || fclose(f) != 0) { fprintf(stderr, "pcbpt-coord serve: %s: cannot write\n", port_file); return 1; }
  }
  pc_wire_log("coordinator listening on %s:%d, data in %s", host, c.bound_port, dir);
  uv_run(loop, UV_RUN_DEFAULT);
  pc_coord_free(&c);
  return 0;
}
