/* pilot.h: `--method auto` (docs/auto.md): a short pilot renders each candidate configuration
 * (BDPT, PCBPT with K in 1, 2, 4, 8, then the best K with another uniform mix) for a slice of
 * the budget, measures its efficiency 1 / (estimated relMSE x render time) from the spread of
 * its own iterations (docs/variance.md), and picks the most efficient. The pilot renders with
 * a seed of its own and none of its iterations reach the image: the image is rendered afterwards
 * with the winner's fixed settings, so conditioned on the choice it is the winner's unbiased
 * estimate, hence unbiased. How a candidate is rendered is the caller's: in this process
 * (pc_pilot_local, for `render` and `study`) or as short farm jobs (`submit`). */
#ifndef PC_PILOT_H
#define PC_PILOT_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "render.h"
#include "scene.h"

#define PC_PILOT_MAX 8
/* Share of a --time budget the pilot may spend, over all candidates. Its cost is certain and
 * its gain is only where candidates differ: where they are within a few percent the choice
 * hardly matters and the pilot is pure loss, where they differ by 2x a few iterations each
 * already rank them. 2.5% leaves half of the 5% by which auto may trail the best fixed choice
 * for choosing between near-equals. */
#define PC_PILOT_FRACTION 0.025
/* A PCBPT candidate is chosen over BDPT only if its efficiency is higher by this factor: the
 * pilot's few iterations see heavy tails (PCBPT's fireflies) less often than a long render does,
 * so its estimate of a heavy-tailed method is more often low than high. */
#define PC_PILOT_BDPT_MARGIN 1.05

typedef struct pc_pilot_candidate {
  pc_render_settings set;
  char label[40];       /* "bdpt", "pcbpt K=2", "pcbpt K=2 mix=0.2" */
  uint64_t iterations;  /* rendered by the pilot */
  double seconds;       /* their cost: CPU seconds in this process (pc_pilot_local), wall
                           seconds of the pilot job on a farm */
  double relmse;        /* estimated relMSE of their mean (< 0: could not tell) */
  double efficiency;    /* 1 / (relmse * seconds); 0 when it could not tell */
} pc_pilot_candidate;

typedef struct pc_pilot {
  int n, best;
  pc_pilot_candidate c[PC_PILOT_MAX];
  double seconds;       /* wall time of the whole pilot (its cost) */
} pc_pilot;

/* Renders `set` for about `seconds` (at least `min_iterations` iterations) and fills
 * iterations, seconds and relmse of *c. */
typedef int (*pc_pilot_render_fn)(void *user, const pc_render_settings *set, double seconds, uint64_t min_iterations,
                                  pc_pilot_candidate *c, pc_err *e);

/* What the pilot spends per candidate for a job bound by seconds (0: none) and iterations
 * (0: none): seconds * PC_PILOT_FRACTION / candidates with --time, else enough for min
 * iterations only (an iteration-bound job pays the pilot on top). */
void pc_pilot_budget(double seconds, uint64_t spp, double *slice_seconds, uint64_t *min_iterations);

/* What is left of a --time budget of `seconds` after a pilot that took `pilot_seconds`: the rest,
 * but at least a tenth of the budget, so a pilot that overran a tiny budget (each candidate
 * renders at least 2 iterations) still leaves the job time for an image; the overrun is
 * reported with the pilot's time. */
double pc_pilot_remaining(double seconds, double pilot_seconds);

/* The pilot seed: never the job's, so no pilot iteration equals one of the image's. */
uint64_t pc_pilot_seed(uint64_t job_seed);

/* Runs the pilot: stage 1 renders BDPT and PCBPT K = 1, 2, then 4 and 8 while doubling K raised
 * the efficiency (the other settings of base);
 * if PCBPT won, stage 2 renders the winning K with the other uniform mix (0.2, or 0.5 when
 * base's is below 0.35). Picks the most efficient (BDPT on a tie within PC_PILOT_BDPT_MARGIN). */
int pc_pilot_run(pc_pilot *p, const pc_render_settings *base, double slice_seconds, uint64_t min_iterations,
                 pc_pilot_render_fn render, void *user, pc_err *e);
/* Picks p->best from the measured candidates (used by pc_pilot_run; exposed for the tests). */
void pc_pilot_choose(pc_pilot *p);

/* One line: "chose pcbpt K=2 (pilot 2.1 s); bdpt eff 10.2 relMSE 0.031 ms/it 41.0 it 12; ..." */
void pc_pilot_report(const pc_pilot *p, char *buf, size_t size);

/* The in-process renderer of candidates: renders on a built scene with `threads` threads. */
typedef struct pc_pilot_local {
  const pc_scene *scene;
  int threads;
} pc_pilot_local;
int pc_pilot_local_render(void *user, const pc_render_settings *set, double seconds, uint64_t min_iterations,
                          pc_pilot_candidate *c, pc_err *e);

#endif
