/* test_pcbpt.c: CBDPT and PCBPT are unbiased (their furnace checks are in test_furnace.c). On
 * the Cornell box the strategies they share with BDPT (pt, nee, lt)
 * are bit-identical to BDPT's for the same seed (same streams, same upper-bound counts), and
 * the inner layer's block means of BDPT, CBDPT, PCBPT (cached, cached with resampled
 * connections whose target knows visibility from the records, from traced shadow rays or
 * from both, exact, --mis standard or a count between 1 and M) and
 * PCBPT with a uniform PMF and K about V (M = 20 paths, ~60 vertices) agree within 4.5
 * combined standard errors measured from independent iterations. (Uniform PCBPT with K = V
 * equals CBDPT in expectation, not sample by sample: its K draws are i.i.d.) With --mis
 * standard or a count other than 1 the inner layer has other weights, so it is compared through
 * the beauty image, and the shared layers are no longer BDPT's. On ajar-door, where the records'
 * visibility is most often wrong, PCBPT whose resampling takes visibility from the records
 * agrees with PCBPT whose candidates are traced.
 * Every shipped scene renders finite with CBDPT and both PCBPT PMF modes. pc_renderer_check
 * refuses what pc_renderer_create refuses without building films of the image's size. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <string.h>
#include <sys/resource.h>

#include "pcbpt.h"
#include "stat_util.h"

static pc_render_request request(pc_method method, int res, int depth) {
  pc_render_request req;
  pc_render_request_default(&req);
  req.set.method = method;
  req.method_set = true;
  req.set.max_depth = depth;
  req.depth_set = true;
  req.set.width = req.set.height = res;
  req.width_set = req.height_set = true;
  req.set.seed = 4321;
  req.set.pcbpt_m = 20;
  req.set.pcbpt_k = 2;
  req.set.cache_fraction = 0.05f;
  return req;
}

#define RES 24
#define BS 8
#define ITER 40

/* Renders iterations [0, n) and returns the film of their sum. */
static void render_film(const pc_scene *scene, const pc_render_settings *set, int n, pc_film *film) {
  pc_err e = {0};
  pc_renderer *r = NULL;
  assert_int_equal(pc_film_init(film, set->width, set->height, 0, &e), 0);
  assert_int_equal(pc_renderer_create(scene, set, 2, &r, &e), 0);
  assert_int_equal(pc_render_iterations(r, 0, (uint64_t)n, film, NULL, NULL, NULL, NULL, &e), 0);
  pc_renderer_destroy(r);
}

static void test_shared_layers_equal_bdpt(void **state) {
  (void)state;
  const pc_method methods[] = {PC_METHOD_CBDPT, PC_METHOD_PCBPT};
  pc_render_request rb = request(PC_METHOD_BDPT, 16, -1);
  pc_scene scene = {0};
  assert_int_equal(stat_load("cornell-box", &rb, &scene), 0);
  pc_film fb;
  render_film(&scene, &rb.set, 2, &fb);
  for (int m = 0; m < 2; m++) {
    pc_render_settings set = rb.set;
    set.method = methods[m];
    set.mis_mode = PC_MIS_UPPER_BOUND; /* BDPT's counts: any other count reweights every strategy */
    pc_film f;
    render_film(&scene, &set, 2, &f);
    for (int l = 0; l < PC_LAYER_STD_COUNT; l++) {
      if (l == PC_LAYER_INNER) continue;
      assert_int_equal(f.layers[l].count, fb.layers[l].count);
      assert_memory_equal(f.layers[l].sum, fb.layers[l].sum, sizeof(double) * 3 * 16 * 16);
    }
    pc_film_free(&f);
  }
  /* With the default count (2) the same paths are weighted otherwise: next-event estimation
   * gives up part of what the inner strategies now take, so its layer is no longer BDPT's */
  pc_render_settings set = rb.set;
  set.method = PC_METHOD_PCBPT;
  pc_film f;
  render_film(&scene, &set, 2, &f);
  assert_memory_not_equal(f.layers[PC_LAYER_NEE].sum, fb.layers[PC_LAYER_NEE].sum, sizeof(double) * 3 * 16 * 16);
  pc_film_free(&f);
  pc_film_free(&fb);
  pc_scene_free(&scene);
}

typedef struct variant {
  const char *name;
  pc_method method;
  pc_pmf_mode pmf;
  pc_mis_mode mis;
  float u;
  int k;
  int candidates; /* resampling candidates (1: none) */
  pc_candidate_visibility vis;
  int layer; /* compared layer: PC_LAYER_INNER or -1 (beauty) */
  float count; /* PC_MIS_COUNT: the inner strategies' count */
  float rate;  /* --pcbpt-rate */
  float dark;  /* --pcbpt-dark-seen (0: no dark eye vertices) */
} variant;

static void test_inner_agrees(void **state) {
  (void)state;
  pc_render_request req = request(PC_METHOD_BDPT, RES, -1);
  pc_scene scene = {0};
  assert_int_equal(stat_load("cornell-box", &req, &scene), 0);
  const variant vs[] = {
      {"cbdpt", PC_METHOD_CBDPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.1f, 1, 1, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.1f, 2, 1, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt-resampled", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.1f, 2, 4, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt-resampled-k1", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.5f, 1, 8, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt-traced-k1", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.5f, 1, 8, PC_CANDVIS_TRACED, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt-uncertain", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.1f, 2, 4, PC_CANDVIS_UNCERTAIN, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt-exact", PC_METHOD_PCBPT, PC_PMF_EXACT, PC_MIS_UPPER_BOUND, 0.1f, 2, 1, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt-uniform", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 1.f, 60, 1, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 1.f, 0.f},
      {"pcbpt-mis-standard", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_STANDARD, 0.1f, 2, 1, PC_CANDVIS_RECORDS, -1, 0.f, 1.f, 0.f},
      {"pcbpt-mis-std-resampled", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_STANDARD, 0.1f, 2, 4, PC_CANDVIS_RECORDS, -1, 0.f, 1.f, 0.f},
      {"pcbpt-mis-std-traced", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_STANDARD, 0.1f, 2, 4, PC_CANDVIS_TRACED, -1, 0.f, 1.f, 0.f},
      {"pcbpt-mis-count", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_COUNT, 0.5f, 1, 1, PC_CANDVIS_RECORDS, -1, 3.f, 1.f, 0.f},
      {"pcbpt-mis-count-traced", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_COUNT, 0.85f, 1, 3, PC_CANDVIS_TRACED, -1, 7.5f, 1.f, 0.f},
      {"pcbpt-rate", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_COUNT, 0.5f, 1, 1, PC_CANDVIS_RECORDS, -1, 2.f, 0.3f, 0.f},
      {"pcbpt-rate-traced", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.85f, 1, 3, PC_CANDVIS_TRACED, PC_LAYER_INNER, 0.f, 0.5f, 0.f},
      {"cbdpt-rate", PC_METHOD_CBDPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.1f, 1, 1, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 0.4f, 0.f},
      /* Every eye vertex dark: three candidates resampled at mix 0.85, traced or by the
       * records' visibility. */
      {"pcbpt-dark", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.1f, 2, 1, PC_CANDVIS_TRACED, PC_LAYER_INNER, 0.f, 1.f, 1.f},
      {"pcbpt-dark-records", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 0.5f, 1, 1, PC_CANDVIS_RECORDS, PC_LAYER_INNER, 0.f, 1.f, 1.f},
      /* Some dark (the default share), with a count */
      {"pcbpt-dark-default", PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_COUNT, 0.5f, 1, 1, PC_CANDVIS_TRACED, -1, 2.f, 1.f, 0.1f},
  };
  const int nv = sizeof vs / sizeof vs[0];
  stat_blocks ref_inner, ref_beauty;
  assert_int_equal(stat_render_blocks(&scene, &req.set, 2, 0, ITER, PC_LAYER_INNER, BS, &ref_inner), 0);
  assert_int_equal(stat_render_blocks(&scene, &req.set, 2, 0, ITER, -1, BS, &ref_beauty), 0);
  for (int i = 0; i < nv; i++) {
    pc_render_settings set = req.set;
    set.method = vs[i].method;
    set.pmf_mode = vs[i].pmf;
    set.mis_mode = vs[i].mis;
    if (vs[i].mis == PC_MIS_COUNT) set.mis_count = vs[i].count;
    set.uniform_mix = vs[i].u;
    set.pcbpt_k = vs[i].k;
    set.pcbpt_candidates = vs[i].candidates;
    set.candidate_visibility = vs[i].vis;
    set.pcbpt_rate = vs[i].rate;
    set.pcbpt_dark_seen = vs[i].dark;
    stat_blocks st;
    const stat_blocks *ref = vs[i].layer < 0 ? &ref_beauty : &ref_inner;
    assert_int_equal(stat_render_blocks(&scene, &set, 2, 1000, ITER, vs[i].layer, BS, &st), 0);
    double worst = stat_largest_z(&st, ref);
    assert_true(worst <= 4.5);
    printf("%-6s %-18s vs bdpt: worst block |z| %.2f over %d blocks\n", vs[i].layer < 0 ? "beauty" : "inner", vs[i].name, worst, st.nblocks);
    stat_free(&st);
  }
  stat_free(&ref_inner);
  stat_free(&ref_beauty);
  pc_scene_free(&scene);
}

/* The dark rule changes the inner draws where it fires (so the variants above test it) and no
 * other strategy: the layers PCBPT shares with BDPT stay bit-identical. */
static void test_dark_touches_inner_only(void **state) {
  (void)state;
  pc_render_request req = request(PC_METHOD_PCBPT, 16, -1);
  pc_scene scene = {0};
  assert_int_equal(stat_load("cornell-box", &req, &scene), 0);
  pc_render_settings off = req.set, on = req.set;
  off.pcbpt_dark_seen = 0.f;
  on.pcbpt_dark_seen = 1.f;
  pc_film a, b;
  render_film(&scene, &off, 2, &a);
  render_film(&scene, &on, 2, &b);
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) {
    if (l == PC_LAYER_INNER) assert_memory_not_equal(a.layers[l].sum, b.layers[l].sum, sizeof(double) * 3 * 16 * 16);
    else assert_memory_equal(a.layers[l].sum, b.layers[l].sum, sizeof(double) * 3 * 16 * 16);
  }
  pc_film_free(&a);
  pc_film_free(&b);
  pc_scene_free(&scene);
}

/* --pcbpt-unseen-rate: in an iteration none of whose records sees a light vertex, an eye
 * vertex connects with probability R and counts 1/R. One stored path, the records of one cache
 * path and paths of at most 3 segments (s = t = 2 only) make such iterations common on the
 * Cornell box (a record on the floor sees nothing of a light vertex on the floor) while other
 * eye vertices do see the light vertex, so enough of the inner layer comes from them that
 * leaving out the 1/R fails this (4 blocks of 12x12, 640 iterations a side): the layer agrees
 * with BDPT's at R = 0.25 and 0.5, and with R = 1. */
static void test_unseen_rate_agrees(void **state) {
  (void)state;
  pc_render_request req = request(PC_METHOD_BDPT, RES, 3);
  pc_scene scene = {0};
  assert_int_equal(stat_load("cornell-box", &req, &scene), 0);
  stat_blocks ref;
  assert_int_equal(stat_render_blocks(&scene, &req.set, 2, 0, 16 * ITER, PC_LAYER_INNER, 12, &ref), 0);
  const float rates[] = {0.25f, 0.5f, 1.f};
  for (int i = 0; i < 3; i++) {
    pc_render_settings set = req.set;
    set.method = PC_METHOD_PCBPT;
    set.mis_mode = PC_MIS_UPPER_BOUND;
    set.pcbpt_m = 1;
    set.pcbpt_k = 1;
    set.knn = 1;
    set.cache_fraction = 1.f / (RES * RES);
    set.pcbpt_unseen_rate = rates[i];
    stat_blocks st;
    assert_int_equal(stat_render_blocks(&scene, &set, 2, 1000, 16 * ITER, PC_LAYER_INNER, 12, &st), 0);
    double worst = stat_largest_z(&st, &ref);
    assert_true(worst <= 4.5);
    printf("inner  unseen rate %.2f vs bdpt: worst block |z| %.2f over %d blocks\n", (double)rates[i], worst, st.nblocks);
    stat_free(&st);
  }
  stat_free(&ref);
  pc_scene_free(&scene);
}

/* Resampling whose target takes visibility from the records (--pcbpt-candidate-visibility
 * records): where no interpolated record sees a light vertex the target keeps a floor, since
 * the eye vertex may see it all the same. A target of 0 there never chooses such a candidate and
 * biases the estimate; a vanishing one (seen x h alone, which the target's underflow guard
 * turns into FLT_MIN) chooses it almost never and then with a weight of ~1/FLT_MIN, unbiased on
 * paper but with its mean in a tail no run reaches. ajar-door is the scene where the records'
 * visibility is most often wrong (they see ~2% of the light vertices; the eye vertices'
 * connections come mostly from the others), so its inner layer with the records' visibility
 * must agree block by block with the same method's with traced candidates (both PCBPT: far less
 * noise than BDPT's there). 640 iterations a side: worst block |z| 1.70 with the floor (1.4-3.3
 * over three offsets of the records run's iterations), 17.2 with a target of 0 there, and
 * 5.5-7.5 with the vanishing one. */
static void test_records_visibility_agrees(void **state) {
  (void)state;
  pc_render_request req = request(PC_METHOD_PCBPT, 32, -1);
  pc_scene scene = {0};
  assert_int_equal(stat_load("ajar-door", &req, &scene), 0);
  pc_render_settings traced = req.set, records = req.set;
  traced.mis_mode = records.mis_mode = PC_MIS_UPPER_BOUND;
  traced.pcbpt_candidates = records.pcbpt_candidates = 3;
  traced.candidate_visibility = PC_CANDVIS_TRACED;
  records.candidate_visibility = PC_CANDVIS_RECORDS;
  stat_blocks ref, st;
  assert_int_equal(stat_render_blocks(&scene, &traced, 2, 0, 16 * ITER, PC_LAYER_INNER, 16, &ref), 0);
  assert_int_equal(stat_render_blocks(&scene, &records, 2, 1000, 16 * ITER, PC_LAYER_INNER, 16, &st), 0);
  double worst = stat_largest_z(&st, &ref);
  printf("inner  candidates' visibility from the records vs traced: worst block |z| %.2f over %d blocks\n", worst, st.nblocks);
  assert_true(worst <= 4.5);
  stat_free(&st);
  stat_free(&ref);
  pc_scene_free(&scene);
}

/* The inner strategies' MIS count: 2 by default, 1 for the upper bound, M for standard
 * weights, a count otherwise, at most M; counts below 1 are refused. */
static void test_inner_count(void **state) {
  (void)state;
  pc_render_settings s;
  pc_render_settings_default(&s);
  s.pcbpt_m = 5;
  assert_true(pc_render_settings_inner_count(&s) == 2.f);
  s.mis_mode = PC_MIS_UPPER_BOUND;
  assert_true(pc_render_settings_inner_count(&s) == 1.f);
  s.mis_mode = PC_MIS_STANDARD;
  assert_true(pc_render_settings_inner_count(&s) == 5.f);
  s.mis_mode = PC_MIS_COUNT;
  s.mis_count = 3.5f;
  assert_true(pc_render_settings_inner_count(&s) == 3.5f);
  s.mis_count = 7.f;
  assert_true(pc_render_settings_inner_count(&s) == 5.f);
  pc_err e = {0};
  s.method = PC_METHOD_PCBPT;
  s.width = s.height = 16;
  assert_int_equal(pc_render_settings_check(&s, &e), PC_OK);
  s.mis_count = 0.5f;
  assert_int_not_equal(pc_render_settings_check(&s, &e), PC_OK);
  s.mis_count = NAN;
  assert_int_not_equal(pc_render_settings_check(&s, &e), PC_OK);
}

/* No NaN or Inf on any shipped scene (glass and mirrors included), per-strategy layers on. */
static void test_all_scenes_finite(void **state) {
  (void)state;
  static const char *const scenes[] = {"cornell-box", "furnace", "ajar-door", "slit-room", "open-room", "glossy-glass"};
  /* cbdpt; pcbpt cached, exact, and cached with resampled connections (records' visibility,
   * traced) */
  const pc_method methods[] = {PC_METHOD_CBDPT, PC_METHOD_PCBPT, PC_METHOD_PCBPT, PC_METHOD_PCBPT, PC_METHOD_PCBPT};
  for (size_t si = 0; si < sizeof scenes / sizeof scenes[0]; si++)
    for (int mi = 0; mi < 5; mi++) {
      pc_render_request req = request(methods[mi], 24, -1);
      req.set.height = 20;
      req.set.strategy_layers = 4;
      req.set.pmf_mode = mi == 2 ? PC_PMF_EXACT : PC_PMF_CACHED;
      req.set.pcbpt_candidates = mi >= 3 ? 4 : 1;
      req.set.candidate_visibility = mi == 4 ? PC_CANDVIS_TRACED : PC_CANDVIS_RECORDS;
      pc_scene scene = {0};
      assert_int_equal(stat_load(scenes[si], &req, &scene), 0);
      pc_film film;
      pc_err e = {0};
      pc_renderer *r = NULL;
      assert_int_equal(pc_film_init(&film, req.set.width, req.set.height, req.set.strategy_layers, &e), 0);
      assert_int_equal(pc_renderer_create(&scene, &req.set, 2, &r, &e), 0);
      pc_render_stats st = {0};
      assert_int_equal(pc_render_iterations(r, 0, 3, &film, &st, NULL, NULL, NULL, &e), 0);
      assert_true(pc_film_is_finite(&film));
      /* Records are reported for cached PCBPT only (the exact mode's store holds scratch). */
      if (mi == 0) assert_int_equal(st.pmf_bytes, 0);
      if (mi == 1 || mi >= 3) assert_true(st.pmf_bytes > 0);
      assert_int_equal(film.dropped_nonfinite, 0);
      pc_renderer_destroy(r);
      pc_film_free(&film);
      pc_scene_free(&scene);
    }
}

/* The stored light vertices and the records are gathered in path order: a render is the same
 * bit for bit with 1 and with 3 threads. */
static void test_thread_count_invariant(void **state) {
  (void)state;
  pc_render_request req = request(PC_METHOD_PCBPT, 32, -1);
  pc_scene scene = {0};
  assert_int_equal(stat_load("ajar-door", &req, &scene), 0);
  pc_film film[2];
  for (int i = 0; i < 2; i++) {
    pc_err e = {0};
    pc_renderer *r = NULL;
    assert_int_equal(pc_film_init(&film[i], req.set.width, req.set.height, 0, &e), 0);
    assert_int_equal(pc_renderer_create(&scene, &req.set, i == 0 ? 1 : 3, &r, &e), 0);
    assert_int_equal(pc_render_iterations(r, 0, 2, &film[i], NULL, NULL, NULL, NULL, &e), 0);
    pc_renderer_destroy(r);
  }
  for (int l = 0; l < film[0].nlayers; l++)
    assert_memory_equal(film[0].layers[l].sum, film[1].layers[l].sum, (size_t)req.set.width * (size_t)req.set.height * 3 * sizeof(double));
  pc_film_free(&film[0]);
  pc_film_free(&film[1]);
  pc_scene_free(&scene);
}

/* The CLI's check of a job's settings builds no film of the image's size (a renderer at
 * 2048x2048 writes 0.1 GB per layer it stores, 0.5 GB on one thread: the peak memory would
 * show it), and refuses what pc_renderer_create refuses, with the same message. */
static long peak_kb(void) {
  struct rusage u;
  assert_int_equal(getrusage(RUSAGE_SELF, &u), 0);
  return u.ru_maxrss;
}

static void test_renderer_check(void **state) {
  (void)state;
  pc_render_request req = request(PC_METHOD_PCBPT, 16, -1);
  pc_scene scene = {0};
  assert_int_equal(stat_load("cornell-box", &req, &scene), 0);
  pc_render_settings big = req.set;
  big.width = big.height = 2048;
  pc_err e = {0};
  long before = peak_kb();
  assert_int_equal(pc_renderer_check(&scene, &big, &e), PC_OK);
  assert_true(peak_kb() - before < 64 * 1024);
  big.width = PC_SCENE_MAX_FILM_DIM + 1;
  assert_int_equal(pc_renderer_check(&scene, &big, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "resolution"));
  pc_render_settings biased = req.set;
  biased.uniform_mix = 0.f;
  pc_err ec = {0}, ek = {0};
  pc_renderer *r = NULL;
  int rc = pc_renderer_create(&scene, &biased, 1, &r, &ec);
  pc_renderer_destroy(r);
  assert_int_not_equal(rc, PC_OK);
  assert_int_equal(pc_renderer_check(&scene, &biased, &ek), rc);
  assert_string_equal(ek.msg, ec.msg);
  pc_scene_free(&scene);
}

/* Records are built only where the connections read them: with a uniform mix of 1, p_conn is
 * the uniform PMF and the build (R x V connections) was pure cost, unless the resampling's
 * target reads the records' seen share. */
static size_t record_bytes(const pc_scene *scene, pc_render_settings set) {
  pc_film film;
  pc_err e = {0};
  pc_renderer *r = NULL;
  assert_int_equal(pc_film_init(&film, set.width, set.height, 0, &e), 0);
  assert_int_equal(pc_renderer_create(scene, &set, 2, &r, &e), 0);
  pc_render_stats st = {0};
  assert_int_equal(pc_render_iterations(r, 0, 2, &film, &st, NULL, NULL, NULL, &e), 0);
  pc_renderer_destroy(r);
  pc_film_free(&film);
  return st.pmf_bytes;
}

static void test_uniform_builds_no_records(void **state) {
  (void)state;
  pc_render_request req = request(PC_METHOD_PCBPT, 24, -1);
  pc_render_settings s = req.set;
  assert_true(pc_pcbpt_reads_records(&s));
  s.uniform_mix = 1.f;
  assert_false(pc_pcbpt_reads_records(&s));
  s.pcbpt_candidates = 3;
  s.candidate_visibility = PC_CANDVIS_TRACED;
  assert_false(pc_pcbpt_reads_records(&s));
  s.candidate_visibility = PC_CANDVIS_RECORDS;
  assert_true(pc_pcbpt_reads_records(&s));
  s.candidate_visibility = PC_CANDVIS_UNCERTAIN;
  assert_true(pc_pcbpt_reads_records(&s));
  s = req.set;
  s.pmf_mode = PC_PMF_EXACT;
  assert_false(pc_pcbpt_reads_records(&s));

  pc_scene scene = {0};
  assert_int_equal(stat_load("cornell-box", &req, &scene), 0);
  pc_render_settings uniform = req.set, seen = req.set;
  uniform.uniform_mix = seen.uniform_mix = 1.f;
  seen.pcbpt_candidates = 3;
  seen.candidate_visibility = PC_CANDVIS_RECORDS;
  size_t built = record_bytes(&scene, req.set), none = record_bytes(&scene, uniform);
  assert_true(none < built);
  assert_true(record_bytes(&scene, seen) > none);
  pc_scene_free(&scene);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_shared_layers_equal_bdpt),
      cmocka_unit_test(test_inner_agrees),
      cmocka_unit_test(test_dark_touches_inner_only),
      cmocka_unit_test(test_unseen_rate_agrees),
      cmocka_unit_test(test_records_visibility_agrees),
      cmocka_unit_test(test_inner_count),
      cmocka_unit_test(test_all_scenes_finite),
      cmocka_unit_test(test_thread_count_invariant),
      cmocka_unit_test(test_renderer_check),
      cmocka_unit_test(test_uniform_builds_no_records),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
