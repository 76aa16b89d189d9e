/* study.h: the equal-time study behind `pcbpt-coord study` (DESIGN.md §6, docs/farm-study.md):
 * each method renders the same scene for the same render time as a farm job, the farm keeps
 * its film at logarithmically spaced times and each is compared with a reference
 * (study_measure.c); several runs give median curves and spreads (study_spread.c); the curves
 * are summarised as final error ratios and time-to-error ratios (study_table.c) and written as
 * CSV, JSON and charts (study_files.c). */
#ifndef PC_STUDY_H
#define PC_STUDY_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "film.h"
#include "metrics.h"
#include "render.h"
#include "scene.h"

#define PC_STUDY_MAX_METHODS 8
#define PC_STUDY_MAX_SNAPSHOTS 1000
/* The first snapshot is taken after this fraction of the budget (log spacing up to 1). */
#define PC_STUDY_FIRST_FRACTION (1.0 / 64)

/* Layer slots of a study: 0 is the beauty, 1 + PC_LAYER_* the standard strategy layers. */
enum { PC_STUDY_BEAUTY = 0, PC_STUDY_NLAYERS = 1 + PC_LAYER_STD_COUNT };
const char *pc_study_layer_name(int slot);   /* "beauty", "pt", "nee", "lt", "inner" */
int pc_study_layer_parse(const char *name);  /* slot, or -1 */

/* The reference image, per slot; NULL where the reference lacks the layer. With `estimated`
 * (a study without a reference) every rgb is NULL and the beauty's errors are each film's own
 * estimates from the spread of its iterations (docs/variance.md): relMSE and RMSE estimated,
 * L1 unknown (NAN); the other layers are not measured. */
typedef struct pc_study_ref {
  int w, h;
  const float *rgb[PC_STUDY_NLAYERS];
  bool estimated;
  const char *weights; /* how its strategy layers are weighted (PC_WEIGHTS_ATTR); NULL: unknown */
} pc_study_ref;

/* Whether the study measures layer slot. */
static inline bool pc_study_ref_has(const pc_study_ref *r, int slot) {
  return r->rgb[slot] || (r->estimated && slot == PC_STUDY_BEAUTY);
}

/* A method of a study: an estimator and, for pcbpt, optionally its own K and connection rate
 * ("pcbpt-k2", "pcbpt-k1-r0.25"), so one study can compare them side by side on the same
 * workers. `name` is what the study's files, tables and charts call it. */
typedef struct pc_study_method {
  pc_method method;
  int pcbpt_k;          /* > 0: --pcbpt-k for this method only; 0: the study's */
  float pcbpt_rate;     /* > 0: --pcbpt-rate for this method only; 0: the study's */
  char name[24];
} pc_study_method;
/* "pt", "lt", "bdpt", "cbdpt", "pcbpt", "auto", "pcbpt-kN" (1 <= N <= 64) or "pcbpt-kN-rR"
 * (0 < R <= 1). */
int pc_study_method_parse(const char *s, pc_study_method *out, pc_err *e);
/* Sets the method and its own K and rate in settings that hold the study's. */
void pc_study_method_apply(const pc_study_method *m, pc_render_settings *set);

typedef struct pc_study_snap {
  double seconds;       /* render time when it was taken (metrics time excluded); on the
                           farm: worker_seconds / the farm size, the time the farm would
                           take rendering this method alone */
  double worker_seconds;/* farm: summed render seconds of the workers' merged uploads */
  double wall;          /* farm: the job's running time (its group's other jobs ran too) */
  uint64_t iterations;
  pc_metrics m[PC_STUDY_NLAYERS]; /* zero where the reference lacks the layer */
} pc_study_snap;

/* Rec. 709 luminance of one rgb value, and the mean over an image (study_tails.c): the
 * brightness the tails and the strategy shares are measured in. */
static inline double pc_study_luminance(const float *rgb) { return pc_luminance709(rgb[0], rgb[1], rgb[2]); }
double pc_study_mean_luminance(const pc_image *im);

/* Heavy tails of a method's final image (study_tails.c): over the pixels whose luminance is above
 * PC_STUDY_TAILS_LIT times the image's mean, the ratio of the pixel's largest single iteration
 * (the film's beauty_max) to its mean; 1 means every iteration gave the same, N (the
 * iterations) that one iteration carried the whole pixel. */
#define PC_STUDY_TAILS_LIT 0.01
typedef struct pc_study_tails {
  bool known;           /* the image had beauty_max over all its iterations */
  uint64_t iterations;  /* N, the bound of every ratio */
  size_t pixels;        /* lit pixels the ratios are over */
  double p50, p99, max; /* NAN when no pixel is lit */
  int max_x, max_y;     /* where the largest ratio is */
  /* The distribution of the per-iteration error (film_trace.h) from the image's header;
   * iter_known false when it has none (fewer than 2 traced iterations, an older image). */
  bool iter_known;
  pc_iteration_errors iter;
} pc_study_tails;
/* From an image the farm wrote; t->known false (and PC_OK) when it has no complete beauty_max. */
int pc_study_tails_exr(const pc_exr_file *x, pc_study_tails *t, pc_err *e);

/* Which strategies carry a method's final image (study_shares.c): the share of the beauty's mean
 * luminance in each standard strategy layer, indexed by PC_LAYER_* (pt: emitter hits, s = 0;
 * nee: s = 1; lt: t = 1; inner: s, t >= 2). known: the image has the beauty and all four
 * layers, and is not black. */
typedef struct pc_study_shares {
  bool known;
  double share[PC_LAYER_STD_COUNT];
} pc_study_shares;
void pc_study_shares_exr(const pc_exr_file *x, pc_study_shares *s);

typedef struct pc_study_run {
  pc_study_method method;
  int threads;
  int workers;          /* farm size of the run (0: the one-machine study) */
  int run;              /* which of --runs (0-based) */
  uint64_t seed;
  uint32_t ranges_rerun;/* ranges re-run after a worker vanished or fell silent */
  double group_wall;    /* seconds from submitting the run's jobs to the end of the last */
  int nsnaps;
  pc_study_snap *snaps;
  bool layer_empty[PC_STUDY_NLAYERS]; /* the method adds nothing to this layer (e.g. pt: inner) */
  /* The method's final image weighs its strategies unlike the reference (pc_weights_unlike):
   * its strategy layers (every slot but the beauty) estimate other shares of the image, so they
   * are left out of those layers' comparisons as empty ones are. weights: what its header says
   * ("" if nothing). */
  bool unlike;
  char weights[96];
  pc_render_stats stats;
  char auto_report[1024]; /* method auto: the pilot's choice and candidates (pilot.h); else "" */
  pc_study_tails tails;  /* of the final image */
  pc_study_shares shares;/* of the final image */
} pc_study_run;

void pc_study_run_free(pc_study_run *run);
/* Whether run is left out of layer slot's comparisons: empty, or weighted unlike the reference. */
static inline bool pc_study_excluded(const pc_study_run *run, int slot) {
  return run->layer_empty[slot] || (run->unlike && slot != PC_STUDY_BEAUTY);
}
/* From the method's final image: run->weights, and run->unlike against ref's weighting. */
void pc_study_weights_exr(const pc_exr_file *x, const pc_study_ref *ref, pc_study_run *run);
/* One point of a farm study's curve from an image the farm wrote (study_measure.c): errors
 * against ref per layer (or the beauty's own estimate without one), its worker-seconds,
 * render time and iterations from the header; seconds is worker-seconds / workers. With
 * layer_empty, which standard layers hold nothing. */
int pc_study_measure_exr(const pc_exr_file *x, const char *path, const pc_study_ref *ref, int workers,
                         pc_study_snap *s, bool layer_empty[PC_STUDY_NLAYERS], pc_err *e);
/* A numeric header attribute, NAN when absent. */
double pc_study_exr_number(const pc_exr_file *x, const char *name);

/* What an image is of beside its size, as far as it is known (NAN or NULL: not said): an image
 * that differs in any of these is of something else, so errors against it have a floor. */
typedef struct pc_image_kind {
  double max_depth;    /* path lengths */
  const char *bundle;  /* PC_SCENE_BUNDLE_ATTR: the scene's files */
  const char *defines; /* PC_SCENE_DEFINES_ATTR: its -D values */
} pc_image_kind;
/* The kind an image's header says. */
pc_image_kind pc_image_kind_exr(const pc_exr_file *x);
/* Into why (at most n bytes), how ref differs from mine in what both say ("" when in nothing):
 * "max depth 11 in the reference, 4 here; other scene files in the reference (...); -D ''
 * in the reference, 'a=1' here", the header's text without control bytes. */
void pc_image_kind_differs(const pc_image_kind *ref, const pc_image_kind *mine, char *why, size_t n);

/* --runs (study_spread.c). */
#define PC_STUDY_MAX_RUNS 100
/* Median of the finite values of v (reordered in place), their min and max; NAN when none. */
double pc_study_median(double *v, int n, double *lo, double *hi);
/* The runs' min and max of a layer's relMSE around the median curve. */
typedef struct pc_study_band {
  int n;
  double *t, *lo, *hi;
} pc_study_band;
/* out: one method's median curve over nruns runs, at npoints times log-spaced from
 * t_end * PC_STUDY_FIRST_FRACTION to t_end (render time, or with `wall` the jobs' running
 * time), each run log-log interpolated; times no run reached are left out. With band, each
 * layer's min and max (free with pc_study_band_free). */
int pc_study_median_run(const pc_study_run *runs, int nruns, int npoints, double t_end, bool wall, pc_study_run *out,
                        pc_study_band band[PC_STUDY_NLAYERS], pc_err *e);
void pc_study_band_free(pc_study_band band[PC_STUDY_NLAYERS]);
/* One method's runs on one layer: final relMSE and time to target (median, min, max; the
 * runs that reached it), and the per-run ratio of its time to first_runs' (paired by run).
 * With t_end > 0 (render seconds) a run's final relMSE is its error at t_end, log-log
 * interpolated as the median curves are: a job's last snapshot comes up to a few per cent
 * past the budget, by how long its ranges in flight take, which differs per method. With
 * t_end <= 0 it is the last snapshot's. */
typedef struct pc_study_spread {
  int n, reached;
  double final_med, final_lo, final_hi;
  double time_med, time_lo, time_hi;
  double ratio_med, ratio_lo, ratio_hi;
} pc_study_spread;
void pc_study_spread_cell(const pc_study_run *runs, int nruns, const pc_study_run *first_runs, int slot, double target,
                          bool wall, double t_end, pc_study_spread *c);

/* How a method reached a target error. */
typedef enum {
  PC_REACH_INTERPOLATED, /* between two snapshots, log-log interpolation */
  PC_REACH_BY_FIRST,     /* already at the first snapshot: the time is an upper bound */
  PC_REACH_NEVER,        /* not within the budget */
  PC_REACH_EXCLUDED,     /* the method leaves this layer empty */
  PC_REACH_UNLIKE,       /* the method weighs this layer's strategies unlike the reference */
} pc_reach;

typedef struct pc_study_cell {
  double final_relmse;
  double relmse_ratio; /* final relMSE / the first method's; NAN when not comparable */
  double time;         /* seconds to reach the target; NAN unless reached */
  pc_reach reach;
  double time_ratio;   /* time / the first method's time; NAN when either is not reached */
} pc_study_cell;

typedef struct pc_study_table {
  int nlayers;
  int slot[PC_STUDY_NLAYERS];       /* layer slots present in the reference, in slot order */
  double target[PC_STUDY_NLAYERS];  /* target relMSE per row of slot[] */
  bool target_given[PC_STUDY_NLAYERS];
  int nmethods;
  const char *name[PC_STUDY_MAX_METHODS]; /* the runs' method names */
  pc_study_cell cell[PC_STUDY_NLAYERS][PC_STUDY_MAX_METHODS];
  int headline;                     /* row of slot[] the headline sentences are about */
} pc_study_table;

/* Seconds for run to first reach relMSE `target` on layer slot, interpolating log(time)
 * against log(relMSE) between the snapshots around the crossing. */
double pc_study_time_to_error(const pc_study_run *run, int slot, double target, pc_reach *how);
/* Builds the table for the layers present in ref; target_error > 0 sets the target of the
 * headline layer, every other target is the worst final relMSE among the methods. */
void pc_study_table_build(const pc_study_run *runs, int nruns, const pc_study_ref *ref, int headline_slot,
                          double target_error, pc_study_table *t);
void pc_study_table_print(FILE *f, const pc_study_table *t);
/* The sentence comparing method row m (m > 0) with the first method on the headline layer:
 * "bdpt needs 3.4x more time than pcbpt to reach beauty relMSE 0.012". */
void pc_study_headline(const pc_study_table *t, int m, char *buf, size_t size);

typedef struct pc_study_info {
  const char *scene_path, *scene_name, *reference_path; /* reference_path NULL: estimated errors */
  double seconds;
  int width, height, max_snaps;
  uint64_t seed;
  int workers, runs;   /* the farm size the table and charts are about; seeds seed..seed+runs-1 */
  const char *host;    /* NULL: the embedded farm */
} pc_study_info;

/* study.csv: method, snapshot, seconds, iterations, layer, relmse, rmse, l1, then workers, run,
 * worker_seconds, wall_seconds (farm studies; every run of every farm size). */
int pc_study_write_csv(const char *path, const pc_study_run *runs, int nruns, const pc_study_ref *ref, pc_err *e);
/* study.json: settings, per-run snapshots (every run of every farm size) and the table (of
 * the median curves of the largest farm size). */
int pc_study_write_json(const char *path, const pc_study_info *info, const pc_study_run *runs, int nruns,
                        const pc_study_ref *ref, const pc_study_table *t, pc_err *e);
/* <dir>/study_<layer>.png and .svg: relMSE against render time, one line per method that
 * adds to the layer; bands (NULL, or per run NULL or PC_STUDY_NLAYERS bands) shade the spread
 * of several runs around a median curve. */
int pc_study_write_chart(const char *dir, const pc_study_info *info, const pc_study_run *runs, int nruns, int slot,
                         const pc_study_band *const *bands, pc_err *e);
/* <dir>/study_shares.png and .svg: which strategies carry each final image, as stacked bars of
 * the shares (pc_study_shares), from runs[run * nmethods + m] (info->runs runs of nmethods
 * methods): one bar per method and run, or, past PC_STUDY_SHARE_BARS_RUNS runs, one per method
 * of its mean over the runs. Runs that cannot tell are left out; *written says whether any
 * could (else no file is written). */
#define PC_STUDY_SHARE_BARS_RUNS 8
int pc_study_write_shares_chart(const char *dir, const pc_study_info *info, const pc_study_run *runs, int nmethods,
                                bool *written, pc_err *e);
/* <dir>/study_iterations.png and .svg: the tail of each method's per-iteration error
 * (pc_iteration_errors), the fraction of iterations whose error exceeds x times their mean
 * against x on log-log axes (per method, the median over its runs of each tail point), from
 * runs[run * nmethods + m]; a light tail falls steeply past x = 1, a heavy one reaches far
 * right. *written says whether any run could tell (else no file is written). */
int pc_study_write_iterations_chart(const char *dir, const pc_study_info *info, const pc_study_run *runs, int nmethods,
                                    bool *written, pc_err *e);

#endif
