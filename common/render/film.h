/* film.h: the framebuffer of a render: one unnormalized RGB sum per strategy layer, each with
 * its own sample count (DESIGN.md §4.2). Workers ship sums and counts; whoever writes an image
 * divides each layer by its own count. Eye-side layers (pt, nee, inner, s>=0,t>=2 debug layers)
 * count iterations, i.e. samples per pixel; light-side layers (lt, t=1 debug layers) count
 * light paths and are scaled by W*H/count. The last layer, "beauty_sq", holds the per-pixel sum
 * over iterations of the square of each iteration's whole beauty (its eye layers plus its light
 * splats scaled by W*H/N_L): with the sums it gives an unbiased estimate of the variance of the
 * mean, i.e. of the image's own error (docs/variance.md). After it, "beauty_max" holds per pixel
 * and channel the largest single iteration's beauty (the same b_i, rounded to single precision):
 * with the mean it tells how much of a pixel one iteration carried (fireflies, docs/variance.md
 * "Heavy tails"). Both count iterations like an eye layer and are shipped and checkpointed like
 * every other layer; beauty_max merges by max, which is exact and order-independent. Beside the
 * layers, the trace keeps block means of each of the job's first iterations (film_trace.h), shipped
 * and checkpointed with them, for the distribution of the per-iteration error. */
#ifndef PC_FILM_H
#define PC_FILM_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "film_trace.h"
#include "image.h"
#include "vecmath.h"

enum { PC_LAYER_PT = 0, PC_LAYER_NEE = 1, PC_LAYER_LT = 2, PC_LAYER_INNER = 3, PC_LAYER_STD_COUNT = 4 };
#define PC_FILM_MAX_LAYERS 64
#define PC_FILM_MAX_ST 10 /* s and t of per-strategy layers stay below this */

/* PC_NORM_SQUARE: the beauty_sq layer (counts iterations; not an image of its own).
 * PC_NORM_MAX: the beauty_max layer (counts iterations; its sums are maxima, merged by max). */
typedef enum { PC_NORM_EYE, PC_NORM_LIGHT, PC_NORM_SQUARE, PC_NORM_MAX } pc_norm;

/* relMSE = mean over pixels and channels of (a - ref)^2 / (ref^2 + PC_RELMSE_EPS): the one
 * definition `compare`, studies and the film's own estimate use. */
#define PC_RELMSE_EPS 0.01

typedef struct pc_film_layer {
  char name[16];   /* "pt", "nee", "lt", "inner", or "s2t3" for per-strategy debug layers */
  pc_norm norm;
  double *sum;     /* w*h*3; NULL for the layers a film only rendered into does not take
                      (pc_film_init_stored) */
  uint64_t count;  /* iterations (eye) or light paths (light) accumulated */
} pc_film_layer;

typedef struct pc_film {
  int w, h;
  int nlayers;
  pc_film_layer layers[PC_FILM_MAX_LAYERS];
  uint64_t dropped_nonfinite; /* samples that would have added NaN/Inf, counted and dropped */
  int8_t strategy_index[PC_FILM_MAX_ST][PC_FILM_MAX_ST]; /* [s][t] -> layer, -1 if not kept */
  pc_film_trace trace; /* the iterations below PC_TRACE_ITERATIONS it holds, one record each */
} pc_film;

/* Creates the four standard layers; with strategy_depth > 0 also one layer per (s,t) with
 * s+t-1 <= strategy_depth (path length in segments), named "s%dt%d"; then beauty_sq and
 * beauty_max. */
int pc_film_init(pc_film *f, int w, int h, int strategy_depth, pc_err *e);
/* The same layers, with storage only for those whose norm is in `stored` (PC_FILM_NORM bits):
 * for a film only rendered into and never read or merged, so its other layers' pages are
 * neither held nor written (the renderer's scratch takes no beauty_sq or beauty_max, its
 * per-thread light splats only the light layers: at 3840x2160 a layer is 0.2 GB). */
#define PC_FILM_NORM(n) (1u << (n))
#define PC_FILM_NORMS_ALL                                                                          \
  (PC_FILM_NORM(PC_NORM_EYE) | PC_FILM_NORM(PC_NORM_LIGHT) | PC_FILM_NORM(PC_NORM_SQUARE) |          \
   PC_FILM_NORM(PC_NORM_MAX))
int pc_film_init_stored(pc_film *f, int w, int h, int strategy_depth, unsigned stored, pc_err *e);
/* pc_film_init_stored's layers with their sums not yet zeroed: the caller zeroes every piece
 * (pc_film_zero_piece) before the film is used, spread over threads where the film is large.
 * Zeroing is a film's first write to its fresh pages, which the kernel clears and, on the VMs
 * the farm runs on, the hypervisor backs: about 3 ms per MB (the ~75 MB of a 512x512 worker's
 * films took 0.22 s on one thread while the other waited). */
int pc_film_alloc_stored(pc_film *f, int w, int h, int strategy_depth, unsigned stored, pc_err *e);
/* Pieces of a film's sums, each PC_FILM_PIECE_BYTES or less within one layer. */
#define PC_FILM_PIECE_BYTES ((size_t)2 << 20)
int pc_film_pieces(const pc_film *f);
void pc_film_zero_piece(pc_film *f, int piece);
/* Zeroes every piece of a film made by pc_film_alloc_stored on a pool's threads. */
struct pc_pool;
void pc_film_zero_on(struct pc_pool *pool, pc_film *f);
/* pc_film_init, zeroed on up to `threads` threads (0: one per core) of a pool made for it: a
 * coordinator's job film, made while the job's workers wait for their first range. */
int pc_film_init_threads(pc_film *f, int w, int h, int strategy_depth, int threads, pc_err *e);
/* The layers pc_film_init makes for a strategy_depth, and how many of them pc_film_init_stored
 * gives storage: the four standard (lt light, the others eye), k + 1 per path length
 * k <= strategy_depth (t = 1 light, the other k eye), beauty_sq and beauty_max. */
static inline int pc_film_layer_count(int strategy_depth) {
  return PC_LAYER_STD_COUNT + strategy_depth * (strategy_depth + 3) / 2 + 2;
}
/* Bytes of the sums f holds (its layers with storage). */
static inline size_t pc_film_held_bytes(const pc_film *f) {
  size_t n = 0;
  for (int i = 0; i < f->nlayers; i++)
    if (f->layers[i].sum) n += (size_t)f->w * (size_t)f->h * 3 * sizeof(double);
  return n;
}
/* Bytes of the sums of a w x h film with every layer (pc_film_init's). */
static inline size_t pc_film_bytes(int w, int h, int strategy_depth) {
  return (size_t)w * (size_t)h * 3 * sizeof(double) * (size_t)pc_film_layer_count(strategy_depth);
}
static inline int pc_film_stored_layer_count(int strategy_depth, unsigned stored) {
  int light = 1 + strategy_depth, eye = PC_LAYER_STD_COUNT - 1 + strategy_depth * (strategy_depth + 1) / 2;
  return (stored & PC_FILM_NORM(PC_NORM_EYE) ? eye : 0) + (stored & PC_FILM_NORM(PC_NORM_LIGHT) ? light : 0) +
         (stored & PC_FILM_NORM(PC_NORM_SQUARE) ? 1 : 0) + (stored & PC_FILM_NORM(PC_NORM_MAX) ? 1 : 0);
}
void pc_film_free(pc_film *f);
void pc_film_clear(pc_film *f); /* zero sums and counts, keep layers */
/* Index of the per-strategy layer (s,t), or -1 if not kept. */
static inline int pc_film_strategy_layer(const pc_film *f, int s, int t) {
  return s >= 0 && t >= 0 && s < PC_FILM_MAX_ST && t < PC_FILM_MAX_ST ? f->strategy_index[s][t] : -1;
}
/* Index of the beauty_sq layer, or -1. */
int pc_film_square_layer(const pc_film *f);
/* Index of the beauty_max layer, or -1. */
int pc_film_max_layer(const pc_film *f);
/* Index of the first of the per-iteration layers at the end (beauty_sq, beauty_max): a
 * checkpoint written before they existed holds the layers before it. */
int pc_film_per_iteration_first(const pc_film *f);
/* Adds src into dst (same shape, same layers): sums and counts; beauty_max by max; the traces
 * concatenated (refused, dst unchanged, when an iteration is traced in both). */
int pc_film_add(pc_film *dst, const pc_film *src, pc_err *e);
/* What layer l's sums are multiplied by to make its image: 1/iterations (eye layers),
 * W*H/light paths (light layers), 1 (beauty_max), 0 when it counted nothing. */
double pc_film_layer_scale(const pc_film *f, const pc_film_layer *l);
/* Normalized RGB of layer i into out (w*h*3). */
void pc_film_layer_image(const pc_film *f, int i, float *out);
/* Beauty = sum of the normalized standard layers. */
void pc_film_beauty(const pc_film *f, float *out);
/* The same (and pc_film_variance below) for rows [y0, y0 + ny) only, into out (ny*w*3): what a
 * writer needs a band at a time, so no whole image is held in floats beside the film. */
void pc_film_layer_rows(const pc_film *f, int i, int y0, int ny, float *out);
void pc_film_beauty_rows(const pc_film *f, int y0, int ny, float *out);
bool pc_film_variance_rows(const pc_film *f, int y0, int ny, float *out);
/* Per-pixel unbiased estimate of the variance of the beauty's mean into out (w*h*3), from the
 * spread of the iterations: (sum_sq/N - mean^2) / (N - 1). Returns false (out untouched) when
 * the film cannot tell: fewer than 2 iterations, or beauty_sq has not seen every iteration the
 * sums have (a job resumed from a checkpoint written before beauty_sq existed). */
bool pc_film_variance(const pc_film *f, float *out);
/* The beauty's relMSE as `compare` would measure it against the exact image, estimated from
 * the film alone: the mean over pixels and channels of variance / (max(mean^2 - variance, 0) +
 * PC_RELMSE_EPS), where mean^2 - variance is the unbiased estimate of the exact value's square
 * (mean^2 alone overestimates it by the variance and biases the estimate low). Returns false
 * like pc_film_variance (*out = NAN). */
bool pc_film_relmse_estimate(const pc_film *f, double *out);
/* Whether beauty_max has seen every iteration the sums have (false for a job resumed from a
 * checkpoint written before it existed, and with no iteration). */
bool pc_film_max_complete(const pc_film *f);
/* Writes the beauty and every layer (each normalized by its count) to a multi-layer EXR, with
 * the per-layer counts and `extra` attributes in the header; when the film can tell, also the
 * layer `variance` (pc_film_variance) and the attribute pcbpt.relmse_estimate, and beauty_max
 * (unscaled) only when pc_film_max_complete. */
int pc_film_write_exr(const pc_film *f, const char *path, const pc_exr_attr *extra, int nextra, pc_err *e);
/* One film of a mix and its weight (>= 0; 0: left out, counts included). */
#define PC_FILM_MIX_MAX_PARTS 4
typedef struct pc_film_part {
  const pc_film *film;
  double weight;
} pc_film_part;
/* Makes out (initialized with the parts' shape and layers) the mix of the parts: each image
 * layer the weighted sum of the parts' images, the counts the sums of the counts of the parts
 * with a weight, beauty_sq such that pc_film_variance gives the sum of weight^2 x each part's
 * variance (unknown when one part's is), beauty_max the largest of theirs, the trace that of the
 * part with the largest weight (the parts are other estimators, their iterations other
 * distributions). The weights are the caller's to make sum to 1. */
int pc_film_mix(pc_film *out, const pc_film_part *parts, int n, pc_err *e);
/* What pc_film_relmse_estimate would give for the mix, without making it. */
bool pc_film_mix_relmse_estimate(const pc_film_part *parts, int n, double *out);
/* The distribution of the per-iteration error of the film's traced iterations against its own
 * image (film_trace.h); false (out zeroed) with fewer than 2 traced iterations or out of memory. */
bool pc_film_iteration_errors(const pc_film *f, pc_iteration_errors *out);
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
