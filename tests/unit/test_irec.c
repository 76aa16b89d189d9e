/* test_irec.c: importance records and the connection PMF on a synthetic scene (random light
 * vertices and records, an analytic importance luminance * cos * cos / d^2 with some zero
 * throughputs and a "basement" that sees nothing; no Embree): rows are normalized, the lazily
 * interpolated PMF is normalized and positive with uniform mixing, sampling follows p_conn
 * (chi-square), a draw from the interpolated PMF is its record's by weight and then that
 * record's CMF inverted, memory is 2*R*V floats plus little (the neighbour-set memo growing with
 * R, capped) and the limit holds, and bad importances are reported. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "chi2.h"
#include "irec.h"

typedef struct light_vertex {
  vec3 p, n;
  float lum; /* luminance of the light-subpath throughput */
} light_vertex;

typedef struct scene {
  int V, R;
  light_vertex *lv;
  pc_irec_site *sites;
  int nan_record; /* site (found by position: records copy sites) whose importance for light
                   * vertex 3 is NaN (-1: none) */
} scene;

static float importance(void *user, int thread, const pc_irec_site *z, int v) {
  (void)thread;
  const scene *sc = user;
  const light_vertex *y = &sc->lv[v];
  if (sc->nan_record >= 0 && v == 3 && !memcmp(&z->p, &sc->sites[sc->nan_record].p, sizeof z->p)) return NAN;
  if (z->p.z < 0.f) return 0.f; /* the basement: every connection occluded */
  vec3 d = v3_sub(z->p, y->p);
  float d2 = fmaxf(v3_len2(d), 1e-2f);
  vec3 w = v3_norm(d);
  float cy = fmaxf(0.f, v3_dot(y->n, w)), cz = fmaxf(0.f, -v3_dot(z->n, w));
  return y->lum * cy * cz / d2;
}

static vec3 rand_dir(pc_rng *r) {
  float z = 1.f - 2.f * pc_rng_f(r), phi = 2.f * PC_PI * pc_rng_f(r);
  float s = sqrtf(fmaxf(0.f, 1.f - z * z));
  return v3(s * cosf(phi), s * sinf(phi), z);
}

/* Directions around +z: records and eye vertices of one surface orientation, as in a scene,
 * so most neighbours agree in normal and incoming direction. */
static vec3 rand_dir_up(pc_rng *r) { return v3_norm(v3_add(rand_dir(r), v3(0, 0, 1.2f))); }

static vec3 rand_point(pc_rng *r) { return v3(pc_rng_f(r), pc_rng_f(r), pc_rng_f(r)); }

/* Light vertices on the cube's walls facing inwards-ish, every 7th with zero throughput;
 * records inside, a tenth of them in the basement (z < 0). */
static scene make_scene(int V, int R, uint64_t seed) {
  scene sc = {V, R, calloc((size_t)V, sizeof(light_vertex)), calloc((size_t)R, sizeof(pc_irec_site)), -1};
  pc_rng r = pc_rng_make(seed, 0, PC_STREAM_MISC, 0);
  for (int v = 0; v < V; v++) {
    sc.lv[v].p = rand_point(&r);
    sc.lv[v].n = rand_dir(&r);
    sc.lv[v].lum = v % 7 == 3 ? 0.f : 0.1f + 2.f * pc_rng_f(&r);
  }
  for (int i = 0; i < R; i++) {
    sc.sites[i].p = rand_point(&r);
    if (i % 10 == 9) sc.sites[i].p.z = -0.5f * pc_rng_f(&r) - 0.01f;
    sc.sites[i].n = rand_dir_up(&r);
    sc.sites[i].wi = rand_dir_up(&r);
  }
  return sc;
}

static void free_scene(scene *sc) {
  free(sc->lv);
  free(sc->sites);
}

static pc_irec_store *build(scene *sc, pc_pool *pool) {
  pc_irec_store *s = NULL;
  pc_err e = {0};
  assert_int_equal(pc_irec_create(4, 6, 64u << 20, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, sc->sites, sc->R, sc->V, importance, sc, pool, &e), PC_OK);
  return s;
}

/* Every non-empty record's PMF sums to 1 and its CMF rises to exactly 1, flat exactly where
 * the importance is 0; the parallel build equals the serial one bit for bit. */
static void test_record_rows(void **state) {
  (void)state;
  scene sc = make_scene(150, 400, 1);
  pc_pool *pool = NULL;
  pc_err e = {0};
  assert_int_equal(pc_pool_create(2, &pool, &e), PC_OK);
  pc_irec_store *s = build(&sc, NULL), *p = build(&sc, pool);
  int empty = 0;
  for (int r = 0; r < sc.R; r++) {
    const float *pmf = pc_irec_pmf(s, r), *cmf = pc_irec_cmf(s, r);
    assert_memory_equal(pmf, pc_irec_pmf(p, r), (size_t)sc.V * sizeof(float));
    assert_memory_equal(cmf, pc_irec_cmf(p, r), (size_t)sc.V * sizeof(float));
    assert_ptr_equal(cmf, pmf + sc.V); /* one contiguous array */
    if (pc_irec_total(s, r) == 0.0) {
      empty++;
      for (int v = 0; v < sc.V; v++) assert_true(pmf[v] == 0.f && cmf[v] == 0.f);
      continue;
    }
    double sum = 0.0;
    for (int v = 0; v < sc.V; v++) {
      float imp = importance(&sc, 0, &sc.sites[r], v);
      assert_true((pmf[v] > 0.f) == (imp > 0.f));
      assert_true(cmf[v] >= (v ? cmf[v - 1] : 0.f));
      if (v) assert_true((cmf[v] > cmf[v - 1]) == (pmf[v] > 0.f));
      sum += pmf[v];
    }
    assert_true(fabs(sum - 1.0) < 1e-5);
    assert_true(cmf[sc.V - 1] == 1.f);
  }
  assert_true(empty >= sc.R / 10);
  pc_irec_destroy(s);
  pc_irec_destroy(p);
  pc_pool_destroy(pool);
  free_scene(&sc);
}

/* At random eye points the interpolated PMF sums to 1, p_conn sums to 1 and is > 0 for every
 * light vertex when u > 0, and the seen share is the weight of the records that see v. */
static void test_interpolated_pmf(void **state) {
  (void)state;
  scene sc = make_scene(120, 300, 2);
  pc_irec_store *s = build(&sc, NULL);
  pc_rng r = pc_rng_make(2, 0, PC_STREAM_MISC, 7);
  int interpolated = 0, multi = 0, partly = 0;
  for (int q = 0; q < 500; q++) {
    pc_irec_site z = {rand_point(&r), rand_dir_up(&r), rand_dir_up(&r), NULL, false};
    pc_irec_lookup L;
    pc_irec_lookup_cached(s, 0, &z, 6, 0.1f, &L);
    assert_true(L.n >= 0 && L.n <= 6);
    double sp = 0.0, sc_ = 0.0, sw = 0.0;
    for (int j = 0; j < L.n; j++) sw += L.w[j];
    if (L.n > 0) {
      interpolated++;
      multi += L.n > 1;
      assert_true(fabs(sw - 1.0) < 1e-12);
      for (int v = 0; v < sc.V; v++) sp += pc_irec_interp_pmf(&L, v);
      assert_true(fabs(sp - 1.0) < 1e-5);
      /* The seen share is the weight of the records with a PMF > 0 at v, by its definition
       * written out: 0 exactly where the interpolated PMF is 0, 1 where every record sees v. */
      for (int v = 0; v < sc.V; v++) {
        double seen = pc_irec_interp_seen(&L, v), want = 0.0;
        bool all = true;
        for (int j = 0; j < L.n; j++) {
          if (L.pmf[j][v] > 0.f) want += L.w[j];
          else all = false;
        }
        assert_true(fabs(seen - want) < 1e-12 && seen <= 1.0 + 1e-12);
        assert_true((seen == 0.0) == (pc_irec_interp_pmf(&L, v) == 0.0));
        if (all) assert_true(fabs(seen - 1.0) < 1e-12);
        partly += seen > 0.0 && seen < 1.0 - 1e-9;
      }
    }
    for (int v = 0; v < sc.V; v++) {
      double pc = pc_irec_pconn(&L, v);
      assert_true(pc >= 0.1 / sc.V * (1 - 1e-6));
      sc_ += pc;
    }
    assert_true(fabs(sc_ - 1.0) < 1e-5);
  }
  assert_true(interpolated > 400);
  assert_true(multi > 300);
  assert_true(partly > 0); /* the scene has light vertices some records see and others do not */
  pc_irec_destroy(s);
  free_scene(&sc);
}

/* Chi-square of n samples against p_conn over the V bins (bins with expectation < 5 merged);
 * asserts the statistic is within 5 standard deviations of its mean (df), deterministic by
 * the fixed seed. Also checks every sample has p_conn > 0 and the returned p equals pconn. */
static void chi_square(const pc_irec_lookup *L, int n, uint64_t seed) {
  int V = L->V;
  long *count = calloc((size_t)V, sizeof *count);
  pc_rng r = pc_rng_make(seed, 0, PC_STREAM_CONNECT, 0);
  for (int i = 0; i < n; i++) {
    int v = -1;
    double p = 0.0;
    assert_int_equal(pc_irec_sample(L, &r, &v, &p), 1);
    assert_true(v >= 0 && v < V);
    assert_true(p > 0.0);
    assert_true(p == pc_irec_pconn(L, v));
    count[v]++;
  }
  double chi = 0.0, exp_acc = 0.0, obs_acc = 0.0;
  int df = -1;
  for (int v = 0; v < V; v++) {
    double ex = n * pc_irec_pconn(L, v);
    if (ex == 0.0) assert_int_equal(count[v], 0);
    exp_acc += ex;
    obs_acc += (double)count[v];
    if (exp_acc >= 5.0 || v == V - 1) {
      if (exp_acc > 0.0) {
        chi += (obs_acc - exp_acc) * (obs_acc - exp_acc) / exp_acc;
        df++;
      }
      exp_acc = obs_acc = 0.0;
    }
  }
  assert_true(df >= 1);
  assert_true(chi < df + 5.0 * sqrt(2.0 * df));
  free(count);
}

static void test_sampling_matches_pconn(void **state) {
  (void)state;
  scene sc = make_scene(80, 200, 3);
  pc_irec_store *s = build(&sc, NULL);
  pc_err e = {0};
  pc_irec_site z = {v3(0.5f, 0.4f, 0.6f), v3_norm(v3(0.2f, -0.3f, 1.f)), v3_norm(v3(0.3f, 0.1f, 1.f)), NULL, false};
  pc_irec_lookup L;
  const float mixes[] = {0.1f, 0.f, 0.5f, 1.f};
  for (int m = 0; m < 4; m++) {
    pc_irec_lookup_cached(s, 0, &z, 6, mixes[m], &L);
    assert_true(L.n > 0);
    chi_square(&L, 200000, 10 + m);
    assert_int_equal(pc_irec_lookup_exact(s, 1, &z, importance, &sc, mixes[m], &L, &e), PC_OK);
    assert_int_equal(L.n, 1);
    chi_square(&L, 200000, 20 + m);
  }
  /* The exact PMF is the normalized importance at z itself. */
  assert_int_equal(pc_irec_lookup_exact(s, 0, &z, importance, &sc, 0.f, &L, &e), PC_OK);
  double total = 0.0;
  for (int v = 0; v < sc.V; v++) total += importance(&sc, 0, &z, v);
  for (int v = 0; v < sc.V; v++)
    assert_true(fabs(pc_irec_pconn(&L, v) - importance(&sc, 0, &z, v) / total) < 1e-6);
  /* its seen share: the light vertices of non-zero importance at z */
  int nonzero = 0;
  for (int v = 0; v < sc.V; v++) nonzero += importance(&sc, 0, &z, v) > 0.f;
  assert_true(nonzero > 0 && nonzero < sc.V);
  assert_true(L.seen == (double)nonzero / sc.V);
  pc_irec_destroy(s);
  free_scene(&sc);
}

/* The draw from the interpolated PMF is the record whose share of the weights holds xi, then a
 * linear scan of that record's CMF for xi rescaled to the share: checked for random numbers
 * and for numbers right at the weight boundaries and at each record's CMF steps, where
 * rounding decides. Every index drawn has p_interp > 0. */
static void test_mixture_draw_equals_scan(void **state) {
  (void)state;
  scene sc = make_scene(97, 250, 4);
  pc_irec_store *s = build(&sc, NULL);
  pc_rng r = pc_rng_make(4, 0, PC_STREAM_MISC, 3);
  int multi = 0;
  for (int q = 0; q < 100; q++) {
    pc_irec_site z = {rand_point(&r), rand_dir_up(&r), rand_dir_up(&r), NULL, false};
    pc_irec_lookup L;
    pc_irec_lookup_cached(s, 0, &z, 1 + q % 12, 0.1f, &L);
    if (L.n == 0) continue;
    multi += L.n > 1;
    double start[PC_IREC_MAX_KNN + 1] = {0.0};
    for (int j = 0; j < L.n; j++) start[j + 1] = start[j] + L.w[j];
    for (int t = 0; t < 200 + L.n * (sc.V + 1); t++) {
      double xi;
      if (t < 200) {
        xi = (double)pc_rng_u32(&r) * 0x1p-32;
      } else {
        int j = (t - 200) / (sc.V + 1), i = (t - 200) % (sc.V + 1);
        xi = i == sc.V ? start[j] : start[j] + L.w[j] * (double)L.cmf[j][i];
      }
      if (!(xi < 1.0)) continue;
      int j = 0;
      while (j < L.n - 1 && !(xi < start[j + 1])) j++;
      double x = (xi - start[j]) / L.w[j];
      if (!(x < 1.0)) x = 0x1.fffffffffffffp-1;
      int lin = 0;
      while (!((double)L.cmf[j][lin] > x)) lin++;
      int drawn = pc_irec_interp_sample(&L, xi);
      assert_int_equal(drawn, lin);
      assert_true(L.pmf[j][drawn] > 0.f);
      assert_true(pc_irec_interp_pmf(&L, drawn) > 0.0);
    }
  }
  assert_true(multi > 50);
  pc_irec_destroy(s);
  free_scene(&sc);
}

static void test_memory_and_limit(void **state) {
  (void)state;
  scene sc = make_scene(200, 300, 5);
  const size_t R = 300, V = 200, nthreads = 4;
  pc_irec_store *s = build(&sc, NULL);
  size_t b = pc_irec_bytes(s), mass = 2 * R * V * sizeof(float);
  assert_true(b >= mass);
  /* plus the per-thread memo of neighbour sets: one 64-byte cache line per entry for knn 6 */
  assert_true(b - mass <= R * 128 + nthreads * (2 * V * sizeof(float) + PC_IREC_CACHE_CELLS * 64) + 4096);
  assert_true(pc_irec_bytes_needed(s, 300, 200) == b);
  pc_irec_destroy(s);

  /* A limit below the need is refused with the figures; exactly the need is accepted. */
  pc_err e = {0};
  assert_int_equal(pc_irec_create(4, 6, mass, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, sc.sites, 300, 200, importance, &sc, NULL, &e), PC_ELIMIT);
  assert_non_null(strstr(e.msg, "300 records x 200 light vertices"));
  assert_non_null(strstr(e.msg, "limit"));
  assert_int_equal(pc_irec_count(s), 0);
  size_t need = pc_irec_bytes_needed(s, 300, 200);
  pc_irec_destroy(s);
  assert_int_equal(pc_irec_create(4, 6, need, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, sc.sites, 300, 200, importance, &sc, NULL, &e), PC_OK);
  assert_true(pc_irec_bytes(s) <= need);
  /* Reshaped builds never hold more than the limit, even with capacities kept. */
  assert_int_equal(pc_irec_build(s, sc.sites, 30, 200, importance, &sc, NULL, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, sc.sites, 300, 100, importance, &sc, NULL, &e), PC_OK);
  assert_true(pc_irec_bytes(s) <= need);
  /* Overflowing figures are a limit error too, not a wrapped allocation. */
  assert_int_equal(pc_irec_build(s, sc.sites, 2000000000, 2000000000, importance, &sc, NULL, &e), PC_ELIMIT);
  pc_irec_destroy(s);
  free_scene(&sc);
}

/* The neighbour-set memo grows with the records (~16 entries per record, at least
 * PC_IREC_CACHE_CELLS per thread, at most 64 MiB over all threads), counts in the bytes held
 * and the limit, and shrinks again; lookups through it equal those of a twin store asked from
 * other threads (ASan runs this too: entries stay in their thread's part of the grown table). */
static void test_memo_grows(void **state) {
  (void)state;
  scene sc = make_scene(20, 2000, 8);
  pc_irec_store *s = build(&sc, NULL), *direct = NULL; /* the twin */
  pc_err e = {0};
  const size_t nthreads = 4, entry = 64;
  size_t mass = 2 * 2000 * 20 * sizeof(float), memo = nthreads * 32768 * entry; /* 16 * 2000 -> 2^15 */
  assert_true(pc_irec_bytes(s) >= mass + memo && pc_irec_bytes(s) < mass + memo + (1u << 20));
  assert_true(pc_irec_bytes_needed(s, 2000, 20) == pc_irec_bytes(s));
  assert_int_equal(pc_irec_create(4, 6, 64u << 20, &direct, &e), PC_OK);
  assert_int_equal(pc_irec_build(direct, sc.sites, sc.R, sc.V, importance, &sc, NULL, &e), PC_OK);
  pc_rng r = pc_rng_make(8, 0, PC_STREAM_MISC, 1);
  int looked = 0;
  for (int q = 0; q < 2000; q++) {
    /* near the records, so that many lookups share a cell and hit the memo */
    pc_irec_site z = sc.sites[q % 50];
    z.p = v3_add(z.p, v3_scale(rand_point(&r), 0.01f));
    pc_irec_lookup a, b;
    pc_irec_lookup_cached(s, q % 4, &z, 6, 0.1f, &a);
    pc_irec_lookup_cached(direct, 3 - q % 4, &z, 6, 0.1f, &b);
    assert_int_equal(a.n, b.n);
    for (int j = 0; j < a.n; j++) {
      assert_true(a.w[j] == b.w[j]);
      assert_memory_equal(a.pmf[j], b.pmf[j], 20 * sizeof(float));
    }
    looked += a.n > 0;
  }
  assert_true(looked > 1000);
  /* half the records (one step smaller) keep the memo: R varies between iterations */
  assert_int_equal(pc_irec_build(s, sc.sites, 1000, sc.V, importance, &sc, NULL, &e), PC_OK);
  assert_true(pc_irec_bytes(s) >= mass + memo);
  /* a build of far fewer records gives the memory back */
  assert_int_equal(pc_irec_build(s, sc.sites, 30, sc.V, importance, &sc, NULL, &e), PC_OK);
  assert_true(pc_irec_bytes(s) < mass + nthreads * PC_IREC_CACHE_CELLS * entry + (1u << 20));
  pc_irec_destroy(direct);
  pc_irec_destroy(s);
  free_scene(&sc);

  /* 16 threads and 20000 records would want 2^19 entries each: capped at 64 MiB in all */
  sc = make_scene(2, 20000, 9);
  assert_int_equal(pc_irec_create(16, 6, 1u << 30, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, sc.sites, sc.R, sc.V, importance, &sc, NULL, &e), PC_OK);
  size_t cap = (size_t)64 << 20, rest = pc_irec_bytes(s) - cap;
  assert_true(pc_irec_bytes(s) > cap && rest < (4u << 20));
  pc_irec_destroy(s);
  free_scene(&sc);
}

static void test_bad_importance(void **state) {
  (void)state;
  scene sc = make_scene(20, 50, 6);
  sc.nan_record = 17;
  pc_irec_store *s = NULL;
  pc_err e = {0};
  assert_int_equal(pc_irec_create(1, 6, 1u << 20, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, sc.sites, sc.R, sc.V, importance, &sc, NULL, &e), PC_ENUMERIC);
  assert_non_null(strstr(e.msg, "record 17"));
  assert_int_equal(pc_irec_count(s), 0);
  pc_irec_lookup L;
  assert_int_equal(pc_irec_lookup_exact(s, 0, &sc.sites[17], importance, &sc, 0.1f, &L, &e), PC_OK); /* V = 0 */
  assert_int_equal(pc_irec_build(s, sc.sites, 0, sc.V, importance, &sc, NULL, &e), PC_OK);
  assert_int_equal(pc_irec_lookup_exact(s, 0, &sc.sites[17], importance, &sc, 0.1f, &L, &e), PC_ENUMERIC);
  pc_irec_destroy(s);
  free_scene(&sc);
}

/* No record with a PMF nearby: uniform with u > 0, nothing drawn with u = 0. Records facing
 * away only: uniform. u = 1: exactly uniform. */
static void test_fallbacks(void **state) {
  (void)state;
  scene sc = make_scene(30, 40, 7);
  for (int i = 0; i < sc.R; i++) sc.sites[i].p.z = -1.f - (float)i; /* all in the basement */
  pc_irec_store *s = build(&sc, NULL);
  pc_irec_site z = {v3(0.5f, 0.5f, -0.5f), v3(0, 0, 1), v3(0, 0, 1), NULL, false};
  pc_irec_lookup L;
  pc_rng r = pc_rng_make(7, 0, PC_STREAM_MISC, 0);
  int v;
  double p;
  pc_irec_lookup_cached(s, 0, &z, 6, 0.f, &L);
  assert_int_equal(L.n, 0);
  assert_int_equal(pc_irec_sample(&L, &r, &v, &p), 0);
  assert_true(pc_irec_pconn(&L, 0) == 0.0);
  pc_irec_lookup_cached(s, 0, &z, 6, 0.2f, &L);
  assert_int_equal(pc_irec_sample(&L, &r, &v, &p), 1);
  assert_true(fabs(p - 1.0 / sc.V) < 1e-12);
  chi_square(&L, 50000, 70);
  pc_irec_destroy(s);

  /* Two records, normals opposite to the query's: both dropped, and p_conn is uniform even
   * with u = 0. */
  pc_irec_site two[2] = {{v3(0.5f, 0.5f, 0.5f), v3(0, 0, -1), v3(0, 0, -1), NULL, false},
                         {v3(0.5f, 0.5f, 0.9f), v3(0, 0, -1), v3(0, 0, -1), NULL, false}};
  s = NULL;
  pc_err e = {0};
  assert_int_equal(pc_irec_create(1, 6, 1u << 20, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, two, 2, sc.V, importance, &sc, NULL, &e), PC_OK);
  assert_true(pc_irec_total(s, 0) > 0.0 && pc_irec_total(s, 1) > 0.0);
  pc_irec_site up = {v3(0.5f, 0.5f, 0.6f), v3(0, 0, 1), v3(0, 0, 1), NULL, false};
  pc_irec_lookup_cached(s, 0, &up, 6, 0.f, &L);
  assert_int_equal(L.n, 0);
  assert_int_equal(pc_irec_sample(&L, &r, &v, &p), 1);
  for (int i = 0; i < sc.V; i++) assert_true(fabs(pc_irec_pconn(&L, i) - 1.0 / sc.V) < 1e-12);
  /* Same orientation: weights follow 1 - d_q / sum d (distances 0.1 and 0.3). */
  pc_irec_site down = {v3(0.5f, 0.5f, 0.6f), v3(0, 0, -1), v3(0, 0, -1), NULL, false};
  pc_irec_lookup_cached(s, 0, &down, 6, 0.f, &L);
  assert_int_equal(L.n, 2);
  assert_true(fabs(L.w[0] - 0.75 / 1.0) < 1e-5 && fabs(L.w[1] - 0.25) < 1e-5);
  /* Incoming directions apart (normals alike): dropped unless both ends are Lambertian. */
  pc_irec_site side = {v3(0.5f, 0.5f, 0.6f), v3(0, 0, -1), v3(0, 1, 0), NULL, false};
  pc_irec_lookup_cached(s, 0, &side, 6, 0.f, &L);
  assert_int_equal(L.n, 0);
  pc_irec_destroy(s);
  two[0].lambertian = two[1].lambertian = true;
  assert_int_equal(pc_irec_create(1, 6, 1u << 20, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, two, 2, sc.V, importance, &sc, NULL, &e), PC_OK);
  pc_irec_lookup_cached(s, 0, &side, 6, 0.f, &L);
  assert_int_equal(L.n, 0); /* the query itself is not Lambertian */
  side.lambertian = true;
  pc_irec_lookup_cached(s, 0, &side, 6, 0.f, &L);
  assert_int_equal(L.n, 2);
  assert_true(fabs(L.w[0] - 0.75) < 1e-5 && fabs(L.w[1] - 0.25) < 1e-5);
  /* One neighbour: its weight is 1 (no distance factor to rank it against). */
  pc_irec_lookup_cached(s, 0, &down, 1, 0.f, &L);
  assert_int_equal(L.n, 1);
  assert_true(L.w[0] == 1.0);
  /* Mixing weight 1 is the uniform PMF whatever the records say. */
  pc_irec_lookup_cached(s, 0, &down, 6, 1.f, &L);
  for (int i = 0; i < sc.V; i++) assert_true(fabs(pc_irec_pconn(&L, i) - 1.0 / sc.V) < 1e-12);
  pc_irec_destroy(s);
  free_scene(&sc);
}

/* The share of the light vertices record r's PMF is > 0 at. */
static double share_of(const pc_irec_store *s, int r) {
  int nz = 0, V = pc_irec_light_count(s);
  for (int v = 0; v < V; v++) nz += pc_irec_pmf(s, r)[v] > 0.f;
  return (double)nz / V;
}

/* A lookup's seen share is its records' shares weighted as the records are; it is 0 with no
 * record. pc_irec_lookup_dark: below the threshold the mix becomes the dark one (kept where no
 * record shapes p_conn) and sampling still follows p_conn; at or above it nothing changes. */
static void test_dark(void **state) {
  (void)state;
  scene sc = make_scene(30, 40, 7);
  pc_irec_site two[2] = {{v3(0.5f, 0.5f, 0.5f), v3(0, 0, -1), v3(0, 0, -1), NULL, false},
                         {v3(0.5f, 0.5f, 0.9f), v3(0, 0, -1), v3(0, 0, -1), NULL, false}};
  pc_irec_store *s = NULL;
  pc_err e = {0};
  assert_int_equal(pc_irec_create(1, 6, 1u << 20, &s, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, two, 2, sc.V, importance, &sc, NULL, &e), PC_OK);
  double s0 = share_of(s, 0), s1 = share_of(s, 1);
  assert_true(s0 > 0.0 && s0 < 1.0 && s1 > 0.0 && s1 < 1.0); /* some light vertices face away */
  pc_irec_site down = {v3(0.5f, 0.5f, 0.6f), v3(0, 0, -1), v3(0, 0, -1), NULL, false};
  pc_irec_lookup L;
  pc_irec_lookup_cached(s, 0, &down, 6, 0.3f, &L);
  assert_int_equal(L.n, 2);
  double seen = L.w[0] * (L.pmf[0] == pc_irec_pmf(s, 0) ? s0 : s1) + L.w[1] * (L.pmf[1] == pc_irec_pmf(s, 0) ? s0 : s1);
  assert_true(fabs(L.seen - seen) < 1e-6);
  assert_false(pc_irec_lookup_dark(&L, (float)(seen * 0.99), 0.9f));
  assert_true(L.u == 0.3f);
  assert_true(pc_irec_lookup_dark(&L, (float)(seen * 1.01), 0.9f));
  assert_true(L.u == 0.9f);
  chi_square(&L, 50000, 71);
  pc_irec_lookup_cached(s, 0, &down, 6, 0.3f, &L); /* 1: dark whatever the share */
  assert_true(pc_irec_lookup_dark(&L, 1.f, 0.9f));
  /* Records facing away: none is interpolated, the share is 0 and p_conn stays uniform. */
  pc_irec_site up = {v3(0.5f, 0.5f, 0.6f), v3(0, 0, 1), v3(0, 0, 1), NULL, false};
  pc_irec_lookup_cached(s, 0, &up, 6, 0.3f, &L);
  assert_int_equal(L.n, 0);
  assert_true(L.seen == 0.0);
  assert_true(pc_irec_lookup_dark(&L, 0.1f, 0.9f));
  assert_true(L.u == 1.f);
  pc_irec_destroy(s);
  free_scene(&sc);
}

static bool same_lookup(const pc_irec_lookup *a, const pc_irec_lookup *b) {
  if (a->n != b->n || a->V != b->V || a->u != b->u) return false;
  for (int j = 0; j < a->n; j++)
    if (a->w[j] != b->w[j] || memcmp(a->pmf[j], b->pmf[j], (size_t)a->V * sizeof(float))) return false;
  return true;
}

/* The record whose PMF row a lookup entry reads. */
static int record_of(const pc_irec_store *s, const float *pmf) {
  return (int)((pmf - pc_irec_pmf(s, 0)) / (pc_irec_pmf(s, 1) - pc_irec_pmf(s, 0)));
}

/* Thousands of scattered queries, most in a cell of their own, so that many cells share a memo
 * entry; visited three times in three orders, every lookup still equals a cold one (a second
 * store rebuilt over the same records before each reference lookup, so its memo holds nothing).
 * test_lookup_is_pure's few hundred queries meet no collision: a memo that checked the build
 * but not the cell passed it. */
static void test_lookup_pure_under_collisions(void **state) {
  (void)state;
  enum { Q = 4000 };
  scene a = make_scene(10, 1000, 9);
  pc_irec_store *s = NULL, *cold = NULL;
  pc_err e = {0};
  assert_int_equal(pc_irec_create(1, 6, 64u << 20, &s, &e), PC_OK);
  assert_int_equal(pc_irec_create(1, 6, 64u << 20, &cold, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, a.sites, a.R, a.V, importance, &a, NULL, &e), PC_OK);
  pc_irec_site *z = malloc(Q * sizeof *z);
  int (*ref)[PC_IREC_MAX_KNN + 1] = malloc(Q * sizeof *ref); /* the records' order in each lookup */
  pc_rng r = pc_rng_make(9, 0, PC_STREAM_MISC, 2);
  for (int q = 0; q < Q; q++) {
    z[q] = (pc_irec_site){rand_point(&r), rand_dir_up(&r), rand_dir_up(&r), NULL, false};
    assert_int_equal(pc_irec_build(cold, a.sites, a.R, a.V, importance, &a, NULL, &e), PC_OK);
    pc_irec_lookup L;
    pc_irec_lookup_cached(cold, 0, &z[q], 6, 0.1f, &L);
    ref[q][0] = L.n;
    for (int j = 0; j < L.n; j++) ref[q][j + 1] = record_of(cold, L.pmf[j]);
  }
  for (int pass = 0; pass < 3; pass++)
    for (int i = 0; i < Q; i++) {
      int q = pass == 0 ? i : pass == 1 ? Q - 1 - i : (int)(((long)i * 2593) % Q); /* 2593 is prime to Q */
      pc_irec_lookup L;
      pc_irec_lookup_cached(s, 0, &z[q], 6, 0.1f, &L);
      assert_int_equal(L.n, ref[q][0]);
      for (int j = 0; j < L.n; j++) assert_int_equal(record_of(s, L.pmf[j]), ref[q][j + 1]);
    }
  free(z);
  free(ref);
  pc_irec_destroy(s);
  pc_irec_destroy(cold);
  free_scene(&a);
}

/* A lookup is a pure function of the eye vertex: the same whichever thread asks, in whatever
 * order, with the per-thread memo of neighbour sets warm or cold, and never a stale set from
 * the previous build. */
static void test_lookup_is_pure(void **state) {
  (void)state;
  enum { Q = 400 };
  scene a = make_scene(60, 300, 8), b = make_scene(60, 300, 8);
  /* b: a's records in reverse order, so the cells (size and origin) are the same and a stale
   * memo entry would name the wrong records */
  for (int i = 0; i < b.R; i++) b.sites[i] = a.sites[b.R - 1 - i];
  pc_irec_store *s = NULL, *fresh = NULL;
  pc_err e = {0};
  assert_int_equal(pc_irec_create(3, 6, 64u << 20, &s, &e), PC_OK);
  assert_int_equal(pc_irec_create(1, 6, 64u << 20, &fresh, &e), PC_OK);
  assert_int_equal(pc_irec_build(s, a.sites, a.R, a.V, importance, &a, NULL, &e), PC_OK);
  assert_int_equal(pc_irec_build(fresh, a.sites, a.R, a.V, importance, &a, NULL, &e), PC_OK);
  pc_irec_site *z = malloc(Q * sizeof *z);
  pc_irec_lookup *ref = malloc(Q * sizeof *ref);
  pc_rng r = pc_rng_make(8, 0, PC_STREAM_MISC, 1);
  for (int q = 0; q < Q; q++) {
    /* pairs of nearby queries, as neighbouring pixels make */
    vec3 p = q % 2 ? v3_add(z[q - 1].p, v3s(0.003f)) : rand_point(&r);
    z[q] = (pc_irec_site){p, rand_dir_up(&r), rand_dir_up(&r), NULL, false};
    pc_irec_lookup_cached(fresh, 0, &z[q], 6, 0.1f, &ref[q]);
  }
  int filled = 0;
  for (int q = 0; q < Q; q++) {
    pc_irec_lookup L;
    pc_irec_lookup_cached(s, 0, &z[q], 6, 0.1f, &L);
    filled += L.n > 1;
    assert_true(same_lookup(&L, &ref[q]) || !"thread 0 in order");
    pc_irec_lookup_cached(s, 2, &z[Q - 1 - q], 6, 0.1f, &L);
    assert_true(same_lookup(&L, &ref[Q - 1 - q]) || !"thread 2 in reverse");
  }
  assert_true(filled > Q / 2);
  /* Rebuild over other records: the warm memo of thread 0 must not leak the old sets. */
  assert_int_equal(pc_irec_build(s, b.sites, b.R, b.V, importance, &b, NULL, &e), PC_OK);
  pc_irec_destroy(fresh);
  assert_int_equal(pc_irec_create(1, 6, 64u << 20, &fresh, &e), PC_OK);
  assert_int_equal(pc_irec_build(fresh, b.sites, b.R, b.V, importance, &b, NULL, &e), PC_OK);
  for (int q = 0; q < Q; q++) {
    pc_irec_lookup L, F;
    pc_irec_lookup_cached(s, 0, &z[q], 6, 0.1f, &L);
    pc_irec_lookup_cached(fresh, 0, &z[q], 6, 0.1f, &F);
    assert_true(same_lookup(&L, &F) || !"after a rebuild");
  }
  free(z);
  free(ref);
  pc_irec_destroy(s);
  pc_irec_destroy(fresh);
  free_scene(&a);
  free_scene(&b);
}


/* Resampling: a synthetic p_conn (one PMF with a zero entry, mixed with the uniform PMF), a
 * target h that disagrees with the contribution c (c = h * g with g in [0, 2], one vertex with
 * h = c = 0) and ncand = 3 candidates with stratified component choices. The exact law of a
 * selection is enumerated independently of the code under test: for each interval of the
 * stratification number xi the candidates are independent with known component PMFs, and a
 * candidate tuple selects slot j with probability (h_j / p_j) / sum. Checked: the selected
 * vertices (the K selections together) follow it (chi-square), the estimate c(v) * factor averages sum_v c(v) (within 5
 * measured standard errors), and a vertex with h = 0 is never selected. The same with a target
 * that knows visibility (--pcbpt-candidate-visibility traced: h = 0 exactly where c = 0, so
 * an occluded candidate, vertex 4, is never selected and all-occluded candidates give 0). */
#define RS_V 6
#define RS_N 3
static const float rs_h[RS_V] = {0.2f, 1.5f, 0.f, 0.7f, 3.f, 0.05f};
static const float rs_g[RS_V] = {1.9f, 0.3f, 0.f, 1.f, 0.f, 2.f}; /* c = h * g: zero where occluded */
static const float rs_h_traced[RS_V] = {0.2f, 1.5f, 0.f, 0.7f, 0.f, 0.05f}; /* rs_h, visibility known */

typedef struct rs_user {
  const float *h;
  int seen[RS_N];
} rs_user;

static float rs_target(void *user, int slot, int v) {
  rs_user *u = user;
  u->seen[slot] = v;
  return u->h[v];
}

static void check_resample(const float *h) {
  const float pmf[RS_V] = {0.4f, 0.f, 0.1f, 0.25f, 0.05f, 0.2f};
  float cmf[RS_V];
  double run = 0.0;
  for (int v = 0; v < RS_V; v++) cmf[v] = (float)(run += pmf[v]);
  pc_irec_lookup L = {.V = RS_V, .u = 0.3f, .n = 1, .w = {1.0}, .pmf = {pmf}, .cmf = {cmf}};
  /* Candidate j is uniform iff (j + xi) / N < u, i.e. xi < uN - j: the patterns change at
   * those breakpoints. */
  double expect[RS_V] = {0}, sum_c = 0.0;
  for (int v = 0; v < RS_V; v++) sum_c += h[v] * rs_g[v];
  double lo = 0.0;
  for (int piece = 0; piece <= RS_N; piece++) {
    double hi = 1.0;
    for (int j = 0; j < RS_N; j++) {
      double b = (double)L.u * RS_N - j;
      if (b > lo && b < hi) hi = b;
    }
    if (!(hi > lo)) break;
    double mid = 0.5 * (lo + hi), q[RS_N][RS_V];
    for (int j = 0; j < RS_N; j++)
      for (int v = 0; v < RS_V; v++) q[j][v] = ((double)j + mid) / RS_N < L.u ? 1.0 / RS_V : pmf[v];
    for (int t = 0; t < RS_V * RS_V * RS_V; t++) {
      int vs[RS_N] = {t % RS_V, t / RS_V % RS_V, t / (RS_V * RS_V)};
      double prob = hi - lo, w[RS_N], wsum = 0.0;
      for (int j = 0; j < RS_N; j++) {
        prob *= q[j][vs[j]];
        w[j] = h[vs[j]] / pc_irec_pconn(&L, vs[j]);
        wsum += w[j];
      }
      if (prob == 0.0 || wsum == 0.0) continue;
      for (int j = 0; j < RS_N; j++) expect[vs[j]] += prob * w[j] / wsum;
    }
    lo = hi;
  }
  assert_true(expect[2] == 0.0);
  enum { TRIALS = 300000, NSEL = 2 };
  double count[NSEL][RS_V] = {{0}}, est = 0.0, est2 = 0.0;
  pc_rng rng = pc_rng_make(5, 0, PC_STREAM_MISC, 0);
  for (int i = 0; i < TRIALS; i++) {
    rs_user user = {h, {0}};
    int slot[NSEL];
    double factor[NSEL], x = 0.0;
    int n = pc_irec_resample(&L, RS_N, NSEL, (double)pc_rng_f(&rng), &rng, rs_target, &user, slot, factor);
    for (int k = 0; k < n; k++) {
      int v = user.seen[slot[k]];
      assert_true(h[v] > 0.f);
      count[k][v] += 1.0;
      x += h[v] * rs_g[v] * factor[k] / n;
    }
    est += x;
    est2 += x * x;
  }
  /* The selections are stratified over one number: each alone is not distributed by the law,
   * their union is (the estimate averages them). */
  pc_chi2_cell cells[RS_V];
  for (int v = 0; v < RS_V; v++) cells[v] = (pc_chi2_cell){count[0][v] + count[1][v], expect[v] * NSEL * TRIALS};
  double stat;
  int dof;
  assert_true(pc_chi2_test(cells, RS_V, &stat, &dof) > 0.001);
  double mean = est / TRIALS, se = sqrt((est2 / TRIALS - mean * mean) / TRIALS);
  assert_true(fabs(mean - sum_c) < 5.0 * se);
  /* Nothing to select when every candidate's target is 0, or p_conn is undefined. */
  rs_user user = {h, {0}};
  int slot[1];
  double factor[1];
  const float zero_pmf[RS_V] = {0.f, 0.f, 1.f, 0.f, 0.f, 0.f}, zero_cmf[RS_V] = {0.f, 0.f, 1.f, 1.f, 1.f, 1.f};
  pc_irec_lookup Z = {.V = RS_V, .u = 0.f, .n = 1, .w = {1.0}, .pmf = {zero_pmf}, .cmf = {zero_cmf}};
  assert_int_equal(pc_irec_resample(&Z, RS_N, 1, 0.5, &rng, rs_target, &user, slot, factor), 0);
  Z.n = 0;
  assert_int_equal(pc_irec_resample(&Z, RS_N, 1, 0.5, &rng, rs_target, &user, slot, factor), 0);
}

static void test_resample(void **state) {
  (void)state;
  check_resample(rs_h);
  check_resample(rs_h_traced);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_record_rows),       cmocka_unit_test(test_interpolated_pmf),
      cmocka_unit_test(test_sampling_matches_pconn), cmocka_unit_test(test_mixture_draw_equals_scan),
      cmocka_unit_test(test_memory_and_limit),  cmocka_unit_test(test_memo_grows),  cmocka_unit_test(test_lookup_is_pure),  cmocka_unit_test(test_lookup_pure_under_collisions),  cmocka_unit_test(test_bad_importance),
      cmocka_unit_test(test_fallbacks),         cmocka_unit_test(test_dark),         cmocka_unit_test(test_resample),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
