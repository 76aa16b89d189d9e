/* film_mix.c: a film whose images are a weighted mix of other films' images (film.h). This is
 * how --method auto's pilot counts in the job's image (docs/auto.md): the pilot's iterations
 * and the job's are two independent unbiased estimates, so any mix with weights fixed
 * independently of their values is unbiased too. A plain pc_film_add could not do it: it
 * weights each iteration by 1/(total count), and the job's count depends on which method the
 * pilot chose. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "film.h"

static double image_scale(const pc_film *f, const pc_film_layer *l) {
  if (l->count == 0) return 0.0;
  return l->norm == PC_NORM_LIGHT ? (double)f->w * f->h / (double)l->count : 1.0 / (double)l->count;
}

/* Whether a film's variance is known: beauty_sq has seen its every iteration, and 2 or more. */
static bool can_tell(const pc_film *f) {
  int q = pc_film_square_layer(f);
  return q >= 0 && f->layers[q].sum && f->layers[q].count >= 2 && f->layers[q].count == f->layers[PC_LAYER_PT].count;
}

int pc_film_mix(pc_film *out, const pc_film_part *parts, int n, pc_err *e) {
  for (int i = 0; i < n; i++) {
    const pc_film *f = parts[i].film;
    if (!(parts[i].weight >= 0.0) || !isfinite(parts[i].weight))
      return pc_errf(e, PC_EINVAL, "film mix: weight %g of part %d", parts[i].weight, i);
    if (f->w != out->w || f->h != out->h || f->nlayers != out->nlayers)
      return pc_errf(e, PC_EINVAL, "film mix: part %d is %dx%d/%d layers, the mix %dx%d/%d", i, f->w, f->h, f->nlayers,
                     out->w, out->h, out->nlayers);
    for (int l = 0; l < f->nlayers; l++)
      if (strcmp(f->layers[l].name, out->layers[l].name) != 0 || !f->layers[l].sum)
        return pc_errf(e, PC_EINVAL, "film mix: part %d's layer %d is '%s', the mix's '%s'", i, l, f->layers[l].name,
                       out->layers[l].name);
  }
  pc_film_clear(out);
  size_t nv = (size_t)out->w * out->h * 3;
  bool tell = true, max_complete = true;
  int q = pc_film_square_layer(out), mx = pc_film_max_layer(out);
  for (int i = 0; i < n; i++) {
    const pc_film *f = parts[i].film;
    if (parts[i].weight == 0.0) continue; /* not in the mix, nor in its counts */
    tell = tell && can_tell(f);
    max_complete = max_complete && pc_film_max_complete(f);
    for (int l = 0; l < out->nlayers; l++) out->layers[l].count += f->layers[l].count;
    out->dropped_nonfinite += f->dropped_nonfinite;
  }
  /* every image layer: the weighted sum of the parts' images, as sums of the mix's counts */
  for (int l = 0; l < out->nlayers; l++) {
    pc_film_layer *o = &out->layers[l];
    if (o->norm == PC_NORM_SQUARE || o->norm == PC_NORM_MAX || o->count == 0) continue;
    double back = 1.0 / image_scale(out, o);
    for (int i = 0; i < n; i++) {
      const pc_film *f = parts[i].film;
      double s = parts[i].weight * image_scale(f, &f->layers[l]) * back;
      if (s == 0.0) continue;
      const double *src = f->layers[l].sum;
      for (size_t j = 0; j < nv; j++) o->sum[j] += s * src[j];
    }
  }
  if (mx >= 0) {
    double *m = out->layers[mx].sum;
    for (int i = 0; i < n; i++) {
      if (parts[i].weight == 0.0) continue;
      const double *src = parts[i].film->layers[mx].sum;
      for (size_t j = 0; j < nv; j++) m[j] = src[j] > m[j] ? src[j] : m[j];
    }
    if (!max_complete) out->layers[mx].count = 0; /* it cannot tell */
  }
  if (q < 0) return PC_OK;
  uint64_t it = out->layers[PC_LAYER_PT].count;
  if (!tell || it < 2) {
    out->layers[q].count = 0; /* the mix cannot tell its variance either */
    return PC_OK;
  }
  /* beauty_sq such that pc_film_variance gives the mix's variance, sum of weight^2 x each
   * part's: (sq/N - m^2)/(N - 1) = V for sq = N((N - 1)V + m^2) */
  float *v = NULL;
  double *sq = out->layers[q].sum, nn = (double)it;
  out->layers[q].count = it;
  for (int i = 0; i < n; i++) {
    double w2 = parts[i].weight * parts[i].weight;
    if (w2 == 0.0) continue;
    if (!v && !(v = malloc(nv * sizeof *v))) return pc_errf(e, PC_ENOMEM, "film mix: out of memory");
    pc_film_variance(parts[i].film, v);
    for (size_t j = 0; j < nv; j++) sq[j] += w2 * (double)v[j];
  }
  free(v);
  double scale[PC_LAYER_STD_COUNT];
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) scale[l] = image_scale(out, &out->layers[l]);
  for (size_t j = 0; j < nv; j++) {
    double m = 0.0;
    for (int l = 0; l < PC_LAYER_STD_COUNT; l++) m += out->layers[l].sum[j] * scale[l];
    sq[j] = nn * ((nn - 1.0) * sq[j] + m * m);
  }
  return PC_OK;
}

bool pc_film_mix_relmse_estimate(const pc_film_part *parts, int n, double *out) {
  *out = NAN;
  const pc_film *shape = NULL;
  for (int i = 0; i < n; i++) {
    if (parts[i].weight == 0.0) continue;
    const pc_film *f = parts[i].film;
    if (!can_tell(f) || f->nlayers < PC_LAYER_STD_COUNT || (shape && (f->w != shape->w || f->h != shape->h))) return false;
    shape = f;
  }
  if (!shape) return false;
  size_t nv = (size_t)shape->w * shape->h * 3;
  double acc = 0.0;
  for (size_t j = 0; j < nv; j++) {
    double m = 0.0, v = 0.0;
    for (int i = 0; i < n; i++) {
      double w = parts[i].weight;
      if (w == 0.0) continue;
      const pc_film *f = parts[i].film;
      const pc_film_layer *q = &f->layers[pc_film_square_layer(f)];
      double mi = 0.0, it = (double)q->count;
      for (int l = 0; l < PC_LAYER_STD_COUNT; l++) mi += f->layers[l].sum[j] * image_scale(f, &f->layers[l]);
      double vi = (q->sum[j] / it - mi * mi) / (it - 1.0);
      m += w * mi;
      v += w * w * (vi > 0.0 ? vi : 0.0);
    }
    acc += v / (fmax(m * m - v, 0.0) + PC_RELMSE_EPS);
  }
  *out = acc / (double)nv;
  return true;
}
