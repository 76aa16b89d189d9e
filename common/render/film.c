/* film.c: per-strategy layers of unnormalized sums and their sample counts (DESIGN.md §4.2),
 * the beauty's variance estimated from the beauty_sq layer and the per-pixel largest iteration
 * in beauty_max (docs/variance.md), and mixes of films with fixed weights (docs/auto.md). */
#include "film.h"

#include "big_alloc.h"
#include "thread_pool.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A layer whose norm is not in `stored` (PC_FILM_NORM bits) has no storage. Its sums are not
 * zeroed here (pc_film_zero_piece). */
static int add_layer(pc_film *f, const char *name, pc_norm norm, unsigned stored, pc_err *e) {
  bool sums = stored & PC_FILM_NORM(norm);
  if (f->nlayers >= PC_FILM_MAX_LAYERS)
    return pc_errf(e, PC_ELIMIT, "film: more than %d layers", PC_FILM_MAX_LAYERS);
  pc_film_layer *l = &f->layers[f->nlayers];
  snprintf(l->name, sizeof l->name, "%.15s", name);
  l->norm = norm;
  l->count = 0;
  l->sum = sums ? pc_big_alloc((size_t)f->w * f->h * 3 * sizeof(double)) : NULL;
  if (sums && !l->sum) return pc_errf(e, PC_ENOMEM, "film: out of memory for layer '%s' (%dx%d)", name, f->w, f->h);
  f->nlayers++;
  return PC_OK;
}

int pc_film_alloc_stored(pc_film *f, int w, int h, int strategy_depth, unsigned stored, pc_err *e) {
  memset(f, 0, sizeof *f);
  if (w < 1 || h < 1 || w > 16384 || h > 16384)
    return pc_errf(e, PC_EINVAL, "film: size %dx%d out of range 1..16384", w, h);
  if (strategy_depth < 0 || strategy_depth > 8)
    return pc_errf(e, PC_EINVAL, "film: strategy layer depth %d out of range 0..8", strategy_depth);
  f->w = w;
  f->h = h;
  memset(f->strategy_index, -1, sizeof f->strategy_index);
  static const char *std_names[PC_LAYER_STD_COUNT] = {"pt", "nee", "lt", "inner"};
  int rc = PC_OK;
  for (int i = 0; i < PC_LAYER_STD_COUNT && rc == PC_OK; i++)
    rc = add_layer(f, std_names[i], i == PC_LAYER_LT ? PC_NORM_LIGHT : PC_NORM_EYE, stored, e);
  /* Path length k (segments) has strategies s + t = k + 1, t >= 1. */
  for (int k = 1; k <= strategy_depth && rc == PC_OK; k++)
    for (int t = 1; t <= k + 1 && rc == PC_OK; t++) {
      char name[32];
      snprintf(name, sizeof name, "s%dt%d", k + 1 - t, t);
      rc = add_layer(f, name, t == 1 ? PC_NORM_LIGHT : PC_NORM_EYE, stored, e);
      if (rc == PC_OK) f->strategy_index[k + 1 - t][t] = (int8_t)(f->nlayers - 1);
    }
  /* last, so a film serialized before they existed is this film's layers but the last */
  if (rc == PC_OK) rc = add_layer(f, "beauty_sq", PC_NORM_SQUARE, stored, e);
  if (rc == PC_OK) rc = add_layer(f, "beauty_max", PC_NORM_MAX, stored, e);
  if (rc != PC_OK) pc_film_free(f);
  return rc;
}

/* Pieces of PIECE_DOUBLES sums, a layer's last one shorter; layers without storage have none. */
#define PIECE_DOUBLES ((size_t)PC_FILM_PIECE_BYTES / sizeof(double))
static size_t layer_pieces(const pc_film *f) { return ((size_t)f->w * f->h * 3 + PIECE_DOUBLES - 1) / PIECE_DOUBLES; }

int pc_film_pieces(const pc_film *f) {
  size_t n = 0;
  for (int i = 0; i < f->nlayers; i++)
    if (f->layers[i].sum) n += layer_pieces(f);
  return (int)n;
}

void pc_film_zero_piece(pc_film *f, int piece) {
  size_t per = layer_pieces(f), left = (size_t)piece, total = (size_t)f->w * f->h * 3;
  for (int i = 0; i < f->nlayers; i++) {
    if (!f->layers[i].sum) continue;
    if (left < per) {
      size_t at = left * PIECE_DOUBLES, n = total - at < PIECE_DOUBLES ? total - at : PIECE_DOUBLES;
      memset(f->layers[i].sum + at, 0, n * sizeof(double));
      return;
    }
    left -= per;
  }
}

static void zero_one(void *arg, int thread, int piece) {
  (void)thread;
  pc_film_zero_piece(arg, piece);
}

void pc_film_zero_on(pc_pool *pool, pc_film *f) { pc_pool_run(pool, pc_film_pieces(f), zero_one, f); }

int pc_film_init_threads(pc_film *f, int w, int h, int strategy_depth, int threads, pc_err *e) {
  int rc = pc_film_alloc_stored(f, w, h, strategy_depth, PC_FILM_NORMS_ALL, e);
  if (rc == PC_OK) pc_pool_run_once(threads, pc_film_pieces(f), zero_one, f);
  return rc;
}

int pc_film_init_stored(pc_film *f, int w, int h, int strategy_depth, unsigned stored, pc_err *e) {
  int rc = pc_film_alloc_stored(f, w, h, strategy_depth, stored, e);
  if (rc == PC_OK)
    for (int i = 0, n = pc_film_pieces(f); i < n; i++) pc_film_zero_piece(f, i);
  return rc;
}

int pc_film_init(pc_film *f, int w, int h, int strategy_depth, pc_err *e) {
  return pc_film_init_stored(f, w, h, strategy_depth, PC_FILM_NORMS_ALL, e);
}

void pc_film_free(pc_film *f) {
  for (int i = 0; i < f->nlayers; i++) free(f->layers[i].sum);
  pc_trace_free(&f->trace);
  memset(f, 0, sizeof *f);
}

static int layer_of_norm(const pc_film *f, pc_norm norm) {
  for (int i = f->nlayers - 1; i >= 0; i--)
    if (f->layers[i].norm == norm) return i;
  return -1;
}
int pc_film_square_layer(const pc_film *f) { return layer_of_norm(f, PC_NORM_SQUARE); }
int pc_film_max_layer(const pc_film *f) { return layer_of_norm(f, PC_NORM_MAX); }

static bool per_iteration(pc_norm norm) { return norm == PC_NORM_SQUARE || norm == PC_NORM_MAX; }

int pc_film_per_iteration_first(const pc_film *f) {
  int i = f->nlayers;
  while (i > 0 && per_iteration(f->layers[i - 1].norm)) i--;
  return i;
}

bool pc_film_max_complete(const pc_film *f) {
  int m = pc_film_max_layer(f);
  return m >= 0 && f->layers[m].sum && f->layers[m].count > 0 && f->layers[m].count == f->layers[PC_LAYER_PT].count;
}

void pc_film_clear(pc_film *f) {
  for (int i = 0; i < f->nlayers; i++) {
    if (f->layers[i].sum) memset(f->layers[i].sum, 0, (size_t)f->w * f->h * 3 * sizeof(double));
    f->layers[i].count = 0;
  }
  f->dropped_nonfinite = 0;
  pc_trace_clear(&f->trace);
}

int pc_film_add(pc_film *dst, const pc_film *src, pc_err *e) {
  if (dst->w != src->w || dst->h != src->h || dst->nlayers != src->nlayers)
    return pc_errf(e, PC_EINVAL, "film: cannot add %dx%d/%d layers into %dx%d/%d layers", src->w, src->h,
                   src->nlayers, dst->w, dst->h, dst->nlayers);
  for (int i = 0; i < dst->nlayers; i++)
    if (strcmp(dst->layers[i].name, src->layers[i].name) != 0)
      return pc_errf(e, PC_EINVAL, "film: layer %d is '%s' here but '%s' in the addend", i, dst->layers[i].name,
                     src->layers[i].name);
  int rc = pc_trace_append(&dst->trace, &src->trace, pc_trace_blocks(dst->w, dst->h), e);
  if (rc != PC_OK) return rc;
  size_t n = (size_t)dst->w * dst->h * 3;
  for (int i = 0; i < dst->nlayers; i++) {
    double *d = dst->layers[i].sum;
    const double *s = src->layers[i].sum;
    if (d && s && dst->layers[i].norm == PC_NORM_MAX)
      for (size_t j = 0; j < n; j++) d[j] = s[j] > d[j] ? s[j] : d[j];
    else if (d && s)
      for (size_t j = 0; j < n; j++) d[j] += s[j];
    dst->layers[i].count += src->layers[i].count;
  }
  dst->dropped_nonfinite += src->dropped_nonfinite;
  return PC_OK;
}

double pc_film_layer_scale(const pc_film *f, const pc_film_layer *l) {
  if (l->count == 0) return 0.0;
  if (l->norm == PC_NORM_MAX) return 1.0; /* a maximum, not a sum */
  return l->norm == PC_NORM_LIGHT ? (double)f->w * f->h / (double)l->count : 1.0 / (double)l->count;
}

void pc_film_layer_rows(const pc_film *f, int i, int y0, int ny, float *out) {
  const pc_film_layer *l = &f->layers[i];
  size_t j0 = (size_t)y0 * f->w * 3, n = (size_t)ny * f->w * 3;
  double scale = pc_film_layer_scale(f, l);
  for (size_t j = 0; j < n; j++) out[j] = l->sum ? (float)(l->sum[j0 + j] * scale) : 0.f;
}

void pc_film_layer_image(const pc_film *f, int i, float *out) { pc_film_layer_rows(f, i, 0, f->h, out); }

void pc_film_beauty_rows(const pc_film *f, int y0, int ny, float *out) {
  size_t j0 = (size_t)y0 * f->w * 3, n = (size_t)ny * f->w * 3;
  memset(out, 0, n * sizeof(float));
  for (int i = 0; i < PC_LAYER_STD_COUNT && i < f->nlayers; i++) {
    const pc_film_layer *l = &f->layers[i];
    if (l->count == 0) continue;
    double scale = pc_film_layer_scale(f, l);
    for (size_t j = 0; j < n; j++) out[j] += (float)(l->sum[j0 + j] * scale);
  }
}

void pc_film_beauty(const pc_film *f, float *out) { pc_film_beauty_rows(f, 0, f->h, out); }

void pc_film_queue_flush(pc_film_queue *q) {
  enum { AHEAD = 8 };
  pc_film *f = q->film;
  for (int k = 0; k < q->n; k++) {
    if (k + AHEAD < q->n) {
      const pc_film_queued *a = &q->q[k + AHEAD];
      __builtin_prefetch(f->layers[a->layer].sum + 3 * (size_t)a->pixel, 1);
    }
    const pc_film_queued *e = &q->q[k];
    double *p = f->layers[e->layer].sum + 3 * (size_t)e->pixel;
    p[0] += e->v[0]; p[1] += e->v[1]; p[2] += e->v[2];
  }
  q->n = 0;
}

/* Whether f's variance is known: beauty_sq has seen its every iteration, and 2 or more. */
static bool variance_known(const pc_film *f) {
  int q = pc_film_square_layer(f);
  if (q < 0 || !f->layers[q].sum || f->nlayers <= PC_LAYER_STD_COUNT) return false;
  return f->layers[q].count >= 2 && f->layers[q].count == f->layers[PC_LAYER_PT].count;
}

/* Calls fn(user, j, variance of the mean, mean) for every value of rows [y0, y0 + ny) (ny < 0:
 * every row) of the beauty of the mix of the parts with a weight (independent estimates: mean
 * sum w m, variance sum w^2 v), in double precision, j counted from the first row's first
 * value, and returns how many values there are; 0 when there is no such part or one of them
 * cannot tell (see pc_film_variance). One part of weight 1 is its film: multiplying by 1
 * and adding to 0 are exact. */
static size_t each_variance(const pc_film_part *parts, int n, int y0, int ny, void (*fn)(void *, size_t, double, double),
                            void *user) {
  if (n < 1 || n > PC_FILM_MIX_MAX_PARTS) return 0;
  const pc_film *shape = NULL;
  double scale[PC_FILM_MIX_MAX_PARTS][PC_LAYER_STD_COUNT], inv_n[PC_FILM_MIX_MAX_PARTS], inv_n1[PC_FILM_MIX_MAX_PARTS];
  const double *sq[PC_FILM_MIX_MAX_PARTS];
  for (int i = 0; i < n; i++) {
    const pc_film *f = parts[i].film;
    if (parts[i].weight == 0.0) continue;
    if (!shape) shape = f;
    if (!variance_known(f) || f->w != shape->w || f->h != shape->h) return 0;
    uint64_t n_it = f->layers[PC_LAYER_PT].count;
    inv_n[i] = 1.0 / (double)n_it;
    inv_n1[i] = 1.0 / (double)(n_it - 1);
    for (int l = 0; l < PC_LAYER_STD_COUNT; l++) scale[i][l] = pc_film_layer_scale(f, &f->layers[l]);
    sq[i] = f->layers[pc_film_square_layer(f)].sum;
  }
  if (!shape) return 0;
  if (ny < 0) ny = shape->h; /* every row */
  size_t j0 = (size_t)y0 * shape->w * 3, nv = (size_t)ny * shape->w * 3;
  for (size_t j = j0; j < j0 + nv; j++) {
    double m = 0.0, v = 0.0;
    for (int i = 0; i < n; i++) {
      double w = parts[i].weight;
      if (w == 0.0) continue;
      const pc_film *f = parts[i].film;
      double mi = 0.0;
      for (int l = 0; l < PC_LAYER_STD_COUNT; l++) mi += f->layers[l].sum[j] * scale[i][l];
      /* rounding can make the difference of two close sums slightly negative */
      double vi = (sq[i][j] * inv_n[i] - mi * mi) * inv_n1[i];
      m += w * mi;
      v += w * w * (vi > 0.0 ? vi : 0.0);
    }
    fn(user, j - j0, v, m);
  }
  return nv;
}

static void put_variance(void *user, size_t j, double v, double m) {
  (void)m;
  ((float *)user)[j] = (float)v;
}

bool pc_film_variance_rows(const pc_film *f, int y0, int ny, float *out) {
  pc_film_part whole = {f, 1.0};
  return each_variance(&whole, 1, y0, ny, put_variance, out) > 0;
}

bool pc_film_variance(const pc_film *f, float *out) { return pc_film_variance_rows(f, 0, f->h, out); }

/* E[m^2] = exact^2 + v, so the denominator subtracts v (docs/variance.md). */
static void add_relative(void *user, size_t j, double v, double m) {
  (void)j;
  *(double *)user += v / (fmax(m * m - v, 0.0) + PC_RELMSE_EPS);
}

bool pc_film_mix_relmse_estimate(const pc_film_part *parts, int n, double *out) {
  double sum = 0.0;
  *out = NAN;
  size_t nv = each_variance(parts, n, 0, -1, add_relative, &sum);
  if (nv == 0) return false;
  *out = sum / (double)nv;
  return true;
}

bool pc_film_relmse_estimate(const pc_film *f, double *out) {
  pc_film_part whole = {f, 1.0};
  return pc_film_mix_relmse_estimate(&whole, 1, out);
}

static void put_double(void *user, size_t j, double v, double m) {
  (void)m;
  ((double *)user)[j] = v;
}

/* The mix is the pilot of --method auto counted in the job's image (docs/auto.md): two
 * independent unbiased estimates, so any mix with weights fixed independently of their values
 * is unbiased too. pc_film_add could not do it: it weights each iteration by 1 / (total count),
 * and the job's count depends on which method the pilot chose. */
int pc_film_mix(pc_film *out, const pc_film_part *parts, int n, pc_err *e) {
  if (n < 1 || n > PC_FILM_MIX_MAX_PARTS) return pc_errf(e, PC_EINVAL, "film mix: %d parts (1 to %d)", n, PC_FILM_MIX_MAX_PARTS);
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
  int heaviest = 0;
  for (int i = 1; i < n; i++)
    if (parts[i].weight > parts[heaviest].weight) heaviest = i;
  pc_film_clear(out);
  int rc = pc_trace_append(&out->trace, &parts[heaviest].film->trace, pc_trace_blocks(out->w, out->h), e);
  if (rc != PC_OK) return rc;
  size_t nv = (size_t)out->w * out->h * 3;
  bool max_complete = true;
  int q = pc_film_square_layer(out), mx = pc_film_max_layer(out);
  for (int i = 0; i < n; i++) {
    const pc_film *f = parts[i].film;
    if (parts[i].weight == 0.0) continue; /* not in the mix, nor in its counts */
    max_complete = max_complete && pc_film_max_complete(f);
    for (int l = 0; l < out->nlayers; l++) out->layers[l].count += f->layers[l].count;
    out->dropped_nonfinite += f->dropped_nonfinite;
  }
  /* every image layer: the weighted sum of the parts' images, as sums of the mix's counts */
  for (int l = 0; l < out->nlayers; l++) {
    pc_film_layer *o = &out->layers[l];
    if (o->norm == PC_NORM_SQUARE || o->norm == PC_NORM_MAX || o->count == 0) continue;
    double back = 1.0 / pc_film_layer_scale(out, o);
    for (int i = 0; i < n; i++) {
      const pc_film *f = parts[i].film;
      double s = parts[i].weight * pc_film_layer_scale(f, &f->layers[l]) * back;
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
  double *sq = out->layers[q].sum, nn = (double)it;
  if (it < 2 || !each_variance(parts, n, 0, -1, put_double, sq)) {
    out->layers[q].count = 0; /* the mix cannot tell its variance either */
    return PC_OK;
  }
  /* beauty_sq such that pc_film_variance gives the mix's variance: (sq/N - m^2)/(N - 1) = V for
   * sq = N((N - 1)V + m^2), with m the mix's own beauty */
  out->layers[q].count = it;
  double scale[PC_LAYER_STD_COUNT];
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) scale[l] = pc_film_layer_scale(out, &out->layers[l]);
  for (size_t j = 0; j < nv; j++) {
    double m = 0.0;
    for (int l = 0; l < PC_LAYER_STD_COUNT; l++) m += out->layers[l].sum[j] * scale[l];
    sq[j] = nn * ((nn - 1.0) * sq[j] + m * m);
  }
  return PC_OK;
}

bool pc_film_is_finite(const pc_film *f) {
  size_t n = (size_t)f->w * f->h * 3;
  for (int i = 0; i < f->nlayers; i++)
    for (size_t j = 0; j < n && f->layers[i].sum; j++)
      if (!isfinite(f->layers[i].sum[j])) return false;
  return true;
}
