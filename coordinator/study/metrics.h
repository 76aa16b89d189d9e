/* metrics.h: image error metrics for `pcbpt-coord compare` and the equal-time studies.
 *
 * For a test image a and a reference b of equal size, over the N finite pairs of samples
 * (every pixel and every one of the 3 channels; a pair with a NaN or Inf on either side is
 * skipped and counted in `nonfinite`):
 *   RMSE   = sqrt( (1/N) sum (a - b)^2 )
 *   relMSE = (1/N) sum (a - b)^2 / (b^2 + 0.01)      (b is the reference)
 *   L1     = (1/N) sum |a - b|
 *   mean_a = (1/N) sum a,   mean_b = (1/N) sum b
 * Sums are in double precision. */
#ifndef PC_METRICS_H
#define PC_METRICS_H

#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "image.h"

#define PC_RELMSE_EPS 0.01

typedef struct pc_metrics {
  double rmse, relmse, l1;
  double mean_a, mean_b;
  uint64_t nonfinite; /* sample pairs skipped because a or b was NaN or Inf */
} pc_metrics;

/* a and ref are w*h*3 floats. */
int pc_metrics_rgb(const float *a, const float *ref, int w, int h, pc_metrics *out, pc_err *e);
/* Refuses images of different sizes. */
int pc_metrics_image(const pc_image *a, const pc_image *ref, pc_metrics *out, pc_err *e);

typedef struct pc_layer_metrics {
  char *name; /* "" is the beauty */
  pc_metrics m;
} pc_layer_metrics;

/* Compares every layer present (by name) in both files, in a's layer order. Refuses files of
 * different sizes and files with no layer in common. *out is malloc'd; free it with
 * pc_layer_metrics_free(*out, *n). */
int pc_metrics_layers(const pc_exr_file *a, const pc_exr_file *ref, pc_layer_metrics **out,
                      int *n, pc_err *e);
void pc_layer_metrics_free(pc_layer_metrics *m, int n);

#endif
