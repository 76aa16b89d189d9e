/* coord.h: the coordinator's in-memory state (`pcbpt-coord serve`): jobs with their open
 * iteration ranges and merged film, connected peers, and the store. Everything here is owned
 * by the loop thread; a job's film is touched by at most one background operation at a time
 * (the job's op queue), never concurrently with the loop. */
#ifndef PC_COORD_H
#define PC_COORD_H

#include <sqlite3.h>
#include <stdbool.h>
#include <stdint.h>
#include <uv.h>

#include "auth.h"
#include "big_alloc.h"
#include "bundle.h"
#include "film.h"
#include "render.h"
#include "pcbpt.pb-c.h"
#include "wire_conn.h"

typedef enum { PC_JOB_QUEUED, PC_JOB_RUNNING, PC_JOB_STOPPING, PC_JOB_DONE, PC_JOB_FAILED, PC_JOB_CANCELLED } pc_job_state;

typedef struct pc_peer pc_peer;
typedef struct pc_coord pc_coord;
typedef struct pc_op pc_op;

/* Iterations [first, first+count) of a job handed to one worker. `acked` iterations from
 * first are committed (checkpoint + store); `merged` >= acked are in the film in memory. */
typedef struct pc_range {
  uint64_t id, first, count, acked, merged;
  pc_peer *owner;
  double orphan_since;  /* when the owner went away; 0 while owned */
  bool merging;         /* an upload for it is being merged */
  uint64_t in_merge;    /* that upload's iterations (while merging): the status's progress */
  bool final;           /* the owner sent its last upload: close at merged on commit */
  double progress_at;   /* its progress deadline runs from here: when it was assigned, its
                           owner's last upload came or was acknowledged (0: not owned) */
  double measured_at;   /* when it was assigned or its owner's last upload came */
  bool stop_asked;      /* overdue: its owner was asked to upload what it has and stop */
  bool revoked;         /* taken back from an owner that ignored that: never re-attached */
  unsigned refused;     /* its films the merge refused in a row for one reason (job.c) */
  uint64_t refused_why; /* that reason's hash */
  struct pc_range *next;
} pc_range;

/* An acknowledgement waiting for the next commit. */
typedef struct pc_pending_ack {
  pc_peer *peer;
  uint64_t range_id, acked_end;
  struct pc_pending_ack *next;
} pc_pending_ack;

typedef struct pc_job {
  uint64_t id;
  char name[128];
  uint8_t bundle[PC_BUNDLE_HASH];
  uint8_t *settings_blob; size_t settings_len;  /* packed proto Settings, as stored */
  pc_render_settings set;
  uint64_t halt_iterations;  /* 0: none */
  double halt_seconds;       /* 0: none */
  double halt_noise;         /* 0: none; else halt once the estimated relMSE is at most this */
  double relmse_est;         /* the merged film's estimated relMSE, < 0 while it cannot tell */
  char auto_report[1024];    /* Settings.auto_report (--method auto's choice), control chars replaced */
  uint64_t noise_check_at;   /* iterations merged before --halt-noise looks again */
  int priority;
  /* equal-time studies (docs/farm-study.md; from the settings, so a restart keeps them) */
  uint64_t study_group;      /* 0: none; else interleaved with the group's other jobs */
  uint32_t group_workers;    /* at most this many workers on the group at once (0: any) */
  double halt_worker_seconds;/* 0: none; else halt at this many merged worker-seconds */
  uint32_t snapshots;        /* merged films kept at log-spaced worker-seconds (0: none) */
  uint32_t snaps_taken;      /* ... written so far (jobs/<id>/snap.<k>.exr, k = 1..) */
  uint32_t snaps_queued;     /* snapshot times passed (and queued for) so far */
  uint32_t snaps_queued_n;   /* snapshot files queued so far */
  double film_seconds;       /* worker-seconds of the uploads in the film (ops only) */
  /* --method auto (job_prior.c, docs/auto.md): a pilot candidate's film goes to pilot_group
   * when done; a job with a prior_group shows the mix of that group's film and its own */
  uint64_t pilot_group, prior_group;
  double prior_amount;       /* the pilot's share, in the unit of the job's budget (proto) */
  bool prior_ready;          /* prior holds the pilot's film (from activation on) */
  pc_film prior;
  uint32_t ranges_rerun;     /* ranges taken back from a vanished or silent worker */
  pc_job_state state;
  uint64_t next_iter, done, ckpt_gen;
  int64_t light_per_iter;    /* light-layer count per iteration, fixed by the first upload */
  double elapsed, stopping_since, last_exr, last_ckpt;
  char error[256];
  char storage_error[300];   /* the last checkpoint could not be written: retried (not stored) */
  double storage_retry;      /* ... at this time */
  bool film_ready;
  bool film_waits;           /* its film did not fit beside the others' yet (logged once) */
  /* the most one upload may hold: a compressed film of the job with its trace (from the first
   * activation on; kept when an ended job's film is freed, so an upload in flight is received
   * to its end and refused rather than its worker dropped) */
  size_t upload_limit;
  pc_film film;
  pc_range *ranges;          /* open ranges */
  bool busy;                 /* a background op runs on the film */
  pc_op *ops, *ops_tail;
  pc_pending_ack *acks;      /* merged, waiting for a commit */
  bool dirty;                /* merged > acked somewhere */
  bool ack_soon;             /* a range's last upload is merged: its worker waits on the ack */
  bool finishing;            /* the final image is being written */
  int failures;              /* ranges workers reported they could not render (stored) */
  uint64_t merges, ckpts;    /* uploads merged and checkpoints written by this process (logged) */
  pc_render_stats stats;        /* work behind the committed iterations (stored) */
  pc_render_stats stats_merged; /* ... and behind everything merged */
  struct pc_job *next;
} pc_job;

/* Bytes being streamed from a file to a peer in bulk chunks (a bundle or a fetched image). */
typedef struct pc_stream_out {
  int fd;
  uint64_t off, total;
  bool is_bundle;
  uint8_t hash[PC_BUNDLE_HASH];
} pc_stream_out;

struct pc_peer {
  pc_conn conn;
  pc_coord *coord;
  int refs;                  /* background ops holding this peer */
  bool closed;
  int role;
  bool authed, hello_seen;
  uint8_t nonce[PC_AUTH_NONCE], client_nonce[PC_AUTH_NONCE];
  char name[64];
  uint32_t threads;
  double connected, last_seen;
  double rate;               /* iterations/s it reports, measured on job rate_job */
  double upload_s;           /* seconds its last upload took to compress, as it reports */
  uint64_t rate_job;         /* the job last assigned to it */
  double mrate;              /* iterations/s its uploads on job mrate_job brought, as measured
                                here (0: none yet): bounds the range sizes its claim earns and
                                sets its ranges' progress deadlines */
  uint64_t mrate_job;
  struct { uint64_t job, iterations; double seconds, mrate; } served[8]; /* per job of its
                                latest ones: the iterations and worker-seconds it rendered (a
                                study group's jobs rotate over it, its ranges there start
                                small) and its measured rate there (kept across switches) */
  uint64_t hb_range, hb_done; /* its last heartbeat: iterations of that range rendered ... */
  double hb_frac;            /* ... and of the iteration in progress ... */
  double hb_time;            /* ... at this time */
  double hb_advanced;        /* when its heartbeats last showed that range advance: progress
                                like an upload's, for iterations longer than any deadline */
  /* upload being assembled */
  uint8_t *up_buf; size_t up_len, up_cap;
  uint32_t up_next, up_nchunks;
  uint64_t up_job, up_range, up_first, up_count, up_raw;
  bool up_final;
  pc_render_stats up_stats;
  bool paused;               /* not read from until upload memory is freed */
  bool idle;                 /* told NoWork: nudged with WorkAvailable when work comes */
  /* bundle being received from a client */
  int bun_fd; char bun_tmp[640]; uint64_t bun_off, bun_total; uint8_t bun_hash[PC_BUNDLE_HASH];
  pc_stream_out out;
  struct pc_peer *next;
};

/* A pilot's films kept for the job that will show them (job_prior.c). */
typedef struct pc_pilot_films {
  uint64_t group;
  pc_film film;              /* the group's done candidates, mixed by iterations */
  double worker_seconds;
  double since;              /* pc_coord_now() of the first */
  struct pc_pilot_films *next;
} pc_pilot_films;
#define PC_COORD_MAX_PILOT_FILMS 8 /* groups kept at once: a pilot whose job never came is dropped */

struct pc_coord {
  uv_loop_t *loop;
  uv_tcp_t listener;
  uv_timer_t tick;
  uv_signal_t sigint, sigterm;
  sqlite3 *db;
  char data_dir[256];
  uint8_t key[PC_AUTH_KEY];
  pc_job *jobs;
  pc_pilot_films *pilot_films;
  pc_peer *peers;
  int bound_port;            /* after listen (for --listen HOST:0) */
  uv_async_t wake;           /* pc_coord_stop from another thread */
  bool stopping;
  double last_tick;
  /* upload bytes held (being assembled or waiting to merge), over all peers: above
   * max_buffered, peers sending uploads are paused so memory does not grow with them */
  size_t buffered, max_buffered;
  size_t merging;            /* of which complete uploads waiting for (or in) their merge */
  /* The buffer of the last merged upload, for the next one: a fresh buffer's pages are each
   * cleared by the kernel at their first write, on the coordinator's loop (docs/performance.md,
   * "An upload's buffer kept for the next"). Freed once no job runs. */
  pc_big_spare spare_up;
  /* tunables */
  double orphan_grace, heartbeat_timeout, range_seconds, ckpt_interval, exr_interval;
  double progress_timeout;   /* seconds a range of a worker not measured yet may go without an upload */
  /* bytes of film the coordinator may hold (--max-film-mb, else the machine's memory; 0: no
   * bound known): a larger job is refused at submit, one that does not fit beside the films
   * held waits */
  size_t max_film;
  int tick_ms;               /* period of liveness, halting and checkpoint checks (250) */
  bool volatile_store;       /* a throw-away data dir (embedded render): no fsync */
  bool one_worker;           /* only one worker will ever come (embedded render): ranges keep nothing back */
  bool trim_due;             /* peers went: return freed memory to the system at the next tick */
  double last_refusal_log;   /* refused handshakes are logged at most every 10 s */
};

double pc_coord_now(void);
const char *pc_job_state_name(pc_job_state s);
int pc_job_state_parse(const char *s, pc_job_state *out);
pc_job *pc_coord_job(pc_coord *c, uint64_t id);

/* store.c: the SQLite job store. */
int pc_store_open(pc_coord *c, pc_err *e);
void pc_store_close(pc_coord *c);
int pc_store_begin(pc_coord *c, pc_err *e);
int pc_store_commit(pc_coord *c, pc_err *e);
void pc_store_rollback(pc_coord *c);
int pc_store_insert_job(pc_coord *c, pc_job *j, pc_err *e);
int pc_store_update_job(pc_coord *c, const pc_job *j, pc_err *e);
int pc_store_insert_range(pc_coord *c, uint64_t job, uint64_t first, uint64_t count, uint64_t *id, pc_err *e);
int pc_store_update_range(pc_coord *c, const pc_range *r, bool open, pc_err *e);
/* Loads every job (in submission order) and the open ranges of unfinished ones. */
int pc_store_load(pc_coord *c, pc_err *e);

/* job.c: job lifecycle: films, checkpoints, images, halting. */
#define PC_JOB_MAX_SNAPSHOTS 1000
#define PC_JOB_SNAPSHOT_FIRST (1.0 / 64) /* the first snapshot's share of the budget */
/* Worker-seconds at which study job j keeps its snapshot k (0-based): with K snapshots,
 * budget * PC_JOB_SNAPSHOT_FIRST^((K - k) / K), so with the image at the budget the K + 1
 * points are evenly spaced in log time. */
double pc_job_snapshot_time(const pc_job *j, int k);
/* job_prior.c: a done pilot candidate's film joins its group (taken from the job); a job with
 * a prior_group takes that group's film at activation (or, after a restart, the copy it saved
 * then). The pilot's weight in an image of the job after `elapsed` seconds and worker_seconds
 * of uploads (a study snapshot: the worker-seconds it was planned at), 0 without a prior; the
 * film the job shows (its own, or the mix made in *tmp); the estimate of the mix. */
void pc_prior_keep(pc_coord *c, pc_job *j);
void pc_prior_attach(pc_coord *c, pc_job *j);
double pc_prior_weight(const pc_job *j, double worker_seconds, double elapsed);
int pc_prior_shown(const pc_job *j, double weight, pc_film *tmp, const pc_film **shown, pc_err *e);
bool pc_prior_relmse_estimate(const pc_job *j, double weight, double *out);
void pc_prior_free_all(pc_coord *c);
int pc_job_activate(pc_coord *c, pc_job *j, pc_err *e);
void pc_job_fail(pc_coord *c, pc_job *j, const char *why);
/* Range r of j could not be rendered on `worker`: it goes to another worker at once, counts in
 * j->failures (stored), and the job fails at the third such range. */
void pc_job_range_failed(pc_coord *c, pc_job *j, pc_range *r, const char *worker, const char *why);
/* The data dir could not be written for j (a checkpoint, with op, or a range): j pauses and
 * retries instead of failing (job.c says how). */
void pc_job_storage_trouble(pc_coord *c, pc_job *j, pc_op *op, const char *why);
void pc_job_cancel(pc_coord *c, pc_job *j);
/* Stops handing out work and finishes the job with what its workers have rendered. */
void pc_job_halt(pc_coord *c, pc_job *j);
void pc_job_tick(pc_coord *c, pc_job *j, double dt);
void pc_job_path(const pc_coord *c, const pc_job *j, const char *leaf, char *out, size_t n);
/* Queues a merge of a received upload (takes buf). */
void pc_job_merge(pc_coord *c, pc_job *j, pc_peer *p, pc_range *r, uint8_t *buf, size_t len, size_t cap, uint64_t raw,
                  uint64_t first, uint64_t count, bool final, const pc_render_stats *stats);
void pc_job_free(pc_job *j);
/* Takes what the coordinator keeps from a job's stored settings besides the render settings:
 * --halt-noise, --method auto's report and the study fields (Settings 20-24). */
void pc_job_take_stored_settings(pc_job *j, const Pcbpt__Settings *s);

/* sched.c: handing out ranges and taking them back. */
void pc_sched_request(pc_coord *c, pc_peer *p);
void pc_sched_peer_gone(pc_coord *c, pc_peer *p);
/* An upload of `count` iterations of r came from its owner p: progress, and a measure of p. */
void pc_sched_progress(pc_job *j, pc_range *r, pc_peer *p, uint64_t count);
/* Progress deadlines of the job's ranges: an overdue owner is asked to upload what it has and
 * stop (the rest goes to others); one that ignores that too loses the range. */
void pc_sched_check_progress(pc_coord *c, pc_job *j);
/* Tells the workers told NoWork that there is work to ask for. */
void pc_sched_nudge(pc_coord *c);
pc_range *pc_sched_find_range(pc_job *j, uint64_t id);
/* p's upload of `iterations` of job `job` carried `seconds` of its render time (sched.c). */
void pc_sched_served(pc_peer *p, uint64_t job, uint64_t iterations, double seconds);

/* serve.c helpers used by the others. */
void pc_peer_send_ack(pc_peer *p, uint64_t range_id, uint64_t acked_end, const char *refused);
void pc_peer_send_cancel(pc_peer *p, uint64_t job, uint64_t range, bool upload_partial);
void pc_peer_ref(pc_peer *p);
void pc_peer_unref(pc_peer *p);
/* Upload memory: account bytes taken (n > 0) or released (n < 0; merged: bytes of a complete
 * upload whose merge ended); resumes paused peers once under the limit or with no merge left. */
void pc_coord_buffered(pc_coord *c, long long n, bool merged);

#endif
