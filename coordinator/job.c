/* job.c: a job's film and its background operations: merging uploads, checkpointing (film to
 * a file by atomic rename, then range progress to the store in one transaction, then the
 * acknowledgements), writing the EXR, halting and finishing. The ops of one job run one at a
 * time on the libuv thread pool, so the film is never touched by two threads at once.
 * Checkpoints are at most one per ckpt_interval, each covering every upload merged since
 * (their acknowledgements wait for it), except after a range's last upload (its worker
 * sends nothing more before that acknowledgement, so its next range's uploads would wait
 * and, once that range is rendered too, its render thread) and when the job is ending:
 * then at once. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include "coord.h"
#include "render_flags.h"
#include "file_read.h"
#include "thread_pool.h"
#include "wire_film.h"
#include "wire_log.h"

typedef struct range_snap { uint64_t id, merged, split_id; bool final; } range_snap;

#define STORAGE_RETRY 2.0 /* seconds between checkpoint attempts while the data dir fails */
#define MAX_RANGE_FAILURES 3 /* ranges that could not be rendered before their job fails */

struct pc_op {
  uv_work_t work;
  pc_coord *c;
  pc_job *j;
  bool is_merge;
  uint32_t snap_k;           /* a study snapshot: write the film as snap.<snap>.exr */
  double wall;               /* the job's render time when it was queued (j->elapsed is the loop's) */
  /* merge */
  pc_peer *peer;
  uint64_t range_id, first, count, raw;
  bool final;
  uint8_t *buf;
  size_t len, cap;
  int64_t light_per_iter;
  double relmse_est;         /* merge: the film's estimated relMSE after it (< 0: cannot tell) */
  uint64_t est_iterations;   /* ... over this many iterations */
  pc_render_stats stats;     /* merge: the upload's; checkpoint: the job's merged total */
  double snap_at;            /* snapshot: the worker-seconds it was planned at */
  /* checkpoint */
  uint64_t gen;
  bool write_exr;
  range_snap *snap;
  int nsnap;
  pc_pending_ack *acks;
  int rc;
  pc_err err;
  pc_op *next;
};

void pc_job_path(const pc_coord *c, const pc_job *j, const char *leaf, char *out, size_t n) {
  /* job names never become paths: only the numeric id does */
  snprintf(out, n, "%s/jobs/%llu%s%s", c->data_dir, (unsigned long long)j->id, leaf ? "/" : "", leaf ? leaf : "");
}

static void op_start(pc_job *j);
static int write_image(const pc_job *j, const char *img, const pc_render_stats *st, double wall, double snap_at, pc_err *e);

/* Appends op to j's queue; op_after starts the next op of the queue. */
static void append_op(pc_job *j, pc_op *op) {
  op->next = NULL;
  if (j->ops_tail) j->ops_tail->next = op;
  else j->ops = op;
  j->ops_tail = op;
}

static void queue_op(pc_job *j, pc_op *op) {
  append_op(j, op);
  if (!j->busy) op_start(j);
}

/* The iterations of an upload of [first, first + count) its trace holds: those below the bound. */
static uint32_t upload_traced(uint64_t first, uint64_t count) {
  if (first >= PC_TRACE_ITERATIONS) return 0;
  uint64_t below = PC_TRACE_ITERATIONS - first;
  return (uint32_t)(count < below ? count : below);
}

/* An upload's per-layer counts must be those of op->count iterations: eye layers count the
 * iterations, light layers the same light paths per iteration as every upload before; its trace
 * must hold exactly its iterations below the trace's bound. */
static int judge_counts(void *user, const pc_wire_film_counts *c, pc_err *e) {
  pc_op *op = user;
  const pc_film *f = &op->j->film;
  const uint64_t *counts = c->counts;
  uint32_t want = upload_traced(op->first, op->count);
  bool exact = c->ntraced == want;
  for (uint32_t k = 0; k < c->ntraced && exact; k++) exact = c->traced[k] >= op->first && c->traced[k] - op->first < want;
  if (!exact) /* no duplicates (the film's check), so n in-range records are the n iterations */
    return pc_errf(e, PC_EINVAL, "upload of iterations %llu..%llu: its trace holds %u iterations, not exactly its %u below %u",
                   (unsigned long long)op->first, (unsigned long long)(op->first + op->count - 1), c->ntraced, want,
                   PC_TRACE_ITERATIONS);
  for (int l = 0; l < f->nlayers; l++) {
    uint64_t cnt = counts[l];
    if (f->layers[l].norm != PC_NORM_LIGHT) {
      if (cnt != op->count)
        return pc_errf(e, PC_EINVAL, "inconsistent counts: layer '%s' counts %llu for %llu iterations", f->layers[l].name,
                       (unsigned long long)cnt, (unsigned long long)op->count);
    } else {
      int64_t per = (int64_t)(cnt / op->count);
      if (cnt % op->count != 0 || (op->light_per_iter >= 0 && per != op->light_per_iter))
        return pc_errf(e, PC_EINVAL, "inconsistent counts: light layer '%s' counts %llu for %llu iterations",
                       f->layers[l].name, (unsigned long long)cnt, (unsigned long long)op->count);
      op->light_per_iter = per;
    }
  }
  return 0;
}

/* The estimated relMSE of the image the job shows after `elapsed` seconds (-1 when it cannot
 * tell) and the job's iterations. */
static void film_estimate(const pc_job *j, double elapsed, double *relmse, uint64_t *iterations) {
  if (!pc_prior_relmse_estimate(j, pc_prior_weight(j, j->film_seconds, elapsed), relmse)) *relmse = -1;
  *iterations = j->film.layers[PC_LAYER_PT].count;
}

/* --halt-noise (docs/variance.md): the estimate is looked at only from NOISE_MIN_ITERATIONS
 * on and then each time the merged iterations grew by an eighth, so the stop depends on a
 * handful of decisions, each on an estimate from many iterations, not on the first lucky dip
 * of a noisy one. */
#define NOISE_MIN_ITERATIONS 16
static void check_noise(pc_coord *c, pc_job *j, uint64_t iterations) {
  if (!(j->halt_noise > 0) || j->state != PC_JOB_RUNNING || j->relmse_est < 0) return;
  if (iterations < NOISE_MIN_ITERATIONS || iterations < j->noise_check_at) return;
  j->noise_check_at = iterations + (iterations + 7) / 8;
  if (j->relmse_est > j->halt_noise) return;
  pc_wire_log("job %llu: estimated relMSE %.4g <= %.4g after %llu iterations", (unsigned long long)j->id, j->relmse_est,
              j->halt_noise, (unsigned long long)iterations);
  pc_job_halt(c, j);
}

/* Study jobs: the merged film is kept at log-spaced worker-seconds (pc_job_snapshot_time; the
 * job's image is the point at the budget), and the job halts once its budget of
 * worker-seconds is merged. */
static void check_study(pc_coord *c, pc_job *j) {
  if (!(j->halt_worker_seconds > 0) || j->state != PC_JOB_RUNNING) return;
  double ws = j->stats_merged.t_total;
  int k = -1; /* the last snapshot time passed */
  for (int i = 0; i < (int)j->snapshots; i++)
    if (ws >= pc_job_snapshot_time(j, i)) k = i;
  /* one snapshot for several times passed at once, as the one-machine study did */
  if (k >= 0 && (uint32_t)k >= j->snaps_queued) {
    pc_op *op = calloc(1, sizeof *op);
    if (op) {
      op->c = c;
      op->j = j;
      op->snap_k = ++j->snaps_queued_n;
      op->snap_at = pc_job_snapshot_time(j, k);
      op->wall = j->elapsed;
      j->snaps_queued = (uint32_t)k + 1;
      append_op(j, op); /* (called from op_after, which starts it) */
    } else {
      pc_wire_log("job %llu: out of memory for a snapshot", (unsigned long long)j->id);
    }
  }
  if (ws >= j->halt_worker_seconds) {
    pc_wire_log("job %llu: %.2f worker-seconds merged (budget %.2f): halting", (unsigned long long)j->id, ws,
                j->halt_worker_seconds);
    pc_job_halt(c, j);
  }
}

double pc_job_snapshot_time(const pc_job *j, int k) {
  int n = (int)j->snapshots;
  if (n < 1) return j->halt_worker_seconds;
  return j->halt_worker_seconds * pow(PC_JOB_SNAPSHOT_FIRST, (double)(n - k) / n);
}

void pc_job_take_stored_settings(pc_job *j, const Pcbpt__Settings *s) {
  j->halt_noise = s->halt_noise;
  snprintf(j->auto_report, sizeof j->auto_report, "%s", s->auto_report ? s->auto_report : "");
  for (char *q = j->auto_report; *q; q++) /* it reaches logs, JSON and image headers */
    if ((unsigned char)*q < 0x20 || *q == 0x7f || *q == '"' || *q == '\\') *q = '?';
  j->study_group = s->study_group;
  j->group_workers = s->group_workers;
  j->halt_worker_seconds = s->halt_worker_seconds;
  j->pilot_group = s->pilot_group;
  j->prior_group = s->prior_group;
  j->prior_amount = s->prior_amount;
  j->snapshots = s->snapshots <= PC_JOB_MAX_SNAPSHOTS ? s->snapshots : PC_JOB_MAX_SNAPSHOTS;
}

/* The ops run on libuv's shared pool threads, each named for what it does now (the name stays
 * through any later file-system work of the loop on that thread until its next op). */
static void merge_work(uv_work_t *w) {
  pc_thread_set_name("pc-merge");
  pc_op *op = w->data;
  pc_job *j = op->j;
  size_t want = pc_wire_film_size_traced(&j->film, upload_traced(op->first, op->count));
  if (op->raw != want) {
    op->rc = pc_errf(&op->err, PC_EINVAL, "upload of %llu bytes, a %dx%d film with %d layers is %zu (wrong resolution?)",
                     (unsigned long long)op->raw, j->film.w, j->film.h, j->film.nlayers, want);
    return;
  }
  op->rc = pc_wire_film_add_z(op->buf, op->len, &j->film, judge_counts, op, &op->err);
  if (!op->rc) j->film_seconds += op->stats.t_total;
  if (!op->rc) film_estimate(j, op->wall, &op->relmse_est, &op->est_iterations);
}

/* The checkpoint streams into its file as it is compressed (no serialized copy of the film). */
typedef struct file_sink { int fd; const char *path; } file_sink;
static int write_sink(void *user, const uint8_t *p, size_t n, pc_err *e) {
  file_sink *f = user;
  return pc_write_all(f->fd, p, n) == 0 ? 0 : pc_errf(e, PC_EIO, "%s: %s", f->path, strerror(errno));
}

/* The film, compressed, to dir/ckpt.GEN through a synced temporary and a rename. */
static int write_ckpt_file(pc_op *op, pc_job *j, const char *dir) {
  char path[600], tmp[640];
  snprintf(path, sizeof path, "%s/ckpt.%llu", dir, (unsigned long long)op->gen);
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return pc_errf(&op->err, PC_EIO, "%s: %s", tmp, strerror(errno));
  file_sink fs = {fd, tmp};
  int rc = pc_wire_film_compress(&j->film, 1, write_sink, &fs, NULL, &op->err);
  if (!rc && fsync(fd) != 0) rc = pc_errf(&op->err, PC_EIO, "%s: %s", tmp, strerror(errno));
  if (rc) {
    close(fd);
    return rc;
  }
  if (close(fd) != 0 || rename(tmp, path) != 0) return pc_errf(&op->err, PC_EIO, "%s: %s", path, strerror(errno));
  int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0 || fsync(dfd) != 0) rc = pc_errf(&op->err, PC_EIO, "%s: fsync: %s", dir, strerror(errno));
  if (dfd >= 0) close(dfd);
  return rc;
}

static void ckpt_work(uv_work_t *w) {
  pc_thread_set_name("pc-checkpoint");
  pc_op *op = w->data;
  pc_job *j = op->j;
  char dir[512];
  pc_job_path(op->c, j, NULL, dir, sizeof dir);
  /* a volatile store is thrown away with its coordinator, which never restarts from it: there
   * the checkpoint only commits the acks, and a film file would never be read */
  if (!op->c->volatile_store) op->rc = write_ckpt_file(op, j, dir);
  if (op->rc || !op->write_exr) return;
  char img[600];
  snprintf(img, sizeof img, "%s/image.exr", dir);
  /* the image is written like the checkpoint: a failure is the data dir's (retried) */
  if (write_image(j, img, &op->stats, op->wall, 0, &op->err) != 0) op->rc = PC_EIO;
}

/* A study snapshot of the merged film (pc_job_snapshot_due). Its worker-seconds are those of
 * the uploads in the film now, which an op queued meanwhile may have added to. */
static void snap_work(uv_work_t *w) {
  pc_thread_set_name("pc-snapshot");
  pc_op *op = w->data;
  pc_job *j = op->j;
  char leaf[40], path[600];
  snprintf(leaf, sizeof leaf, "snap.%u.exr", op->snap_k);
  pc_job_path(op->c, j, leaf, path, sizeof path);
  pc_render_stats st = j->stats_merged;
  st.t_total = j->film_seconds;
  op->rc = write_image(j, path, &st, op->wall, op->snap_at, &op->err);
}

/* The same header as a standalone `render` writes, plus the job id and, for studies, the
 * worker-seconds behind the film. */
static int write_image(const pc_job *j, const char *img, const pc_render_stats *st, double wall, double snap_at, pc_err *e) {
  char defines[PC_SCENE_DEFINES_TEXT];
  pc_scene_defines_text(&j->set.defines, defines, sizeof defines);
  char idbuf[32], seed[32], version[64], pcbpt_flags[320], weights[96], bundle[2 * PC_BUNDLE_HASH + 1];
  pc_film mix;
  const pc_film *shown;
  double pilot_weight = pc_prior_weight(j, snap_at > 0 ? snap_at : st->t_total, wall);
  int rc = pc_prior_shown(j, pilot_weight, &mix, &shown, e);
  if (rc) return rc;
  pc_render_settings_pcbpt_flags(&j->set, pcbpt_flags, sizeof pcbpt_flags);
  /* a pilot's films in the image weigh their strategies as their own methods do */
  if (shown != &j->film) snprintf(weights, sizeof weights, "%s", PC_WEIGHTS_MIXED);
  else pc_render_settings_weights(&j->set, weights, sizeof weights);
  snprintf(idbuf, sizeof idbuf, "%llu", (unsigned long long)j->id);
  pc_bundle_hex(j->bundle, bundle);
  snprintf(seed, sizeof seed, "%llu", (unsigned long long)j->set.seed);
  snprintf(version, sizeof version, "pcbpt %s", PCBPT_VERSION);
  pc_exr_attr attrs[] = {
    {.name = "pcbpt.job", .type = PC_ATTR_STRING, .s = idbuf},
    {.name = "pcbpt.method", .type = PC_ATTR_STRING, .s = pc_method_name(j->set.method)},
    {.name = "pcbpt.iterations", .type = PC_ATTR_DOUBLE, .d = (double)j->film.layers[PC_LAYER_PT].count},
    {.name = "pcbpt.seed", .type = PC_ATTR_STRING, .s = seed},
    {.name = "pcbpt.max_depth", .type = PC_ATTR_DOUBLE, .d = j->set.max_depth},
    {.name = PC_WEIGHTS_ATTR, .type = PC_ATTR_STRING, .s = weights},
    {.name = "pcbpt.render_seconds", .type = PC_ATTR_DOUBLE, .d = wall},
    {.name = "pcbpt.worker_seconds", .type = PC_ATTR_DOUBLE, .d = st->t_total},
    {.name = "pcbpt.cpu_seconds", .type = PC_ATTR_DOUBLE, .d = st->t_cpu},
    {.name = "pcbpt.rays", .type = PC_ATTR_DOUBLE, .d = (double)st->rays},
    {.name = "pcbpt.time_paths", .type = PC_ATTR_DOUBLE, .d = st->t_paths},
    {.name = "pcbpt.time_lt", .type = PC_ATTR_DOUBLE, .d = st->t_lt},
    {.name = "pcbpt.time_pmf", .type = PC_ATTR_DOUBLE, .d = st->t_pmf},
    {.name = "pcbpt.time_connect", .type = PC_ATTR_DOUBLE, .d = st->t_connect},
    {.name = "pcbpt.pmf_bytes", .type = PC_ATTR_DOUBLE, .d = (double)st->pmf_bytes},
    {.name = "pcbpt.scene", .type = PC_ATTR_STRING, .s = j->name},
    /* the scene's files as shipped: an image of an edited scene or mesh is told apart */
    {.name = PC_SCENE_BUNDLE_ATTR, .type = PC_ATTR_STRING, .s = bundle},
    {.name = PC_SCENE_DEFINES_ATTR, .type = PC_ATTR_STRING, .s = defines}, /* its -D values: "" for none */
    {.name = "pcbpt.halt_noise", .type = PC_ATTR_DOUBLE, .d = j->halt_noise},
    /* how much of the image is the pilot's (docs/auto.md) */
    {.name = "pcbpt.pilot_weight", .type = PC_ATTR_DOUBLE, .d = pilot_weight},
    {.name = "pcbpt.pilot_iterations", .type = PC_ATTR_DOUBLE,
     .d = j->prior_ready ? (double)j->prior.layers[PC_LAYER_PT].count : 0.0},
    /* what the weight is made of: the pilot's amount a, in the unit of the job's budget */
    {.name = "pcbpt.pilot_amount", .type = PC_ATTR_DOUBLE, .d = j->prior_ready ? j->prior_amount : 0.0},
    {.name = "software", .type = PC_ATTR_STRING, .s = version},
    {.name = "pcbpt.pcbpt_flags", .type = PC_ATTR_STRING, .s = pcbpt_flags}, /* only when set */
    {.name = "pcbpt.auto", .type = PC_ATTR_STRING, .s = j->auto_report},     /* only when set */
  };
  int nattrs = (int)(sizeof attrs / sizeof attrs[0]) - 2;
  if (pcbpt_flags[0]) attrs[nattrs++] = attrs[sizeof attrs / sizeof attrs[0] - 2];
  if (j->auto_report[0]) attrs[nattrs++] = attrs[sizeof attrs / sizeof attrs[0] - 1];
  rc = pc_film_write_exr(shown, img, attrs, nattrs, e);
  if (shown != &j->film) pc_film_free(&mix);
  return rc;
}

static void free_range_list_closed(pc_job *j) {
  pc_range **pp = &j->ranges;
  while (*pp) {
    pc_range *r = *pp;
    if (r->acked == r->count && !r->merging) {
      *pp = r->next;
      free(r);
    } else {
      pp = &r->next;
    }
  }
}

static void check_finished(pc_coord *c, pc_job *j);
static void maybe_ckpt(pc_coord *c, pc_job *j);

static bool job_live(const pc_job *j) { return j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING; }

/* Answers acknowledgements that no checkpoint will commit (the job ended first): a worker
 * uploads nothing more until its last upload is answered, so silence would wedge it. */
static void refuse_acks(pc_pending_ack **list, const char *why) {
  while (*list) {
    pc_pending_ack *a = *list;
    *list = a->next;
    if (!a->peer->closed) pc_peer_send_ack(a->peer, a->range_id, 0, why);
    pc_peer_unref(a->peer);
    free(a);
  }
}

/* Records a checkpoint's range progress and the job in one transaction, then (only once
 * that committed) applies it in memory, removes the previous checkpoint file and sends the
 * acknowledgements. On a store error nothing changed: the caller retries. */
static int commit_ckpt(pc_coord *c, pc_job *j, pc_op *op, pc_err *e) {
  int rc = pc_store_begin(c, e);
  uint64_t added = 0;
  for (int i = 0; !rc && i < op->nsnap; i++) {
    range_snap *sn = &op->snap[i];
    pc_range *r = pc_sched_find_range(j, sn->id);
    sn->split_id = 0;
    if (!r) continue;
    pc_range upd = *r;
    added += sn->merged - r->acked;
    upd.acked = sn->merged;
    if (sn->final && upd.acked < upd.count) {
      /* the rest of a range its worker stopped early is a new range (while running) */
      if (j->state == PC_JOB_RUNNING)
        rc = pc_store_insert_range(c, j->id, r->first + upd.acked, r->count - upd.acked, &sn->split_id, e);
      upd.count = upd.acked;
    }
    if (!rc) rc = pc_store_update_range(c, &upd, upd.acked < upd.count, e);
  }
  uint64_t old_gen = j->ckpt_gen;
  pc_render_stats old_stats = j->stats;
  j->ckpt_gen = op->gen;
  j->done += added;
  j->stats = op->stats;
  if (!rc) rc = pc_store_update_job(c, j, e);
  if (!rc) rc = pc_store_commit(c, e);
  if (rc) {
    pc_store_rollback(c);
    j->ckpt_gen = old_gen;
    j->done -= added;
    j->stats = old_stats;
    return rc;
  }
  for (int i = 0; i < op->nsnap; i++) {
    range_snap *sn = &op->snap[i];
    pc_range *r = pc_sched_find_range(j, sn->id);
    if (!r) continue;
    if (sn->split_id) {
      pc_range *nr = calloc(1, sizeof *nr);
      if (!nr) {
        /* stored: a restarted coordinator has it; this one cannot finish the job */
        pc_job_fail(c, j, "out of memory");
      } else {
        nr->id = sn->split_id;
        nr->first = r->first + sn->merged;
        nr->count = r->count - sn->merged;
        nr->orphan_since = 1; /* available at once */
        nr->next = r->next;
        r->next = nr;
        pc_sched_nudge(c);
      }
    }
    r->acked = sn->merged;
    if (sn->final) r->count = sn->merged < r->count ? sn->merged : r->count;
    if (r->acked == r->count) r->owner = NULL;
  }
  if (old_gen) {
    char p[600], leaf[40];
    snprintf(leaf, sizeof leaf, "ckpt.%llu", (unsigned long long)old_gen);
    pc_job_path(c, j, leaf, p, sizeof p);
    if (unlink(p) != 0 && errno != ENOENT) pc_wire_log("job %llu: cannot remove %s: %s", (unsigned long long)j->id, p, strerror(errno));
  }
  double now = pc_coord_now();
  while (op->acks) {
    pc_pending_ack *a = op->acks;
    op->acks = a->next;
    /* its next upload was held back for this: the progress deadlines restart */
    for (pc_range *r = j->ranges; r; r = r->next)
      if (r->owner == a->peer && r->progress_at > 0 && r->progress_at < now) r->progress_at = now;
    if (!a->peer->closed) pc_peer_send_ack(a->peer, a->range_id, a->acked_end, NULL);
    pc_peer_unref(a->peer);
    free(a);
  }
  free_range_list_closed(j);
  return 0;
}

/* A checkpoint could not be written or recorded (a full or failing disk): the job keeps
 * what is merged in memory and its last good checkpoint on disk, its workers keep their
 * unacknowledged uploads (nothing more is taken from them meanwhile), and the checkpoint is
 * tried again every few seconds; status shows why. The store still says running, so a
 * restart resumes from the last good checkpoint and the workers send the rest again. */
void pc_job_storage_trouble(pc_coord *c, pc_job *j, pc_op *op, const char *why) {
  if (!j->storage_error[0]) pc_wire_log("job %llu: paused until the data dir can be written: %s", (unsigned long long)j->id, why);
  snprintf(j->storage_error, sizeof j->storage_error, "waiting for the data dir: %.250s", why);
  j->storage_retry = pc_coord_now() + STORAGE_RETRY;
  j->dirty = true;
  if (op) {
    pc_pending_ack **tail = &op->acks;
    while (*tail) tail = &(*tail)->next;
    *tail = j->acks;
    j->acks = op->acks;
    op->acks = NULL;
  }
  (void)c;
}

/* FNV-1a of a refusal's reason, to tell a deterministic refusal repeating from other ones. */
static uint64_t reason_hash(const char *s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 0x100000001b3ull;
  return h;
}

/* An ended job's films, once no background operation uses them (a pilot candidate's goes to
 * its group: pc_prior_keep takes it). Jobs waiting for memory may fit now. */
static void release_films(pc_coord *c, pc_job *j) {
  bool ended = j->state == PC_JOB_DONE || j->state == PC_JOB_FAILED || j->state == PC_JOB_CANCELLED;
  if (j->busy || j->ops || !j->film_ready || !ended) return;
  pc_prior_keep(c, j);
  if (j->film_ready) pc_film_free(&j->film);
  j->film_ready = false;
  if (j->prior_ready) pc_film_free(&j->prior);
  j->prior_ready = false;
  pc_sched_nudge(c);
}

static void op_after(uv_work_t *w, int status) {
  pc_op *op = w->data;
  pc_coord *c = op->c;
  pc_job *j = op->j;
  j->busy = false;
  if (status != 0 && !op->rc) op->rc = pc_errf(&op->err, PC_EIO, "background work cancelled: %s", uv_strerror(status));
  if (op->snap_k) {
    if (op->rc) pc_wire_log("job %llu: snapshot %u not kept: %s", (unsigned long long)j->id, op->snap_k, op->err.msg);
    else if (op->snap_k > j->snaps_taken) j->snaps_taken = op->snap_k;
  } else if (op->is_merge) {
    pc_range *r = pc_sched_find_range(j, op->range_id);
    if (r) r->merging = false, r->in_merge = 0;
    if (op->rc) {
      pc_wire_log("job %llu: refused upload from %s for range %llu [%llu,+%llu): %s", (unsigned long long)j->id,
                  op->peer->conn.peer, (unsigned long long)op->range_id, (unsigned long long)op->first,
                  (unsigned long long)op->count, op->err.msg);
      if (!op->peer->closed) pc_peer_send_ack(op->peer, op->range_id, 0, op->err.msg);
      /* A range's iterations render the same film on any worker (the seed fixes them), so a
       * film refused for what it holds (e.g. sums beyond any radiance, from a scene's absurd
       * emitter) is refused again, for the same reason, however often the range is re-run.
       * From its second time in a row the range counts as one that could not be rendered, or
       * the job would never end; bad uploads of other kinds (a broken or hostile worker's)
       * differ in their reasons and only send the range to another worker. */
      if (r) {
        uint64_t why_hash = reason_hash(op->err.msg);
        r->refused = r->refused > 0 && r->refused_why == why_hash ? r->refused + 1 : 1;
        r->refused_why = why_hash;
      }
      if (r && r->owner == op->peer) {
        if (r->refused >= 2) {
          char why[300];
          snprintf(why, sizeof why, "its film of iterations [%llu,+%llu) was refused %u times in a row: %.200s",
                   (unsigned long long)op->first, (unsigned long long)op->count, r->refused, op->err.msg);
          pc_job_range_failed(c, j, r, op->peer->name, why);
        } else {
          /* the worker drops the range; hand it to someone else at once */
          r->owner = NULL;
          r->orphan_since = 1;
          pc_sched_nudge(c);
        }
      }
    } else if (r && !job_live(j)) {
      /* merged into a film nobody will write: the job ended while it ran */
      if (!op->peer->closed) pc_peer_send_ack(op->peer, op->range_id, 0, "job is not running");
    } else if (r) {
      r->merged += op->count;
      r->final = r->final || op->final;
      j->ack_soon = j->ack_soon || op->final;
      pc_render_stats_add(&j->stats_merged, &op->stats);
      j->merges++;
      j->light_per_iter = op->light_per_iter;
      j->relmse_est = op->relmse_est;
      j->dirty = true;
      check_noise(c, j, op->est_iterations);
      pc_sched_served(op->peer, j->id, op->count, op->stats.t_total);
      check_study(c, j);
      pc_pending_ack *a = calloc(1, sizeof *a);
      if (a) {
        a->peer = op->peer;
        pc_peer_ref(op->peer);
        a->range_id = r->id;
        a->acked_end = r->first + r->merged;
        a->next = j->acks;
        j->acks = a;
      }
    }
    pc_peer_unref(op->peer);
    pc_big_spare_keep(&c->spare_up, op->buf, op->cap);
    pc_coord_buffered(c, -(long long)op->len, true);
  } else {
    pc_err e = {0};
    bool stored = !op->rc && commit_ckpt(c, j, op, &e) == 0;
    if (!stored && !job_live(j)) {
      /* the job ended while it ran: its acknowledgements are refused below */
    } else if (!stored && (!op->rc || op->rc == PC_EIO)) {
      pc_job_storage_trouble(c, j, op, op->rc ? op->err.msg : e.msg);
    } else if (!stored) {
      pc_job_fail(c, j, op->err.msg);
    } else {
      if (op->write_exr) j->last_exr = pc_coord_now();
      j->ckpts++;
      if (j->storage_error[0]) pc_wire_log("job %llu: the data dir is writable again", (unsigned long long)j->id);
      j->storage_error[0] = 0;
    }
    refuse_acks(&op->acks, "job is not running"); /* what a checkpoint of an ended job did not commit */
    free(op->snap);
    /* (an upload that came after all, or a range left open, makes it a checkpoint like others) */
    bool done = j->finishing && !op->rc && !j->storage_error[0] && j->state != PC_JOB_FAILED && !j->ranges && !j->ops && !j->dirty;
    j->finishing = false;
    if (done) {
      j->state = PC_JOB_DONE;
      pc_err e;
      if (pc_store_update_job(c, j, &e) != 0) pc_wire_log("job %llu: %s", (unsigned long long)j->id, e.msg);
      pc_wire_log("job %llu: done, %llu iterations (%llu uploads merged, %llu checkpoints)", (unsigned long long)j->id,
                  (unsigned long long)j->done, (unsigned long long)j->merges, (unsigned long long)j->ckpts);
    }
  }
  free(op);
  if (j->ops) op_start(j);
  else if (!j->finishing) {
    maybe_ckpt(c, j);
    check_finished(c, j);
  }
  release_films(c, j);
}

static void op_start(pc_job *j) {
  pc_op *op = j->ops;
  j->ops = op->next;
  if (!j->ops) j->ops_tail = NULL;
  j->busy = true;
  op->work.data = op;
  if (op->is_merge) op->light_per_iter = j->light_per_iter;
  int r = uv_queue_work(op->c->loop, &op->work, op->snap_k ? snap_work : op->is_merge ? merge_work : ckpt_work, op_after);
  if (r) {
    op->rc = pc_errf(&op->err, PC_EIO, "uv_queue_work: %s", uv_strerror(r));
    op_after(&op->work, 0);
  }
}

void pc_job_merge(pc_coord *c, pc_job *j, pc_peer *p, pc_range *r, uint8_t *buf, size_t len, size_t cap, uint64_t raw,
                  uint64_t first, uint64_t count, bool final, const pc_render_stats *stats) {
  pc_op *op = calloc(1, sizeof *op);
  if (!op) {
    free(buf);
    pc_coord_buffered(c, -(long long)len, true);
    pc_peer_send_ack(p, r->id, 0, "coordinator out of memory");
    return;
  }
  op->stats = *stats;
  op->c = c;
  op->j = j;
  op->is_merge = true;
  op->peer = p;
  pc_peer_ref(p);
  op->range_id = r->id;
  op->first = first;
  op->count = count;
  op->final = final;
  op->buf = buf;
  op->len = len;
  op->cap = cap;
  op->raw = raw;
  op->wall = j->elapsed;
  r->merging = true;
  r->in_merge = count;
  queue_op(j, op);
}

/* Snapshots range progress and pending acks, and queues a checkpoint. */
static void queue_ckpt(pc_coord *c, pc_job *j, bool exr) {
  pc_op *op = calloc(1, sizeof *op);
  int n = 0;
  for (pc_range *r = j->ranges; r; r = r->next) n++;
  if (op) op->snap = calloc((size_t)n + 1, sizeof *op->snap);
  if (!op || !op->snap) { free(op); pc_wire_log("job %llu: out of memory for a checkpoint", (unsigned long long)j->id); return; }
  op->c = c;
  op->j = j;
  op->gen = j->ckpt_gen + 1;
  op->write_exr = exr;
  for (pc_range *r = j->ranges; r; r = r->next) {
    if (r->merged == r->acked && !r->final) continue;
    op->snap[op->nsnap].id = r->id;
    op->snap[op->nsnap].merged = r->merged;
    op->snap[op->nsnap].final = r->final;
    op->nsnap++;
  }
  op->acks = j->acks;
  op->stats = j->stats_merged;
  op->wall = j->elapsed;
  j->acks = NULL;
  j->dirty = j->ack_soon = false;
  j->last_ckpt = pc_coord_now();
  queue_op(j, op);
}

/* Nothing more will be merged but what the ranges' last uploads bring: the checkpoints that
 * close them, and so the job, should not wait for the interval. */
static bool ending(const pc_job *j) {
  if (j->state == PC_JOB_STOPPING) return true;
  if (!j->halt_iterations || j->next_iter < j->halt_iterations) return false;
  for (const pc_range *r = j->ranges; r; r = r->next)
    if (!r->final && r->merged < r->count) return false;
  return true;
}

/* A checkpoint now would close every open range (complete, or final while stopping), so it
 * can be the job's last one, with the image, instead of being followed by another. */
static bool closes_all(const pc_job *j) {
  for (const pc_range *r = j->ranges; r; r = r->next)
    if (r->merged < r->count && !(r->final && j->state == PC_JOB_STOPPING)) return false;
  return ending(j);
}

/* Queues a checkpoint of what is merged when one is due. */
static void maybe_ckpt(pc_coord *c, pc_job *j) {
  double now = pc_coord_now();
  if ((j->state != PC_JOB_RUNNING && j->state != PC_JOB_STOPPING) || !j->dirty || j->busy || j->ops) return;
  if (j->storage_error[0] && now < j->storage_retry) return;
  if (now - j->last_ckpt < c->ckpt_interval && !ending(j) && !j->ack_soon) return;
  bool last = closes_all(j);
  j->finishing = last;
  queue_ckpt(c, j, last || now - j->last_exr >= c->exr_interval);
}

static void check_finished(pc_coord *c, pc_job *j) {
  if (j->state != PC_JOB_RUNNING && j->state != PC_JOB_STOPPING) return;
  if (j->busy || j->ops || j->dirty || j->finishing) return;
  bool halted = j->state == PC_JOB_STOPPING || (j->halt_iterations && j->next_iter >= j->halt_iterations);
  if (!halted || j->ranges) return;
  j->finishing = true;
  queue_ckpt(c, j, true);
}

/* Removes the checkpoint files of j but its current one: a kill between writing a checkpoint
 * and recording it, or between recording it and removing the one before, leaves them. */
static void remove_stale_ckpts(pc_coord *c, pc_job *j, const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return;
  char keep[40];
  snprintf(keep, sizeof keep, "ckpt.%llu", (unsigned long long)j->ckpt_gen);
  for (struct dirent *de; (de = readdir(d)) != NULL;) {
    if (strncmp(de->d_name, "ckpt.", 5) != 0 || (j->ckpt_gen && strcmp(de->d_name, keep) == 0)) continue;
    char p[900];
    snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
    if (unlink(p) != 0) pc_wire_log("job %llu: cannot remove %s: %s", (unsigned long long)j->id, p, strerror(errno));
  }
  closedir(d);
  (void)c;
}

int pc_job_activate(pc_coord *c, pc_job *j, pc_err *e) {
  if (j->film_ready) return 0;
  char dir[512];
  snprintf(dir, sizeof dir, "%s/jobs", c->data_dir);
  if (mkdir(dir, 0700) != 0 && errno != EEXIST) return pc_errf(e, PC_EIO, "%s: %s", dir, strerror(errno));
  pc_job_path(c, j, NULL, dir, sizeof dir);
  if (mkdir(dir, 0700) != 0 && errno != EEXIST) return pc_errf(e, PC_EIO, "%s: %s", dir, strerror(errno));
  remove_stale_ckpts(c, j, dir);
  int rc = pc_film_init_threads(&j->film, j->set.width, j->set.height, j->set.strategy_layers, 0, e);
  if (rc) return rc;
  if (j->ckpt_gen) {
    char path[600], leaf[40];
    snprintf(leaf, sizeof leaf, "ckpt.%llu", (unsigned long long)j->ckpt_gen);
    pc_job_path(c, j, leaf, path, sizeof path);
    FILE *f = fopen(path, "rb");
    uint8_t *z = NULL;
    long zn = -1;
    if (f && fseek(f, 0, SEEK_END) == 0) zn = ftell(f);
    if (f && zn > 0 && fseek(f, 0, SEEK_SET) == 0 && (z = malloc((size_t)zn)) && fread(z, 1, (size_t)zn, f) == (size_t)zn) {
      rc = pc_wire_film_load(z, (size_t)zn, &j->film, e);
      if (rc) {
        pc_err why = *e; /* names the checkpoint: a refused one must say which file */
        pc_errf(e, rc, "%s: %s", path, why.msg);
      }
    } else {
      rc = pc_errf(e, PC_EIO, "%s: cannot read checkpoint: %s", path, strerror(errno));
    }
    if (f) fclose(f);
    free(z);
    if (rc) { pc_film_free(&j->film); return rc; }
  }
  j->upload_limit = ZSTD_compressBound(pc_wire_film_size_traced(&j->film, PC_TRACE_ITERATIONS));
  pc_prior_attach(c, j);
  uint64_t n;
  /* the checkpoint's film holds the committed uploads: their worker-seconds are stored */
  j->film_seconds = j->stats_merged.t_total;
  film_estimate(j, j->elapsed, &j->relmse_est, &n);
  for (int k = 0; k < (int)j->snapshots; k++)
    if (j->stats_merged.t_total >= pc_job_snapshot_time(j, k)) j->snaps_queued = (uint32_t)k + 1;
  j->film_ready = true;
  if (j->state == PC_JOB_QUEUED) {
    j->state = PC_JOB_RUNNING;
    if ((rc = pc_store_update_job(c, j, e)) != 0) return rc;
  }
  return 0;
}

void pc_job_fail(pc_coord *c, pc_job *j, const char *why) {
  pc_wire_log("job %llu: failed: %s", (unsigned long long)j->id, why);
  snprintf(j->error, sizeof j->error, "%s", why);
  j->state = PC_JOB_FAILED;
  j->finishing = false;
  j->storage_error[0] = 0;
  refuse_acks(&j->acks, "job failed");
  for (pc_range *r = j->ranges; r; r = r->next)
    if (r->owner && !r->owner->closed) pc_peer_send_cancel(r->owner, j->id, 0, false);
  pc_err e;
  if (pc_store_update_job(c, j, &e) != 0) pc_wire_log("job %llu: %s", (unsigned long long)j->id, e.msg);
  release_films(c, j);
}

void pc_job_range_failed(pc_coord *c, pc_job *j, pc_range *r, const char *worker, const char *why) {
  r->owner = NULL;
  r->orphan_since = 1; /* to another worker at once */
  pc_sched_nudge(c);
  pc_wire_log("job %llu: range %llu failed on %s: %s", (unsigned long long)j->id, (unsigned long long)r->id, worker, why);
  j->failures++;
  pc_err e;
  if (pc_store_update_job(c, j, &e) != 0) pc_wire_log("job %llu: %s", (unsigned long long)j->id, e.msg);
  if (j->failures >= MAX_RANGE_FAILURES && job_live(j)) {
    char msg[400];
    snprintf(msg, sizeof msg, "render failed on worker %s: %s", worker, why);
    pc_job_fail(c, j, msg);
  }
}

void pc_job_cancel(pc_coord *c, pc_job *j) {
  if (j->state == PC_JOB_DONE || j->state == PC_JOB_FAILED || j->state == PC_JOB_CANCELLED) return;
  for (pc_range *r = j->ranges; r; r = r->next)
    if (r->owner && !r->owner->closed) pc_peer_send_cancel(r->owner, j->id, 0, false);
  j->state = PC_JOB_CANCELLED;
  j->finishing = false;
  j->storage_error[0] = 0;
  refuse_acks(&j->acks, "job cancelled");
  pc_err e;
  if (pc_store_update_job(c, j, &e) != 0) pc_wire_log("job %llu: %s", (unsigned long long)j->id, e.msg);
  pc_wire_log("job %llu: cancelled", (unsigned long long)j->id);
  release_films(c, j);
}

void pc_job_halt(pc_coord *c, pc_job *j) {
  if (j->state == PC_JOB_QUEUED) {
    pc_job_cancel(c, j);
    return;
  }
  if (j->state != PC_JOB_RUNNING) return;
  j->state = PC_JOB_STOPPING;
  j->stopping_since = pc_coord_now();
  for (pc_range *r = j->ranges; r; r = r->next)
    if (r->owner && !r->owner->closed) pc_peer_send_cancel(r->owner, j->id, r->id, true);
  pc_wire_log("job %llu: halting; collecting what is rendered", (unsigned long long)j->id);
}

void pc_job_tick(pc_coord *c, pc_job *j, double dt) {
  if (j->state != PC_JOB_RUNNING && j->state != PC_JOB_STOPPING) return;
  double now = pc_coord_now();
  if (j->state == PC_JOB_RUNNING && !j->storage_error[0]) { /* paused time is not render time */
    j->elapsed += dt;
    if (j->halt_seconds > 0 && j->elapsed >= j->halt_seconds) pc_job_halt(c, j);
  }
  if (j->state == PC_JOB_STOPPING) {
    /* ranges nobody will finish are closed at what is merged */
    bool force = now - j->stopping_since > c->orphan_grace + 10;
    for (pc_range *r = j->ranges; r; r = r->next)
      if (!r->merging && (!r->owner || force) && !r->final) { r->final = true; j->dirty = true; }
  }
  maybe_ckpt(c, j);
  check_finished(c, j);
}

void pc_job_free(pc_job *j) {
  while (j->ranges) {
    pc_range *r = j->ranges;
    j->ranges = r->next;
    free(r);
  }
  while (j->acks) {
    pc_pending_ack *a = j->acks;
    j->acks = a->next;
    free(a);
  }
  if (j->film_ready) pc_film_free(&j->film);
  if (j->prior_ready) pc_film_free(&j->prior);
  free(j->settings_blob);
  free(j);
}

