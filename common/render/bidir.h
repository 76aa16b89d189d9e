/* bidir.h: the building blocks every bidirectional method shares: tracing light and eye
 * sub-paths into pc_path_vertex arrays (with their MIS quantities), the one connection routine
 * (any light vertex with any eye vertex, the camera included), and the weight of an eye
 * sub-path that hits an emitter (s=0). LT, BDPT, and later CBDPT/PCBPT differ only in which
 * vertices they connect and with what counts. */
#ifndef PC_BIDIR_H
#define PC_BIDIR_H

#include "integrator.h"
#include "path_vertex.h"

/* Counts of this render: n_lt = N_L / (W*H), n_inner = 1, heuristic from the settings. */
pc_mis_counts pc_mis_counts_bdpt(const pc_render_settings *set, uint64_t n_light);

/* Traces light sub-path `index` of the iteration (stream PC_STREAM_LIGHT/index) into v: v[0] is
 * the point on the light (depth 1), at most c->max_segments vertices. Returns the count. */
int pc_light_subpath(pc_tctx *c, const pc_mis_counts *n, uint64_t index, pc_path_vertex *v);

/* Called for every eye vertex that lies on an emitter: t = v->depth, s = 0; `le` the emitted
 * radiance toward the previous vertex (already checked non-zero). */
typedef void (*pc_emitter_hit_fn)(pc_tctx *c, void *user, const pc_path_vertex *v, int light, vec3 le);

/* Traces the eye sub-path of pixel (x,y) with the pixel's stream `rng` (PC_STREAM_EYE): v[0] is
 * the camera (depth 1), at most max_vertices (<= c->max_segments + 1) vertices. Emitter hits are
 * reported to `hit` (may be NULL). Returns the count. */
int pc_eye_subpath(pc_tctx *c, const pc_mis_counts *n, pc_rng *rng, int x, int y, int max_vertices, pc_path_vertex *v,
                   pc_emitter_hit_fn hit, void *user);

/* MIS weight of the s=0 strategy for eye vertex v on light `light`. */
float pc_mis_weight_hit(const pc_scene *s, const pc_mis_counts *n, const pc_path_vertex *v, int light);

/* A light vertex for next-event estimation (s=1) and for the start of light sub-paths: a point
 * on a light chosen by power, uniform by area, from four uniform numbers; for the environment a
 * PC_VTX_ENV vertex, its direction sampled by pc_env_sample. */
void pc_light_vertex_sample(const pc_scene *s, const pc_mis_counts *n, float u0, float u1, float u2, float u3,
                            pc_path_vertex *out);

/* Area density of the first surface vertex of an environment light path, per unit of its
 * cosine: the uniform density on the disk of radius env_radius. */
float pc_env_disk_pdf(const pc_scene *s);

typedef struct pc_connection {
  vec3 f;          /* unweighted contribution (path throughput / pdf) */
  float weight;    /* MIS weight of strategy (s,t) */
  float px, py;    /* t = 1: raster position of the splat */
  /* weighted: weight = mis_own / (mis_own + the two sides' sums); mis_eye is the light side's.
   * At the camera (t = 1) that is every strategy with more eye vertices, all of which sample
   * the camera ray: under a filter, pixel j's weight has mis_eye times pc_mis(its filter
   * density at px, py) (pc_lt_pixel_weight). */
  float mis_own, mis_eye;
} pc_connection;

/* Connects light vertex lv (s = lv->depth) to eye vertex ev (t = ev->depth; the camera when
 * t = 1): evaluates both ends, the geometry term, the MIS weight (1 if !weighted), and last the
 * visibility. Returns false when the contribution is zero (delta endpoint, back side, outside
 * the image, occluded ...). The caller checks the path length against maxDepth. */
bool pc_connect(pc_tctx *c, const pc_mis_counts *n, const pc_path_vertex *lv, const pc_path_vertex *ev, bool weighted,
                pc_connection *out);

/* pc_connect in two steps, for callers that look at the unoccluded contribution before paying
 * for the shadow ray (PCBPT's resampling): pc_connect_unoccluded is everything but the
 * visibility test, pc_connect_visible the test itself (counted in c->rays). */
bool pc_connect_unoccluded(pc_tctx *c, const pc_mis_counts *n, const pc_path_vertex *lv, const pc_path_vertex *ev,
                           bool weighted, pc_connection *out);
bool pc_connect_visible(pc_tctx *c, const pc_path_vertex *lv, const pc_path_vertex *ev);

/* Strategy s=1 at eye vertex ev (its t): a fresh light sample from rng, connected and added to
 * the nee layer of pixel (x,y). */
void pc_connect_nee(pc_tctx *c, const pc_mis_counts *n, pc_rng *rng, const pc_path_vertex *ev, int x, int y);

/* A light splat into layer `layer` and, with --strategy-layers, into layer s%dt%d. */
void pc_film_queue_add_strategy(pc_film_queue *q, int strategy_layers, int layer, int s, int t, int x, int y, vec3 v);

/* The MIS weight of weighted t = 1 connection k in a pixel whose filter density at k's raster
 * point is `density` (k->weight for the pixel box's 1); 0 where it is not a valid weight. */
float pc_lt_pixel_weight(const pc_mis_counts *n, const pc_connection *k, float density);

/* Light tracing: connects light vertices v[0..nl-1] of light path `index` to the camera (a thin
 * lens at lens points keyed by index), splats into c->splat. */
void pc_lt_splat(pc_tctx *c, const pc_path_vertex *v, int nl, uint64_t index);

/* The pixel an eye sub-path belongs to; pc_emitter_hit (a pc_emitter_hit_fn taking one as
 * `user`) adds the weighted s=0 contribution to layer pt. */
typedef struct pc_pixel_target {
  int x, y;
} pc_pixel_target;
void pc_emitter_hit(pc_tctx *c, void *user, const pc_path_vertex *v, int light, vec3 le);

/* Monotonic clock in seconds, for the per-thread time split. */
double pc_seconds(void);

/* Reading the clock around every phase of every pixel costs a few per cent: one pixel (or light
 * path) in PC_TIMED_EVERY is timed and counts that many times (the stats only split the render
 * time by the phases' proportions). A prime, so the timed pixels do not line up in columns. */
#define PC_TIMED_EVERY 17
static inline bool pc_timed(uint64_t index) { return index % PC_TIMED_EVERY == 0; }
static inline double pc_stamp(bool timed) { return timed ? pc_seconds() : 0.0; }

#endif
