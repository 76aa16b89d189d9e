/* render.h: what a render is asked to do (pc_render_settings) and the one entry point that
 * renders a range of iterations of a job into a film: the same call on a standalone render,
 * on a farm worker, and in the tests. Iteration i is seeded from (seed, i) only, so any
 * machine rendering it produces the same sums. */
#ifndef PC_RENDER_H
#define PC_RENDER_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "film.h"
#include "scene.h"

typedef enum { PC_MIS_BALANCE, PC_MIS_POWER } pc_mis_heuristic;
/* PCBPT correlated MIS: the sample count the inner strategies carry in the weights: 1 (the
 * upper bound of Popov et al., eqs. 16-17), M (standard, as if the stored paths were
 * independent) or a count in between (pc_render_settings.mis_count; the default, 2). */
typedef enum { PC_MIS_UPPER_BOUND, PC_MIS_STANDARD, PC_MIS_COUNT } pc_mis_mode;
typedef enum { PC_PMF_CACHED, PC_PMF_EXACT } pc_pmf_mode;
/* What the resampling target knows of a candidate connection's visibility: the records'
 * blurred estimate only, its own shadow ray unless every nearby record sees the light vertex,
 * or its own shadow ray always (the selected candidate then reuses a traced ray). */
typedef enum { PC_CANDVIS_RECORDS, PC_CANDVIS_UNCERTAIN, PC_CANDVIS_TRACED } pc_candidate_visibility;

typedef struct pc_render_settings {
  pc_method method;
  int width, height;       /* film size (overrides the scene's hdrfilm when set) */
  int max_depth;           /* Mitsuba convention: -1 infinite, 1 = emitters seen directly */
  uint64_t seed;
  uint64_t light_paths;    /* N_L: light-tracing paths per iteration (0 = W*H) */
  pc_mis_heuristic mis_heuristic;
  int strategy_layers;     /* >0: keep per-(s,t) layers up to this path length */
  /* PCBPT */
  int pcbpt_m;             /* stored light paths per iteration (default 100) */
  int pcbpt_k;             /* connections per eye vertex */
  float pcbpt_rate;        /* share of eye vertices that connect to the stored paths, (0, 1] */
  float pcbpt_unseen_rate; /* PCBPT: the same in an iteration whose records see no light vertex */
  int pcbpt_candidates;    /* candidates drawn from p_conn and resampled per eye vertex (1: none) */
  float pcbpt_dark_seen;   /* eye vertices whose records see less than this share of the light
                              vertices are dark (0: none is, 1: all are) */
  int pcbpt_dark_candidates; /* candidates per connection at a dark eye vertex (K times this, at
                                most PC_IREC_MAX_CANDIDATES, at least pcbpt_candidates) */
  float pcbpt_dark_mix;    /* uniform_mix at a dark eye vertex */
  pc_candidate_visibility candidate_visibility;
  float cache_fraction;    /* importance-record eye paths per pixel (0.004; pc_cache_path_count) */
  int knn;                 /* records interpolated per lookup (6) */
  float uniform_mix;       /* weight of the uniform PMF blended into p_conn */
  pc_mis_mode mis_mode;
  float mis_count;         /* PC_MIS_COUNT: the inner strategies' count (>= 1; M where larger) */
  pc_pmf_mode pmf_mode;
  pc_scene_defines defines; /* -D name=value: part of what the scene is, so workers get them */
  /* Debug (tests): every strategy gets weight 1, so each per-strategy layer is on its own an
   * estimate of its whole path length; the beauty is then not an estimate of anything. */
  bool unweighted;
} pc_render_settings;

/* Defaults for every field (method pt, seed 1, 256x256, max_depth -1 ...). */
void pc_render_settings_default(pc_render_settings *s);
/* Validates ranges; message names the offending setting. */
int pc_render_settings_check(const pc_render_settings *s, pc_err *e);
/* The sample count of the inner strategies in the MIS weights (pc_mis_counts.n_inner). */
float pc_render_settings_inner_count(const pc_render_settings *s);

/* How an image's strategy layers (pt, nee, lt, inner and the per-(s,t) ones) are weighted: the
 * strategies the method has, the heuristic and the counts it weighs them with, e.g.
 * "bidirectional balance n_lt=1 n_inner=2". Two images estimate the same layers only where
 * these agree: PCBPT's inner layer at count 2 carries more of the image than BDPT's, and PT's
 * nee layer more than BDPT's. Written into every image's header as PC_WEIGHTS_ATTR; an image
 * that mixes films of other weightings (--method auto's pilot) says PC_WEIGHTS_MIXED. Returns
 * the length snprintf would write. */
#define PC_WEIGHTS_ATTR "pcbpt.weights"
#define PC_WEIGHTS_MIXED "mixed"
int pc_render_settings_weights(const pc_render_settings *s, char *buf, size_t size);
/* Whether two images' strategy layers estimate different things: both weightings known
 * (non-NULL, from their headers) and different. An image without one (another renderer's, or
 * pcbpt's before the attribute) is taken as comparable. */
bool pc_weights_unlike(const char *a, const char *b);
/* Whether an EXR layer is a strategy layer, weighted as pc_render_settings_weights says:
 * "pt", "nee", "lt", "inner", "s<S>t<T>". */
bool pc_weights_layer(const char *name);
/* What else an image's header says it is of, beside its size and "pcbpt.max_depth": the hex
 * hash of the scene's files as a job ships them (an edited scene, mesh or texture, or another
 * scene, hashes otherwise; an unchanged copy of the folder alike), and its -D values
 * (pc_scene_defines_text, "" for none). */
#define PC_SCENE_BUNDLE_ATTR "pcbpt.scene_bundle"
#define PC_SCENE_DEFINES_ATTR "pcbpt.defines"

/* Time (seconds) and work spent, summed over iterations; printed and stored in headers. */
typedef struct pc_render_stats {
  uint64_t iterations;
  uint64_t eye_paths, light_paths;
  uint64_t rays;           /* closest-hit and shadow rays */
  double t_total;          /* wall seconds inside pc_render_iterations */
  double t_cpu;            /* CPU seconds of the render threads meanwhile (< 0: unknown): what a
                              method costs, without the time other load took from it */
  double t_paths;          /* eye/light sub-path generation */
  double t_lt;             /* light tracing splats */
  double t_pmf;            /* PCBPT importance records */
  double t_connect;        /* connections (inner strategies) incl. shadow rays */
  uint64_t pmf_bytes;      /* PCBPT: most bytes the importance records (PMF/CMF, records, kd-tree)
                              held in any iteration; merge by max */
} pc_render_stats;

/* Adds src's work into dst (times and counts add; pmf_bytes is a maximum). */
void pc_render_stats_add(pc_render_stats *dst, const pc_render_stats *src);

typedef struct pc_renderer pc_renderer; /* thread pool + per-thread scratch for one scene */

/* Creates a renderer for a built scene; threads = 0 uses every core. The film must have been
 * initialised with the settings' width and height. */
int pc_renderer_create(const pc_scene *scene, const pc_render_settings *settings, int threads,
                       pc_renderer **out, pc_err *e);
/* What pc_renderer_create would refuse for these settings and this scene, without allocating
 * what grows with the image (its films): the settings are checked, then a renderer of one
 * thread is made at 1x1. Every refusal but running out of memory is independent of the size.
 * The scene may be built or only checked (pc_scene_check). */
int pc_renderer_check(const pc_scene *scene, const pc_render_settings *settings, pc_err *e);
/* Bytes of the films a renderer of these settings and threads (0: one per core) holds: its
 * scratch and its per-thread light splats. */
size_t pc_renderer_film_bytes(const pc_render_settings *settings, int threads);
/* Zeroes a film made by pc_film_alloc_stored on the renderer's threads (a worker's pending film
 * beside the renderer's own, which pc_renderer_create zeroes so). */
void pc_renderer_zero_film(pc_renderer *r, pc_film *f);
void pc_renderer_destroy(pc_renderer *r);
int pc_renderer_threads(const pc_renderer *r);
/* How much of the iteration being rendered is done, in [0, 1) (0 between iterations); safe
 * to call from another thread while pc_render_iterations runs. An iteration of a large film
 * can take minutes: this is what a farm worker shows meanwhile to prove it renders. */
double pc_renderer_progress(const pc_renderer *r);

/* Renders iterations [first, first+count) adding into film (sums and counts) and stats.
 * `cancel`, if non-NULL, is polled between work items; when it becomes true the call returns
 * PC_ECANCELED and the film holds only whole iterations (none of the partial one).
 * `progress(user, done)` is called after each finished iteration (may be NULL). Iterations
 * below PC_TRACE_ITERATIONS are also traced into film->trace, each once: one the film's trace
 * holds already (the same iteration rendered into it again) is not traced twice. */
int pc_render_iterations(pc_renderer *r, uint64_t first, uint64_t count, pc_film *film,
                         pc_render_stats *stats, atomic_bool *cancel,
                         void (*progress)(void *user, uint64_t done), void *user, pc_err *e);

#endif
