/* test_sampling_weight.c: Mitsuba's emitter samplingWeight changes how often each light is
 * chosen, never the image. The Cornell box with its area light, an added point light and a
 * constant environment (seen through the open front) is rendered by every method with the
 * weights (1, 1, 1), (1, 30, 1), (30, 1, 1) and (1, 1, 30); block means of the
 * independent iterations must agree within 4.5 standard errors (measured from the iterations,
 * fixed seeds), which a light-selection pdf used inconsistently anywhere would break. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <sys/stat.h>

#include "stat_util.h"
#include "../unit/test_helpers_fs.h"

#define RES 32
#define BLOCK 8
#define ITERATIONS 64

static int render(const char *path, const char *wa, const char *wp, const char *we, pc_method m, stat_blocks *st) {
  pc_scene_defines d = {0};
  pc_err e = {0};
  if (pc_scene_defines_add(&d, wa, &e) || pc_scene_defines_add(&d, wp, &e) || pc_scene_defines_add(&d, we, &e)) return -1;
  pc_scene_load_opts o = {.defines = &d};
  pc_render_request req;
  pc_scene scene;
  int rc = stat_load_file(path, &o, m, RES, 77, &req, &scene);
  if (rc) return rc;
  rc = stat_render_blocks(&scene, &req.set, 2, 0, ITERATIONS, -1, BLOCK, st);
  pc_scene_free(&scene);
  return rc;
}

static void test_weights(void **state) {
  (void)state;
  const char *src = getenv("PCBPT_SOURCE_DIR");
  assert_non_null(src);
  char dir[] = "/tmp/pcbpt_weight_XXXXXX", cmd[4096], path[256];
  assert_non_null(mkdtemp(dir));
  snprintf(cmd, sizeof cmd, "cp -R '%s/scenes/cornell-box/meshes' '%s/'", src, dir);
  assert_int_equal(system(cmd), 0);
  /* the shipped scene with samplingWeight on its light, a point light beside it and an environment */
  snprintf(path, sizeof path, "%s/scenes/cornell-box/scene.xml", src);
  size_t n = 0;
  char *xml = th_read(path, &n);
  assert_non_null(xml);
  char *light = strstr(xml, "<emitter type=\"area\"><rgb name=\"radiance\" value=\"17, 12, 4\"/>");
  char *end = strstr(xml, "</scene>");
  assert_non_null(light);
  assert_non_null(end);
  char *out = malloc(n + 1024);
  size_t at = (size_t)(light - xml) + strlen("<emitter type=\"area\"><rgb name=\"radiance\" value=\"17, 12, 4\"/>");
  memcpy(out, xml, at);
  size_t len = at;
  len += (size_t)sprintf(out + len, "<float name=\"samplingWeight\" value=\"$wa\"/>");
  memcpy(out + len, xml + at, (size_t)(end - xml) - at);
  len += (size_t)(end - xml) - at;
  len += (size_t)sprintf(out + len, "<emitter type=\"point\"><point name=\"position\" x=\"0.4\" y=\"1.3\" z=\"0.2\"/>"
                                    "<rgb name=\"intensity\" value=\"0.8, 0.8, 1\"/><float name=\"samplingWeight\" value=\"$wp\"/>"
                                    "</emitter><emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.3, 0.4, 0.5\"/>"
                                    "<float name=\"samplingWeight\" value=\"$we\"/></emitter></scene>\n");
  out[len] = 0;
  assert_int_equal(th_write_str(dir, "scene.xml", out), 0);
  free(out);
  free(xml);
  snprintf(path, sizeof path, "%s/scene.xml", dir);
  static const char *const wa[] = {"wa=1", "wa=1", "wa=30", "wa=1"}, *const wp[] = {"wp=1", "wp=30", "wp=1", "wp=1"},
                           *const we[] = {"we=1", "we=1", "we=1", "we=30"};
  const pc_method methods[] = {PC_METHOD_PT, PC_METHOD_LT, PC_METHOD_BDPT, PC_METHOD_CBDPT, PC_METHOD_PCBPT};
  double worst = 0;
  for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
    stat_blocks st[4] = {{0}};
    for (int v = 0; v < 4; v++) assert_int_equal(render(path, wa[v], wp[v], we[v], methods[k], &st[v]), 0);
    double mk = 0;
    for (int v = 1; v < 4; v++)
      for (int b = 0; b < st[0].nblocks; b++) {
        double se = sqrt(stat_se(&st[0], b) * stat_se(&st[0], b) + stat_se(&st[v], b) * stat_se(&st[v], b));
        double z = se > 0 ? fabs(stat_mean(&st[0], b) - stat_mean(&st[v], b)) / se : 0;
        if (z > mk) mk = z;
      }
    printf("samplingWeight %-5s: largest block difference %.2f standard errors over %d blocks x 3 weightings\n",
           pc_method_name(methods[k]), mk, st[0].nblocks);
    if (mk > worst) worst = mk;
    for (int v = 0; v < 4; v++) stat_free(&st[v]);
  }
  th_rm_rf(dir);
  assert_true(worst < 4.5);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_weights)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
