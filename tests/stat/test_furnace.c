/* test_furnace.c: the white furnace (scenes/furnace: a closed sphere emitting Le inward with
 * diffuse albedo a) has the exact radiance Le * sum_{k<d} a^k everywhere for maxDepth d.
 * Every method (PCBPT with cached and exact PMF, both MIS modes, resampled connections with
 * each candidate-visibility mode, and every eye vertex dark) must reproduce it for
 * d = 1..5 and infinite: the image mean
 * of each independent iteration is one sample, the tolerance is 4 standard errors measured
 * from those samples (and the estimate must be within 1.5% in any case). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define RES 32
#define ITERATIONS 48

typedef struct variant {
  pc_method method;
  pc_pmf_mode pmf;
  pc_mis_mode mis;
  int iterations;
  int candidates; /* PCBPT resampling candidates (1: none) */
  pc_candidate_visibility vis;
  float count; /* PC_MIS_COUNT: the inner strategies' count */
  float dark;  /* --pcbpt-dark-seen (0: no dark eye vertex; 1: every one) */
} variant;

static void check(variant v) {
  const int depths[] = {1, 2, 3, 4, 5, -1};
  for (size_t k = 0; k < sizeof depths / sizeof depths[0]; k++) {
    pc_render_request req;
    pc_render_request_default(&req);
    req.set.method = v.method;
    req.method_set = true;
    req.set.max_depth = depths[k];
    req.depth_set = true;
    req.set.width = req.set.height = RES;
    req.width_set = req.height_set = true;
    req.set.seed = 1234;
    req.set.pmf_mode = v.pmf;
    req.set.mis_mode = v.mis;
    if (v.mis == PC_MIS_COUNT) req.set.mis_count = v.count;
    /* A small light-path store and a dense cache keep the correlated estimators' cost low at
     * this resolution while exercising sampling (K > 1) and interpolation. */
    req.set.pcbpt_m = 20;
    req.set.pcbpt_k = 2;
    req.set.cache_fraction = 0.05f;
    req.set.pcbpt_candidates = v.candidates;
    req.set.candidate_visibility = v.vis;
    req.set.pcbpt_dark_seen = v.dark;
    pc_scene scene = {0};
    assert_int_equal(stat_load("furnace", &req, &scene), 0);
    assert_true(scene.nlights == 1 && scene.lights[0].type == PC_LIGHT_AREA);
    const pc_shape *sh = &scene.shapes[scene.lights[0].shape];
    const pc_material *m = &scene.materials[sh->material];
    assert_true(m->type == PC_MAT_DIFFUSE && m->reflectance.tex < 0);
    double le = scene.lights[0].radiance.x, a = m->reflectance.value.x;
    double exact = 0, ak = 1;
    int d = depths[k] < 0 ? 100000 : depths[k];
    for (int i = 0; i < d && ak > 1e-12; i++, ak *= a) exact += le * ak;

    stat_blocks st = {0};
    assert_int_equal(stat_render_blocks(&scene, &req.set, 2, 0, v.iterations, -1, RES, &st), 0);
    double mean = stat_mean(&st, 0), se = stat_se(&st, 0);
    double err = fabs(mean - exact);
    printf("furnace %-5s pmf %-6s mis %-11s cand %d vis %d dark %g maxDepth %2d: mean %.6f exact %.6f  err %.2e  se %.2e  (%.2f%%)\n",
           pc_method_name(v.method), v.pmf == PC_PMF_EXACT ? "exact" : "cached",
           v.mis == PC_MIS_STANDARD ? "standard" : v.mis == PC_MIS_COUNT ? "count" : "upper-bound", v.candidates, (int)v.vis, (double)v.dark, depths[k], mean, exact, err, se, 100 * err / exact);
    assert_true(err <= fmax(4 * se, 1e-5 * exact));
    assert_true(err <= 0.015 * exact);
    stat_free(&st);
    pc_scene_free(&scene);
  }
}

static void test_furnace_pt(void **state) {
  (void)state;
  check((variant){PC_METHOD_PT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, ITERATIONS, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
}

static void test_furnace_lt(void **state) {
  (void)state;
  check((variant){PC_METHOD_LT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, ITERATIONS, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
}

static void test_furnace_bdpt(void **state) {
  (void)state;
  check((variant){PC_METHOD_BDPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, ITERATIONS, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
}

static void test_furnace_cbdpt(void **state) {
  (void)state;
  check((variant){PC_METHOD_CBDPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, 16, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
}

static void test_furnace_pcbpt(void **state) {
  (void)state;
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, ITERATIONS, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, ITERATIONS, 4, PC_CANDVIS_RECORDS, 0.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_UPPER_BOUND, ITERATIONS, 4, PC_CANDVIS_TRACED, 0.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_STANDARD, ITERATIONS, 4, PC_CANDVIS_UNCERTAIN, 0.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_EXACT, PC_MIS_UPPER_BOUND, 16, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_STANDARD, ITERATIONS, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_EXACT, PC_MIS_STANDARD, 16, 1, PC_CANDVIS_RECORDS, 0.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_COUNT, ITERATIONS, 1, PC_CANDVIS_RECORDS, 4.f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_COUNT, ITERATIONS, 3, PC_CANDVIS_TRACED, 2.5f, 0.f});
  check((variant){PC_METHOD_PCBPT, PC_PMF_CACHED, PC_MIS_COUNT, ITERATIONS, 1, PC_CANDVIS_TRACED, 2.f, 1.f});
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_furnace_pt),
      cmocka_unit_test(test_furnace_lt),
      cmocka_unit_test(test_furnace_bdpt),
      cmocka_unit_test(test_furnace_cbdpt),
      cmocka_unit_test(test_furnace_pcbpt),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
