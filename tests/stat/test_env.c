/* test_env.c: the environment emitters in every method, against exact answers. A diffuse
 * sphere of albedo a under an environment of constant radiance L (scenes/env-constant, and
 * scenes/env-white-map: an envmap of one colour, which must equal it) shows exactly a*L on
 * every pixel that sees only the sphere (a convex object sees only the environment) and L on
 * every pixel that sees only the background. The image is split into blocks; a block whose
 * pixels' corner rays all hit the sphere (or all miss it) is checked against a*L (or L) within
 * 5 standard errors measured from the independent iterations, and the mean over all such
 * blocks within 4 standard errors and 1.5%; with the balance and the power heuristic, and with
 * N_L light paths other than W*H. The standard errors have a floor (5e-4 of the exact value per
 * block, 2e-4 over all blocks): where the background is nearly all s=0 (the power heuristic,
 * N_L < W*H), the rare light-tracing splats that carry the rest land in a block a few times in
 * the whole run, so the spread of the iterations misses their share (measured: 1.6e-4 of 2 in
 * one block with N_L = 300 and se 2.8e-5). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define RES 32
#define BLOCK 4

/* 1: every corner ray of the block's pixels hits the sphere, 0: none does, -1: mixed. */
static int block_kind(const pc_scene *s, int bx, int by) {
  const pc_shape *sh = &s->shapes[0];
  int hits = 0, n = 0;
  for (int y = by * BLOCK; y <= (by + 1) * BLOCK; y++)
    for (int x = bx * BLOCK; x <= (bx + 1) * BLOCK; x++) {
      vec3 d = v3_norm(pc_camera_ray_dir(&s->camera, (float)x, (float)y));
      vec3 oc = v3_sub(s->camera.pos, sh->center);
      float b = v3_dot(oc, d), c = v3_dot(oc, oc) - sh->radius * sh->radius;
      hits += b * b - c > 0.f && b < 0.f;
      n++;
    }
  return hits == n ? 1 : (hits == 0 ? 0 : -1);
}

typedef struct method_case {
  pc_method method;
  int iterations;
  pc_mis_heuristic h;
  uint64_t light_paths; /* N_L, 0 = W*H */
} method_case;

static void check_scene(const char *name) {
  const method_case cases[] = {{PC_METHOD_PT, 64, PC_MIS_BALANCE, 0},     {PC_METHOD_LT, 256, PC_MIS_BALANCE, 0},
                               {PC_METHOD_BDPT, 64, PC_MIS_BALANCE, 0},   {PC_METHOD_CBDPT, 32, PC_MIS_BALANCE, 0},
                               {PC_METHOD_PCBPT, 64, PC_MIS_BALANCE, 0},  {PC_METHOD_PT, 64, PC_MIS_POWER, 0},
                               {PC_METHOD_BDPT, 64, PC_MIS_POWER, 300},   {PC_METHOD_LT, 256, PC_MIS_POWER, 3000},
                               {PC_METHOD_PCBPT, 64, PC_MIS_POWER, 2000}};
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    pc_render_request req;
    pc_render_request_default(&req);
    req.set.method = cases[k].method;
    req.method_set = true;
    req.set.width = req.set.height = RES;
    req.width_set = req.height_set = true;
    req.set.seed = 77;
    req.set.mis_heuristic = cases[k].h;
    req.set.light_paths = cases[k].light_paths;
    req.set.pcbpt_m = 20;
    req.set.pcbpt_k = 2;
    req.set.cache_fraction = 0.05f;
    pc_scene scene = {0};
    assert_int_equal(stat_load(name, &req, &scene), 0);
    assert_true(scene.env_light >= 0 && scene.nshapes == 1 && scene.shapes[0].kind == PC_SHAPE_SPHERE);
    const pc_light *env = &scene.lights[scene.env_light];
    const pc_material *m = &scene.materials[scene.shapes[0].material];
    double le = v3_luminance(pc_env_le(env, v3(0.3f, 0.8f, -0.52f))), a = m->reflectance.value.x;
    stat_blocks st = {0};
    assert_int_equal(stat_render_blocks(&scene, &req.set, 2, 0, cases[k].iterations, -1, BLOCK, &st), 0);
    double sum[2] = {0}, var[2] = {0};
    int count[2] = {0};
    for (int by = 0; by < st.bh; by++)
      for (int bx = 0; bx < st.bw; bx++) {
        int kind = block_kind(&scene, bx, by);
        if (kind < 0) continue;
        int b = by * st.bw + bx;
        double exact = kind ? a * le : le, mean = stat_mean(&st, b), se = stat_se(&st, b);
        if (!(fabs(mean - exact) <= fmax(5 * se, 5e-4 * exact))) {
          printf("%s %s block (%d,%d) %s: mean %.5f exact %.5f se %.2e\n", name, pc_method_name(cases[k].method), bx,
                 by, kind ? "sphere" : "background", mean, exact, se);
          fail();
        }
        sum[kind] += mean;
        var[kind] += se * se;
        count[kind]++;
      }
    assert_true(count[0] >= 8 && count[1] >= 8);
    for (int kind = 0; kind < 2; kind++) {
      double exact = kind ? a * le : le, mean = sum[kind] / count[kind], se = sqrt(var[kind]) / count[kind];
      printf("%-13s %-5s %-7s N_L %4llu %-10s (%2d blocks): mean %.5f exact %.5f  se %.2e  err %.2f%%\n", name,
             pc_method_name(cases[k].method), cases[k].h == PC_MIS_POWER ? "power" : "balance",
             (unsigned long long)cases[k].light_paths, kind ? "sphere" : "background", count[kind], mean, exact, se,
             100 * fabs(mean - exact) / exact);
      assert_true(fabs(mean - exact) <= fmax(4 * se, 2e-4 * exact));
      assert_true(fabs(mean - exact) <= 0.015 * exact);
    }
    stat_free(&st);
    pc_scene_free(&scene);
  }
}

static void test_constant(void **state) {
  (void)state;
  check_scene("env-constant");
}

static void test_white_envmap(void **state) {
  (void)state;
  check_scene("env-white-map");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_constant),
      cmocka_unit_test(test_white_envmap),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
