/* sched.c: hands out iteration ranges. Orphaned ranges (their worker went away longer than
 * the grace period ago) go first, split at what is acknowledged so the late uploads of the
 * old owner can never be counted twice; then fresh iterations, sized to a few seconds of the
 * asking worker's measured throughput and, for iteration-bounded jobs, shrinking towards the
 * end with what is left and what the other workers still have to render (range_size.h), so
 * that the workers finish together and late joiners get work at once. Jobs are served by
 * priority, then submission. Workers told there is no work are nudged when some comes. */
#include <stdlib.h>

#include "coord.h"
#include "range_size.h"
#include "wire_log.h"
#include "wire_settings.h"

pc_range *pc_sched_find_range(pc_job *j, uint64_t id) {
  for (pc_range *r = j->ranges; r; r = r->next)
    if (r->id == id) return r;
  return NULL;
}

static void send_assign(pc_coord *c, pc_peer *p, pc_job *j, pc_range *r) {
  (void)c;
  Pcbpt__Settings *s = pcbpt__settings__unpack(NULL, j->settings_len, j->settings_blob);
  if (!s) { pc_job_fail(c, j, "stored settings do not decode"); return; }
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Assign a = PCBPT__ASSIGN__INIT;
  a.job_id = j->id;
  a.range_id = r->id;
  a.first = r->first + r->acked;
  a.count = r->count - r->acked;
  a.bundle_hash.data = j->bundle;
  a.bundle_hash.len = PC_BUNDLE_HASH;
  a.settings = s;
  env.msg_case = PCBPT__ENVELOPE__MSG_ASSIGN;
  env.assign = &a;
  r->owner = p;
  r->orphan_since = 0;
  r->progress_at = r->measured_at = pc_coord_now();
  r->stop_asked = r->revoked = false;
  p->idle = false;
  /* the worker measures its rate afresh on a new job; until it reports, it is unknown */
  if (p->rate_job != j->id) p->rate = 0;
  p->rate_job = j->id;
  pc_conn_send(&p->conn, &env);
  pcbpt__settings__free_unpacked(s, NULL);
  pc_wire_log("job %llu: range %llu [%llu,+%llu) -> %s (%s)", (unsigned long long)j->id, (unsigned long long)r->id,
              (unsigned long long)a.first, (unsigned long long)a.count, p->name, p->conn.peer);
}

/* Takes back an orphan: closes it at its acknowledged prefix and opens the rest as a new range. */
static pc_range *claim_orphan(pc_coord *c, pc_job *j, pc_range *r, pc_err *e) {
  if (r->acked == 0) return r;
  uint64_t id;
  pc_range old = *r;
  old.count = r->acked;
  int rc = pc_store_begin(c, e);
  if (!rc) rc = pc_store_update_range(c, &old, false, e);
  if (!rc) rc = pc_store_insert_range(c, j->id, r->first + r->acked, r->count - r->acked, &id, e);
  if (!rc) rc = pc_store_commit(c, e);
  if (rc) { pc_store_rollback(c); return NULL; }
  pc_range *nr = calloc(1, sizeof *nr);
  if (!nr) { pc_errf(e, PC_ENOMEM, "out of memory"); return NULL; }
  nr->id = id;
  nr->first = r->first + r->acked;
  nr->count = r->count - r->acked;
  nr->next = r->next;
  r->count = r->acked; /* closed; freed at the next checkpoint sweep */
  r->next = nr;
  return nr;
}

/* Iterations of r not rendered yet as far as the coordinator can tell: its owner's last
 * heartbeat, advanced at the owner's rate since, or else what is merged. */
static double unrendered(const pc_range *r, double now) {
  double done = (double)r->merged;
  const pc_peer *q = r->owner;
  if (q && q->hb_range == r->id) {
    double est = (double)q->hb_done + (q->rate > 0 ? q->rate * (now - q->hb_time) : 0);
    if (est > done) done = est;
  }
  return done < (double)r->count ? (double)r->count - done : 0;
}

/* The job a worker holds a range of (NULL when idle). */
static const pc_job *job_of(const pc_coord *c, const pc_peer *q) {
  for (const pc_job *j = c->jobs; j; j = j->next)
    for (const pc_range *r = j->ranges; r; r = r->next)
      if (r->owner == q) return j;
  return NULL;
}

/* The rate a worker's ranges on j are sized by: what it claims, trusted up to 4x what its
 * uploads on j brought (so a false claim earns no more than a few seconds of real work); a
 * worker not measured on j yet gets a probe. */
static double trusted_rate(const pc_peer *q, const pc_job *j) {
  if (q->mrate_job != j->id || !(q->mrate > 0)) return 0;
  double claimed = q->rate_job == j->id ? q->rate : 0;
  return claimed > 0 && claimed < 4 * q->mrate ? claimed : claimed > 0 ? 4 * q->mrate : q->mrate;
}

static uint64_t fresh_size(pc_coord *c, pc_peer *p, pc_job *j, double now) {
  pc_range_size_in in = {.rate = trusted_rate(p, j), .range_seconds = c->range_seconds};
  if (j->halt_iterations) {
    in.bounded = true;
    in.unassigned = j->halt_iterations - j->next_iter;
    /* p asks only when its own ranges are rendered; every other open range is still to do */
    for (const pc_range *r = j->ranges; r; r = r->next)
      if (r->owner != p) in.outstanding += r->owner ? unrendered(r, now) : (double)(r->count - r->merged);
    /* a worker not measured on this job yet (it will ask soon) is taken to be as fast as p */
    for (const pc_peer *q = c->peers; q; q = q->next) {
      if (q == p || !q->authed || q->role != PCBPT__ROLE__ROLE_WORKER) continue;
      const pc_job *qj = job_of(c, q);
      double qr = trusted_rate(q, j);
      if (!qj || qj == j) in.others_rate += qr > 0 ? qr : in.rate;
    }
  }
  return pc_range_size(&in);
}

static bool try_job(pc_coord *c, pc_peer *p, pc_job *j) {
  double now = pc_coord_now();
  pc_err e = {0};
  if (!j->film_ready && pc_job_activate(c, j, &e) != 0) { pc_job_fail(c, j, e.msg); return false; }
  for (pc_range *r = j->ranges; r; r = r->next) {
    if (r->owner || r->merging || r->final || r->merged != r->acked || r->acked == r->count) continue;
    if (r->orphan_since == 0 || now - r->orphan_since < c->orphan_grace) continue;
    pc_range *g = claim_orphan(c, j, r, &e);
    if (!g && e.code == PC_ENOMEM) { pc_job_fail(c, j, e.msg); return false; }
    if (!g) { pc_job_storage_trouble(c, j, NULL, e.msg); return false; }
    send_assign(c, p, j, g);
    return true;
  }
  if (j->halt_iterations && j->next_iter >= j->halt_iterations) return false;
  uint64_t n = fresh_size(c, p, j, now);
  uint64_t id;
  int rc = pc_store_begin(c, &e);
  if (!rc) rc = pc_store_insert_range(c, j->id, j->next_iter, n, &id, &e);
  j->next_iter += n;
  if (!rc) rc = pc_store_update_job(c, j, &e);
  if (!rc) rc = pc_store_commit(c, &e);
  pc_range *r = rc ? NULL : calloc(1, sizeof *r);
  if (!r) {
    pc_store_rollback(c);
    j->next_iter -= n;
    if (rc) pc_job_storage_trouble(c, j, NULL, e.msg);
    else pc_job_fail(c, j, "out of memory");
    return false;
  }
  r->id = id;
  r->first = j->next_iter - n;
  r->count = n;
  r->next = j->ranges;
  j->ranges = r;
  send_assign(c, p, j, r);
  return true;
}

void pc_sched_request(pc_coord *c, pc_peer *p) {
  /* highest priority first (pass 0), then any runnable job; each in submission order */
  for (int pri_pass = 0; pri_pass < 2; pri_pass++) {
    int top = -2147483647;
    for (pc_job *j = c->jobs; j; j = j->next)
      if ((j->state == PC_JOB_QUEUED || j->state == PC_JOB_RUNNING) && j->priority > top) top = j->priority;
    for (pc_job *j = c->jobs; j; j = j->next) {
      if ((j->state != PC_JOB_QUEUED && j->state != PC_JOB_RUNNING) || j->finishing) continue;
      if (pri_pass == 0 && j->priority != top) continue;
      if (try_job(c, p, j)) return;
    }
  }
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__NoWork nw = PCBPT__NO_WORK__INIT;
  nw.retry_ms = 500;
  env.msg_case = PCBPT__ENVELOPE__MSG_NO_WORK;
  env.no_work = &nw;
  p->idle = true;
  pc_conn_send(&p->conn, &env);
}

void pc_sched_nudge(pc_coord *c) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__WorkAvailable wa = PCBPT__WORK_AVAILABLE__INIT;
  env.msg_case = PCBPT__ENVELOPE__MSG_WORK_AVAILABLE;
  env.work_available = &wa;
  for (pc_peer *p = c->peers; p; p = p->next)
    if (p->idle && !p->closed) {
      p->idle = false;
      pc_conn_send(&p->conn, &env);
    }
}

void pc_sched_peer_gone(pc_coord *c, pc_peer *p) {
  double now = pc_coord_now();
  for (pc_job *j = c->jobs; j; j = j->next)
    for (pc_range *r = j->ranges; r; r = r->next)
      if (r->owner == p) {
        r->owner = NULL;
        r->orphan_since = now;
        pc_wire_log("job %llu: range %llu orphaned (%s gone), %llu of %llu iterations acknowledged",
                    (unsigned long long)j->id, (unsigned long long)r->id, p->name, (unsigned long long)r->acked,
                    (unsigned long long)r->count);
      }
}

void pc_sched_progress(pc_job *j, pc_range *r, pc_peer *p, uint64_t count) {
  double now = pc_coord_now(), dt = now - r->measured_at;
  if (p->mrate_job != j->id) {
    p->mrate = 0;
    p->mrate_job = j->id;
  }
  if (count && r->measured_at > 0 && dt > 0) {
    double inst = (double)count / dt;
    p->mrate = p->mrate > 0 ? 0.5 * (p->mrate + inst) : inst;
  }
  r->progress_at = r->measured_at = now;
  r->stop_asked = false;
}

/* p uploads nothing more while an upload of it waits for its acknowledgement (a checkpoint,
 * or the data dir coming back): that time is ours, not its. */
static bool waits_for_ack(const pc_job *j, const pc_peer *p) {
  for (const pc_range *r = j->ranges; r; r = r->next)
    if (r->owner == p && (r->merging || r->merged > r->acked)) return true;
  return false;
}

/* Seconds r's owner may go without an upload: a few of its upload intervals, each at least
 * one iteration at its measured rate; a worker not measured on the job (its first range is
 * a probe of one iteration, after the scene loads) gets --progress-timeout. */
static double allowance(const pc_coord *c, const pc_job *j, const pc_peer *p) {
  if (p->mrate_job != j->id || !(p->mrate > 0)) return c->progress_timeout;
  return 3 * (PC_WIRE_UPLOAD_INTERVAL + 1 / p->mrate);
}

void pc_sched_check_progress(pc_coord *c, pc_job *j) {
  if (j->state != PC_JOB_RUNNING || j->storage_error[0]) return; /* a stopping job has its own deadline */
  double now = pc_coord_now();
  for (pc_range *r = j->ranges; r; r = r->next) {
    pc_peer *p = r->owner;
    /* an upload arriving, or held back by our own back-pressure, is not overdue */
    if (!p || p->closed || r->final || p->paused || p->up_next > 0 || r->progress_at <= 0 || waits_for_ack(j, p)) continue;
    /* heartbeats that show the range advancing count like uploads: an iteration of a large
     * film on a slow worker may take longer than any allowance, and is not hoarding */
    double last = p->hb_range == r->id && p->rate_job == j->id && p->hb_advanced > r->progress_at ? p->hb_advanced : r->progress_at;
    double idle = now - last;
    if (idle <= allowance(c, j, p)) continue;
    if (!r->stop_asked) {
      pc_wire_log("job %llu: range %llu overdue on %s (no upload for %.1f s): asking it to upload what it has and stop",
                  (unsigned long long)j->id, (unsigned long long)r->id, p->name, idle);
      r->stop_asked = true;
      r->progress_at = now;
      p->mrate *= 0.5; /* its deadline was too short, so was its range */
      pc_peer_send_cancel(p, j->id, r->id, true);
      continue;
    }
    pc_wire_log("job %llu: range %llu taken back from %s (no upload for %.1f s after the request to stop)",
                (unsigned long long)j->id, (unsigned long long)r->id, p->name, idle);
    pc_peer_send_cancel(p, j->id, r->id, false);
    r->owner = NULL;
    r->orphan_since = 1; /* to another worker at once, split at what is acknowledged */
    r->stop_asked = false;
    r->revoked = true;
    p->mrate = 0;        /* it gets probes until its uploads measure it again */
    pc_sched_nudge(c);
  }
}
