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
/* Starts the worker with `threads` render threads (0 = every core). Started after the job is
 * submitted, its first work request gets the job at once instead of a retry later. */
int pc_embedded_start_worker(pc_embedded *f, int threads, pc_err *e);
/* Stops both, restores stderr and removes the temporary directory. */
void pc_embedded_stop(pc_embedded *f);

#endif
