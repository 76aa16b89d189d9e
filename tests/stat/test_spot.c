/* test_spot.c: a scene lit only by Mitsuba's `spot`. Analytic: a white diffuse floor (albedo a)
 * at distance d below a spot of intensity I pointing straight down shows, at horizontal distance
 * rho, L = a/pi * I * falloff(theta) * cos(theta) / r^2 (r^2 = d^2 + rho^2): I a d / (pi r^3)
 * inside the beam, 0 beyond the cutoff; checked pixel by pixel on pt's image. Agreement: with a
 * wall and a sphere added (indirect light, occlusion), lt, bdpt, cbdpt and pcbpt agree with pt
 * block by block within 4.5 standard errors measured from the iterations (fixed seeds). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define D 1.0          /* spot height above the floor */
#define INTENSITY 2.0
#define ALBEDO 0.5
#define CUTOFF 40.0    /* degrees */
#define BEAM 25.0

static const char *scene_head =
    "<scene version=\"0.6.0\"><integrator type=\"path\"><integer name=\"maxDepth\" value=\"6\"/></integrator>"
    "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/><transform name=\"toWorld\">"
    "<lookat origin=\"0, 0, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>"
    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film></sensor>"
    "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"3\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf></shape>"
    "<emitter type=\"spot\"><transform name=\"toWorld\"><lookat origin=\"0, 0, 1\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>"
    "<rgb name=\"intensity\" value=\"2\"/><float name=\"cutoffAngle\" value=\"40\"/><float name=\"beamWidth\" value=\"25\"/></emitter>";
/* A wall beside the spot's cone and a sphere in it. */
static const char *scene_more =
    "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"1.5\"/><rotate y=\"1\" angle=\"-90\"/>"
    "<translate x=\"0.9\" z=\"1.5\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.6, 0.4\"/></bsdf></shape>"
    "<shape type=\"sphere\"><point name=\"center\" x=\"-0.2\" y=\"0.1\" z=\"0.3\"/><float name=\"radius\" value=\"0.2\"/>"
    "<bsdf type=\"roughplastic\"><float name=\"alpha\" value=\"0.2\"/></bsdf></shape>";

static int render(const char *dir, const char *xml, pc_method m, int res, int iterations, int block, stat_blocks *st,
                  pc_scene *keep) {
  return stat_render_xml(dir, xml, m, res, 31, 0, iterations, block, st, keep);
}

/* The analytic radiance of the floor at horizontal distance rho from below the spot, and
 * whether the falloff is smooth over [rho - h, rho + h] (not across the beam's or cutoff's edge). */
static double floor_radiance(double rho) {
  double r = sqrt(D * D + rho * rho), th = atan2(rho, D) * 180 / M_PI;
  double f = th >= CUTOFF ? 0 : th <= BEAM ? 1 : (CUTOFF - th) / (CUTOFF - BEAM);
  return ALBEDO / M_PI * INTENSITY * f * (D / r) / (r * r);
}
static bool smooth_over(double rho, double h) {
  double a = atan2(fmax(rho - h, 0), D) * 180 / M_PI, b = atan2(rho + h, D) * 180 / M_PI;
  return !((a <= BEAM && b >= BEAM) || (a <= CUTOFF && b >= CUTOFF));
}

static void test_analytic(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_spot_XXXXXX", xml[4096];
  assert_non_null(mkdtemp(dir));
  snprintf(xml, sizeof xml, "%s</scene>", scene_head);
  enum { RES = 64, IT = 64 };
  stat_blocks st = {0};
  pc_scene s;
  assert_int_equal(render(dir, xml, PC_METHOD_PT, RES, IT, 1, &st, &s), 0);
  int inside = 0, transition = 0, dark = 0;
  double worst = 0;
  double px = 2 * 3 * tan(30 * M_PI / 180) / RES; /* pixel width on the floor */
  for (int y = 0; y < RES; y++)
    for (int x = 0; x < RES; x++) {
      vec3 d = pc_camera_ray_dir(&s.camera, x + 0.5f, y + 0.5f);
      double t = -s.camera.pos.z / d.z, fx = s.camera.pos.x + t * d.x, fy = s.camera.pos.y + t * d.y;
      double rho = sqrt(fx * fx + fy * fy);
      if (!smooth_over(rho, px)) continue;
      double expect = floor_radiance(rho), got = stat_mean(&st, y * RES + x);
      if (expect == 0) {
        assert_true(got == 0);
        dark++;
        continue;
      }
      /* The only noise is the jitter within the pixel (the light is a point): its standard error,
       * measured over the iterations, plus 0.2% for the curvature over a pixel (second order). */
      double z = fabs(got - expect) / (stat_se(&st, y * RES + x) + 2e-3 * expect);
      if (z > worst) worst = z;
      if (atan2(rho, D) * 180 / M_PI < BEAM) inside++;
      else transition++;
    }
  printf("spot over a floor, pt %dx%d, %d iterations: %d pixels in the beam, %d in the transition, largest difference %.2f standard errors (+0.2%%);"
         " %d pixels beyond the cutoff exactly 0\n",
         RES, RES, IT, inside, transition, worst, dark);
  assert_true(inside > 100 && transition > 50 && dark > 1000);
  assert_true(worst < 4.5);
  stat_free(&st);
  pc_scene_free(&s);
  th_rm_rf(dir);
}

static void test_agreement(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_spot_XXXXXX", xml[8192];
  assert_non_null(mkdtemp(dir));
  snprintf(xml, sizeof xml, "%s%s</scene>", scene_head, scene_more);
  double worst = stat_agreement(dir, xml, "spot scene", 32, 31, 0, 256, 8);
  th_rm_rf(dir);
  assert_true(worst < 4.5);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_analytic), cmocka_unit_test(test_agreement)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
