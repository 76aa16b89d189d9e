/* worker.h: the farm worker, used by pcbpt-worker and by the embedded farm of
 * `pcbpt-coord render`: pc_worker runs the protocol on its own libuv loop; pc_wrender is the
 * range being rendered, shared between that loop and the render thread under one mutex. The
 * loop never touches a film: the render thread adds batches to the pending film and, when the
 * loop asks, compresses it into an upload, so the loop answers heartbeats at once whatever
 * the film's size. */
#ifndef PC_WORKER_H
#define PC_WORKER_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <uv.h>

#include "big_alloc.h"
#include "film.h"
#include "render.h"

typedef struct pc_wrender {
  uv_mutex_t mu;
  uv_cond_t cv;
  uv_thread_t thread;
  uv_async_t *notify;      /* woken on the loop after each batch and at the end of a range */
  int threads;
  size_t max_film;         /* pc_worker_opts.max_film, 0 resolved */
  /* the assignment (written by the loop while the thread is idle) */
  bool have_range, range_done, failed, quit;
  uint64_t job_id, range_id, first, count;
  pc_render_settings set;
  char scene_path[1200];
  char scene_root[1200];   /* the bundle's folder: what the scene's files may come from */
  atomic_bool cancel;
  /* progress (thread writes, loop reads, under mu) */
  uint64_t rendered;       /* iterations of the range rendered so far */
  uint64_t pend_first, pend_count; /* rendered, not yet taken for upload (in the thread's film) */
  pc_render_stats pend_stats; /* work behind them */
  double rate;             /* iterations per second */
  const pc_renderer *rend; /* the job's renderer while it exists: its progress in an iteration */
  char error[512];
  /* an upload: the loop asks (take), the thread compresses what is pending into zip */
  bool take;
  bool zip_ready;
  uint8_t *zip;
  size_t zip_len, zip_cap, zip_raw;
  double zip_seconds;      /* the last compression's wall time */
  uint64_t zip_range, zip_first, zip_count;
  pc_render_stats zip_stats;
  pc_big_spare spare; /* an upload's buffer the loop is done with, for the next */
} pc_wrender;

int pc_wrender_start(pc_wrender *w, int threads, size_t max_film, uv_async_t *notify, pc_err *e);
void pc_wrender_stop(pc_wrender *w);
/* Starts a range (the thread must be idle: no range, possibly compressing an upload of the
 * last one, which it then drops). */
void pc_wrender_assign(pc_wrender *w, uint64_t job, uint64_t range, uint64_t first, uint64_t count,
                       const pc_render_settings *s, const char *scene_path, const char *scene_root);
/* Asks the thread to compress what is pending into zip (zip_ready under mu, then notify),
 * between batches or at once when idle; nothing if an upload is already asked or waiting. */
void pc_wrender_take(pc_wrender *w);

/* A worker connected to one coordinator (reconnecting with backoff while it is away). */
typedef struct pc_worker pc_worker;
typedef struct pc_worker_opts {
  const char *host;
  int port;
  const uint8_t *key;      /* PC_AUTH_KEY bytes, copied */
  int threads;             /* render threads, 0 = every core */
  const char *name;        /* NULL: host-pid */
  const char *cache_dir;   /* scene bundles by hash (created) */
  bool handle_signals;     /* SIGINT/SIGTERM stop the worker (the standalone process) */
  /* > 0: uploads within a range are spaced so that compressing them takes at most about
   * this share of the render thread's time (wire_upload.h: between PC_WIRE_UPLOAD_INTERVAL
   * and PC_WIRE_UPLOAD_MAX_INTERVAL apart); 0: every PC_WIRE_UPLOAD_INTERVAL. pcbpt-worker
   * sets PC_WIRE_UPLOAD_SHARE, the share the coordinator sizes ranges by. The embedded farm
   * sets much less (embedded.h): its coordinator shares the machine, so every upload's
   * sealing, decompression and merge are the render's own cost too, and a crash loses the
   * whole render anyway. */
  double upload_share;
  /* Bytes of films the worker may make for one job (its pending film and the renderer's);
   * 0: what pc_big_memory_limit says the machine has. A job needing more fails its ranges
   * here with one line, where making the films would get the process killed. */
  size_t max_film;
} pc_worker_opts;

int pc_worker_create(const pc_worker_opts *o, pc_worker **out, pc_err *e);
/* Runs the worker's loop until pc_worker_stop (or a signal with handle_signals); an error
 * when it stopped because the coordinator holds a different token. */
int pc_worker_run(pc_worker *w, pc_err *e);
/* Thread-safe: makes pc_worker_run return. */
void pc_worker_stop(pc_worker *w);
void pc_worker_destroy(pc_worker *w);

#endif
