/* tails.h: heavy tails of an estimator in a study (docs/auto.md): the distribution of the
 * per-iteration errors (each iteration's own beauty against the reference, or, without one,
 * against the mean of the iterations before it) and the largest single-iteration pixel value
 * relative to that pixel's final mean (a firefly's weight: N means one iteration carried the
 * whole pixel). The film is observed after every iteration; an iteration's beauty is the
 * difference of its layer sums from the previous observation. */
#ifndef PC_STUDY_TAILS_H
#define PC_STUDY_TAILS_H

#include <stdint.h>
#include <stdio.h>

#include "error.h"
#include "film.h"

typedef struct pc_study_tails {
  int w, h;
  uint64_t n;               /* iterations observed */
  double *err;              /* per-iteration error (relMSE definition), nerr of them */
  size_t nerr;
  size_t cap;
  double *prev;             /* the standard layers' sums at the last observation */
  uint64_t prev_lt_count;
  float *pix_max;           /* per pixel: the largest single-iteration luminance */
  /* summary (pc_study_tails_finish) */
  double err_median, err_p90, err_p99, err_max, err_mean;
  double spike_max, spike_p99; /* max_i b_i(p) / mean(p), over pixels above 1% of the image mean */
  int spike_x, spike_y;
} pc_study_tails;

int pc_study_tails_init(pc_study_tails *t, int w, int h, pc_err *e);
/* After each iteration: ref is the reference beauty (w*h*3) or NULL. */
int pc_study_tails_observe(pc_study_tails *t, const pc_film *film, const float *ref, pc_err *e);
/* Computes the summary from the film's final mean; frees the per-iteration state but err. */
void pc_study_tails_finish(pc_study_tails *t, const pc_film *film);
void pc_study_tails_free(pc_study_tails *t);
/* "tails: per-iteration relMSE median .. p90 .. p99 .. max .. (max/median ..); largest sample / pixel mean .. at (x,y), p99 .." */
void pc_study_tails_print(FILE *f, const char *method, const pc_study_tails *t);
/* {"iterations": n, "iteration_relmse": {"median": .., ...}, "spike_max": .., ...} */
void pc_study_tails_json(FILE *f, const pc_study_tails *t);

#endif
