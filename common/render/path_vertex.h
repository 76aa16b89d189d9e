/* path_vertex.h: the one path-vertex type of the bidirectional integrators (LT, BDPT, and
 * CBDPT/PCBPT built on them) and the recursive MIS bookkeeping each vertex carries.
 *
 * A complete path x_0 .. x_k (x_0 on a light, x_k the camera, k segments) is sampled by strategy
 * (s,t), s + t = k + 1: s light vertices x_0..x_{s-1} and t eye vertices x_s..x_k. Its weight is
 *   w_{s,t} = (n_{s,t} p_{s,t})^b / sum_j (n_j p_j)^b      (b = 1 balance, 2 power heuristic)
 * with n the per-iteration sample count of the strategy (pc_mis_count). As in SmallVCM
 * (Georgiev's "Implementing VCM", and eq. 8.7 of the GPU thesis), the sum over strategies
 * that move the connection into one sub-path is accumulated while that sub-path is traced, so a
 * connection costs O(1). Every vertex v at depth d of its sub-path (d = number of vertices of
 * the sub-path up to and including v) carries, with P(v) its area pdf from its own side:
 *   mis_near = 1 / P(v)^b, without count: the strategy that moves only v to the other side;
 *   mis_far  = the sum of all strategies moving v and more vertices to the other side, divided by
 *              P(v)^b, missing only the factor pdf_rev(v)^b (v's reverse direction pdf, which
 *              depends on the connection partner and is supplied at connection time).
 * Russian roulette q(v) is local and enters the pdf in both directions. Dirac factors of delta
 * lobes cancel between strategies (Veach); a strategy connecting at a delta vertex has pdf 0,
 * so sampling through a delta lobe zeroes mis_near and drops the previous mis_near from mis_far.
 * The camera (pinhole) and point lights cannot be hit: they pass cos_out = 0, which zeroes the
 * terms of the strategies that would need to hit them.
 *
 * The environment is a vertex at infinity (PC_VTX_ENV; pbrt-v3's treatment of infinite lights
 * in BDPT): its pdfs from both sides are per unit solid angle of its direction, never converted
 * to area (d2 = 1 and no cosine at it); the surface vertex a light path from it reaches first has
 * the area pdf of the disk the path started on, times that vertex's cosine. So an environment
 * vertex extends and connects with d2 = 1, cos 1 at its end, and pdf_fwd = 1 / (pi R^2) for the
 * disk of radius R (scene.h env_radius). */
#ifndef PC_PATH_VERTEX_H
#define PC_PATH_VERTEX_H

#include <stdbool.h>

#include "bsdf.h"
#include "vecmath.h"

typedef enum { PC_VTX_CAMERA, PC_VTX_LIGHT, PC_VTX_SURFACE, PC_VTX_ENV } pc_vertex_kind;

/* Per-iteration sample counts of the strategy classes, and the heuristic. */
typedef struct pc_mis_counts {
  float n_lt;    /* light tracing (t=1): N_L / (W*H) */
  float n_inner; /* each inner strategy (s>=2, t>=2): 1 for BDPT; PCBPT sets its own */
  bool power;    /* power heuristic (beta = 2), else balance */
} pc_mis_counts;

typedef struct pc_path_vertex {
  pc_vertex_kind kind;
  vec3 p;
  vec3 ng;         /* geometric normal (zero for the camera and point lights) */
  float eps;       /* where ng is not zero: rays leave and reach p that far off (PC_OFFSET_RELATIVE) */
  pc_shading sh;   /* surfaces */
  vec3 wo;         /* unit direction toward the previous vertex of the sub-path (surfaces);
                      PC_VTX_ENV: the direction its light travels into the scene */
  pc_bsdf_out out; /* surfaces: wo as the BSDF queries of every connection here need it */
  vec3 beta;       /* sub-path contribution / pdf up to this vertex, excluding its own scattering;
                      light vertex: Le (or intensity) / (choice pdf * area pdf) */
  int material;    /* surfaces */
  int light;       /* PC_VTX_LIGHT, PC_VTX_ENV: index of the light */
  int depth;       /* s or t of a connection ending here */
  float q;         /* Russian-roulette continuation probability (surfaces) */
  bool delta;      /* every lobe is a Dirac delta: never a connection endpoint */
  float mis_near, mis_far;
} pc_path_vertex;

static inline float pc_mis(const pc_mis_counts *n, float x) { return n->power ? x * x : x; }

/* Sample count of strategy (s,t) per pixel and iteration. */
static inline float pc_mis_count(const pc_mis_counts *n, int s, int t) {
  if (t == 1) return n->n_lt;
  if (s <= 1) return 1.f;
  return n->n_inner;
}

/* Count of the strategy that moves vertex v (depth d) to the other side, when that strategy is
 * inside mis_far of a later vertex: on the light side it has s = d-1 light vertices (and t >= 3);
 * on the eye side t = d-1 eye vertices (and s >= 2). */
static inline float pc_mis_count_moved(const pc_mis_counts *n, const pc_path_vertex *v, bool light_side) {
  return light_side ? pc_mis_count(n, v->depth - 1, 3) : pc_mis_count(n, 2, v->depth - 1);
}

/* MIS quantities of `next`, reached from `prev` by a direction sampled at prev with solid-angle
 * pdf pdf_fwd and reverse pdf pdf_rev (both including q(prev); lobe probabilities when
 * `delta`). cos_out: |cos| at prev of the sampled direction (geometric normal; 0 for the camera
 * and point lights); cos_in: the same at next; d2: squared distance. cos_in and pdf_fwd must be
 * > 0 (callers end the sub-path otherwise). */
static inline void pc_mis_extend(const pc_mis_counts *n, const pc_path_vertex *prev, bool light_side, pc_path_vertex *next,
                                 float pdf_fwd, float pdf_rev, bool delta, float cos_out, float cos_in, float d2) {
  if (delta) {
    next->mis_near = 0.f;
    next->mis_far = pc_mis(n, cos_out * pdf_rev / (pdf_fwd * cos_in)) * prev->mis_far;
  } else {
    float moved = pc_mis(n, pc_mis_count_moved(n, prev, light_side)) * prev->mis_near;
    next->mis_near = pc_mis(n, d2 / (pdf_fwd * cos_in));
    next->mis_far = pc_mis(n, cos_out / (pdf_fwd * cos_in)) * (moved + prev->mis_far * pc_mis(n, pdf_rev));
  }
}

/* Sum over the strategies that move the connection into the sub-path ending at v, relative to
 * the pdf of the strategy used (without its count): p_conn is the area pdf with which the other
 * endpoint would sample v (0 if v cannot be hit), pdf_rev v's reverse direction pdf toward its
 * predecessor given the connection direction, n_moved the count of the strategy moving v. */
static inline float pc_mis_side(const pc_mis_counts *n, const pc_path_vertex *v, float p_conn, float pdf_rev, float n_moved) {
  if (!(p_conn > 0.f)) return 0.f;
  return pc_mis(n, p_conn) * (pc_mis(n, n_moved) * v->mis_near + v->mis_far * pc_mis(n, pdf_rev));
}

#endif
