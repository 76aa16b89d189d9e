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
  /* Farm size: the pilot's slices are worth slice x workers worker-seconds, and each candidate
   * runs on at most `workers` workers at once (a study's farm size); 0: every worker connected. */
  int workers;
  /* Whether the films of the candidates whose iterations count (pc_pilot_candidate.counts)
   * are kept in a pilot group for the chosen job's image (coordinator/job_prior.c): only a job
   * with a budget can fix the pilot's weight in advance (not --halt-noise alone). */
  bool keep;
  double worker_seconds; /* out: the summed worker-seconds of every candidate's job */
  double counted_worker_seconds; /* out: ... of the candidates that count */
  uint64_t counted_iterations;   /* out: their iterations */
  uint64_t pilot_group;  /* out: their group (0: none), the chosen job's prior_group */
  int farm_size;         /* out: the workers the pilot counted on */
} pc_pilot_farm;

/* pc_pilot_render_fn: submits the batch's candidates as jobs of one study group (interleaved by
 * least worker time), each bound by the batch's iterations, waits for their end and fetches
 * their images. A candidate's cost is its job's worker-seconds (the render seconds of its merged
 * uploads), which on a shared farm measures the candidate rather than the queue it waited in. */
int pc_pilot_farm_render(void *user, const pc_pilot_candidate *c, int n, uint64_t iterations, uint64_t salt,
                         pc_pilot_candidate *out, pc_err *e);

/* --method auto for a job request: runs the pilot on the farm (its budget from req's --time or
 * --spp), gives req the winner's settings (its own seed kept) and what is left of --time, and
 * writes the one-line report; *pilot_seconds is the pilot's wall time. The job is then to be
 * submitted with fp->pilot_group as its prior_group and *prior_amount (0: no prior): the
 * counted candidates' iterations with --spp; with --time their worker-seconds over the farm
 * size, the wall time the farm would take to render them (the pilot's own wall time also
 * holds its jobs' round trips, which would weigh its few iterations up to 3x too much). */
int pc_pilot_farm_choose(pc_pilot_farm *fp, pc_render_request *req, char *report, size_t size, double *pilot_seconds,
                         double *prior_amount, pc_err *e);

#endif
