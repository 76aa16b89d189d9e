/* sched.c: hands out iteration ranges. Orphaned ranges (their worker went away longer than
 * the grace period ago) go first, split at what is acknowledged so the late uploads of the
 * old owner can never be counted twice; then fresh iterations, sized to a few seconds of the
 * asking worker's measured throughput and, for iteration-bounded jobs, shrinking towards the
 * end with what is left and what the other workers still have to render (range_size.h), so
 * that the workers finish together and late joiners get work at once. Jobs are served by
 * priority, then submission; the jobs of a study group (docs/farm-study.md) take turns: a
 * request goes to the group's job with the least worker time had or in hand, and among jobs
 * about even, to the one this worker has served least, so the methods of a study share the
 * workers and rotate over them. Workers told there is no work are nudged when some comes. */
#include <math.h>
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

/* p's entry for job (created, the oldest job's going, when create). */
static int served_slot(const pc_peer *p, uint64_t job, bool create) {
  int slot = 0;
  for (int i = 0; i < 8; i++) {
    if (p->served[i].job == job) return i;
    if (p->served[i].job < p->served[slot].job) slot = i;
  }
  return create ? slot : -1;
}

static double served_by(const pc_peer *p, uint64_t job) {
  int i = served_slot(p, job, false);
  return i >= 0 ? p->served[i].seconds : 0;
}

void pc_sched_served(pc_peer *p, uint64_t job, uint64_t iterations, double seconds) {
  int i = served_slot(p, job, false);
  if (i < 0) {
    i = served_slot(p, job, true);
    p->served[i].job = job;
    p->served[i].iterations = 0;
    p->served[i].seconds = p->served[i].mrate = 0;
  }
  p->served[i].iterations += iterations;
  p->served[i].seconds += seconds;
}

/* The rate a worker's ranges on j are sized by: what it claims, trusted up to 4x what its
 * uploads on j brought (so a false claim earns no more than a few seconds of real work); a
 * worker not measured on j yet gets a probe. The embedded farm's one worker is the render
 * command's own: its claim is trusted at once, so the range it asks for while its probe's
 * upload is still being merged is not a second probe (at 512x512 each range's end costs
 * ~0.2 s of packing and merging). */
static double trusted_rate(const pc_coord *c, const pc_peer *q, const pc_job *j) {
  double mrate = q->mrate_job == j->id ? q->mrate : 0;
  if (q->mrate_job != j->id) {
    /* measured on j before it went to another job (a study group's jobs take turns) */
    int i = served_slot(q, j->id, false);
    mrate = i >= 0 ? q->served[i].mrate : 0;
  }
  double claimed = q->rate_job == j->id ? q->rate : 0;
  if (!(mrate > 0)) return c->one_worker && claimed > 0 ? claimed : 0;
  return claimed > 0 && claimed < 4 * mrate ? claimed : claimed > 0 ? 4 * mrate : mrate;
}

static double attained(const pc_coord *c, const pc_job *j, double now);

/* A study job's range ends by its next snapshot time (or its budget), shared among the
 * group's workers, so the early snapshots, a fraction of a second of worker time apart, each
 * find an upload there. */
static double study_range_seconds(const pc_coord *c, const pc_job *j, double now) {
  double got = attained(c, j, now), next = j->halt_worker_seconds;
  for (int k = 0; k < (int)j->snapshots; k++) {
    double t = pc_job_snapshot_time(j, k);
    if (t > got) { next = t; break; }
  }
  double s = (next - got) / (j->group_workers ? j->group_workers : 1);
  return s < PC_RANGE_MIN_SECONDS ? PC_RANGE_MIN_SECONDS : s > c->range_seconds ? c->range_seconds : s;
}

static uint64_t fresh_size(pc_coord *c, pc_peer *p, pc_job *j, double now) {
  pc_range_size_in in = {.rate = trusted_rate(c, p, j), .range_seconds = c->range_seconds, .alone = c->one_worker,
                         .upload_seconds = p->upload_s};
  if (j->halt_worker_seconds > 0) {
    in.range_seconds = study_range_seconds(c, j, now);
    in.upload_seconds = 0; /* a study's ranges end at its snapshot times */
    /* a study's worker-seconds are counted per upload: a range sized on a one-iteration probe
     * (often several times too fast) would overrun the early snapshots and the interleaving,
     * so a worker's ranges of a study job grow from the probe by at most doubling */
    int i = served_slot(p, j->id, false);
    uint64_t cap = 2 * (i >= 0 ? p->served[i].iterations : 0) + 1, n = pc_range_size(&in);
    return n < cap ? n : cap;
  }
  if (j->halt_iterations) {
    in.bounded = true;
    in.unassigned = j->halt_iterations - j->next_iter;
    if (j->study_group) in.interleaved = j->halt_iterations;
    /* p asks only when its own ranges are rendered; every other open range is still to do */
    for (const pc_range *r = j->ranges; r; r = r->next)
      if (r->owner != p) in.outstanding += r->owner ? unrendered(r, now) : (double)(r->count - r->merged);
    /* a worker not measured on this job yet (it will ask soon) is taken to be as fast as p */
    for (const pc_peer *q = c->peers; q; q = q->next) {
      if (q == p || !q->authed || q->role != PCBPT__ROLE__ROLE_WORKER) continue;
      const pc_job *qj = job_of(c, q);
      double qr = trusted_rate(c, q, j);
      if (!qj || qj == j) in.others_rate += qr > 0 ? qr : in.rate;
    }
  }
  return pc_range_size(&in);
}

/* Whether j's film fits beside the films the coordinator holds, under max_film. A job that
 * does not fit stays queued until a running job's film is freed (submit refused the jobs that
 * could never fit, so one always fits once the others are done). */
static bool film_fits(pc_coord *c, pc_job *j) {
  if (!c->max_film) return true;
  size_t held = 0;
  for (const pc_job *k = c->jobs; k; k = k->next) {
    if (k->film_ready) held += pc_film_held_bytes(&k->film);
    if (k->prior_ready) held += pc_film_held_bytes(&k->prior);
  }
  for (const pc_pilot_films *g = c->pilot_films; g; g = g->next) held += pc_film_held_bytes(&g->film);
  size_t need = pc_film_bytes(j->set.width, j->set.height, j->set.strategy_layers);
  if (held <= c->max_film && need <= c->max_film - held) return true;
  if (!j->film_waits)
    pc_wire_log("job %llu: waits for memory: its film takes %zu MB, and the running jobs' hold %zu of %zu MB",
                (unsigned long long)j->id, pc_big_mb(need), pc_big_mb(held), pc_big_mb(c->max_film));
  j->film_waits = true;
  return false;
}

static bool try_job(pc_coord *c, pc_peer *p, pc_job *j) {
  double now = pc_coord_now();
  pc_err e = {0};
  if (!j->film_ready && !film_fits(c, j)) return false;
  if (!j->film_ready && pc_job_activate(c, j, &e) != 0) { pc_job_fail(c, j, e.msg); return false; }
  for (pc_range *r = j->ranges; r; r = r->next) {
    if (r->owner || r->merging || r->final || r->merged != r->acked || r->acked == r->count) continue;
    if (r->orphan_since == 0 || now - r->orphan_since < c->orphan_grace) continue;
    pc_range *g = claim_orphan(c, j, r, &e);
    if (!g && e.code == PC_ENOMEM) { pc_job_fail(c, j, e.msg); return false; }
    if (!g) { pc_job_storage_trouble(c, j, NULL, e.msg); return false; }
    j->ranges_rerun++;
    pc_wire_log("job %llu: range %llu re-run from iteration %llu (its worker went away or fell silent)",
                (unsigned long long)j->id, (unsigned long long)g->id, (unsigned long long)g->first);
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

static bool runnable(const pc_job *j) { return (j->state == PC_JOB_QUEUED || j->state == PC_JOB_RUNNING) && !j->finishing; }

/* Worker-seconds study job j has had or has in hand: merged, plus what is left of each open
 * range a worker holds at that worker's measured rate (a range's worth while unmeasured). */
static double attained(const pc_coord *c, const pc_job *j, double now) {
  double s = j->stats_merged.t_total;
  for (const pc_range *r = j->ranges; r; r = r->next) {
    if (!r->owner || r->final) continue;
    double rate = r->owner->mrate_job == j->id ? r->owner->mrate : 0;
    s += rate > 0 ? fmin(unrendered(r, now) / rate, 2 * c->range_seconds) : c->range_seconds;
  }
  return s;
}

/* Workers other than p holding an unfinished range of the group. */
static int group_busy(const pc_coord *c, uint64_t group, const pc_peer *p) {
  int n = 0;
  for (const pc_peer *q = c->peers; q; q = q->next) {
    if (q == p || q->closed) continue;
    bool holds = false;
    for (const pc_job *j = c->jobs; j && !holds; j = j->next)
      if (j->study_group == group && (j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING))
        for (const pc_range *r = j->ranges; r && !holds; r = r->next) holds = r->owner == q && !r->final && r->merged < r->count;
    n += holds;
  }
  return n;
}

/* Hands p a range of study group g: the runnable job with the least attained worker time;
 * among those within half a range of it, the one p served least. */
static bool try_group(pc_coord *c, pc_peer *p, const pc_job *first, int top, bool pri_only) {
  uint64_t g = first->study_group;
  if (first->group_workers && group_busy(c, g, p) >= (int)first->group_workers) return false;
  double now = pc_coord_now();
  pc_job *tried[64];
  int ntried = 0;
  for (;;) {
    double least = INFINITY;
    pc_job *best = NULL;
    for (pc_job *j = c->jobs; j; j = j->next)
      if (j->study_group == g && runnable(j) && (!pri_only || j->priority == top)) least = fmin(least, attained(c, j, now));
    double best_served = INFINITY;
    for (pc_job *j = c->jobs; j; j = j->next) {
      if (j->study_group != g || !runnable(j) || (pri_only && j->priority != top)) continue;
      bool done = false;
      for (int i = 0; i < ntried; i++) done = done || tried[i] == j;
      if (done || attained(c, j, now) > least + 0.5 * c->range_seconds) continue;
      double sv = served_by(p, j->id);
      if (sv < best_served) { best_served = sv; best = j; }
    }
    if (!best || ntried == 64) return false;
    if (try_job(c, p, best)) return true;
    tried[ntried++] = best;
  }
}

void pc_sched_request(pc_coord *c, pc_peer *p) {
  /* highest priority first (pass 0), then any runnable job; each in submission order */
  for (int pri_pass = 0; pri_pass < 2; pri_pass++) {
    int top = -2147483647;
    for (pc_job *j = c->jobs; j; j = j->next)
      if ((j->state == PC_JOB_QUEUED || j->state == PC_JOB_RUNNING) && j->priority > top) top = j->priority;
    for (pc_job *j = c->jobs; j; j = j->next) {
      if (!runnable(j)) continue;
      if (pri_pass == 0 && j->priority != top) continue;
      if (j->study_group) {
        /* the group's turn is taken at its first job in submission order */
        bool first = true;
        for (pc_job *k = c->jobs; k != j && first; k = k->next)
          first = !(k->study_group == j->study_group && runnable(k) && (pri_pass || k->priority == top));
        if (first && try_group(c, p, j, top, pri_pass == 0)) return;
        continue;
      }
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
    /* kept per job, so a worker coming back to a job is not probed again */
    int i = served_slot(p, p->mrate_job, false);
    if (i >= 0) p->served[i].mrate = p->mrate;
    i = served_slot(p, j->id, false);
    p->mrate = i >= 0 ? p->served[i].mrate : 0;
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
