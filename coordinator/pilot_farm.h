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
  /* Farm size: each candidate is bound by slice x workers worker-seconds, on at most `workers`
   * workers at once (a study's farm size); 0: every worker connected. */
  int workers;
  double worker_seconds; /* out: the summed worker-seconds of every candidate's job */
} pc_pilot_farm;

/* pc_pilot_render_fn: submits the candidates as jobs of one study group (interleaved by least
 * worker time), waits for their end and fetches their images. A candidate's cost is its job's
 * worker-seconds (the render seconds of its merged uploads), which on a shared farm measures
 * the candidate rather than the queue it waited in. */
int pc_pilot_farm_render(void *user, pc_pilot_candidate *c, int n, double seconds, uint64_t min_iterations, pc_err *e);

#endif
