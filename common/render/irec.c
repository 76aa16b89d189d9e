/* irec.c: see irec.h. The PMF and CMF rows are built so that sampling never returns a light
 * vertex with zero probability: a row's CMF is the running sum of its (already rounded) float
 * PMF, so a zero PMF entry leaves the CMF exactly unchanged, and a binary search that stops
 * where the interpolated CMF rises has found an entry whose interpolated PMF is > 0. */
#include "irec.h"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* What a lookup reads of record r, packed into 44 bytes. Its PMF is at mass[2*r*V ..), its CMF
 * right after it. */
typedef struct pc_irec_record {
  vec3 p, n, wi;
  bool lambertian;
  bool seen;        /* its importance sum is > 0: it has a distribution */
  float seen_share; /* the share of the V light vertices its PMF is > 0 at */
} pc_irec_record;

/* The first bad callback value a thread met during a build (record < 0: none). */
typedef struct thread_err {
  int record, v;
  float value;
} thread_err;

struct pc_irec_store {
  int nthreads;
  size_t max_bytes;
  int R, V;
  int nseen;            /* records with a distribution: with none, every lookup is uniform */
  pc_irec_record *rec;
  double *total;        /* per record: unnormalized importance sum; 0: sees no light vertex */
  vec3 *pos;            /* record positions, the kd-tree's input */
  size_t rec_cap;
  float *mass;          /* all PMFs and CMFs: 2*R*V floats */
  size_t mass_cap;
  float *scratch;       /* exact mode: 2*V floats per thread */
  size_t scratch_cap;
  pc_kdtree tree;
  thread_err *terr;
  float cell;           /* neighbour-set cell size of this build; 0: exact query positions */
  vec3 cell_origin;
  uint32_t epoch;       /* build counter: cached neighbour sets of older builds are stale */
  int cache_k;          /* neighbours memoised per cell (the knn given at creation) */
  size_t cache_stride;  /* bytes per cache entry */
  int cache_bits;       /* entries per thread: 2^cache_bits (memo_bits) */
  unsigned char *cache; /* per thread: 2^cache_bits entries, each on its own cache lines */
};

/* A memoised neighbour set: the cache_k nearest records of one cell's centre, and how many of
 * them have a distribution (none: the lookup is over without reading a record). The entries
 * are cache-line aligned, so a probe that hits reads one line for knn <= 12. */
typedef struct cell_entry {
  uint64_t key;
  uint32_t epoch;
  int16_t n, seen;
  int idx[];
} cell_entry;
#define CACHE_LINE 64

static size_t per_record_bytes(void) {
  return sizeof(pc_irec_record) + sizeof(double) + sizeof(vec3) + PC_KDTREE_POINT_BYTES;
}

/* The memo of all threads with 2^bits entries each. */
static size_t memo_bytes(const pc_irec_store *s, int bits) {
  return (size_t)s->nthreads * ((size_t)1 << bits) * s->cache_stride;
}

/* The memo's size for R records: ~16 entries per record, at least PC_IREC_CACHE_CELLS, and all
 * threads' memos together within MEMO_MAX_BYTES. A record's neighbourhood spans a few query
 * cells (ajar-door at 128x128: ~900 cells in use for ~200 records), so this keeps the table
 * about a quarter full. A fixed 2^13 entries did up to ~1800 records: at 512x512 (~3150) a
 * quarter of the lookups missed on collisions and searched the kd-tree. */
#define MEMO_MAX_BYTES ((size_t)64 << 20)
static int memo_bits(const pc_irec_store *s, int R) {
  int bits = PC_IREC_CACHE_BITS;
  while (bits < 24 && ((size_t)1 << bits) < 16 * (size_t)R && memo_bytes(s, bits + 1) <= MEMO_MAX_BYTES) bits++;
  return bits;
}

static size_t fixed_bytes(const pc_irec_store *s) {
  return sizeof *s + (size_t)s->nthreads * sizeof(thread_err);
}

/* Bytes for the given capacities, or SIZE_MAX on overflow. */
static size_t bytes_for(const pc_irec_store *s, size_t rec, size_t mass, size_t scratch, int bits) {
  if (rec > SIZE_MAX / per_record_bytes() || mass > SIZE_MAX / 8 || scratch > SIZE_MAX / 8) return SIZE_MAX;
  size_t a = rec * per_record_bytes(), b = mass * sizeof(float), c = scratch * sizeof(float);
  size_t f = fixed_bytes(s) + memo_bytes(s, bits);
  if (a > SIZE_MAX - b || a + b > SIZE_MAX - c || a + b + c > SIZE_MAX - f) return SIZE_MAX;
  return a + b + c + f;
}

/* Makes the memo 2^bits entries per thread, all stale. */
static int resize_memo(pc_irec_store *s, int bits, pc_err *e) {
  if (bits == s->cache_bits) return PC_OK;
  free(s->cache);
  s->cache = aligned_alloc(CACHE_LINE, memo_bytes(s, bits));
  if (!s->cache) {
    s->cache_bits = 0;
    return pc_errf(e, PC_ENOMEM, "importance records: out of memory for the neighbour-set memo (%zu bytes)",
                   memo_bytes(s, bits));
  }
  memset(s->cache, 0, memo_bytes(s, bits));
  s->cache_bits = bits;
  return PC_OK;
}

/* Floats of PMF+CMF and of scratch a build needs, or SIZE_MAX on overflow. */
static size_t mass_floats(int R, int V) {
  if (R > 0 && (size_t)V > SIZE_MAX / 2 / (size_t)R) return SIZE_MAX;
  return 2 * (size_t)R * (size_t)V;
}

int pc_irec_create(int nthreads, int knn, size_t max_bytes, pc_irec_store **out, pc_err *e) {
  *out = NULL;
  if (nthreads < 1 || nthreads > 4096) return pc_errf(e, PC_EINVAL, "importance records: thread count %d out of range 1..4096", nthreads);
  if (knn < 1 || knn > PC_IREC_MAX_KNN) return pc_errf(e, PC_EINVAL, "importance records: knn %d out of range 1..%d", knn, PC_IREC_MAX_KNN);
  pc_irec_store *s = calloc(1, sizeof *s);
  if (s) s->terr = calloc((size_t)nthreads, sizeof *s->terr);
  if (!s || !s->terr) {
    if (s) free(s->terr);
    free(s);
    return pc_errf(e, PC_ENOMEM, "importance records: out of memory");
  }
  s->cache_k = knn;
  s->cache_stride = (sizeof(cell_entry) + (size_t)knn * sizeof(int) + CACHE_LINE - 1) & ~(size_t)(CACHE_LINE - 1);
  s->nthreads = nthreads;
  s->max_bytes = max_bytes;
  int rc = resize_memo(s, PC_IREC_CACHE_BITS, e);
  if (rc != PC_OK) {
    pc_irec_destroy(s);
    return rc;
  }
  *out = s;
  return PC_OK;
}

static void release_buffers(pc_irec_store *s) {
  free(s->rec);
  free(s->total);
  free(s->pos);
  free(s->mass);
  free(s->scratch);
  pc_kdtree_free(&s->tree);
  s->rec = NULL;
  s->total = NULL;
  s->pos = NULL;
  s->mass = NULL;
  s->scratch = NULL;
  s->rec_cap = s->mass_cap = s->scratch_cap = 0;
}

void pc_irec_destroy(pc_irec_store *s) {
  if (!s) return;
  release_buffers(s);
  free(s->terr);
  free(s->cache);
  free(s);
}

size_t pc_irec_bytes(const pc_irec_store *s) {
  return bytes_for(s, s->rec_cap, s->mass_cap, s->scratch_cap, s->cache_bits);
}

size_t pc_irec_bytes_needed(const pc_irec_store *s, int nrecords, int nlight) {
  if (nrecords < 0 || nlight < 0) return SIZE_MAX;
  size_t mass = mass_floats(nrecords, nlight), scratch = mass_floats(s->nthreads, nlight);
  if (mass == SIZE_MAX || scratch == SIZE_MAX) return SIZE_MAX;
  return bytes_for(s, (size_t)nrecords, mass, scratch, memo_bits(s, nrecords));
}

bool pc_irec_none_seen(const pc_irec_store *s) { return s->R > 0 && s->nseen == 0; }

int pc_irec_count(const pc_irec_store *s) { return s->R; }
int pc_irec_light_count(const pc_irec_store *s) { return s->V; }
const float *pc_irec_pmf(const pc_irec_store *s, int r) { return s->mass + 2 * (size_t)r * (size_t)s->V; }
const float *pc_irec_cmf(const pc_irec_store *s, int r) { return pc_irec_pmf(s, r) + s->V; }
double pc_irec_total(const pc_irec_store *s, int r) { return s->total[r]; }

/* Fills one PMF/CMF row for the eye vertex z, and in *nonzero how many of its entries are > 0.
 * Returns the importance sum, or -1 after noting the first bad value in *te. */
static double fill_row(pc_irec_importance_fn fn, void *user, int thread, const pc_irec_site *z, int V, float *pmf,
                       float *cmf, int record, thread_err *te, int *nonzero) {
  *nonzero = 0;
  double total = 0.0;
  for (int v = 0; v < V; v++) {
    float x = fn(user, thread, z, v);
    if (!(x >= 0.f) || !isfinite(x)) {
      if (te->record < 0) *te = (thread_err){record, v, x};
      return -1.0;
    }
    pmf[v] = x;
    total += x;
  }
  if (total == 0.0) {
    memset(cmf, 0, (size_t)V * sizeof *cmf);
    return 0.0;
  }
  /* The CMF sums the rounded PMF, so zero entries stay flat, and is divided by its own total
   * so it ends at exactly 1. */
  double sum = 0.0;
  int nz = 0;
  for (int v = 0; v < V; v++) {
    pmf[v] = (float)(pmf[v] / total);
    sum += pmf[v];
    nz += pmf[v] > 0.f;
  }
  *nonzero = nz;
  double run = 0.0;
  for (int v = 0; v < V; v++) {
    run += pmf[v];
    cmf[v] = (float)(run / sum);
  }
  return total;
}

typedef struct build_job {
  pc_irec_store *s;
  const pc_irec_site *sites;
  pc_irec_importance_fn fn;
  void *user;
} build_job;

static void build_record(void *arg, int thread, int r) {
  build_job *j = arg;
  pc_irec_store *s = j->s;
  float *pmf = s->mass + 2 * (size_t)r * (size_t)s->V;
  int nonzero;
  s->total[r] = fill_row(j->fn, j->user, thread, &j->sites[r], s->V, pmf, pmf + s->V, r, &s->terr[thread], &nonzero);
  s->rec[r].seen = s->total[r] > 0.0;
  s->rec[r].seen_share = s->V > 0 ? (float)nonzero / (float)s->V : 0.f;
}

/* Grows the buffers to the build's needs, never past the limit: capacities kept from an
 * earlier build count against it too, so when keeping them would not fit they are released. */
static int reserve(pc_irec_store *s, int R, int V, pc_err *e) {
  size_t need = pc_irec_bytes_needed(s, R, V);
  if (need > s->max_bytes) {
    double mib = 1.0 / (1024.0 * 1024.0);
    return pc_errf(e, PC_ELIMIT,
                   "importance records: %d records x %d light vertices need %.1f MiB (2*R*V floats of PMF and CMF),"
                   " over the limit of %.1f MiB",
                   R, V, need == SIZE_MAX ? INFINITY : (double)need * mib, (double)s->max_bytes * mib);
  }
  size_t want_rec = (size_t)R, want_mass = mass_floats(R, V), want_scratch = mass_floats(s->nthreads, V);
  size_t keep_rec = want_rec > s->rec_cap ? want_rec : s->rec_cap;
  size_t keep_mass = want_mass > s->mass_cap ? want_mass : s->mass_cap;
  size_t keep_scratch = want_scratch > s->scratch_cap ? want_scratch : s->scratch_cap;
  /* The memo grows with the records, and shrinks only by more than a step (R varies from one
   * iteration to the next, and each resize clears it) while the larger one fits the limit. */
  int bits = memo_bits(s, R);
  if (bits == s->cache_bits - 1 && bytes_for(s, want_rec, want_mass, want_scratch, s->cache_bits) <= s->max_bytes)
    bits = s->cache_bits;
  if (bytes_for(s, keep_rec, keep_mass, keep_scratch, bits) > s->max_bytes) release_buffers(s);
  int rc = resize_memo(s, bits, e);
  if (rc != PC_OK) return rc;
  if (want_rec > s->rec_cap) {
    pc_irec_record *r = realloc(s->rec, want_rec * sizeof *r);
    if (r) s->rec = r;
    double *t = realloc(s->total, want_rec * sizeof *t);
    if (t) s->total = t;
    vec3 *p = realloc(s->pos, want_rec * sizeof *p);
    if (p) s->pos = p;
    if (!r || !t || !p) return pc_errf(e, PC_ENOMEM, "importance records: out of memory for %d records", R);
    s->rec_cap = want_rec;
  }
  if (want_mass > s->mass_cap) {
    float *m = realloc(s->mass, want_mass * sizeof *m);
    if (!m) return pc_errf(e, PC_ENOMEM, "importance records: out of memory for %zu PMF/CMF floats", want_mass);
    s->mass = m;
    s->mass_cap = want_mass;
  }
  if (want_scratch > s->scratch_cap) {
    float *m = realloc(s->scratch, want_scratch * sizeof *m);
    if (!m) return pc_errf(e, PC_ENOMEM, "importance records: out of memory for the exact-PMF scratch");
    s->scratch = m;
    s->scratch_cap = want_scratch;
  }
  return PC_OK;
}

static int cmp_float(const void *a, const void *b) {
  float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

/* The cell size for this build's neighbour sets: a fraction of the median distance from a
 * record to its cache_k-th nearest other record, so a query moves at most a small part of
 * its neighbourhood's radius when it is snapped to its cell centre. Measured on at most
 * CELL_SAMPLES records spread over the set, so the cost stays flat as R grows. */
#define CELL_SAMPLES 512
static void set_cell(pc_irec_store *s) {
  s->epoch++;
  s->cell = 0.f;
  if (s->R < 2) return;
  int k = s->cache_k + 1 < s->R ? s->cache_k + 1 : s->R, n = s->R < CELL_SAMPLES ? s->R : CELL_SAMPLES;
  float radius[CELL_SAMPLES], d2[PC_IREC_MAX_KNN + 1];
  int idx[PC_IREC_MAX_KNN + 1];
  vec3 lo = s->pos[0];
  for (int r = 1; r < s->R; r++) lo = v3(fminf(lo.x, s->pos[r].x), fminf(lo.y, s->pos[r].y), fminf(lo.z, s->pos[r].z));
  for (int i = 0; i < n; i++) {
    int m = pc_kdtree_knn(&s->tree, s->pos[(int)((int64_t)i * s->R / n)], k, idx, d2);
    radius[i] = m > 0 ? sqrtf(d2[m - 1]) : 0.f;
  }
  qsort(radius, (size_t)n, sizeof *radius, cmp_float);
  float c = radius[n / 2] * PC_IREC_CELL_FRACTION;
  if (c > 0.f && isfinite(c)) {
    s->cell = c;
    s->cell_origin = lo;
  }
}

int pc_irec_build(pc_irec_store *s, const pc_irec_site *sites, int nrecords, int nlight, pc_irec_importance_fn fn,
                  void *user, pc_pool *pool, pc_err *e) {
  s->R = 0;
  s->nseen = 0;
  s->V = 0;
  s->tree.n = 0;
  if (nrecords < 0 || nlight < 0) return pc_errf(e, PC_EINVAL, "importance records: negative count (%d records, %d light vertices)", nrecords, nlight);
  if (pool && pc_pool_size(pool) > s->nthreads)
    return pc_errf(e, PC_EINVAL, "importance records: pool of %d threads, store made for %d", pc_pool_size(pool), s->nthreads);
  int rc = reserve(s, nrecords, nlight, e);
  if (rc != PC_OK) return rc;
  for (int r = 0; r < nrecords; r++) {
    s->rec[r] = (pc_irec_record){sites[r].p, sites[r].n, sites[r].wi, sites[r].lambertian, false, 0.f};
    s->total[r] = 0.0;
    s->pos[r] = sites[r].p;
  }
  rc = pc_kdtree_build(&s->tree, s->pos, nrecords, e);
  if (rc != PC_OK) return rc;
  for (int t = 0; t < s->nthreads; t++) s->terr[t].record = -1;
  s->V = nlight;
  build_job job = {s, sites, fn, user};
  if (nlight > 0) {
    if (pool) pc_pool_run(pool, nrecords, build_record, &job);
    else
      for (int r = 0; r < nrecords; r++) build_record(&job, 0, r);
  }
  /* Report the lowest bad record, so the message does not depend on thread timing. */
  const thread_err *bad = NULL;
  for (int t = 0; t < s->nthreads; t++)
    if (s->terr[t].record >= 0 && (!bad || s->terr[t].record < bad->record)) bad = &s->terr[t];
  if (bad) {
    s->V = 0;
    s->tree.n = 0;
    return pc_errf(e, PC_ENUMERIC, "importance records: importance of light vertex %d for record %d is %g (must be finite and >= 0)",
                   bad->v, bad->record, (double)bad->value);
  }
  s->R = nrecords;
  s->nseen = 0;
  for (int r = 0; r < nrecords; r++) s->nseen += s->rec[r].seen;
  set_cell(s);
  return PC_OK;
}

/* Keeps the entries with positive weight and normalizes them. If none has one, the records
 * near z all face another way (often the other side of a thin wall, with a PMF of another
 * room): p_conn falls back to the uniform PMF (u = 1) rather than trust them. */
static void normalize_weights(pc_irec_lookup *L) {
  double sum = 0.0;
  int m = 0;
  for (int j = 0; j < L->n; j++) {
    if (!(L->w[j] > 0.0)) continue;
    L->w[m] = L->w[j];
    L->pmf[m] = L->pmf[j];
    L->cmf[m] = L->cmf[j];
    sum += L->w[m++];
  }
  if (m == 0) {
    L->n = 0;
    L->u = 1.f;
    return;
  }
  L->n = m;
  for (int j = 0; j < m; j++) L->w[j] /= sum;
}

/* Cell coordinates within +-2^20 pack into one 63-bit key. */
#define CELL_RANGE 1048576.f

/* floorf for |x| < CELL_RANGE, where the int conversion is exact: floorf itself is a libm call
 * without SSE4.1, ~18 instructions each, three per lookup. */
static inline float floor_in_range(float x) {
  float t = (float)(int32_t)x;
  return t > x ? t - 1.f : t;
}

/* How many of the n records idx[] have a distribution. */
static int count_seen(const pc_irec_store *s, const int *idx, int n) {
  int seen = 0;
  for (int j = 0; j < n; j++) seen += s->rec[idx[j]].seen;
  return seen;
}

/* The kd-tree's knn nearest records of q into buf. */
static const int *search(const pc_irec_store *s, vec3 q, int knn, int *buf, int *count, int *seen) {
  float d2[PC_IREC_MAX_KNN];
  *count = pc_kdtree_knn(&s->tree, q, knn, buf, d2);
  *seen = count_seen(s, buf, *count);
  return buf;
}

/* The cell of p (its integer coordinates in *f) and its key; false when the build has no cell
 * size or p lies absurdly far out. */
static inline bool cell_of(const pc_irec_store *s, vec3 p, vec3 *f, uint64_t *key) {
  if (!(s->cell > 0.f)) return false;
  vec3 g = v3_scale(v3_sub(p, s->cell_origin), 1.f / s->cell);
  if (!(fabsf(g.x) < CELL_RANGE && fabsf(g.y) < CELL_RANGE && fabsf(g.z) < CELL_RANGE)) return false;
  *f = v3(floor_in_range(g.x), floor_in_range(g.y), floor_in_range(g.z));
  *key = (uint64_t)(int64_t)(f->x + CELL_RANGE) << 42 | (uint64_t)(int64_t)(f->y + CELL_RANGE) << 21 |
         (uint64_t)(int64_t)(f->z + CELL_RANGE);
  return true;
}

/* The memo entry a cell's key maps to in thread's memo. Fibonacci hashing: the product's top
 * bits mix every bit of the key. (Its middle bits did not: 1.9% of the lookups missed on
 * collisions with ~900 cells in use, now 0.2%.) */
static inline cell_entry *memo_entry(const pc_irec_store *s, int thread, uint64_t key) {
  size_t slot = (size_t)((key * 0x9E3779B97F4A7C15ull) >> (64 - s->cache_bits));
  return (cell_entry *)(s->cache + (((size_t)thread << s->cache_bits) + slot) * s->cache_stride);
}

void pc_irec_prefetch(const pc_irec_store *s, int thread, vec3 p) {
  vec3 f;
  uint64_t key;
  if (s->nseen > 0 && cell_of(s, p, &f, &key)) __builtin_prefetch(memo_entry(s, thread, key));
}

/* The knn nearest records of the centre of z's cell (of z itself when the build has no cell
 * size or z lies absurdly far out): a pure function of the position, so the lookup does not
 * depend on which thread asks or in what order. Returns their indices (in `buf`, or in the
 * memo) and count, and in *seen how many of them have a distribution. The cache_k-neighbour
 * sets are memoised per thread: neighbouring pixels mostly share a cell, and the kd-tree search
 * is the costliest part of a lookup. */
static const int *neighbours(pc_irec_store *s, int thread, vec3 p, int knn, int *buf, int *count, int *seen) {
  vec3 f;
  uint64_t key;
  if (!cell_of(s, p, &f, &key)) return search(s, p, knn, buf, count, seen);
  vec3 centre = v3_add(s->cell_origin, v3_scale(v3_add(f, v3s(0.5f)), s->cell));
  if (knn != s->cache_k) return search(s, centre, knn, buf, count, seen);
  cell_entry *c = memo_entry(s, thread, key);
  if (c->epoch != s->epoch || c->key != key) {
    int n, sn;
    search(s, centre, knn, c->idx, &n, &sn);
    c->n = (int16_t)n;
    c->seen = (int16_t)sn;
    c->key = key;
    c->epoch = s->epoch;
  }
  *count = c->n;
  *seen = c->seen;
  return c->idx;
}

void pc_irec_lookup_cached(pc_irec_store *s, int thread, const pc_irec_site *z, int knn, float uniform_mix,
                           pc_irec_lookup *L) {
  L->V = s->V;
  L->u = uniform_mix;
  L->n = 0;
  L->seen = 0.0;
  if (s->V == 0 || s->nseen == 0) return;
  if (knn < 1) knn = 1;
  if (knn > PC_IREC_MAX_KNN) knn = PC_IREC_MAX_KNN;
  int buf[PC_IREC_MAX_KNN], k, seen;
  double d[PC_IREC_MAX_KNN], dsum = 0.0;
  const int *idx = neighbours(s, thread, z->p, knn, buf, &k, &seen);
  if (seen == 0) return; /* none of them has a distribution */
  for (int j = 0; j < k; j++) {
    d[j] = v3_len(v3_sub(z->p, s->rec[idx[j]].p));
    dsum += d[j];
  }
  double seen_sum = 0.0, w_sum = 0.0;
  for (int j = 0; j < k; j++) {
    const pc_irec_record *rec = &s->rec[idx[j]];
    if (!rec->seen) continue; /* no distribution to contribute */
    double cn = v3_dot(z->n, rec->n), cw = z->lambertian && rec->lambertian ? 1.0 : v3_dot(z->wi, rec->wi);
    double w = 0.0;
    /* The distance factor ranks records against each other; a lone record keeps factor 1. */
    if (cn > 0.0 && cw > 0.0) w = cn * cw * (k > 1 && dsum > 0.0 ? 1.0 - d[j] / dsum : 1.0);
    if (w > 0.0) {
      seen_sum += w * rec->seen_share;
      w_sum += w;
    }
    L->w[L->n] = w;
    L->pmf[L->n] = pc_irec_pmf(s, idx[j]);
    L->cmf[L->n] = L->pmf[L->n] + s->V;
    L->n++;
  }
  if (L->n > 0) normalize_weights(L);
  if (w_sum > 0.0) L->seen = seen_sum / w_sum; /* over the records of weight > 0, which it keeps */
}

int pc_irec_lookup_exact(pc_irec_store *s, int thread, const pc_irec_site *z, pc_irec_importance_fn fn, void *user,
                         float uniform_mix, pc_irec_lookup *L, pc_err *e) {
  L->V = s->V;
  L->u = uniform_mix;
  L->n = 0;
  L->seen = 0.0;
  if (thread < 0 || thread >= s->nthreads) return pc_errf(e, PC_EINVAL, "importance records: thread %d out of range", thread);
  if (s->V == 0) return PC_OK;
  float *pmf = s->scratch + 2 * (size_t)thread * (size_t)s->V, *cmf = pmf + s->V;
  thread_err te = {-1, 0, 0.f};
  int nonzero;
  double total = fill_row(fn, user, thread, z, s->V, pmf, cmf, 0, &te, &nonzero);
  if (total < 0.0)
    return pc_errf(e, PC_ENUMERIC, "exact PMF: importance of light vertex %d is %g (must be finite and >= 0)", te.v, (double)te.value);
  if (total > 0.0) {
    L->n = 1;
    L->seen = (double)nonzero / s->V;
    L->w[0] = 1.0;
    L->pmf[0] = pmf;
    L->cmf[0] = cmf;
  }
  return PC_OK;
}

bool pc_irec_lookup_dark(pc_irec_lookup *L, float below, float mix) {
  if (!(L->seen < (double)below) && below < 1.f) return false;
  if (L->n > 0) L->u = mix;
  return true;
}

double pc_irec_interp_pmf(const pc_irec_lookup *L, int i) {
  double p = 0.0;
  for (int j = 0; j < L->n; j++) p += L->w[j] * (double)L->pmf[j][i];
  return p;
}

double pc_irec_interp_seen(const pc_irec_lookup *L, int i) {
  double w = 0.0;
  for (int j = 0; j < L->n; j++)
    if (L->pmf[j][i] > 0.f) w += L->w[j];
  return w;
}

/* p_interp is the mixture sum_j w_j pmf_j, so it is sampled by choosing record j with
 * probability w_j and inverting j's own CMF: one binary search over one row, where inverting
 * the weighted sum of the rows probed all n rows at every step (n times the reads, scattered
 * over n rows). xi picks the record and, rescaled to that record's share, the index; the index is
 * the first whose CMF exceeds it, so its PMF is > 0 (fill_row: zero entries leave the CMF
 * flat) and its row ends at exactly 1. */
int pc_irec_interp_sample(const pc_irec_lookup *L, double xi) {
  int j = 0;
  double below = 0.0;
  while (j < L->n - 1 && !(xi < below + L->w[j])) below += L->w[j++];
  double x = (xi - below) / L->w[j];
  if (!(x < 1.0)) x = 0x1.fffffffffffffp-1; /* rounding in the running sum at the top */
  if (!(x > 0.0)) x = 0.0;
  const float *cmf = L->cmf[j];
  int lo = 0, hi = L->V - 1;
  while (lo < hi) {
    int mid = lo + (hi - lo) / 2;
    if ((double)cmf[mid] > x) hi = mid;
    else lo = mid + 1;
  }
  return lo;
}

double pc_irec_pconn(const pc_irec_lookup *L, int v) {
  if (L->V <= 0 || v < 0 || v >= L->V) return 0.0;
  double uni = 1.0 / L->V;
  if (L->n == 0) return L->u > 0.f ? uni : 0.0;
  return (1.0 - L->u) * pc_irec_interp_pmf(L, v) + L->u * uni;
}

/* Unbiased integer in [0, n) (Lemire 2019: multiply, reject the short interval). */
static uint32_t rng_below(pc_rng *rng, uint32_t n) {
  uint64_t m = (uint64_t)pc_rng_u32(rng) * n;
  uint32_t low = (uint32_t)m;
  if (low < n) {
    uint32_t threshold = (uint32_t)(-n) % n;
    while (low < threshold) {
      m = (uint64_t)pc_rng_u32(rng) * n;
      low = (uint32_t)m;
    }
  }
  return (uint32_t)(m >> 32);
}

int pc_irec_sample(const pc_irec_lookup *L, pc_rng *rng, int *v, double *p_conn) {
  return pc_irec_sample_mix(L, (double)pc_rng_f(rng), rng, v, p_conn);
}

int pc_irec_sample_mix(const pc_irec_lookup *L, double xi_mix, pc_rng *rng, int *v, double *p_conn) {
  if (L->V <= 0 || (L->n == 0 && !(L->u > 0.f))) return 0;
  if (L->n == 0 || (L->u > 0.f && xi_mix < L->u)) {
    *v = (int)rng_below(rng, (uint32_t)L->V);
  } else {
    double xi = (double)pc_rng_u32(rng) * 0x1p-32;
    *v = pc_irec_interp_sample(L, xi);
  }
  *p_conn = pc_irec_pconn(L, *v);
  return 1;
}

int pc_irec_resample(const pc_irec_lookup *L, int ncand, int nsel, double xi_mix, pc_rng *rng, pc_irec_target_fn target,
                     void *user, int *sel_slot, double *sel_factor) {
  if (ncand < 1 || ncand > PC_IREC_MAX_CANDIDATES || nsel < 1) return 0;
  double h[PC_IREC_MAX_CANDIDATES], cum[PC_IREC_MAX_CANDIDATES], wsum = 0.0;
  for (int j = 0; j < ncand; j++) {
    int v;
    double p;
    if (!pc_irec_sample_mix(L, ((double)j + xi_mix) / ncand, rng, &v, &p)) return 0;
    float t = target(user, j, v);
    h[j] = t > 0.f && isfinite(t) ? (double)t : 0.0;
    wsum += h[j] / p;
    cum[j] = wsum;
  }
  if (!(wsum > 0.0) || !isfinite(wsum)) return 0;
  double mean = wsum / ncand, xi = (double)pc_rng_u32(rng) * 0x1p-32;
  for (int k = 0; k < nsel; k++) {
    /* The first candidate whose running weight passes the stratified target: never one of
     * weight 0, since it leaves the running sum unchanged. */
    double at = ((double)k + xi) / nsel * wsum;
    int j = 0;
    while (j < ncand - 1 && !(cum[j] > at)) j++;
    while (!(h[j] > 0.0)) j--; /* rounding at the top end: step back to the last positive one */
    sel_slot[k] = j;
    sel_factor[k] = mean / h[j];
  }
  return nsel;
}
