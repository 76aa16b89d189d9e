/* test_film_filter.c: a scene's reconstruction filter is every method's pixel measurement.
 * Analytic: the camera looks straight at an emitter of radiance 1 that ends in a vertical edge
 * across the middle of the image, so pixel column i measures the share of its filter (over the
 * film) that falls on the emitter's side of the edge: exactly 1 or 0 away from the edge, the film's
 * edge columns included (where the film cuts the filter), and in between near it. pt (eye samples
 * drawn from each pixel's filter), lt (light-traced splats over the filter's footprint, weighed
 * against the emitter seen directly), bdpt and pcbpt must give it in every pixel within 4.5
 * standard errors measured from their iterations, pt exactly where its samples cannot differ;
 * for Mitsuba's gaussian and tent and a box of radius 1.3 pixels. Agreement: the Cornell box of
 * test_directional's kind (a floor and a back wall that fill the view, an area light, two
 * spheres) under a gaussian filter, every method against pt block by block (fixed seeds): with
 * a black background, pt's few samples in a filter's far tail leave blocks exactly 0 that light
 * tracing's splats give a few 1e-9. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define RES 16
#define EDGE_X 0.1 /* world x of the emitter's edge: 0.73 pixels off the image's centre */

static void edge_scene(char *xml, size_t n, const char *rfilter) {
  snprintf(xml, n,
           "<scene version=\"0.6.0\"><integrator type=\"path\"><integer name=\"maxDepth\" value=\"3\"/></integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><transform name=\"toWorld\">"
           "<lookat origin=\"0, 0, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"%d\"/><integer name=\"height\" value=\"%d\"/>%s</film></sensor>"
           "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"1\" y=\"1.5\"/><translate x=\"%g\"/></transform>"
           "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>"
           "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape></scene>",
           RES, RES, rfilter, EDGE_X - 1);
}

/* The emitter's share of column i's filter: the film part of [lo, hi] in raster x. */
static double covered(const pc_rfilter *f, int i, double lo, double hi) {
  double c = i + 0.5, sum = 0;
  enum { STEPS = 200000 };
  double a = fmax(0, fmax(lo, c - f->radius)), b = fmin(RES, fmin(hi, c + f->radius));
  for (int k = 0; k < STEPS && b > a; k++) sum += pc_rfilter_value(f, (float)(a + (k + 0.5) * (b - a) / STEPS - c));
  return sum * (b > a ? (b - a) / STEPS : 0) / pc_rfilter_mass(f, (float)c, RES);
}

static void check_filter(const char *dir, const char *rfilter) {
  char xml[4096];
  edge_scene(xml, sizeof xml, rfilter);
  const pc_method methods[] = {PC_METHOD_PT, PC_METHOD_LT, PC_METHOD_BDPT, PC_METHOD_PCBPT};
  for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
    stat_blocks st = {0};
    pc_scene scene;
    assert_int_equal(stat_render_xml(dir, xml, methods[k], RES, 5, 0, 256, 1, &st, &scene), 0);
    const pc_camera *cam = &scene.camera;
    assert_false(pc_rfilter_is_pixel(&cam->filter));
    /* where the edge is in raster x, and which side the emitter lies on */
    float ex, ey, ix, iy;
    assert_true(pc_camera_raster(cam, v3_sub(v3((float)EDGE_X, 0, 0), cam->pos), &ex, &ey));
    assert_true(pc_camera_raster(cam, v3_sub(v3((float)EDGE_X - 0.5f, 0, 0), cam->pos), &ix, &iy));
    double lo = ix < ex ? -1 : ex, hi = ix < ex ? ex : RES + 1;
    double worst = 0;
    int exact = 0;
    for (int y = 0; y < RES; y++)
      for (int x = 0; x < RES; x++) {
        int b = y * RES + x;
        double c = x + 0.5, r = cam->filter.radius, from = fmax(0, c - r), to = fmin(RES, c + r);
        bool all = from >= lo && to <= hi, none = to <= lo || from >= hi;
        double expect = all ? 1 : none ? 0 : covered(&cam->filter, x, lo, hi), m = stat_mean(&st, b), se = stat_se(&st, b);
        if (methods[k] == PC_METHOD_PT && (all || none)) {
          assert_true(fabs(m - expect) < 1e-5); /* every sample there sees the emitter, or none does */
          exact++;
          continue;
        }
        if (se == 0) { /* every sample on one side: a share of 0.03 or more of the filter on the
                          other is missed by all 256 with probability 0.97^256 = 4e-4 at most */
          assert_true(fabs(m - expect) < 0.03);
          continue;
        }
        double z = fabs(m - expect) / se;
        if (z > worst) worst = z;
      }
    printf("%s %-5s: edge at raster x %.3f, largest pixel difference %.2f standard errors (%d pixels exact)\n", rfilter,
           pc_method_name(methods[k]), (double)ex, worst, exact);
    assert_true(worst < 4.5);
    if (methods[k] == PC_METHOD_PT) assert_true(exact >= RES * (RES - 6));
    stat_free(&st);
    pc_scene_free(&scene);
  }
}

static void test_edge(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_filter_XXXXXX";
  assert_non_null(mkdtemp(dir));
  check_filter(dir, "<rfilter type=\"gaussian\"/>");
  check_filter(dir, "<rfilter type=\"tent\"/>");
  check_filter(dir, "<rfilter type=\"box\"><float name=\"radius\" value=\"1.3\"/></rfilter>");
  th_rm_rf(dir);
}

static void test_agreement(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_filter_XXXXXX", xml[8192];
  assert_non_null(mkdtemp(dir));
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\"><integrator type=\"path\"><integer name=\"maxDepth\" value=\"5\"/></integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/>"
           "<transform name=\"toWorld\"><lookat origin=\"0, 1, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/>"
           "<rfilter type=\"gaussian\"><float name=\"stddev\" value=\"0.6\"/></rfilter></film></sensor>"
           "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"3\"/><rotate x=\"1\" angle=\"-90\"/></transform>"
           "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf></shape>"
           "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"3\"/><translate y=\"3\" z=\"-3\"/></transform>"
           "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf></shape>"
           "<shape type=\"sphere\"><point name=\"center\" x=\"-0.5\" y=\"0.4\" z=\"0\"/><float name=\"radius\" value=\"0.4\"/>"
           "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8\"/></bsdf></shape>"
           "<shape type=\"sphere\"><point name=\"center\" x=\"0.6\" y=\"0.3\" z=\"0.3\"/><float name=\"radius\" value=\"0.3\"/>"
           "<bsdf type=\"roughplastic\"><float name=\"alpha\" value=\"0.2\"/></bsdf></shape>"
           "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"0.3\"/><rotate x=\"1\" angle=\"90\"/>"
           "<translate y=\"2\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"20\"/></emitter></shape></scene>");
  double worst = stat_agreement(dir, xml, "gaussian filter", 32, 9, 0, 192, 4);
  assert_true(worst < 4.5);
  th_rm_rf(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_edge),
      cmocka_unit_test(test_agreement),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
