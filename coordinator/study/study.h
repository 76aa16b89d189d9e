/* study.h: the equal-time study behind `pcbpt-coord study` (DESIGN.md §6): each method renders
 * the same scene for the same render time, the film is compared with a reference at
 * logarithmically spaced snapshots (study_run.c), and the error curves are summarised as final
 * error ratios and time-to-error ratios (study_table.c) and written as CSV, JSON and charts
 * (study_files.c). */
#ifndef PC_STUDY_H
#define PC_STUDY_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "film.h"
#include "metrics.h"
#include "render.h"
#include "scene.h"

#define PC_STUDY_MAX_METHODS 5
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
} pc_study_ref;

/* Whether the study measures layer slot. */
static inline bool pc_study_ref_has(const pc_study_ref *r, int slot) {
  return r->rgb[slot] || (r->estimated && slot == PC_STUDY_BEAUTY);
}

typedef struct pc_study_snap {
  double seconds;       /* render time when it was taken (metrics time excluded) */
  uint64_t iterations;
  pc_metrics m[PC_STUDY_NLAYERS]; /* zero where the reference lacks the layer */
} pc_study_snap;

typedef struct pc_study_run {
  pc_method method;
  int threads;
  int nsnaps;
  pc_study_snap *snaps;
  bool layer_empty[PC_STUDY_NLAYERS]; /* the method adds nothing to this layer (e.g. pt: inner) */
  pc_render_stats stats;
} pc_study_run;

/* Renders set->method for `seconds` of render time into film (initialised for the settings'
 * size, empty), one iteration at a time, taking up to max_snaps snapshots (with an estimated
 * reference, none before 2 iterations: one iteration cannot tell its error) at times
 * seconds * PC_STUDY_FIRST_FRACTION^((K-1-k)/(K-1)), each after whole iterations. When one
 * iteration passes several snapshot times only one snapshot is taken, so run->nsnaps may be
 * smaller than max_snaps; the last one is always at the end of the budget. */
int pc_study_render(const pc_scene *scene, const pc_render_settings *set, int threads, double seconds,
                    int max_snaps, const pc_study_ref *ref, pc_film *film, pc_study_run *run, pc_err *e);
void pc_study_run_free(pc_study_run *run);

/* How a method reached a target error. */
typedef enum {
  PC_REACH_INTERPOLATED, /* between two snapshots, log-log interpolation */
  PC_REACH_BY_FIRST,     /* already at the first snapshot: the time is an upper bound */
  PC_REACH_NEVER,        /* not within the budget */
  PC_REACH_EXCLUDED,     /* the method leaves this layer empty */
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
  pc_method method[PC_STUDY_MAX_METHODS];
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
} pc_study_info;

/* study.csv: method, snapshot, seconds, iterations, layer, relmse, rmse, l1. */
int pc_study_write_csv(const char *path, const pc_study_run *runs, int nruns, const pc_study_ref *ref, pc_err *e);
/* study.json: settings, per-method snapshots and the table. */
int pc_study_write_json(const char *path, const pc_study_info *info, const pc_study_run *runs, int nruns,
                        const pc_study_ref *ref, const pc_study_table *t, pc_err *e);
/* <dir>/study_<layer>.png and .svg: relMSE against render time, one line per method that
 * adds to the layer. */
int pc_study_write_chart(const char *dir, const pc_study_info *info, const pc_study_run *runs, int nruns, int slot,
                         pc_err *e);

#endif
