/* integrator.h: what every integrator's per-sample routine sees: the scene, the settings, the
 * iteration being rendered, and the films it adds to. Eye-side routines own their pixel for
 * the iteration and add to it through pc_tctx_add (the caller moves the pixel's sums into
 * `film` with pc_tctx_flush_pixel); light-side splats go to the thread's own `splat` film,
 * merged after the iteration. */
#ifndef PC_INTEGRATOR_H
#define PC_INTEGRATOR_H

#include <stdint.h>

#include "film.h"
#include "path_vertex.h"
#include "render.h"
#include "rng.h"
#include "scene.h"

/* Hard cap on path length (segments) for maxDepth -1: Russian roulette ends paths long before;
 * this only guards against a ray trapped between perfect mirrors. */
#define PC_MAX_SEGMENTS 1024

typedef struct pc_tctx {
  const pc_scene *scene;
  const pc_render_settings *set;
  int max_segments;     /* maxDepth resolved: PC_MAX_SEGMENTS when infinite */
  uint64_t iteration;
  uint64_t n_light;     /* N_L: light paths per iteration */
  pc_mis_counts counts; /* MIS sample counts of the method */
  bool weighted;        /* false: every strategy weight 1 (debug, per-strategy tests) */
  pc_film *film;        /* the iteration's eye-side film (shared; pixels are disjoint) */
  double pixel_sum[PC_LAYER_STD_COUNT][3]; /* the current pixel's pt, nee and inner sums so far */
  uint64_t dropped;     /* non-finite eye-side samples this iteration: `film` is shared, this is not */
  pc_film_queue *splat; /* queue into this thread's light-splat film (flushed after each work item) */
  uint64_t rays;
  pc_path_vertex *light_path, *eye_path; /* sub-path buffers, PC_MAX_SEGMENTS + 2 vertices each */
  double t_paths, t_lt, t_connect;       /* thread-seconds per phase, for pc_render_stats */
  int thread;                            /* this context's pool thread */
  struct pc_pcbpt *pcbpt;                /* CBDPT/PCBPT: the iteration's stored light vertices and records */
} pc_tctx;

/* Adds v to the current pixel (x,y) in eye layer `layer` (pt, nee or inner) and, with
 * --strategy-layers, in layer s%dt%d of the film. A BDPT sample makes a dozen such adds; the
 * standard layers' ones are summed here and reach the film once per pixel. The film's sums of
 * an iteration start at zero and take the same additions in the same order, so they are
 * bit-identical to adding into the film each time. */
static inline void pc_tctx_add(pc_tctx *c, int layer, int s, int t, int x, int y, vec3 v) {
  int layers = c->set->strategy_layers;
  int l = layers > 0 && s + t - 1 <= layers ? pc_film_strategy_layer(c->film, s, t) : -1;
  if (!v3_is_finite(v)) {
    c->dropped += l >= 0 ? 2 : 1; /* one per layer it would have gone to */
    return;
  }
  double *a = c->pixel_sum[layer];
  a[0] += v.x;
  a[1] += v.y;
  a[2] += v.z;
  if (l >= 0) pc_film_add_sample(c->film, l, x, y, v);
}

/* Moves the pixel's sums into the film and zeroes them, after each pixel routine. */
static inline void pc_tctx_flush_pixel(pc_tctx *c, int x, int y) {
  static const int eye_layers[] = {PC_LAYER_PT, PC_LAYER_NEE, PC_LAYER_INNER};
  size_t k = 3 * ((size_t)y * c->film->w + (size_t)x);
  for (int i = 0; i < 3; i++) {
    double *a = c->pixel_sum[eye_layers[i]], *p = c->film->layers[eye_layers[i]].sum + k;
    p[0] += a[0];
    p[1] += a[1];
    p[2] += a[2];
    a[0] = a[1] = a[2] = 0.0;
  }
}

/* MIS weight of a strategy with pdf a against the others' summed (already heuristic-mapped)
 * terms; the heuristic maps a pdf (times its sample count) to its weight term. */
static inline float pc_mis_term(const pc_render_settings *s, float p) {
  return s->mis_heuristic == PC_MIS_POWER ? p * p : p;
}

/* The shading point of a hit reached from direction wo, shared by integrators (its material's
 * bump map applied). */
static inline void pc_shading_from_hit(pc_shading *sh, const pc_scene *s, const pc_hit *h, vec3 wo) {
  const pc_material *m = &s->materials[s->shapes[h->shape].material];
  const frame *f = pc_hit_frame(s, h);
  if (f) pc_shading_make_framed(sh, m, s->textures, h->ng, f, h->dpdu, h->dpdv, h->uv, wo);
  else pc_shading_make(sh, m, s->textures, h->ng, h->ns, h->dpdu, h->dpdv, h->uv, wo);
}

/* Unidirectional path tracer with next-event estimation (strategies s=0 and s=1). */
void pc_pt_pixel(pc_tctx *c, int x, int y);

/* Bidirectional path tracing for pixel (x,y): its eye sub-path, the s=0, s=1 and inner
 * strategies with light path (pixel index mod N_L), and that light path's light tracing (t=1)
 * when the pixel index is below N_L. */
void pc_bdpt_pixel(pc_tctx *c, int x, int y);
/* Light tracing of light path `index` (t=1 splats into c->splat); used for the light paths
 * that no pixel is paired with, and by the lt method for all. */
void pc_lt_light_path(pc_tctx *c, uint64_t index);
/* Eye pass of the lt method: the camera ray of pixel (x,y) and s=0 for emitters seen directly. */
void pc_lt_pixel(pc_tctx *c, int x, int y);
/* CBDPT and PCBPT for pixel (x,y): BDPT's s=0, s=1 and t=1, and the inner strategies through
 * the iteration's stored light vertices (c->pcbpt, prepared before the eye pass). */
void pc_pcbpt_pixel(pc_tctx *c, int x, int y);

#endif
