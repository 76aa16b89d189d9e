/* test_motion.c: motion blur in every method, against an exact answer. A black bar moves across
 * a wall that emits radiance 1, during a shutter of [0, 1]: a pixel whose ray crosses the bar's
 * plane at x is dark for the fraction of the shutter the bar covers x, so it shows 1 - that
 * fraction (averaged over the pixel). The same image comes from a still bar seen by a camera
 * that moves the other way. Blocks of pixels are checked against it within 5 standard errors
 * measured from the independent iterations (each iteration renders one time, so the spread
 * includes the time's), and their mean within 4. A second scene (a sphere that turns and moves
 * over a lit floor) checks that every bidirectional method agrees with pt when light and eye
 * paths meet a moving shape. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define RES 32
#define BLOCK 4
#define BAR_Z 5.0
#define BAR_W 0.4 /* half-width */
#define BAR_X0 -1.0
#define BAR_DX 2.0 /* distance moved during the shutter */

static const char *sensor_still =
    "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>"
    "<float name=\"shutterOpen\" value=\"0\"/><float name=\"shutterClose\" value=\"1\"/>"
    "<transform name=\"toWorld\"><lookat origin=\"0, 0, 0\" target=\"0, 0, 1\" up=\"0, 1, 0\"/></transform>"
    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film></sensor>";
static const char *sensor_moving =
    "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>"
    "<float name=\"shutterOpen\" value=\"0\"/><float name=\"shutterClose\" value=\"1\"/>"
    "<animation name=\"toWorld\">"
    "<transform time=\"0\"><lookat origin=\"0, 0, 0\" target=\"0, 0, 1\" up=\"0, 1, 0\"/></transform>"
    "<transform time=\"1\"><lookat origin=\"-2, 0, 0\" target=\"-2, 0, 1\" up=\"0, 1, 0\"/></transform></animation>"
    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film></sensor>";
static const char *wall =
    "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"20\"/><rotate y=\"1\" angle=\"180\"/>"
    "<translate z=\"10\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>";
static const char *bar_moving =
    "<shape type=\"rectangle\"><animation name=\"toWorld\">"
    "<transform time=\"0\"><scale x=\"0.4\" y=\"10\"/><translate x=\"-1\" z=\"5\"/></transform>"
    "<transform time=\"1\"><scale x=\"0.4\" y=\"10\"/><translate x=\"1\" z=\"5\"/></transform></animation>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf></shape>";
static const char *bar_still =
    "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"0.4\" y=\"10\"/><translate x=\"-1\" z=\"5\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf></shape>";

static int render(const char *dir, const char *xml, pc_method m, int iterations, int block, stat_blocks *st, pc_scene *keep) {
  return stat_render_xml(dir, xml, m, RES, 41, 4, iterations, block, st, keep);
}

/* The fraction of the shutter during which the bar covers x on its plane (relative to the
 * camera at time 0). */
static double covered(double x) {
  double lo = fmax(0.0, (x - BAR_W - BAR_X0) / BAR_DX), hi = fmin(1.0, (x + BAR_W - BAR_X0) / BAR_DX);
  return hi > lo ? hi - lo : 0.0;
}

/* The exact mean of block column bx: each pixel's value averaged over its width (the bar spans
 * the whole height). */
static double exact_block(const pc_scene *s, int bx) {
  enum { SUB = 64 };
  double sum = 0;
  for (int x = bx * BLOCK; x < (bx + 1) * BLOCK; x++)
    for (int k = 0; k < SUB; k++) {
      vec3 d = pc_camera_ray_dir(&s->camera, x + (k + 0.5f) / SUB, RES / 2.f);
      sum += 1.0 - covered(s->camera.pos.x + BAR_Z * d.x / d.z);
    }
  return sum / (BLOCK * SUB);
}

static void check_analytic(const char *name, const char *sensor, const char *bar) {
  char dir[] = "/tmp/pcbpt_motion_XXXXXX", xml[4096];
  assert_non_null(mkdtemp(dir));
  snprintf(xml, sizeof xml, "<scene version=\"0.6.0\">%s%s%s</scene>", sensor, wall, bar);
  const struct { pc_method m; int it; } cases[] = {
      {PC_METHOD_PT, 2048}, {PC_METHOD_LT, 2048}, {PC_METHOD_BDPT, 2048}, {PC_METHOD_CBDPT, 1024}, {PC_METHOD_PCBPT, 1024}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    stat_blocks st = {0};
    pc_scene s;
    assert_int_equal(render(dir, xml, cases[c].m, cases[c].it, BLOCK, &st, &s), 0);
    assert_true(pc_scene_moves(&s));
    double worst = 0, sum = 0, sum_exact = 0, var = 0, lo = 1, hi = 0;
    for (int by = 0; by < st.bh; by++)
      for (int bx = 0; bx < st.bw; bx++) {
        int b = by * st.bw + bx;
        double exact = exact_block(&s, bx), mean = stat_mean(&st, b), se = stat_se(&st, b);
        double z = fabs(mean - exact) / fmax(se, 1e-4);
        if (z > worst) worst = z;
        if (z > 5) printf("%s %s block (%d,%d): mean %.4f exact %.4f se %.4f\n", name, pc_method_name(cases[c].m), bx, by, mean, exact, se);
        sum += mean, sum_exact += exact, var += se * se;
        lo = fmin(lo, exact), hi = fmax(hi, exact);
      }
    double z_all = fabs(sum - sum_exact) / sqrt(var);
    printf("%-15s %-5s %4d iterations: exact block means %.3f..%.3f, largest block difference %.2f se, mean %.4f exact %.4f (%.2f se)\n",
           name, pc_method_name(cases[c].m), cases[c].it, lo, hi, worst, sum / st.nblocks, sum_exact / st.nblocks, z_all);
    assert_true(hi - lo > 0.3); /* the blur spans the view */
    assert_true(worst < 5.0);
    assert_true(z_all < 4.0);
    stat_free(&st);
    pc_scene_free(&s);
  }
  th_rm_rf(dir);
}

static void test_moving_bar(void **state) {
  (void)state;
  check_analytic("moving bar", sensor_still, bar_moving);
}

static void test_moving_camera(void **state) {
  (void)state;
  check_analytic("moving camera", sensor_moving, bar_still);
}

/* A glossy sphere that turns a quarter and moves over a diffuse floor under a small light. */
static void test_agreement(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_motion_XXXXXX";
  assert_non_null(mkdtemp(dir));
  const char *xml =
      "<scene version=\"0.6.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>"
      "<float name=\"shutterOpen\" value=\"0.25\"/><float name=\"shutterClose\" value=\"0.75\"/>"
      STAT_VIEW_OF_LIT_FLOOR
      "<shape type=\"cube\"><animation name=\"toWorld\">"
      "<transform time=\"0\"><scale value=\"0.3\"/><translate x=\"-0.8\" y=\"0.3\"/></transform>"
      "<transform time=\"1\"><scale value=\"0.3\"/><rotate y=\"1\" angle=\"90\"/><translate x=\"0.8\" y=\"0.5\"/></transform>"
      "</animation><bsdf type=\"roughplastic\"><float name=\"alpha\" value=\"0.2\"/></bsdf></shape></scene>";
  double worst = stat_agreement(dir, xml, "moving cube", RES, 41, 4, 512, 8);
  th_rm_rf(dir);
  assert_true(worst < 4.5);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_moving_bar), cmocka_unit_test(test_moving_camera),
                                     cmocka_unit_test(test_agreement)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
