/* irec.h: PCBPT importance records (Popov et al. 2015, sect. 4.2 and 6) for one iteration and
 * the connection PMF p_conn they define at any eye vertex.
 *
 * A record sits at a vertex z of a cache eye path and holds the PMF over the V connectable
 * light vertices of the iteration's M stored light paths, proportional to
 * luminance(light-subpath throughput x f_conn(y, z)), f_conn = rho_y * G * V * rho_z (the
 * integrator may fold in more, e.g. the MIS weight), and its CMF. All PMFs and CMFs live in one contiguous float array (2*R*V floats, bounded by a limit
 * given at creation); records hold offsets into it. The importance of light vertex v seen
 * from an eye vertex is computed by a caller-supplied callback, so this module knows nothing
 * of the path-vertex type, BSDFs or ray casting.
 *
 * At an eye vertex, a lookup interpolates the knn records nearest to the centre of the eye
 * vertex's cell (weighted by normal and incoming-direction similarity and distance) lazily,
 * without adding up their rows: p_conn(v) is the weighted sum of their PMFs at v, and sampling
 * picks one record by its weight and inverts that record's CMF. The result is blended with
 * the uniform PMF:
 *   p_conn(v) = (1 - u) * p_interp(v) + u / V.
 * The exact mode (--pmf exact) computes the PMF at the eye vertex itself instead. */
#ifndef PC_IREC_H
#define PC_IREC_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"
#include "kdtree.h"
#include "rng.h"
#include "thread_pool.h"
#include "vecmath.h"

#define PC_IREC_MAX_KNN PC_KDTREE_MAX_K
/* Memoised neighbour sets per thread: at least this many, more as the records grow (irec.c,
 * memo_bits). */
#define PC_IREC_CACHE_BITS 13
#define PC_IREC_CACHE_CELLS (1 << PC_IREC_CACHE_BITS)
/* Cell size as a fraction of the median record-neighbourhood radius. */
#define PC_IREC_CELL_FRACTION 0.5f

/* Where an eye vertex is, as far as caching is concerned. Records and lookups must use the same
 * conventions: n the unit shading normal, wi the unit direction towards the previous vertex of
 * the eye path. `vertex` is passed through untouched to the importance callback (the
 * integrator's full path vertex: material, frame, throughput); it may be NULL. */
typedef struct pc_irec_site {
  vec3 p, n, wi;
  const void *vertex;
  bool lambertian; /* the BSDF here is Lambertian: its PMF does not depend on wi */
} pc_irec_site;

/* Unnormalized connection importance of light vertex v (0 <= v < V) for the eye vertex z:
 * luminance(throughput_y * rho_y * G * V * rho_z), visibility included. Must be finite and
 * >= 0; called concurrently, `thread` is the calling pool thread (0..nthreads-1). */
typedef float (*pc_irec_importance_fn)(void *user, int thread, const pc_irec_site *z, int v);

typedef struct pc_irec_store pc_irec_store;

/* nthreads: the most threads that will build or look up concurrently (per-thread scratch for
 * the exact mode and neighbour-set memo); knn: the neighbour count lookups will use (memoised).
 * max_bytes: hard limit on the memory the store may hold. */
int pc_irec_create(int nthreads, int knn, size_t max_bytes, pc_irec_store **out, pc_err *e);
void pc_irec_destroy(pc_irec_store *s);

/* Builds the iteration's records: one per site (nrecords may be 0, e.g. in exact mode) over
 * nlight light vertices, evaluating fn for every (record, light vertex) pair in parallel on
 * `pool` (NULL: on the calling thread, as thread 0). Reuses the previous iteration's memory.
 * Fails with PC_ELIMIT (naming the figures) when the records would exceed the store's limit,
 * PC_ENUMERIC when fn returns a negative or non-finite value, PC_EINVAL on bad counts or a pool
 * with more threads than the store was created for. On failure the store holds no records. */
int pc_irec_build(pc_irec_store *s, const pc_irec_site *sites, int nrecords, int nlight,
                  pc_irec_importance_fn fn, void *user, pc_pool *pool, pc_err *e);

/* Bytes held: 2*R*V floats of PMF/CMF plus the records, the kd-tree, the exact-mode scratch
 * and the per-thread neighbour-set memo (capacity: a later smaller build keeps the larger
 * allocation; the memo grows with R, at most 64 MiB over all threads). */
size_t pc_irec_bytes(const pc_irec_store *s);
/* Bytes a build of R records over V light vertices needs (what the limit is checked against);
 * SIZE_MAX when the figure overflows. */
size_t pc_irec_bytes_needed(const pc_irec_store *s, int nrecords, int nlight);
int pc_irec_count(const pc_irec_store *s);
/* Records were built and none of them sees a light vertex (every lookup is then uniform). */
bool pc_irec_none_seen(const pc_irec_store *s);
int pc_irec_light_count(const pc_irec_store *s);
/* Record r's PMF and CMF (V floats each, inside the one shared array) and its unnormalized
 * importance sum; a record with sum 0 sees no light vertex and holds zeros. */
const float *pc_irec_pmf(const pc_irec_store *s, int r);
const float *pc_irec_cmf(const pc_irec_store *s, int r);
double pc_irec_total(const pc_irec_store *s, int r);

/* The connection PMF at one eye vertex: valid until the next build. Plain data on the stack. */
typedef struct pc_irec_lookup {
  int V;
  float u;                               /* uniform mix in [0, 1] */
  int n;                                 /* distributions interpolated; 0: none (see below) */
  double seen;                           /* the share of the light vertices they see (below) */
  double w[PC_IREC_MAX_KNN];             /* their weights, summing to 1 */
  const float *pmf[PC_IREC_MAX_KNN], *cmf[PC_IREC_MAX_KNN];
} pc_irec_lookup;

/* Interpolates the knn (1..PC_IREC_MAX_KNN) records nearest to the centre of z's cell: cells
 * are cubes of PC_IREC_CELL_FRACTION times the build's median record-neighbourhood radius, so
 * the neighbour set is a pure function of z's position (any thread, any order: unbiased and
 * reproducible), and memoising it per cell and thread saves most kd-tree searches (the knn
 * given at creation is memoised; others are searched every time). A record's weight is
 * cos(n, n_q) * cos(wi, wi_q) * (1 - d_q / sum_j d_j) over the knn found records (Popov et
 * al. sect. 6: product of the cosines, times the distance normalized over the selected
 * records), without the cos(wi, wi_q) factor when both z and the record are Lambertian (their
 * PMFs do not depend on wi, and the factor only lowers the number of records that count);
 * records with a non-positive cosine or weight, and records that see no light
 * vertex, are dropped. If every record with a PMF is dropped for its weight, p_conn falls
 * back to the uniform PMF (n = 0, u = 1). If none of the found records has a PMF, n = 0:
 * p_conn is then the uniform PMF when u > 0, and undefined (pc_irec_sample draws nothing)
 * when u == 0. */
void pc_irec_lookup_cached(pc_irec_store *s, int thread, const pc_irec_site *z, int knn, float uniform_mix,
                           pc_irec_lookup *L);

/* A dark eye vertex: one whose interpolated records see (have a PMF > 0 at) less than `below`
 * of the V light vertices (every one when below >= 1), their shares weighted as the records
 * are (L->seen; 0 when no record is interpolated; in exact mode the share of the exact PMF,
 * which the integrator does not use). There p_conn's uniform mix
 * becomes `mix` (mix > 0 keeps every light vertex drawable), and the caller may draw more
 * candidates: a proposal chosen from the records alone, so the estimate stays unbiased.
 * Returns whether L is dark. */
bool pc_irec_lookup_dark(pc_irec_lookup *L, float below, float mix);

/* Starts loading the memoised neighbour set a lookup at p would read (the memo's entries are
 * spread over more memory than stays in cache), so that it is there when the lookup comes. */
void pc_irec_prefetch(const pc_irec_store *s, int thread, vec3 p);

/* --pmf exact: evaluates fn over all V light vertices at z itself into `thread`'s scratch
 * (valid until that thread's next exact lookup) and sets L to that PMF. PC_ENUMERIC when fn
 * returns a negative or non-finite value. */
int pc_irec_lookup_exact(pc_irec_store *s, int thread, const pc_irec_site *z, pc_irec_importance_fn fn,
                         void *user, float uniform_mix, pc_irec_lookup *L, pc_err *e);

/* Draws light vertex *v from p_conn with rng: with probability u from the uniform PMF,
 * otherwise by inverting the interpolated CMF. Returns 1 and sets *v and *p_conn > 0, or 0
 * when p_conn is undefined (V == 0, or n == 0 with u == 0). */
int pc_irec_sample(const pc_irec_lookup *L, pc_rng *rng, int *v, double *p_conn);
/* The same with the uniform-or-interpolated choice made by xi_mix in [0, 1) (uniform when
 * xi_mix < u): K draws at one eye vertex stratify it, (k + xi) / K, so each draw still follows
 * p_conn while the K of them split between the two components in proportion. */
int pc_irec_sample_mix(const pc_irec_lookup *L, double xi_mix, pc_rng *rng, int *v, double *p_conn);
/* p_conn(v), 0 when undefined; > 0 for every v whenever u > 0 and V > 0, and for every v
 * pc_irec_sample can return. */
double pc_irec_pconn(const pc_irec_lookup *L, int v);

/* Resampled importance sampling over p_conn (Talbot et al. 2005, "Importance resampling for
 * global illumination"): draws ncand candidates from p_conn (their uniform-or-interpolated
 * choices stratified by xi_mix as in pc_irec_sample_mix), asks target(user, slot, v) for each
 * candidate's target value h >= 0 (slot 0..ncand-1; the caller keeps what it computed there),
 * and selects nsel of them with probability proportional to h / p_conn, the selections
 * stratified over one uniform number. For every selection it returns the slot and the factor
 *   W / h(selected),  W = (1/ncand) sum_j h_j / p_conn(v_j),
 * so that contribution(selected) * factor is an unbiased estimate of the sum of the
 * contributions over all V light vertices, provided h > 0 wherever the contribution is
 * non-zero. (Unbiased because each candidate follows p_conn: E[sum_j (h_j / sum h) c_j W / h_j]
 * = E[(1/N) sum_j c_j / p_j]; independence of the candidates is not needed.) Returns nsel, or 0
 * when p_conn is undefined or every candidate's target is 0 (the estimate is then 0).
 * 1 <= ncand <= PC_IREC_MAX_CANDIDATES, nsel >= 1. */
#define PC_IREC_MAX_CANDIDATES 64
typedef float (*pc_irec_target_fn)(void *user, int slot, int v);
int pc_irec_resample(const pc_irec_lookup *L, int ncand, int nsel, double xi_mix, pc_rng *rng, pc_irec_target_fn target,
                     void *user, int *sel_slot, double *sel_factor);

/* The interpolated component alone (n > 0): its PMF at index i, and a draw from it for xi in
 * [0, 1): the record j whose share of the weights holds xi (the first with xi < w_0 + ... +
 * w_j, else the last), then the smallest i with cmf_j(i) > (xi - w_0 - ... - w_{j-1}) / w_j.
 * Exposed for tests. */
double pc_irec_interp_pmf(const pc_irec_lookup *L, int i);
int pc_irec_interp_sample(const pc_irec_lookup *L, double xi);
/* The summed weight (in [0, 1]) of the interpolated records whose PMF is > 0 at i: the
 * records' blurred estimate of whether light vertex i is visible from here (0 when n == 0). */
double pc_irec_interp_seen(const pc_irec_lookup *L, int i);

#endif
