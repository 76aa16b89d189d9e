/* render.c: the renderer: a thread pool bound to a scene and settings, and the iteration loop
 * that every front end (standalone render, farm worker, tests) calls. One iteration renders the
 * whole image into a scratch film that is added to the caller's film only when complete, so a
 * cancelled call never leaves a partial iteration behind. An iteration is an eye pass over
 * pixel tiles (pt, lt's s=0, or BDPT with its paired light paths) and, for lt and bdpt, a light
 * pass over the light paths no pixel is paired with; the threads' light splats are then merged
 * and the light layers count N_L light paths. */
#include "render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bidir.h"
#include "irec.h"
#include "pcbpt.h"
#include "thread_pool.h"

#define TILE 16
#define FOLD_ROWS 8 /* rows per work item of the fold (fold_iteration) */
#define LIGHT_CHUNK 1024 /* light paths per work item of the light pass */

struct pc_renderer {
  const pc_scene *scene;
  pc_scene *view;           /* a moving scene's view at the current iteration's time, else NULL */
  pc_render_settings set;
  pc_pool *pool;
  pc_film scratch;     /* the iteration being rendered */
  pc_film *splat;      /* one per thread */
  pc_film_queue *splatq; /* one per thread, into splat */
  pc_tctx *tctx;       /* one per thread */
  atomic_bool *cancel;
  int tiles_x, tiles_y;
  uint64_t n_light;       /* N_L */
  uint64_t light_first;   /* first light path of the light pass (the others are paired) */
  pc_path_vertex *verts;  /* per-thread sub-path buffers */
  pc_pcbpt *pcbpt;        /* CBDPT/PCBPT per-iteration state */
  double *band_blocks;    /* a traced iteration's luminance per band of rows and trace block */
  /* the iteration's work items (eye tiles, light chunks): all, and finished so far */
  atomic_uint_fast64_t items_total, items_done;
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
  s->pcbpt_rate = 1.f;
  /* In an iteration none of whose records sees a light vertex (slit-room while no stored path
   * got through the slit), an eye vertex connects with probability 1/4 and counts 4: its lookup
   * and connection cost as much as ever and almost never find anything (over 8 such iterations
   * at 128x128, 501162 connections added 0.53 in luminance; 8 iterations of ajar-door, 17627).
   * On slit-room the estimated beauty relMSE after 64 iterations is the same to 4 digits (seeds
   * 1-3) and PCBPT's time per iteration over BDPT's from 1.11-1.14 to 1.09-1.10 (bench_alternate,
   * 256x256, 2 threads, 48 iterations); every other shipped scene has records that see something in every
   * iteration and renders bit-identically. The same rule per eye vertex (its nearest records
   * see nothing) cost ajar-door 9% in beauty relMSE against a reference (docs/pmf-ceiling.md). */
  s->pcbpt_unseen_rate = 0.25f;
  s->pcbpt_candidates = 1;
  /* With resampling on, the candidates' own shadow rays in the target: inner relMSE per
   * iteration at N = 4 (K = 1, 128x128, 64 iterations, median of 3 seeds) 0.154 against 0.185
   * with the records' visibility on ajar-door, 0.00031 against 0.00035 on cornell-box, 0.0038
   * against 0.0042 on open-room, equal on slit-room, for about 10-15% more time per iteration
   * (docs/pmf-ceiling.md). */
  s->candidate_visibility = PC_CANDVIS_TRACED;
  /* Where the records nearby see less than a tenth of the light vertices, a draw from p_conn
   * mostly meets occluded or unseen ones; three candidates resampled by their traced
   * contribution, drawn with a mix of 0.85 (the records' blurred view is worth little there),
   * find the visible ones. The rule reads only the records, so it changes the proposal and
   * not the estimate's expectation. Estimated beauty relMSE x CPU per iteration after 64
   * iterations at 128x128, one thread, seeds 1-2 (docs/pmf-ceiling.md, "Dark eye vertices"):
   * ajar-door -12% (99.8% of its lookups are dark), cornell-box, open-room and slit-room
   * within 1% (3%, 8% and 51% dark), glass-lamp and env-objects about 4% worse (their
   * instructions); three candidates at every vertex lost 6-7% on cornell-box and open-room.
   * Not with K > PC_IREC_MAX_CANDIDATES, which cannot be resampled. */
  s->pcbpt_dark_seen = 0.1f;
  s->pcbpt_dark_candidates = 3;
  s->pcbpt_dark_mix = 0.85f;
  s->cache_fraction = 0.004f;
  s->knn = 6;
  /* Defensive mixing (Popov et al. sect. 6, after Georgiev et al. 2012): p_conn >= u/V for
   * every light vertex, so where the cached PMF is wrong (a vertex it thinks is dark is not)
   * a sample's weight 1/(M p_conn) is at most V/(u M), 1/u times the uniform (CBDPT-like)
   * weight: variance there is bounded by about 1/u times CBDPT's, while the interpolated PMF
   * keeps 1-u of the samples where it is right. In 30 s equal-time runs against the 900 s
   * BDPT reference, ajar-door's inner relMSE was 0.44 / 0.22 / 0.17 for u = 0.1 / 0.3 / 0.5
   * (BDPT 0.29), while slit-room stayed at 0.09 for all three (BDPT 2.1).
   * What the interpolated PMF misses is not the 1/d^2 peak of the records' G term. Measured
   * as inner relMSE x iterations (per-iteration variance, free of how many iterations the
   * 30 s allowed), ajar-door gave 14.6 / 14.0 (seeds 99 / 7) at u = 0.5, and clamping d to
   * >= 0.05 or 0.2 scene radii in the record importance, or dropping 1/d^2, changed that by
   * < 1.5%. The exact PMF at the query reaches about 8, so interpolating the records costs
   * ~1.8x. u = 0.7 / 0.85 / 1 gave 13.5 / 13.7 / 24 (seed 7: 13.2 / 13.2), but slit-room's
   * 10.0 (seed 7: 28.3) at u = 0.5 went to 10.4 / 11.7 / 14 (seed 7, u = 0.7: 27.0 and 29.2
   * in two runs differing only in iteration count), so 0.5 stays: the few per cent between
   * 0.5 and 0.7 are within the run-to-run spread. */
  s->uniform_mix = 0.5f;
  /* Inner strategies count 2 in the weights: between the paper's conservative 1 (which treats
   * the inner samples of a pixel as fully correlated) and M (independent). Beauty relMSE after
   * 128 iterations at 128x128, K = 1, count 2 against 1 (docs/pmf-ceiling.md): slit-room -22%,
   * furnace -18%, ajar-door -10%, outdoor -7%, cornell-box -5%, open-room, thin-glass and the
   * environment scenes within 1%, glossy-floor +1.4%. Count 4 gained more on the diffuse
   * scenes and lost 2-8% on open-room, thin-glass and glossy-floor (auto may choose it:
   * pilot.h); M gave the spiky noise of the paper's Fig. 8 (3x on glossy-floor). The count
   * changes no work, only how the image is shared out among the strategies. */
  s->mis_mode = PC_MIS_COUNT;
  s->mis_count = 2.f;
  s->pmf_mode = PC_PMF_CACHED;
}

int pc_render_settings_check(const pc_render_settings *s, pc_err *e) {
  if (s->method == PC_METHOD_AUTO) return pc_errf(e, PC_EINVAL, "method: auto must be resolved by its pilot before rendering");
  if (s->method < PC_METHOD_PT || s->method > PC_METHOD_PCBPT) return pc_errf(e, PC_EINVAL, "method: unknown method %d", (int)s->method);
  if (s->width < 1 || s->width > PC_SCENE_MAX_FILM_DIM || s->height < 1 || s->height > PC_SCENE_MAX_FILM_DIM)
    return pc_errf(e, PC_EINVAL, "resolution %dx%d out of range 1..%d", s->width, s->height, PC_SCENE_MAX_FILM_DIM);
  if (s->max_depth == 0 || s->max_depth < -1 || s->max_depth > PC_MAX_SEGMENTS)
    return pc_errf(e, PC_EINVAL, "max-depth %d out of range (-1 for infinite, or 1..%d)", s->max_depth, PC_MAX_SEGMENTS);
  if (s->light_paths > (uint64_t)1 << 32) return pc_errf(e, PC_EINVAL, "light-paths %llu too large", (unsigned long long)s->light_paths);
  if (s->strategy_layers < 0 || s->strategy_layers > 8) return pc_errf(e, PC_EINVAL, "strategy-layers %d out of range 0..8", s->strategy_layers);
  if (s->pcbpt_m < 1 || s->pcbpt_m > 100000) return pc_errf(e, PC_EINVAL, "pcbpt-m %d out of range 1..100000", s->pcbpt_m);
  if (s->pcbpt_k < 1 || s->pcbpt_k > 1000000) return pc_errf(e, PC_EINVAL, "pcbpt-k %d out of range 1..1000000", s->pcbpt_k);
  if (!(s->pcbpt_rate > 0.f && s->pcbpt_rate <= 1.f)) return pc_errf(e, PC_EINVAL, "pcbpt-rate %g out of range (0, 1]", (double)s->pcbpt_rate);
  if (!(s->pcbpt_unseen_rate > 0.f && s->pcbpt_unseen_rate <= 1.f))
    return pc_errf(e, PC_EINVAL, "pcbpt-unseen-rate %g out of range (0, 1]", (double)s->pcbpt_unseen_rate);
  if (s->pcbpt_candidates < 1 || s->pcbpt_candidates > PC_IREC_MAX_CANDIDATES)
    return pc_errf(e, PC_EINVAL, "pcbpt-candidates %d out of range 1..%d", s->pcbpt_candidates, PC_IREC_MAX_CANDIDATES);
  if (s->pcbpt_candidates > 1 && s->pcbpt_k > PC_IREC_MAX_CANDIDATES)
    return pc_errf(e, PC_EINVAL, "pcbpt-k %d with resampling (pcbpt-candidates %d) out of range 1..%d", s->pcbpt_k,
                   s->pcbpt_candidates, PC_IREC_MAX_CANDIDATES);
  if (!(s->pcbpt_dark_seen >= 0.f && s->pcbpt_dark_seen <= 1.f))
    return pc_errf(e, PC_EINVAL, "pcbpt-dark-seen %g out of range [0, 1]", (double)s->pcbpt_dark_seen);
  if (s->pcbpt_dark_candidates < 1 || s->pcbpt_dark_candidates > PC_IREC_MAX_CANDIDATES)
    return pc_errf(e, PC_EINVAL, "pcbpt-dark-candidates %d out of range 1..%d", s->pcbpt_dark_candidates, PC_IREC_MAX_CANDIDATES);
  /* 0 would leave light vertices no nearby record sees undrawable: biased, as uniform-mix 0 */
  if (!(s->pcbpt_dark_mix > 0.f && s->pcbpt_dark_mix <= 1.f))
    return pc_errf(e, PC_EINVAL, "pcbpt-dark-mix %g out of range (0, 1]", (double)s->pcbpt_dark_mix);
  if (s->candidate_visibility < PC_CANDVIS_RECORDS || s->candidate_visibility > PC_CANDVIS_TRACED)
    return pc_errf(e, PC_EINVAL, "pcbpt-candidate-visibility %d unknown", (int)s->candidate_visibility);
  if (!(s->cache_fraction > 0.f && s->cache_fraction <= 1.f)) return pc_errf(e, PC_EINVAL, "cache-fraction %g out of range (0, 1]", s->cache_fraction);
  if (s->knn < 1 || s->knn > 64) return pc_errf(e, PC_EINVAL, "knn %d out of range 1..64", s->knn);
  if (!(s->uniform_mix >= 0.f && s->uniform_mix <= 1.f)) return pc_errf(e, PC_EINVAL, "uniform-mix %g out of range [0, 1]", s->uniform_mix);
  if (s->mis_mode < PC_MIS_UPPER_BOUND || s->mis_mode > PC_MIS_COUNT) return pc_errf(e, PC_EINVAL, "mis mode %d unknown", (int)s->mis_mode);
  if (s->mis_mode == PC_MIS_COUNT && !(s->mis_count >= 1.f && s->mis_count <= 100000.f))
    return pc_errf(e, PC_EINVAL, "mis count %g out of range 1..100000", (double)s->mis_count);
  if (s->method == PC_METHOD_PCBPT && s->pmf_mode == PC_PMF_CACHED && s->uniform_mix == 0.f)
    return pc_errf(e, PC_EINVAL, "uniform-mix 0 with the cached PMF would be biased (a light vertex that no nearby "
                                 "record sees could never be sampled): use a value > 0 or --pmf exact");
  return PC_OK;
}

float pc_render_settings_inner_count(const pc_render_settings *s) {
  switch (s->mis_mode) {
  case PC_MIS_STANDARD: return (float)s->pcbpt_m;
  case PC_MIS_COUNT: return s->mis_count < (float)s->pcbpt_m ? s->mis_count : (float)s->pcbpt_m;
  default: return 1.f;
  }
}

int pc_render_settings_weights(const pc_render_settings *s, char *buf, size_t size) {
  if (s->unweighted) return snprintf(buf, size, "unweighted");
  const char *h = s->mis_heuristic == PC_MIS_POWER ? "power" : "balance";
  if (s->method == PC_METHOD_PT) return snprintf(buf, size, "pt %s", h);
  /* as pc_mis_counts_bdpt makes it, so that equal counts print equally */
  pc_mis_counts n = pc_mis_counts_bdpt(s, s->light_paths ? s->light_paths : (uint64_t)s->width * (uint64_t)s->height);
  if (s->method == PC_METHOD_LT) return snprintf(buf, size, "lt %s n_lt=%.9g", h, (double)n.n_lt);
  if (s->method == PC_METHOD_CBDPT || s->method == PC_METHOD_PCBPT) n.n_inner = pc_render_settings_inner_count(s);
  return snprintf(buf, size, "bidirectional %s n_lt=%.9g n_inner=%.9g", h, (double)n.n_lt, (double)n.n_inner);
}

bool pc_weights_unlike(const char *a, const char *b) { return a && b && strcmp(a, b) != 0; }

bool pc_weights_layer(const char *name) {
  static const char *const std[] = {"pt", "nee", "lt", "inner"};
  for (size_t i = 0; i < sizeof std / sizeof std[0]; i++)
    if (strcmp(name, std[i]) == 0) return true;
  int s, t, k = 0;
  return sscanf(name, "s%dt%d%n", &s, &t, &k) == 2 && name[k] == '\0';
}

void pc_render_stats_add(pc_render_stats *dst, const pc_render_stats *src) {
  dst->iterations += src->iterations;
  dst->eye_paths += src->eye_paths;
  dst->light_paths += src->light_paths;
  dst->rays += src->rays;
  dst->t_total += src->t_total;
  dst->t_cpu = dst->t_cpu < 0 || src->t_cpu < 0 ? -1.0 : dst->t_cpu + src->t_cpu;
  dst->t_paths += src->t_paths;
  dst->t_lt += src->t_lt;
  dst->t_pmf += src->t_pmf;
  dst->t_connect += src->t_connect;
  if (src->pmf_bytes > dst->pmf_bytes) dst->pmf_bytes = src->pmf_bytes;
}

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The scratch film and the per-thread splat films, one per pool item so their pages are
 * first written on every core at once: a fresh page costs its clearing, ~1 GB/s on the VMs
 * measured here (3840x2160: 0.2 GB a layer). fold_iteration writes beauty_sq and beauty_max
 * straight into the caller's film, so these have none, and the splats (t = 1, queued by
 * pc_lt_splat) and their fold are of the light layers alone. */
#define SCRATCH_NORMS (PC_FILM_NORM(PC_NORM_EYE) | PC_FILM_NORM(PC_NORM_LIGHT))
#define SPLAT_NORMS PC_FILM_NORM(PC_NORM_LIGHT)

size_t pc_renderer_film_bytes(const pc_render_settings *s, int threads) {
  if (threads == 0) threads = pc_cpu_count();
  size_t layer = (size_t)s->width * (size_t)s->height * 3 * sizeof(double);
  return layer * (size_t)(pc_film_stored_layer_count(s->strategy_layers, SCRATCH_NORMS) +
                          threads * pc_film_stored_layer_count(s->strategy_layers, SPLAT_NORMS));
}

void pc_renderer_zero_film(pc_renderer *r, pc_film *f) { pc_film_zero_on(r->pool, f); }

static int make_films(pc_renderer *r, int threads, pc_err *e) {
  const pc_render_settings *s = &r->set;
  int rc = pc_film_alloc_stored(&r->scratch, s->width, s->height, s->strategy_layers, SCRATCH_NORMS, e);
  for (int t = 0; t < threads && rc == PC_OK; t++)
    rc = pc_film_alloc_stored(&r->splat[t], s->width, s->height, s->strategy_layers, SPLAT_NORMS, e);
  if (rc != PC_OK) return rc;
  pc_renderer_zero_film(r, &r->scratch);
  for (int t = 0; t < threads; t++) pc_renderer_zero_film(r, &r->splat[t]);
  return PC_OK;
}

int pc_renderer_create(const pc_scene *scene, const pc_render_settings *settings, int threads, pc_renderer **out,
                       pc_err *e) {
  int rc = pc_render_settings_check(settings, e);
  if (rc != PC_OK) return rc;
  if (threads < 0 || threads > 1024) return pc_errf(e, PC_EINVAL, "threads %d out of range 0..1024", threads);
  if (threads == 0) threads = pc_cpu_count();
  pc_renderer *r = calloc(1, sizeof *r);
  if (!r) return pc_errf(e, PC_ENOMEM, "out of memory for the renderer");
  r->set = *settings;
  if (pc_scene_moves(scene)) {
    rc = pc_scene_view_create(scene, &r->view, e);
    if (rc != PC_OK) {
      free(r);
      return rc;
    }
    scene = r->view;
  }
  r->scene = scene;
  r->tiles_x = (settings->width + TILE - 1) / TILE;
  r->tiles_y = (settings->height + TILE - 1) / TILE;
  rc = pc_pool_create(threads, &r->pool, e);
  if (rc == PC_OK) {
    r->splat = calloc((size_t)threads, sizeof(pc_film));
    r->tctx = calloc((size_t)threads, sizeof(pc_tctx));
    r->splatq = calloc((size_t)threads, sizeof(pc_film_queue));
    r->verts = calloc((size_t)threads * 2 * (PC_MAX_SEGMENTS + 2), sizeof(pc_path_vertex));
    r->band_blocks = malloc((size_t)(settings->height + FOLD_ROWS - 1) / FOLD_ROWS *
                            (size_t)pc_trace_blocks(settings->width, settings->height) * sizeof(double));
    if (!r->splat || !r->tctx || !r->splatq || !r->verts || !r->band_blocks)
      rc = pc_errf(e, PC_ENOMEM, "out of memory for the renderer");
  }
  if (rc == PC_OK) rc = make_films(r, threads, e);
  if (rc != PC_OK) {
    pc_renderer_destroy(r);
    return rc;
  }
  int max_seg = settings->max_depth < 0 ? PC_MAX_SEGMENTS : settings->max_depth;
  uint64_t npix = (uint64_t)settings->width * (uint64_t)settings->height;
  r->n_light = settings->light_paths ? settings->light_paths : npix;
  r->light_first = settings->method == PC_METHOD_LT ? 0 : npix;
  for (int i = 0; i < threads; i++) {
    pc_path_vertex *v = r->verts + (size_t)i * 2 * (PC_MAX_SEGMENTS + 2);
    r->tctx[i].light_path = v;
    r->tctx[i].eye_path = v + PC_MAX_SEGMENTS + 2;
    r->tctx[i].n_light = r->n_light;
    r->tctx[i].counts = pc_mis_counts_bdpt(settings, r->n_light);
    r->tctx[i].weighted = !settings->unweighted;
    r->tctx[i].scene = scene;
    r->tctx[i].set = &r->set;
    r->tctx[i].max_segments = max_seg;
    r->tctx[i].film = &r->scratch;
    r->splatq[i].film = &r->splat[i];
    r->tctx[i].splat = &r->splatq[i];
    r->tctx[i].thread = i;
  }
  if (settings->method == PC_METHOD_CBDPT || settings->method == PC_METHOD_PCBPT) {
    rc = pc_pcbpt_create(settings, threads, &r->pcbpt, e);
    if (rc != PC_OK) {
      pc_renderer_destroy(r);
      return rc;
    }
    for (int i = 0; i < threads; i++) {
      r->tctx[i].pcbpt = r->pcbpt;
      r->tctx[i].counts.n_inner = pc_render_settings_inner_count(settings);
    }
  }
  *out = r;
  return PC_OK;
}

int pc_renderer_check(const pc_scene *scene, const pc_render_settings *settings, pc_err *e) {
  int rc = pc_render_settings_check(settings, e);
  if (rc != PC_OK) return rc;
  pc_render_settings tiny = *settings;
  tiny.width = tiny.height = 1;
  /* A still copy: a moving scene's view is made from its BVH, which a checked scene
   * (pc_scene_check) does not have, and refuses no setting. */
  pc_scene still = *scene;
  still.nmotions = 0;
  still.camera_anim.n = 0;
  pc_renderer *r = NULL;
  rc = pc_renderer_create(&still, &tiny, 1, &r, e);
  pc_renderer_destroy(r);
  return rc;
}

void pc_renderer_destroy(pc_renderer *r) {
  if (!r) return;
  int n = r->pool ? pc_pool_size(r->pool) : 0;
  pc_pool_destroy(r->pool);
  if (r->splat)
    for (int i = 0; i < n; i++) pc_film_free(&r->splat[i]);
  free(r->splat);
  free(r->tctx);
  free(r->splatq);
  free(r->verts);
  free(r->band_blocks);
  pc_pcbpt_destroy(r->pcbpt);
  pc_film_free(&r->scratch);
  pc_scene_view_destroy(r->view);
  free(r);
}

int pc_renderer_threads(const pc_renderer *r) { return pc_pool_size(r->pool); }

double pc_renderer_progress(const pc_renderer *r) {
  uint64_t total = atomic_load_explicit(&r->items_total, memory_order_relaxed);
  uint64_t done = atomic_load_explicit(&r->items_done, memory_order_relaxed);
  return total && done < total ? (double)done / (double)total : 0.0;
}

static bool cancelled(const pc_renderer *r) { return r->cancel && atomic_load(r->cancel); }

static void eye_tile(void *arg, int thread, int item) {
  pc_renderer *r = arg;
  if (cancelled(r)) return;
  pc_tctx *c = &r->tctx[thread];
  int tx = item % r->tiles_x, ty = item / r->tiles_x;
  int x1 = (tx + 1) * TILE < r->set.width ? (tx + 1) * TILE : r->set.width;
  int y1 = (ty + 1) * TILE < r->set.height ? (ty + 1) * TILE : r->set.height;
  void (*pixel)(pc_tctx *, int, int) = r->set.method == PC_METHOD_LT ? pc_lt_pixel
                                       : r->set.method == PC_METHOD_BDPT ? pc_bdpt_pixel
                                       : r->set.method == PC_METHOD_PT   ? pc_pt_pixel
                                                                         : pc_pcbpt_pixel;
  for (int y = ty * TILE; y < y1; y++)
    for (int x = tx * TILE; x < x1; x++) {
      pixel(c, x, y);
      pc_tctx_flush_pixel(c, x, y);
    }
  pc_film_queue_flush(c->splat);
  atomic_fetch_add_explicit(&r->items_done, 1, memory_order_relaxed);
}

static void light_chunk(void *arg, int thread, int item) {
  pc_renderer *r = arg;
  if (cancelled(r)) return;
  uint64_t a = r->light_first + (uint64_t)item * LIGHT_CHUNK;
  uint64_t b = a + LIGHT_CHUNK < r->n_light ? a + LIGHT_CHUNK : r->n_light;
  for (uint64_t i = a; i < b; i++) pc_lt_light_path(&r->tctx[thread], i);
  pc_film_queue_flush(r->tctx[thread].splat);
  atomic_fetch_add_explicit(&r->items_done, 1, memory_order_relaxed);
}

/* Folds a finished iteration into the caller's film, in parallel over bands of rows: each
 * layer's scratch sums plus, for light layers, every thread's splats, which are zeroed on the
 * way so the next iteration starts clean; and the square of the iteration's whole beauty into
 * beauty_sq and its maximum into beauty_max (its light splats are complete only here, after
 * every thread's light paths), and for one of the job's first iterations its luminance summed
 * per block of the trace's grid (each band its own sums, added in band order: the same sums
 * whatever the thread count). Done
 * serially this pass would cap the thread speed-up (it moves every layer of the image once per
 * iteration). */
typedef struct fold_job {
  pc_renderer *r;
  pc_film *film;
  bool light;
  int square;                  /* the film's beauty_sq layer, -1 if none */
  int max;                     /* the film's beauty_max layer, -1 if none */
  double beauty_scale[PC_LAYER_STD_COUNT]; /* one iteration's layer sums -> its beauty */
  atomic_uint_fast64_t dropped; /* squares that overflowed */
  double *band_blocks;         /* traced: [band][block] luminance sums; else NULL */
} fold_job;

/* Band item's luminance per block of the trace's grid, from the scratch layers the fold has
 * completed (the light splats are in) and not yet moved into the film. */
static void trace_rows(const fold_job *j, int item) {
  const pc_renderer *r = j->r;
  int w = r->set.width, h = r->set.height, nb = pc_trace_blocks(w, h);
  double *out = j->band_blocks + (size_t)item * (size_t)nb;
  const double *s[PC_LAYER_STD_COUNT];
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) s[l] = r->scratch.layers[l].sum;
  const double *c = j->beauty_scale;
  int y1 = (item + 1) * FOLD_ROWS < h ? (item + 1) * FOLD_ROWS : h, gx = w < PC_TRACE_GRID ? w : PC_TRACE_GRID;
  for (int y = item * FOLD_ROWS; y < y1; y++) {
    int row = pc_trace_block_of(w, h, 0, y);
    for (int bx = 0, x = 0; bx < gx; bx++) {
      int x1 = pc_trace_column_start(w, gx, bx + 1);
      double sum = 0.0;
      for (; x < x1; x++) {
        size_t k = 3 * ((size_t)y * (size_t)w + (size_t)x);
        double b[3];
        for (int ch = 0; ch < 3; ch++)
          b[ch] = s[0][k + ch] * c[0] + s[1][k + ch] * c[1] + s[2][k + ch] * c[2] + s[3][k + ch] * c[3];
        sum += pc_luminance709(b[0], b[1], b[2]);
      }
      out[row + bx] += sum;
    }
  }
}

static void fold_rows(void *arg, int thread, int item) {
  (void)thread;
  fold_job *j = arg;
  pc_renderer *r = j->r;
  size_t row = (size_t)r->set.width * 3;
  size_t lo = (size_t)item * FOLD_ROWS * row;
  size_t hi = lo + FOLD_ROWS * row;
  size_t n = row * (size_t)r->set.height;
  if (hi > n) hi = n;
  int nthreads = pc_pool_size(r->pool);
  if (j->light)
    for (int i = 0; i < r->scratch.nlayers; i++) {
      if (r->scratch.layers[i].norm != PC_NORM_LIGHT) continue;
      double *s = r->scratch.layers[i].sum;
      for (int t = 0; t < nthreads; t++) {
        double *p = r->splat[t].layers[i].sum;
        for (size_t k = lo; k < hi; k++) {
          s[k] += p[k];
          p[k] = 0.0;
        }
      }
    }
  if (j->band_blocks) trace_rows(j, item);
  if (j->square >= 0 || j->max >= 0) {
    double *q = j->square >= 0 ? j->film->layers[j->square].sum : NULL;
    double *mx = j->max >= 0 ? j->film->layers[j->max].sum : NULL;
    const double *s0 = r->scratch.layers[0].sum, *s1 = r->scratch.layers[1].sum, *s2 = r->scratch.layers[2].sum,
                 *s3 = r->scratch.layers[3].sum;
    const double *c = j->beauty_scale;
    uint64_t bad = 0;
    /* each square is rounded to single precision (relative 6e-8, far below any variance
     * worth estimating): a few iterations' sum then leaves the low byte planes of an upload
     * zero, which halves what beauty_sq adds to its compressed size (docs/variance.md); the
     * maximum likewise (a maximum of rounded values stays one) */
    for (size_t k = lo; k < hi; k++) {
      double b = s0[k] * c[0] + s1[k] * c[1] + s2[k] * c[2] + s3[k] * c[3];
      if (mx) {
        double bf = (double)(float)b;
        if (bf > mx[k] && isfinite(bf)) mx[k] = bf;
      }
      if (!q) continue;
      double b2 = (double)(float)(b * b);
      if (isfinite(b2)) q[k] += b2;
      else bad++;
    }
    if (bad) atomic_fetch_add(&j->dropped, bad);
  }
  for (int i = 0; i < r->scratch.nlayers; i++) {
    double *d = j->film->layers[i].sum, *s = r->scratch.layers[i].sum;
    if (!s) continue;
    for (size_t k = lo; k < hi; k++) {
      d[k] += s[k];
      s[k] = 0.0;
    }
  }
}

/* traced: iteration goes into the film's trace too (the caller reserved room). */
static void fold_iteration(pc_renderer *r, pc_film *film, bool light, uint64_t iteration, bool traced) {
  double *band_blocks = traced ? r->band_blocks : NULL;
  fold_job j = {.r = r, .film = film, .light = light, .square = pc_film_square_layer(film), .band_blocks = band_blocks};
  _Static_assert(PC_LAYER_PT == 0 && PC_LAYER_NEE == 1 && PC_LAYER_LT == 2 && PC_LAYER_INNER == 3 &&
                     PC_LAYER_STD_COUNT == 4, "fold_rows adds the four standard layers by index");
  /* the beauty is the standard layers each normalized by its count: 1 iteration for the eye
   * layers, N_L light paths (W*H/N_L per path) for lt when this iteration traced light */
  for (int i = 0; i < PC_LAYER_STD_COUNT; i++)
    j.beauty_scale[i] = r->scratch.layers[i].norm == PC_NORM_EYE ? 1.0
                        : light ? (double)r->set.width * r->set.height / (double)r->n_light
                                : 0.0;
  if (j.square >= 0 && !film->layers[j.square].sum) j.square = -1;
  j.max = pc_film_max_layer(film);
  if (j.max >= 0 && !film->layers[j.max].sum) j.max = -1;
  atomic_init(&j.dropped, 0);
  int nbands = (r->set.height + FOLD_ROWS - 1) / FOLD_ROWS, nb = pc_trace_blocks(r->set.width, r->set.height);
  if (band_blocks) memset(band_blocks, 0, (size_t)nbands * (size_t)nb * sizeof *band_blocks);
  pc_pool_run(r->pool, nbands, fold_rows, &j);
  if (band_blocks) {
    double sum[PC_TRACE_MAX_BLOCKS] = {0};
    uint32_t count[PC_TRACE_MAX_BLOCKS];
    float mean[PC_TRACE_MAX_BLOCKS];
    pc_trace_block_pixels(r->set.width, r->set.height, count);
    for (int b = 0; b < nbands; b++)
      for (int k = 0; k < nb; k++) sum[k] += band_blocks[(size_t)b * (size_t)nb + (size_t)k];
    for (int k = 0; k < nb; k++) mean[k] = (float)(sum[k] / count[k]);
    pc_trace_put(&film->trace, nb, (uint32_t)iteration, mean);
  }
  for (int i = 0; i < film->nlayers; i++) {
    if (r->scratch.layers[i].norm != PC_NORM_LIGHT) film->layers[i].count += 1;
    else if (light) film->layers[i].count += r->n_light;
  }
  film->dropped_nonfinite += r->scratch.dropped_nonfinite + atomic_load(&j.dropped);
  r->scratch.dropped_nonfinite = 0;
  for (int t = 0; t < pc_pool_size(r->pool); t++) {
    film->dropped_nonfinite += r->splat[t].dropped_nonfinite + r->tctx[t].dropped;
    r->splat[t].dropped_nonfinite = 0;
    r->tctx[t].dropped = 0;
  }
}

/* One iteration, `it`, into film (and stats). */
static int render_one(pc_renderer *r, uint64_t it, pc_film *film, pc_render_stats *stats, pc_err *e) {
  int nthreads = pc_pool_size(r->pool);
  uint64_t npix = (uint64_t)r->set.width * (uint64_t)r->set.height;
  bool traced = it < PC_TRACE_ITERATIONS && !pc_trace_has(&film->trace, (uint32_t)it);
  if (traced) {
    int rc = pc_trace_reserve(&film->trace, film->trace.n + 1, pc_trace_blocks(r->set.width, r->set.height), e);
    if (rc != PC_OK) return rc;
  }
  double t0 = now_seconds(), cpu0 = stats ? pc_pool_cpu_seconds(r->pool) : 0.0;
  if (r->view) {
    int rc = pc_scene_view_set_time(r->view, pc_scene_time(r->view, r->set.seed, it), e);
    if (rc != PC_OK) return rc;
  }
  for (int i = 0; i < nthreads; i++) {
    r->tctx[i].iteration = it;
    r->tctx[i].rays = 0;
    r->tctx[i].t_paths = r->tctx[i].t_lt = r->tctx[i].t_connect = 0.0;
  }
  bool light = r->set.method != PC_METHOD_PT;
  int n_eye = r->tiles_x * r->tiles_y;
  int n_chunks = light && r->n_light > r->light_first ? (int)((r->n_light - r->light_first + LIGHT_CHUNK - 1) / LIGHT_CHUNK) : 0;
  atomic_store_explicit(&r->items_done, 0, memory_order_relaxed);
  atomic_store_explicit(&r->items_total, (uint64_t)(n_eye + n_chunks), memory_order_relaxed);
  double t_pmf = 0.0;
  if (r->pcbpt) {
    int rc = pc_pcbpt_prepare(r->pcbpt, r->tctx, r->pool, e);
    if (rc != PC_OK) return rc;
    t_pmf = now_seconds() - t0;
  }
  pc_pool_run(r->pool, n_eye, eye_tile, r);
  if (n_chunks) pc_pool_run(r->pool, n_chunks, light_chunk, r);
  if (cancelled(r)) {
    pc_film_clear(&r->scratch);
    for (int i = 0; i < nthreads; i++) {
      pc_film_clear(&r->splat[i]);
      r->tctx[i].dropped = 0;
    }
    return pc_errf(e, PC_ECANCELED, "render cancelled");
  }
  double t1 = now_seconds();
  fold_iteration(r, film, light, it, traced);
  if (stats) {
    stats->iterations++;
    stats->eye_paths += npix;
    if (light) stats->light_paths += r->n_light;
    /* The phases interleave on every thread: split the iteration's render time by the
     * threads' summed time per phase. */
    double tp = 0, tl = 0, tc = 0;
    for (int i = 0; i < nthreads; i++) {
      stats->rays += r->tctx[i].rays;
      tp += r->tctx[i].t_paths;
      tl += r->tctx[i].t_lt;
      tc += r->tctx[i].t_connect;
    }
    double busy = tp + tl + tc, span = t1 - t0 - t_pmf;
    stats->t_pmf += t_pmf;
    uint64_t pmf_bytes = r->pcbpt && r->pcbpt->store ? pc_irec_bytes(r->pcbpt->store) : 0;
    if (pmf_bytes > stats->pmf_bytes) stats->pmf_bytes = pmf_bytes;
    if (r->set.method == PC_METHOD_PT || !(busy > 0)) {
      stats->t_paths += span;
    } else {
      stats->t_paths += span * tp / busy;
      stats->t_lt += span * tl / busy;
      stats->t_connect += span * tc / busy;
    }
    stats->t_total += now_seconds() - t0;
    double cpu1 = pc_pool_cpu_seconds(r->pool);
    stats->t_cpu = stats->t_cpu < 0 || cpu0 < 0 || cpu1 < cpu0 ? -1.0 : stats->t_cpu + (cpu1 - cpu0);
  }
  return PC_OK;
}

int pc_render_iterations(pc_renderer *r, uint64_t first, uint64_t count, pc_film *film, pc_render_stats *stats,
                         atomic_bool *cancel, void (*progress)(void *user, uint64_t done), void *user, pc_err *e) {
  if (film->w != r->set.width || film->h != r->set.height || film->nlayers != r->scratch.nlayers)
    return pc_errf(e, PC_EINVAL, "film is %dx%d with %d layers, the render needs %dx%d with %d", film->w, film->h,
                   film->nlayers, r->set.width, r->set.height, r->scratch.nlayers);
  r->cancel = cancel;
  for (int i = 0; i < film->nlayers; i++)
    if (strcmp(film->layers[i].name, r->scratch.layers[i].name) != 0)
      return pc_errf(e, PC_EINVAL, "film layer %d is '%s', the render writes '%s'", i, film->layers[i].name,
                     r->scratch.layers[i].name);
  int rc = PC_OK;
  for (uint64_t k = 0; k < count && rc == PC_OK; k++) {
    rc = render_one(r, first + k, film, stats, e);
    if (progress && rc == PC_OK) progress(user, k + 1);
  }
  return rc;
}
