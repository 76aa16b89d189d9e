/* render.c: the renderer: a thread pool bound to a scene and settings, and the iteration loop
 * that every front end (standalone render, farm worker, tests) calls. One iteration renders the
 * whole image into a scratch film that is added to the caller's film only when complete, so a
 * cancelled call never leaves a partial iteration behind. */
#include "render.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "integrator.h"
#include "thread_pool.h"

#define TILE 16

struct pc_renderer {
  const pc_scene *scene;
  pc_render_settings set;
  pc_pool *pool;
  pc_film scratch;     /* the iteration being rendered */
  pc_film *splat;      /* one per thread */
  pc_tctx *tctx;       /* one per thread */
  atomic_bool *cancel;
  int tiles_x, tiles_y;
};

void pc_render_settings_default(pc_render_settings *s) {
  memset(s, 0, sizeof *s);
  s->method = PC_METHOD_PT;
  s->width = 256;
  s->height = 256;
  s->max_depth = -1;
  s->seed = 1;
  s->light_paths = 0;
  s->mis_heuristic = PC_MIS_BALANCE;
  s->strategy_layers = 0;
  s->pcbpt_m = 100;
  s->pcbpt_k = 1;
  s->cache_fraction = 0.004f;
  s->knn = 6;
  /* Defensive mixing (Popov et al. sect. 6, after Georgiev et al. 2012): p_conn >= u/V for
   * every light vertex, so where the cached PMF is wrong (a vertex it thinks is dark is not)
   * a sample's weight 1/(M p_conn) is at most V/(u M), 1/u = 10 times the uniform (CBDPT-like)
   * weight: variance there is bounded by about 1/u times CBDPT's, while the interpolated PMF
   * keeps 90% of the samples where it is right. */
  s->uniform_mix = 0.1f;
  s->mis_mode = PC_MIS_UPPER_BOUND;
  s->pmf_mode = PC_PMF_CACHED;
}

int pc_render_settings_check(const pc_render_settings *s, pc_err *e) {
  if (s->method < PC_METHOD_PT || s->method > PC_METHOD_PCBPT) return pc_errf(e, PC_EINVAL, "method: unknown method %d", (int)s->method);
  if (s->width < 1 || s->width > PC_SCENE_MAX_FILM_DIM || s->height < 1 || s->height > PC_SCENE_MAX_FILM_DIM)
    return pc_errf(e, PC_EINVAL, "resolution %dx%d out of range 1..%d", s->width, s->height, PC_SCENE_MAX_FILM_DIM);
  if (s->max_depth == 0 || s->max_depth < -1 || s->max_depth > PC_MAX_SEGMENTS)
    return pc_errf(e, PC_EINVAL, "max-depth %d out of range (-1 for infinite, or 1..%d)", s->max_depth, PC_MAX_SEGMENTS);
  if (s->light_paths > (uint64_t)1 << 32) return pc_errf(e, PC_EINVAL, "light-paths %llu too large", (unsigned long long)s->light_paths);
  if (s->strategy_layers < 0 || s->strategy_layers > 8) return pc_errf(e, PC_EINVAL, "strategy-layers %d out of range 0..8", s->strategy_layers);
  if (s->pcbpt_m < 1 || s->pcbpt_m > 100000) return pc_errf(e, PC_EINVAL, "pcbpt-m %d out of range 1..100000", s->pcbpt_m);
  if (s->pcbpt_k < 1 || s->pcbpt_k > 1000000) return pc_errf(e, PC_EINVAL, "pcbpt-k %d out of range 1..1000000", s->pcbpt_k);
  if (!(s->cache_fraction > 0.f && s->cache_fraction <= 1.f)) return pc_errf(e, PC_EINVAL, "cache-fraction %g out of range (0, 1]", s->cache_fraction);
  if (s->knn < 1 || s->knn > 64) return pc_errf(e, PC_EINVAL, "knn %d out of range 1..64", s->knn);
  if (!(s->uniform_mix >= 0.f && s->uniform_mix <= 1.f)) return pc_errf(e, PC_EINVAL, "uniform-mix %g out of range [0, 1]", s->uniform_mix);
  return PC_OK;
}

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int pc_renderer_create(const pc_scene *scene, const pc_render_settings *settings, int threads, pc_renderer **out,
                       pc_err *e) {
  int rc = pc_render_settings_check(settings, e);
  if (rc != PC_OK) return rc;
  if (settings->method != PC_METHOD_PT)
    return pc_errf(e, PC_EUNSUPPORTED, "method %s is not implemented yet", pc_method_name(settings->method));
  if (threads < 0 || threads > 1024) return pc_errf(e, PC_EINVAL, "threads %d out of range 0..1024", threads);
  if (threads == 0) threads = pc_cpu_count();
  pc_renderer *r = calloc(1, sizeof *r);
  if (!r) return pc_errf(e, PC_ENOMEM, "out of memory for the renderer");
  r->scene = scene;
  r->set = *settings;
  r->tiles_x = (settings->width + TILE - 1) / TILE;
  r->tiles_y = (settings->height + TILE - 1) / TILE;
  rc = pc_film_init(&r->scratch, settings->width, settings->height, settings->strategy_layers, e);
  if (rc == PC_OK) rc = pc_pool_create(threads, &r->pool, e);
  if (rc == PC_OK) {
    r->splat = calloc((size_t)threads, sizeof(pc_film));
    r->tctx = calloc((size_t)threads, sizeof(pc_tctx));
    if (!r->splat || !r->tctx) rc = pc_errf(e, PC_ENOMEM, "out of memory for the renderer");
  }
  for (int i = 0; rc == PC_OK && i < threads; i++)
    rc = pc_film_init(&r->splat[i], settings->width, settings->height, settings->strategy_layers, e);
  if (rc != PC_OK) {
    pc_renderer_destroy(r);
    return rc;
  }
  int max_seg = settings->max_depth < 0 ? PC_MAX_SEGMENTS : settings->max_depth;
  for (int i = 0; i < threads; i++) {
    r->tctx[i].scene = scene;
    r->tctx[i].set = &r->set;
    r->tctx[i].max_segments = max_seg;
    r->tctx[i].film = &r->scratch;
    r->tctx[i].splat = &r->splat[i];
  }
  *out = r;
  return PC_OK;
}

void pc_renderer_destroy(pc_renderer *r) {
  if (!r) return;
  int n = r->pool ? pc_pool_size(r->pool) : 0;
  pc_pool_destroy(r->pool);
  if (r->splat)
    for (int i = 0; i < n; i++) pc_film_free(&r->splat[i]);
  free(r->splat);
  free(r->tctx);
  pc_film_free(&r->scratch);
  free(r);
}

int pc_renderer_threads(const pc_renderer *r) { return pc_pool_size(r->pool); }

static bool cancelled(const pc_renderer *r) { return r->cancel && atomic_load(r->cancel); }

static void eye_tile(void *arg, int thread, int item) {
  pc_renderer *r = arg;
  if (cancelled(r)) return;
  pc_tctx *c = &r->tctx[thread];
  int tx = item % r->tiles_x, ty = item / r->tiles_x;
  int x1 = (tx + 1) * TILE < r->set.width ? (tx + 1) * TILE : r->set.width;
  int y1 = (ty + 1) * TILE < r->set.height ? (ty + 1) * TILE : r->set.height;
  for (int y = ty * TILE; y < y1; y++)
    for (int x = tx * TILE; x < x1; x++) pc_pt_pixel(c, x, y);
}

int pc_render_iterations(pc_renderer *r, uint64_t first, uint64_t count, pc_film *film, pc_render_stats *stats,
                         atomic_bool *cancel, void (*progress)(void *user, uint64_t done), void *user, pc_err *e) {
  if (film->w != r->set.width || film->h != r->set.height || film->nlayers != r->scratch.nlayers)
    return pc_errf(e, PC_EINVAL, "film is %dx%d with %d layers, the render needs %dx%d with %d", film->w, film->h,
                   film->nlayers, r->set.width, r->set.height, r->scratch.nlayers);
  r->cancel = cancel;
  int nthreads = pc_pool_size(r->pool);
  uint64_t npix = (uint64_t)r->set.width * (uint64_t)r->set.height;
  for (uint64_t k = 0; k < count; k++) {
    double t0 = now_seconds();
    pc_film_clear(&r->scratch);
    for (int i = 0; i < nthreads; i++) {
      r->tctx[i].iteration = first + k;
      r->tctx[i].rays = 0;
    }
    pc_pool_run(r->pool, r->tiles_x * r->tiles_y, eye_tile, r);
    if (cancelled(r)) return pc_errf(e, PC_ECANCELED, "render cancelled");
    double t1 = now_seconds();
    for (int i = 0; i < r->scratch.nlayers; i++)
      if (r->scratch.layers[i].norm == PC_NORM_EYE) r->scratch.layers[i].count = 1;
    int rc = pc_film_add(film, &r->scratch, e);
    if (rc != PC_OK) return rc;
    if (stats) {
      stats->iterations++;
      stats->eye_paths += npix;
      for (int i = 0; i < nthreads; i++) stats->rays += r->tctx[i].rays;
      stats->t_paths += t1 - t0;
      stats->t_total += now_seconds() - t0;
    }
    if (progress) progress(user, k + 1);
  }
  return PC_OK;
}
