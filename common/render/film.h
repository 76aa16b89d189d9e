/* film.h: the framebuffer of a render: one unnormalized RGB sum per strategy layer, each with
 * its own sample count (DESIGN.md §4.2). Workers ship sums and counts; whoever writes an image
 * divides each layer by its own count. Eye-side layers (pt, nee, inner, s>=0,t>=2 debug layers)
 * count iterations, i.e. samples per pixel; light-side layers (lt, t=1 debug layers) count
 * light paths and are scaled by W*H/count. */
#ifndef PC_FILM_H
#define PC_FILM_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "image.h"
#include "vecmath.h"

enum { PC_LAYER_PT = 0, PC_LAYER_NEE = 1, PC_LAYER_LT = 2, PC_LAYER_INNER = 3, PC_LAYER_STD_COUNT = 4 };
#define PC_FILM_MAX_LAYERS 64
#define PC_FILM_MAX_ST 10 /* s and t of per-strategy layers stay below this */

typedef enum { PC_NORM_EYE, PC_NORM_LIGHT } pc_norm;

typedef struct pc_film_layer {
  char name[16];   /* "pt", "nee", "lt", "inner", or "s2t3" for per-strategy debug layers */
  pc_norm norm;
  double *sum;     /* w*h*3 */
  uint64_t count;  /* iterations (eye) or light paths (light) accumulated */
} pc_film_layer;

typedef struct pc_film {
  int w, h;
  int nlayers;
  pc_film_layer layers[PC_FILM_MAX_LAYERS];
  uint64_t dropped_nonfinite; /* samples that would have added NaN/Inf, counted and dropped */
  int8_t strategy_index[PC_FILM_MAX_ST][PC_FILM_MAX_ST]; /* [s][t] -> layer, -1 if not kept */
} pc_film;

/* Creates the four standard layers; with strategy_depth > 0 also one layer per (s,t) with
 * s+t-1 <= strategy_depth (path length in segments), named "s%dt%d". */
int pc_film_init(pc_film *f, int w, int h, int strategy_depth, pc_err *e);
void pc_film_free(pc_film *f);
void pc_film_clear(pc_film *f); /* zero sums and counts, keep layers */
/* Index of the per-strategy layer (s,t), or -1 if not kept. */
static inline int pc_film_strategy_layer(const pc_film *f, int s, int t) {
  return s >= 0 && t >= 0 && s < PC_FILM_MAX_ST && t < PC_FILM_MAX_ST ? f->strategy_index[s][t] : -1;
}
/* Adds src into dst (same shape, same layers): sums and counts. */
int pc_film_add(pc_film *dst, const pc_film *src, pc_err *e);
/* Normalized RGB of layer i into out (w*h*3). */
void pc_film_layer_image(const pc_film *f, int i, float *out);
/* Beauty = sum of the normalized standard layers. */
void pc_film_beauty(const pc_film *f, float *out);
/* Writes the beauty and every layer (each normalized by its count) to a multi-layer EXR, with
 * the per-layer counts and `extra` attributes in the header. */
int pc_film_write_exr(const pc_film *f, const char *path, const pc_exr_attr *extra, int nextra, pc_err *e);
/* True if every sum is finite. */
bool pc_film_is_finite(const pc_film *f);

/* Adds c to pixel (x,y) of layer i after checking it is finite (drops and counts otherwise). */
static inline void pc_film_add_sample(pc_film *f, int i, int x, int y, vec3 c) {
  if (!v3_is_finite(c)) { f->dropped_nonfinite++; return; }
  double *p = f->layers[i].sum + 3 * ((size_t)y * f->w + x);
  p[0] += c.x; p[1] += c.y; p[2] += c.z;
}

/* Adds to a film at scattered pixels (light-tracing splats) through a short queue: each add into
 * a large film misses the cache, and stalled among the path tracing the misses are paid one by
 * one; the queue replays them in a tight loop that prefetches a few entries ahead, so the misses
 * overlap. The adds reach the film in the order they were made: the sums are bit-identical to
 * adding directly. Flush before reading the film. */
#define PC_FILM_QUEUE 2048
typedef struct pc_film_queued {
  uint32_t layer;
  uint32_t pixel; /* y*w + x */
  float v[3];
} pc_film_queued;

typedef struct pc_film_queue {
  pc_film *film;
  int n;
  pc_film_queued q[PC_FILM_QUEUE];
} pc_film_queue;

void pc_film_queue_flush(pc_film_queue *q);

static inline void pc_film_queue_add(pc_film_queue *q, int i, int x, int y, vec3 c) {
  if (!v3_is_finite(c)) { q->film->dropped_nonfinite++; return; }
  pc_film_queued *e = &q->q[q->n++];
  e->layer = (uint32_t)i;
  e->pixel = (uint32_t)y * (uint32_t)q->film->w + (uint32_t)x;
  e->v[0] = c.x; e->v[1] = c.y; e->v[2] = c.z;
  if (q->n == PC_FILM_QUEUE) pc_film_queue_flush(q);
}

#endif
