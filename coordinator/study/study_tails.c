/* study_tails.c: how heavy-tailed a method's image is, from its final EXR alone: per pixel,
 * how much of the pixel its largest single iteration carried (the film's beauty_max over its
 * mean, docs/variance.md "Heavy tails"), summarised over the image's lit pixels; and the
 * distribution of the per-iteration error the film wrote in the header (film_trace.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "study.h"

double pc_study_mean_luminance(const pc_image *im) {
  size_t np = (size_t)im->w * (size_t)im->h;
  double sum = 0;
  for (size_t p = 0; p < np; p++) sum += pc_study_luminance(im->rgb + 3 * p);
  return np ? sum / (double)np : 0;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The q-quantile of sorted v[0..n) (nearest rank). */
static double quantile(const double *v, size_t n, double q) {
  size_t k = (size_t)ceil(q * (double)n);
  return v[k > 0 ? k - 1 : 0];
}

/* pcbpt.iteration_error.* of the header: known only whole and consistent. */
static void iteration_errors(const pc_exr_file *x, pc_study_tails *t) {
  pc_iteration_errors *ie = &t->iter;
  double n = pc_study_exr_number(x, "pcbpt.iteration_error.n"), worst = pc_study_exr_number(x, "pcbpt.iteration_error.worst");
  ie->mean = pc_study_exr_number(x, "pcbpt.iteration_error.mean");
  ie->p50 = pc_study_exr_number(x, "pcbpt.iteration_error.p50");
  ie->p90 = pc_study_exr_number(x, "pcbpt.iteration_error.p90");
  ie->p99 = pc_study_exr_number(x, "pcbpt.iteration_error.p99");
  ie->max = pc_study_exr_number(x, "pcbpt.iteration_error.max");
  ie->top1 = pc_study_exr_number(x, "pcbpt.iteration_error.top1");
  if (!(n >= 2 && n <= PC_TRACE_ITERATIONS) || !(worst >= 0 && worst < PC_TRACE_ITERATIONS)) return;
  double v[] = {ie->mean, ie->p50, ie->p90, ie->p99, ie->max, ie->top1};
  for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
    if (!(v[i] >= 0) || !isfinite(v[i])) return;
  ie->n = (uint32_t)n;
  ie->worst = (uint32_t)worst;
  const char *s = pc_exr_attr_get(x, "pcbpt.iteration_error.tail");
  while (s && *s && ie->ntail < PC_TRACE_TAIL_MAX) {
    char *end;
    double d = strtod(s, &end);
    if (end == s || !(d >= 0) || !isfinite(d)) return;
    ie->tail[ie->ntail++] = d;
    s = end;
  }
  t->iter_known = true;
}

int pc_study_tails_exr(const pc_exr_file *x, pc_study_tails *t, pc_err *e) {
  memset(t, 0, sizeof *t);
  t->p50 = t->p99 = t->max = NAN;
  t->max_x = t->max_y = -1;
  iteration_errors(x, t);
  const pc_image *beauty = NULL, *mx = NULL;
  for (int i = 0; i < x->nlayers; i++) {
    if (x->names[i][0] == '\0') beauty = &x->layers[i];
    if (strcmp(x->names[i], "beauty_max") == 0) mx = &x->layers[i];
  }
  double n_max = pc_study_exr_number(x, "pcbpt.count.beauty_max"), n_pt = pc_study_exr_number(x, "pcbpt.count.pt");
  /* the film writes beauty_max only when it saw every iteration; an older image has none */
  if (!beauty || !mx || !(n_max >= 1) || n_max != n_pt) return PC_OK;
  t->iterations = (uint64_t)n_max;
  size_t np = (size_t)x->w * x->h;
  double mean = pc_study_mean_luminance(beauty);
  double *r = malloc((np ? np : 1) * sizeof *r);
  if (!r) return pc_errf(e, PC_ENOMEM, "out of memory for the tails of a %dx%d image", x->w, x->h);
  size_t n = 0;
  for (size_t p = 0; p < np; p++) {
    double y = pc_study_luminance(beauty->rgb + 3 * p);
    if (!(y > PC_STUDY_TAILS_LIT * mean)) continue;
    /* the luminance of the per-channel maxima: at least the largest iteration's luminance, the
     * same when one iteration holds all three channels' maxima (a firefly does), and still at
     * most N times the mean */
    double ratio = pc_study_luminance(mx->rgb + 3 * p) / y;
    r[n++] = ratio;
    if (!(ratio <= t->max)) {
      t->max = ratio;
      t->max_x = (int)(p % (size_t)x->w);
      t->max_y = (int)(p / (size_t)x->w);
    }
  }
  t->known = true;
  t->pixels = n;
  if (n) {
    qsort(r, n, sizeof *r, cmp_double);
    t->p50 = quantile(r, n, 0.5);
    t->p99 = quantile(r, n, 0.99);
  }
  free(r);
  return PC_OK;
}
