/* tails.c: per-iteration errors and fireflies of a study's method (tails.h). */
#include "tails.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metrics.h"

static double lum(const double *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

int pc_study_tails_init(pc_study_tails *t, int w, int h, pc_err *e) {
  memset(t, 0, sizeof *t);
  t->w = w;
  t->h = h;
  size_t n = (size_t)w * h;
  t->prev = calloc(n * 3 * PC_LAYER_STD_COUNT, sizeof *t->prev);
  t->pix_max = calloc(n, sizeof *t->pix_max);
  t->cap = 256;
  t->err = malloc(t->cap * sizeof *t->err);
  if (!t->prev || !t->pix_max || !t->err) {
    pc_study_tails_free(t);
    return pc_errf(e, PC_ENOMEM, "study: out of memory for the tail statistics");
  }
  return PC_OK;
}

int pc_study_tails_observe(pc_study_tails *t, const pc_film *film, const float *ref, pc_err *e) {
  size_t np = (size_t)t->w * t->h, n3 = np * 3;
  uint64_t lt_paths = film->layers[PC_LAYER_LT].count - t->prev_lt_count;
  double lt_scale = lt_paths ? (double)np / (double)lt_paths : 0;
  double err = 0;
  uint64_t nvals = 0;
  for (size_t p = 0; p < np; p++) {
    double b[3] = {0, 0, 0}, mean_before[3] = {0, 0, 0};
    for (int l = 0; l < PC_LAYER_STD_COUNT; l++) {
      const double *s = film->layers[l].sum + 3 * p;
      double *q = t->prev + (size_t)l * n3 + 3 * p;
      double scale = l == PC_LAYER_LT ? lt_scale : 1.0;
      /* the mean of the earlier iterations: eye layers / n, light layer / its paths x W*H */
      double before_scale = l == PC_LAYER_LT ? (t->prev_lt_count ? (double)np / (double)t->prev_lt_count : 0)
                                             : (t->n ? 1.0 / (double)t->n : 0);
      for (int c = 0; c < 3; c++) {
        b[c] += (s[c] - q[c]) * scale;
        mean_before[c] += q[c] * before_scale;
        q[c] = s[c];
      }
    }
    float l = (float)lum(b);
    if (l > t->pix_max[p]) t->pix_max[p] = l;
    if (!ref && t->n == 0) continue;
    for (int c = 0; c < 3; c++) {
      double r = ref ? ref[3 * p + c] : mean_before[c];
      if (!isfinite(r) || !isfinite(b[c])) continue;
      err += (b[c] - r) * (b[c] - r) / (r * r + PC_RELMSE_EPS);
      nvals++;
    }
  }
  t->prev_lt_count = film->layers[PC_LAYER_LT].count;
  t->n++;
  if (!nvals) return PC_OK;
  if (t->nerr == t->cap) {
    double *g = realloc(t->err, 2 * t->cap * sizeof *g);
    if (!g) return pc_errf(e, PC_ENOMEM, "study: out of memory for the tail statistics");
    t->err = g;
    t->cap *= 2;
  }
  t->err[t->nerr++] = err / (double)nvals;
  return PC_OK;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static double quantile(const double *sorted, size_t n, double q) {
  if (!n) return NAN;
  size_t i = (size_t)(q * (double)(n - 1) + 0.5);
  return sorted[i < n ? i : n - 1];
}

void pc_study_tails_finish(pc_study_tails *t, const pc_film *film) {
  t->err_median = t->err_p90 = t->err_p99 = t->err_max = t->err_mean = t->spike_max = t->spike_p99 = NAN;
  t->spike_x = t->spike_y = -1;
  if (t->nerr) {
    double *s = malloc(t->nerr * sizeof *s);
    if (s) {
      memcpy(s, t->err, t->nerr * sizeof *s);
      qsort(s, t->nerr, sizeof *s, cmp_double);
      double sum = 0;
      for (size_t i = 0; i < t->nerr; i++) sum += s[i];
      t->err_mean = sum / (double)t->nerr;
      t->err_median = quantile(s, t->nerr, 0.5);
      t->err_p90 = quantile(s, t->nerr, 0.9);
      t->err_p99 = quantile(s, t->nerr, 0.99);
      t->err_max = s[t->nerr - 1];
      free(s);
    }
  }
  size_t np = (size_t)t->w * t->h;
  float *mean = malloc(np * 3 * sizeof *mean);
  double *ratio = malloc(np * sizeof *ratio);
  if (mean && ratio && t->n && t->pix_max) {
    pc_film_beauty(film, mean);
    double image = 0;
    for (size_t p = 0; p < np; p++) image += 0.2126 * mean[3 * p] + 0.7152 * mean[3 * p + 1] + 0.0722 * mean[3 * p + 2];
    image /= (double)np;
    size_t nr = 0;
    for (size_t p = 0; p < np; p++) {
      double m = 0.2126 * mean[3 * p] + 0.7152 * mean[3 * p + 1] + 0.0722 * mean[3 * p + 2];
      /* dark pixels (below 1% of the image's mean) would make any sample look like a spike */
      if (!(m > 0.01 * image) || !(m > 0)) continue;
      double r = t->pix_max[p] / m;
      ratio[nr++] = r;
      if (!(r <= t->spike_max)) {
        t->spike_max = r;
        t->spike_x = (int)(p % (size_t)t->w);
        t->spike_y = (int)(p / (size_t)t->w);
      }
    }
    if (nr) {
      qsort(ratio, nr, sizeof *ratio, cmp_double);
      t->spike_p99 = quantile(ratio, nr, 0.99);
    }
  }
  free(mean);
  free(ratio);
  free(t->prev);
  free(t->pix_max);
  t->prev = NULL;
  t->pix_max = NULL;
}

void pc_study_tails_free(pc_study_tails *t) {
  free(t->err);
  free(t->prev);
  free(t->pix_max);
  memset(t, 0, sizeof *t);
}

void pc_study_tails_print(FILE *f, const char *method, const pc_study_tails *t) {
  fprintf(f, "%s tails: per-iteration relMSE median %.4g p90 %.4g p99 %.4g max %.4g (max/median %.3g, %zu iterations); "
             "largest one-iteration pixel / pixel mean %.4g at (%d,%d), 99th percentile %.4g\n",
          method, t->err_median, t->err_p90, t->err_p99, t->err_max, t->err_max / t->err_median, t->nerr, t->spike_max,
          t->spike_x, t->spike_y, t->spike_p99);
}

static void num(FILE *f, const char *name, double v, const char *sep) {
  if (isfinite(v)) fprintf(f, "\"%s\": %.6g%s", name, v, sep);
  else fprintf(f, "\"%s\": null%s", name, sep);
}

void pc_study_tails_json(FILE *f, const pc_study_tails *t) {
  fprintf(f, "{\"iterations\": %zu, \"iteration_relmse\": {", t->nerr);
  num(f, "mean", t->err_mean, ", ");
  num(f, "median", t->err_median, ", ");
  num(f, "p90", t->err_p90, ", ");
  num(f, "p99", t->err_p99, ", ");
  num(f, "max", t->err_max, "}, ");
  num(f, "spike_max", t->spike_max, ", ");
  num(f, "spike_p99", t->spike_p99, ", ");
  fprintf(f, "\"spike_pixel\": [%d, %d]}", t->spike_x, t->spike_y);
}
