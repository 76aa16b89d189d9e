/* embedded.h: the one-machine farm behind `pcbpt-coord render` (DESIGN.md §1): a coordinator
 * on 127.0.0.1:<ephemeral> with a fresh temporary data dir and token, and one in-process
 * worker with all the render threads, so a local render goes through the real protocol. */
#ifndef PC_EMBEDDED_H
#define PC_EMBEDDED_H

#include <stdbool.h>
#include <uv.h>

#include "coord.h"
#include "error.h"
#include "worker.h"

typedef struct pc_embedded {
  char dir[256];         /* temporary: data/, cache/, token, farm.log; removed by stop */
  char token[300];
  char hostport[64];
  uint8_t key[PC_AUTH_KEY];
  int term_fd;           /* the original stderr (the farm's log goes to dir/farm.log) */
  uv_loop_t loop;
  pc_coord coord;
  uv_thread_t coord_thread, worker_thread;
  pc_worker *worker;
  bool loop_ready, coord_running, worker_running;
} pc_embedded;

/* Starts the coordinator. */
int pc_embedded_start(pc_embedded *f, pc_err *e);
/* The share of the render thread's time the embedded worker's uploads may take to compress
 * (pc_worker_opts.upload_share), which spaces its uploads within a range:
 * - LIVE where the merged image is read while it renders (a noise target is checked at each
 *   merge; a study's snapshots);
 * - SPARSE otherwise, where the uploads before the last only refresh the progress bar's
 *   estimate: an upload's whole cost (its sealing and copies on both loops, the merge) was
 *   about three times its compression (docs/performance.md, by thread at 128 spp), so this
 *   keeps all of it near 1% of the render. Films that compress in milliseconds still upload
 *   every PC_WIRE_UPLOAD_INTERVAL, and none waits more than PC_WIRE_UPLOAD_MAX_INTERVAL. */
#define PC_EMBEDDED_UPLOAD_SHARE_LIVE 0.01
#define PC_EMBEDDED_UPLOAD_SHARE_SPARSE 0.0025
/* Starts the worker with `threads` render threads (0 = every core) and the upload share above.
 * Started after the job is submitted, its first work request gets the job at once instead of
 * a retry later. */
int pc_embedded_start_worker(pc_embedded *f, int threads, double upload_share, pc_err *e);
/* Whether `jobs` jobs of `set` fit this machine's memory on the one-process farm: each job's
 * film on the coordinator, and at least one job's films on the worker (its pending film and
 * the renderer's, on `threads` threads). Where the kernel overcommits, films that do not fit
 * are allocated and the process is killed while they are zeroed; this is one line before any
 * farm starts instead. PC_ELIMIT when they do not fit. */
int pc_embedded_check_memory(const pc_render_settings *set, int threads, int jobs, pc_err *e);
/* Stops both, restores stderr and removes the temporary directory. */
void pc_embedded_stop(pc_embedded *f);

#endif
