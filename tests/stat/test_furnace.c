/* test_furnace.c: the white furnace (scenes/furnace: a closed sphere emitting Le inward with
 * diffuse albedo a) has the exact radiance Le * sum_{k<d} a^k everywhere for maxDepth d.
 * Every method that is implemented must reproduce it for d = 1..5 and infinite: the image mean
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

static void check_method(pc_method method) {
  const int depths[] = {1, 2, 3, 4, 5, -1};
  for (size_t k = 0; k < sizeof depths / sizeof depths[0]; k++) {
    pc_render_request req;
    pc_render_request_default(&req);
    req.set.method = method;
    req.method_set = true;
    req.set.max_depth = depths[k];
    req.depth_set = true;
    req.set.width = req.set.height = RES;
    req.width_set = req.height_set = true;
    req.set.seed = 1234;
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
    assert_int_equal(stat_render_blocks(&scene, &req.set, 2, 0, ITERATIONS, -1, RES, &st), 0);
    double mean = stat_mean(&st, 0), se = stat_se(&st, 0);
    double err = fabs(mean - exact);
    printf("furnace %-5s maxDepth %2d: mean %.6f exact %.6f  err %.2e  se %.2e  (%.2f%%)\n", pc_method_name(method),
           depths[k], mean, exact, err, se, 100 * err / exact);
    assert_true(err <= fmax(4 * se, 1e-5 * exact));
    assert_true(err <= 0.015 * exact);
    stat_free(&st);
    pc_scene_free(&scene);
  }
}

static void test_furnace_pt(void **state) {
  (void)state;
  check_method(PC_METHOD_PT);
}

static void test_furnace_lt(void **state) {
  (void)state;
  check_method(PC_METHOD_LT);
}

static void test_furnace_bdpt(void **state) {
  (void)state;
  check_method(PC_METHOD_BDPT);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_furnace_pt),
      cmocka_unit_test(test_furnace_lt),
      cmocka_unit_test(test_furnace_bdpt),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
