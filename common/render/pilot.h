/* pilot.h: `--method auto` (docs/auto.md): a short pilot renders each candidate configuration
 * (BDPT, PT, PCBPT with K in 1 and 2, then 4 and 8 while doubling K still paid, then K = 1
 * with a raised MIS count for its inner strategies, then the best PCBPT one with a quarter and
 * a sixteenth of the light-tracing paths while that paid) on the same
 * iterations (the same seeds, so the bidirectional ones share their eye and light paths and the
 * noise those carry), measures its efficiency 1 / (estimated relMSE x render time) from the
 * spread of its iterations (docs/variance.md), and picks the most efficient. The pilot renders with a seed of
 * its own, and the job is rendered afterwards with the winner's fixed settings; the candidates
 * rendered whatever the data says may be mixed into the image with a weight fixed in advance
 * (coordinator/job_prior.c). How a batch of candidates is rendered is the caller's (short farm
 * jobs: coordinator/pilot_farm.h; in process in tests/stat/test_auto.c). */
#ifndef PC_PILOT_H
#define PC_PILOT_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "render.h"
#include "scene.h"

#define PC_PILOT_MAX 10
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
/* PT is chosen over the winner of BDPT and PCBPT only if its efficiency is higher by this
 * factor, for the same reason: where PT fails, its few iterations miss the rare paths that carry
 * the light (its relMSE also carries what its image disagrees with the others', pooled_relmse).
 * On thin-glass (light through glass) a 2-iteration pilot at 128x128 put PT 1.04x ahead of BDPT
 * where 20 s of each put it 1.24x behind; where PT wins it wins by 1.6-2.9x (env-constant,
 * env-white-map, env-objects, glossy-floor, outdoor: docs/auto.md). */
#define PC_PILOT_PT_MARGIN 1.2
/* A doubled K replaces the smaller one only if its efficiency is higher by this factor. The
 * pilot measures the K = 2 / K = 1 efficiency ratio to about 5% (sd of its log): its relMSE
 * part from the ring (pooled_relmse) within 2% of a long render's, sd 0.004-0.044 over pilots
 * of 14 iterations (tests/bench/bench_pilot), its cost part, with the candidates taking turns
 * (PC_RANGE_INTERLEAVE), to sd 0.014-0.019. A doubling worth 13% (ajar-door's K = 2 in CPU
 * time, 1.106x at equal wall time with both threads) then gets through in about 9 pilots of
 * 10, and one 3-5% worse (glossy-floor, slit-room, cornell-box) in about 1 of 20, by those
 * spreads; measured over 10 pilots each, ajar-door took K = 2 in 10 and cornell-box kept K = 1
 * in 10. (It was 2
 * while the pilot's K ratio was noise: sd of its log 0.44-1.37 when the candidates rendered
 * iterations of their own, docs/auto.md.) */
#define PC_PILOT_K_MARGIN 1.05
/* Stage 4 tries PCBPT K = 1 with its inner strategies counting this much in the MIS weights
 * (the default is 2), and where K = 1 is the chosen K keeps it if its efficiency is higher by
 * PC_PILOT_COUNT_MARGIN.
 * The two candidates render the same paths and connections, only weighted otherwise, so their
 * ratio is far less noisy than K's; the margin guards against the heavier tails of a larger
 * count (glossy scenes), which a few iterations see less often than a long render. At 128x128
 * and 128 iterations, count 4 against 2: slit-room -19%, furnace -13%, outdoor -8%, ajar-door
 * -3%, glossy-floor +6% (docs/pmf-ceiling.md). */
#define PC_PILOT_RAISED_COUNT 4.f
#define PC_PILOT_COUNT_MARGIN 1.1
/* Stage 5 tries the PCBPT configuration chosen so far with the light-tracing paths (N_L, the
 * t = 1 strategy's samples) divided by PC_PILOT_LIGHT_DIVISOR, then by its square, each kept
 * only if its efficiency is higher by PC_PILOT_LIGHT_MARGIN, and not on scenes with caustics
 * (pc_pilot_run's with_fewer_lights). PCBPT's inner connections use its
 * M stored paths, so unlike BDPT (one light sub-path per pixel for its connections) it traces
 * only N_L light paths besides them: fewer cost less, and where light tracing carries little
 * the other strategies take its share in the MIS weights. Where it carries caustics seen
 * directly (glass-lamp), the error is in rare large samples, which neither a few pilot
 * iterations nor an image's own estimate measure: those put a quarter 1.4x better and 1.35x
 * worse there, a reference about even and a sixteenth 1.2-3x worse per iteration. Hence no
 * stage 5 where the scene has caustics, and the margin.
 * 128x128, 64 iterations, one thread, the image's own relMSE x CPU time, a quarter against
 * W*H: furnace 0.61, cornell-box 0.81, ajar-door 0.80, open-room 0.78, slit-room 0.91,
 * glossy-glass 0.90, thin-glass 0.97, glossy-floor 0.96, glass-lamp 1.35 (docs/auto.md). */
#define PC_PILOT_LIGHT_DIVISOR 4
#define PC_PILOT_LIGHT_MARGIN 1.1

/* A candidate keeps its image (a fixed subsample of at most this many pixels) so that every
 * candidate's error is measured against the same denominator: the mean of all candidates'
 * images, which estimates the exact image far better than any one candidate's few iterations
 * (a candidate's own relMSE estimate divides by its own noisy mean, which on a heavy-tailed
 * scene makes two iterations' figures differ by 10x between candidates of equal merit). */
#define PC_PILOT_MAX_PIXELS (1 << 18)

typedef struct pc_pilot_candidate {
  pc_render_settings set;
  char label[40];       /* "bdpt", "pcbpt K=2" */
  bool mis_raised;      /* PCBPT with the raised MIS count of stage 4 */
  int light_step;       /* stage 5: the base's light-tracing paths divided by
                           PC_PILOT_LIGHT_DIVISOR this many times (0: as they are) */
  bool counts;          /* its iterations may count in the image (docs/auto.md): rendered
                           whatever the data says (stages 1 and 4) and not PT (its fireflies
                           where it fails); K = 4 and 8 and stage 5's are not */
  uint64_t iterations;  /* rendered by the pilot */
  double seconds;       /* worker-seconds (wall) of the candidate's jobs: what the pilot spent */
  double cpu_seconds;   /* CPU seconds of the render threads over them (<= 0: unknown): the cost
                           compared, unless a candidate lacks it (pilot_cost in pilot.c) */
  double own_relmse;    /* the image's own relMSE estimate (< 0: could not tell) */
  double relmse;        /* relMSE against the candidates' pooled mean (pc_pilot_choose; the
                           own estimate when no image was kept); < 0: could not tell */
  double efficiency;    /* 1 / (relmse * seconds); 0 when it could not tell */
  int npix;             /* pixels kept (0: none) */
  int nx;               /* their grid's width (npix / nx rows) */
  float *mean, *var;    /* npix * 3: the image and the variance of each value's mean */
} pc_pilot_candidate;

typedef struct pc_pilot {
  int n, best;
  pc_pilot_candidate c[PC_PILOT_MAX];
  double seconds;       /* wall time of the whole pilot (its cost) */
} pc_pilot;

void pc_pilot_free(pc_pilot *p);

/* Keeps candidate c's image: mean and variance of the mean (w*h*3 each, var NULL when the
 * image cannot tell), subsampled on a fixed grid to at most PC_PILOT_MAX_PIXELS pixels. */
int pc_pilot_keep_image(pc_pilot_candidate *c, int w, int h, const float *mean, const float *var, pc_err *e);

/* Renders one batch: `iterations` iterations (0 to iterations - 1) of each of the n candidates
 * with the seed c[i].set.seed ^ salt, side by side (interleaved, so a change of the machine's
 * load falls on all of them alike), and fills out[i] (zeroed by the caller) with their
 * iterations, cost (seconds, in the unit of the pilot's slices, and cpu_seconds), own_relmse
 * and, if it can, the image (pc_pilot_keep_image). */
typedef int (*pc_pilot_render_fn)(void *user, const pc_pilot_candidate *c, int n, uint64_t iterations, uint64_t salt,
                                  pc_pilot_candidate *out, pc_err *e);

/* What the pilot spends for a job bound by seconds (0: none) and iterations (0: none): with
 * --time a slice of seconds * PC_PILOT_FRACTION / 5 (stage 1's three candidates share 5 slices;
 * K = 4 and 8, where tried, render the same iterations on top), else min iterations per
 * candidate only, PC_PILOT_FRACTION of the spp over stage 1 (an iteration-bound job pays the
 * pilot on top). */
void pc_pilot_budget(double seconds, uint64_t spp, double *slice_seconds, uint64_t *min_iterations);

/* What is left of a --time budget of `seconds` after a pilot that took `pilot_seconds`: the rest,
 * but at least a tenth of the budget, so a pilot that overran a tiny budget (each candidate
 * renders at least 2 iterations) still leaves the job time for an image; the overrun is
 * reported with the pilot's time. */
double pc_pilot_remaining(double seconds, double pilot_seconds);

/* The pilot seed: never the job's, so no pilot iteration equals one of the image's. */
uint64_t pc_pilot_seed(uint64_t job_seed);

/* Runs the pilot: stage 1 renders BDPT, PT and PCBPT K = 1 and 2 on the same iterations, first
 * min_iterations of them, then as many more as 5 slices (slice_seconds, in the unit of the
 * render's cost: worker-seconds on a farm; 0: none) buy at their cost; stages 2 and 3 render
 * K = 4 and 8 on those same iterations, each only while the last doubling paid by
 * PC_PILOT_K_MARGIN; where stage 1 had room for its second batch, stage 4 renders K = 1 with the
 * raised MIS count on them too; stage 5 (always) the PCBPT configuration chosen so far with
 * fewer light-tracing paths (PC_PILOT_LIGHT_DIVISOR, then its square while that paid). Picks that
 * PCBPT K (K = 1 with the raised count where that is better by PC_PILOT_COUNT_MARGIN; then its
 * fewer light paths where better by PC_PILOT_LIGHT_MARGIN), or BDPT unless the PCBPT candidate beats it by
 * PC_PILOT_BDPT_MARGIN, then PT if it beats that winner by PC_PILOT_PT_MARGIN. PT is a
 * candidate only `with_pt`: where it cannot sample every path of the scene
 * (pc_scene_pt_complete), its image lacks light however long it runs. Stage 5 runs only
 * `with_fewer_lights`: not where the scene has caustics (pc_scene_has_caustics), which light
 * tracing carries and a few pilot iterations with fewer light paths miss. Free with
 * pc_pilot_free, also after a failure. */
int pc_pilot_run(pc_pilot *p, const pc_render_settings *base, bool with_pt, bool with_fewer_lights,
                 double slice_seconds, uint64_t min_iterations, pc_pilot_render_fn render, void *user, pc_err *e);

/* Measures every candidate against the pooled mean of their images (candidates without an
 * image keep their own estimate) and picks p->best by pc_pilot_run's rule: the PCBPT K reached
 * from K = 1 by doublings each better by PC_PILOT_K_MARGIN, against BDPT, then PT against the
 * winner; PT's relMSE also carries how far its image disagrees with the others' beyond their
 * variances (used by pc_pilot_run; exposed for the tests). */
void pc_pilot_choose(pc_pilot *p);

/* The share of the counted candidates' summed work (iterations or worker-seconds) that their
 * mixed film is worth as the job's prior (coordinator/job_prior.c): 1 / their number. They
 * render the same iterations with the same seeds, so they share their paths and their images
 * are strongly correlated (open-room, BDPT and PCBPT K = 1 of one seed at 128x128: 0.82; stage
 * 4's twin renders the very same connections), and their mean is worth about one of them, not
 * all. Weighted by their sum, the mix cost the job more than it added (docs/auto.md). 0 when
 * none counts. Fixed by which candidates count, which the budget alone decides. */
double pc_pilot_counted_share(const pc_pilot *p);

/* One line: "chose pcbpt K=2 (pilot 2.1 s); bdpt eff 10.2 relMSE 0.031 ms/it 41.0 it 12; ..." */
void pc_pilot_report(const pc_pilot *p, char *buf, size_t size);

#endif
