/* test_thinlens.c: Mitsuba's thin-lens sensor in every method, against an exact answer. A wall
 * that emits radiance 1 on x > 0 stands at depth 4; the lens (radius R) is focused at depth 2.
 * The ray from lens point l toward the focus-plane point of a pixel (slope u) crosses depth 4 at
 * x = 4u - l_x, so the pixel sees the fraction of the lens disk with l_x < 4u: a circular
 * segment. Blocks of pixels are checked against it (averaged over each pixel's width) within 5
 * standard errors measured from the iterations, and their mean within 4: light tracing and
 * BDPT's t=1 connections must sample the lens and find the pixel exactly as the eye paths do.
 * A second scene (a sphere on a lit floor, out of focus) checks that every bidirectional method
 * agrees with pt. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define RES 32
#define BLOCK 4
#define LENS_R 0.8
#define FOCUS 2.0
#define WALL 4.0

static int render(const char *dir, const char *xml, pc_method m, int iterations, int block, stat_blocks *st, pc_scene *keep) {
  return stat_render_xml(dir, xml, m, RES, 43, 4, iterations, block, st, keep);
}

/* The fraction of a disk of radius LENS_R whose x lies below a. */
static double disk_below(double a) {
  double t = a / LENS_R;
  if (t <= -1) return 0;
  if (t >= 1) return 1;
  return 1 - (acos(t) - t * sqrt(1 - t * t)) / M_PI;
}

static double exact_block(const pc_scene *s, int bx) {
  enum { SUB = 64 };
  double sum = 0;
  for (int x = bx * BLOCK; x < (bx + 1) * BLOCK; x++)
    for (int k = 0; k < SUB; k++) {
      vec3 d = pc_camera_ray_dir(&s->camera, x + (k + 0.5f) / SUB, RES / 2.f);
      sum += disk_below(WALL * d.x / d.z);
    }
  return sum / (BLOCK * SUB);
}

static void test_defocused_edge(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_thinlens_XXXXXX";
  assert_non_null(mkdtemp(dir));
  const char *xml =
      "<scene version=\"0.6.0\"><sensor type=\"thinlens\"><float name=\"fov\" value=\"40\"/>"
      "<float name=\"apertureRadius\" value=\"0.8\"/><float name=\"focusDistance\" value=\"2\"/>"
      "<transform name=\"toWorld\"><lookat origin=\"0, 0, 0\" target=\"0, 0, 1\" up=\"0, 1, 0\"/></transform>"
      "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film></sensor>"
      "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"10\" y=\"20\"/><rotate y=\"1\" angle=\"180\"/>"
      "<translate x=\"10\" z=\"4\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>"
      "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape></scene>";
  const struct { pc_method m; int it; } cases[] = {
      {PC_METHOD_PT, 1024}, {PC_METHOD_LT, 1024}, {PC_METHOD_BDPT, 1024}, {PC_METHOD_CBDPT, 512}, {PC_METHOD_PCBPT, 512}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    stat_blocks st = {0};
    pc_scene s;
    assert_int_equal(render(dir, xml, cases[c].m, cases[c].it, BLOCK, &st, &s), 0);
    assert_true(s.camera.aperture_radius == 0.8f && s.camera.focus_distance == 2.f);
    double worst = 0, sum = 0, sum_exact = 0, var = 0;
    int partial = 0;
    for (int by = 0; by < st.bh; by++)
      for (int bx = 0; bx < st.bw; bx++) {
        int b = by * st.bw + bx;
        double exact = exact_block(&s, bx), mean = stat_mean(&st, b), se = stat_se(&st, b);
        /* a block the whole lens sees lit or dark is exact in every sample */
        double z = fabs(mean - exact) / fmax(se, 1e-3 * fmax(exact, 1e-2));
        if (z > 5) printf("thinlens %s block (%d,%d): mean %.4f exact %.4f se %.4f\n", pc_method_name(cases[c].m), bx, by, mean, exact, se);
        if (z > worst) worst = z;
        partial += exact > 0.02 && exact < 0.98;
        sum += mean, sum_exact += exact, var += se * se;
      }
    double z_all = fabs(sum - sum_exact) / fmax(sqrt(var), 1e-4 * sum_exact);
    printf("defocused edge %-5s %4d iterations: %d blocks in the blur, largest block difference %.2f se, mean %.4f exact %.4f (%.2f se)\n",
           pc_method_name(cases[c].m), cases[c].it, partial, worst, sum / st.nblocks, sum_exact / st.nblocks, z_all);
    assert_true(partial >= 24); /* the blur spans 3 of the 8 block columns */
    assert_true(worst < 5.0);
    assert_true(z_all < 4.0);
    stat_free(&st);
    pc_scene_free(&s);
  }
  th_rm_rf(dir);
}

static void test_agreement(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_thinlens_XXXXXX";
  assert_non_null(mkdtemp(dir));
  const char *xml =
      "<scene version=\"0.6.0\"><sensor type=\"thinlens\"><float name=\"fov\" value=\"60\"/>"
      "<float name=\"apertureRadius\" value=\"0.15\"/><float name=\"focusDistance\" value=\"2\"/>"
      STAT_VIEW_OF_LIT_FLOOR
      "<shape type=\"sphere\"><point name=\"center\" x=\"0.4\" y=\"0.4\" z=\"-0.5\"/><float name=\"radius\" value=\"0.4\"/>"
      "<bsdf type=\"roughplastic\"><float name=\"alpha\" value=\"0.2\"/></bsdf></shape></scene>";
  double worst = stat_agreement(dir, xml, "thin lens over a lit floor", RES, 43, 4, 512, 8);
  th_rm_rf(dir);
  assert_true(worst < 4.5);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_defocused_edge), cmocka_unit_test(test_agreement)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
