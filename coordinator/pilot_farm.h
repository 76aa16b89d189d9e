/* pilot_farm.h: --method auto's pilot on a farm (pilot.h, docs/auto.md): each candidate is a
 * short job of its own, so every worker renders it and a larger farm tunes sooner. Used by
 * `submit` (the pilot takes a share of the job's wall-time budget) and by a farm study (the
 * pilot takes a share of auto's worker-seconds budget, so its cost counts as the other methods'
 * render time does). */
#ifndef PC_PILOT_FARM_H
#define PC_PILOT_FARM_H

#include <stdint.h>

#include "client.h"
#include "pilot.h"

typedef struct pc_pilot_farm {
  pc_client *cl;
  const uint8_t *hash;   /* the scene's bundle, already sent */
  const char *name;      /* the job's name: candidates are "<name> [auto pilot: <label>]" */
  int priority;
  /* 0: each candidate is bound by wall seconds (submit). > 0: by slice x workers worker-seconds,
   * on at most `workers` workers at once (a study of that farm size). */
  int workers;
  double worker_seconds; /* out: the summed worker-seconds of every candidate's job */
} pc_pilot_farm;

/* pc_pilot_render_fn: submits the candidate as a job and waits for its end. Its cost is the
 * job's worker-seconds (the render seconds of its merged uploads), which on a shared farm
 * measures the candidate rather than the queue it waited in. */
int pc_pilot_farm_render(void *user, const pc_render_settings *set, double seconds, uint64_t min_iterations,
                         pc_pilot_candidate *c, pc_err *e);

#endif
