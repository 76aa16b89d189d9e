/* test_directional.c: Mitsuba's `directional` emitter, a distant light of irradiance E along a
 * fixed direction. Analytic: a one-sided diffuse plane of albedo a lit at angle theta shows
 * L = a/pi * E * cos(theta) everywhere; pt renders it exactly (next-event estimation is then
 * deterministic), lt, bdpt and pcbpt within 4.5 standard errors per block measured from their
 * iterations; lit from behind, every method renders exactly 0. Agreement: on a floor with an
 * area light, a wall, a diffuse sphere casting a shadow and a rough plastic one, lt, bdpt,
 * cbdpt and pcbpt agree with pt block by block within 4.5 standard errors (fixed seeds). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define ALBEDO 0.5
#define IRRADIANCE 2.0
#define THETA_DEG 30.0

/* The plane z = 0 (normal +z, 6x6 m) seen from above; the light's direction has z component dz. */
static void plane_scene(char *xml, size_t n, double dz) {
  double th = THETA_DEG * M_PI / 180;
  snprintf(xml, n,
           "<scene version=\"0.6.0\"><integrator type=\"path\"><integer name=\"maxDepth\" value=\"6\"/></integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><transform name=\"toWorld\">"
           "<lookat origin=\"0, 0, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film></sensor>"
           "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"3\"/></transform>"
           "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"%g\"/></bsdf></shape>"
           "<emitter type=\"directional\"><vector name=\"direction\" x=\"%.9g\" y=\"0\" z=\"%.9g\"/>"
           "<rgb name=\"irradiance\" value=\"%g\"/></emitter></scene>",
           ALBEDO, sin(th), dz * cos(th), IRRADIANCE);
}

static void test_analytic(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_directional_XXXXXX", xml[4096];
  assert_non_null(mkdtemp(dir));
  plane_scene(xml, sizeof xml, -1);
  const double expect = ALBEDO / M_PI * IRRADIANCE * cos(THETA_DEG * M_PI / 180);
  const pc_method methods[] = {PC_METHOD_PT, PC_METHOD_LT, PC_METHOD_BDPT, PC_METHOD_PCBPT};
  for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
    stat_blocks st = {0};
    assert_int_equal(stat_render_xml(dir, xml, methods[k], 32, 3, 0, 128, 8, &st, NULL), 0);
    double worst = 0, mean = 0;
    for (int b = 0; b < st.nblocks; b++) {
      double m = stat_mean(&st, b), se = stat_se(&st, b);
      mean += m / st.nblocks;
      if (methods[k] == PC_METHOD_PT) {
        /* exact up to float rounding: no randomness reaches the estimate */
        assert_true(fabs(m - expect) < 1e-5 * expect);
        continue;
      }
      assert_true(se > 0);
      double z = fabs(m - expect) / se;
      if (z > worst) worst = z;
    }
    printf("plane lit at %g degrees, %-5s: image mean %.6f (exact %.6f), largest block difference %.2f standard errors\n",
           THETA_DEG, pc_method_name(methods[k]), mean, expect, worst);
    assert_true(worst < 4.5);
    stat_free(&st);
  }
  /* Lit from behind: a one-sided diffuse surface reflects nothing of it, and no method sees the
   * light itself. */
  plane_scene(xml, sizeof xml, 1);
  for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
    stat_blocks st = {0};
    assert_int_equal(stat_render_xml(dir, xml, methods[k], 32, 3, 0, 16, 8, &st, NULL), 0);
    for (int b = 0; b < st.nblocks; b++) assert_true(stat_mean(&st, b) == 0);
    stat_free(&st);
  }
  th_rm_rf(dir);
}

static void test_agreement(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_directional_XXXXXX", xml[8192];
  assert_non_null(mkdtemp(dir));
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\"><integrator type=\"path\"><integer name=\"maxDepth\" value=\"6\"/></integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>" STAT_VIEW_OF_LIT_FLOOR
           "<emitter type=\"directional\"><transform name=\"toWorld\"><lookat origin=\"0, 0, 0\" target=\"0.5, -1, -0.4\""
           " up=\"0, 1, 0\"/></transform><rgb name=\"irradiance\" value=\"1.5, 1.2, 0.9\"/></emitter>"
           "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"1.5\"/><rotate y=\"1\" angle=\"90\"/>"
           "<translate x=\"-1.2\" y=\"1\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.6, 0.4\"/></bsdf></shape>"
           "<shape type=\"sphere\"><point name=\"center\" x=\"0.3\" y=\"0.5\" z=\"0.2\"/><float name=\"radius\" value=\"0.3\"/>"
           "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7\"/></bsdf></shape>"
           "<shape type=\"sphere\"><point name=\"center\" x=\"-0.5\" y=\"0.25\" z=\"0.6\"/><float name=\"radius\" value=\"0.25\"/>"
           "<bsdf type=\"roughplastic\"><float name=\"alpha\" value=\"0.2\"/></bsdf></shape></scene>");
  double worst = stat_agreement(dir, xml, "directional scene", 32, 31, 0, 256, 8);
  th_rm_rf(dir);
  assert_true(worst < 4.5);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_analytic), cmocka_unit_test(test_agreement)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
