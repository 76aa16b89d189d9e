/* test_cylinder_transport.c: Mitsuba's exact `cylinder` in light transport. A horizontal emitting tube
 * and an upright open tube, two-sided and seen inside, over a floor: lt, bdpt, cbdpt and pcbpt
 * agree with pt block by block (the emitter is hit, sampled for next-event estimation and
 * started from, each with its own pdf); and the same scene with both tubes tessellated into
 * 512 flat quads (Embree's triangles, the area table of a mesh emitter) agrees with the exact
 * one, within 4.5 standard errors measured from the iterations (fixed seeds). The
 * tessellation's own bias (its area is 1 - 2.5e-5 of the circle's) is far below that. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define SEGMENTS 512

/* %s: the light's shape (type and parameters), then the open tube's */
static const char *scene_fmt =
    "<scene version=\"0.6.0\"><integrator type=\"path\"><integer name=\"maxDepth\" value=\"5\"/></integrator>"
    "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/>"
    "<transform name=\"toWorld\"><lookat origin=\"0, 3, 5\" target=\"0, 0.5, 0\" up=\"0, 1, 0\"/></transform>"
    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film></sensor>"
    "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"4\"/><rotate x=\"1\" angle=\"-90\"/></transform>"
    "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf></shape>"
    "<shape type=\"%s\">%s<transform name=\"toWorld\"><scale x=\"%s\" y=\"%s\" z=\"2\"/><rotate y=\"1\" angle=\"90\"/>"
    "<translate x=\"-1\" y=\"1.6\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.2\"/></bsdf>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"8, 6, 4\"/></emitter></shape>"
    "<shape type=\"%s\">%s<transform name=\"toWorld\"><scale x=\"%s\" y=\"%s\"/><rotate x=\"1\" angle=\"-90\"/>"
    "<translate x=\"0.3\"/></transform><bsdf type=\"twosided\"><bsdf type=\"diffuse\">"
    "<rgb name=\"reflectance\" value=\"0.2, 0.7, 0.3\"/></bsdf></bsdf></shape></scene>";

static void exact_scene(char *xml, size_t cap) {
  snprintf(xml, cap, scene_fmt, "cylinder", "<float name=\"radius\" value=\"0.15\"/>", "1", "1", "cylinder",
           "<float name=\"radius\" value=\"0.5\"/>", "1", "1");
}

/* The unit tube (radius 1, z from 0 to 1) as SEGMENTS flat quads facing out, in dir/tube.obj,
 * and the scene that scales it as the exact one's parameters do. */
static void mesh_scene(const char *dir, char *xml, size_t cap) {
  char path[4200];
  snprintf(path, sizeof path, "%s/tube.obj", dir);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  for (int i = 0; i < SEGMENTS; i++) {
    double a = 2 * M_PI * i / SEGMENTS;
    fprintf(f, "v %.9f %.9f 0\nv %.9f %.9f 1\n", cos(a), sin(a), cos(a), sin(a));
  }
  for (int i = 0; i < SEGMENTS; i++) {
    int j = (i + 1) % SEGMENTS, b0 = 2 * i + 1, t0 = 2 * i + 2, b1 = 2 * j + 1, t1 = 2 * j + 2;
    fprintf(f, "f %d %d %d\nf %d %d %d\n", b0, b1, t1, b0, t1, t0);
  }
  assert_int_equal(fclose(f), 0);
  const char *obj = "<string name=\"filename\" value=\"tube.obj\"/>";
  snprintf(xml, cap, scene_fmt, "obj", obj, "0.15", "0.15", "obj", obj, "0.5", "0.5");
}

static void test_agreement(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_cylinder_XXXXXX", xml[8192];
  assert_non_null(mkdtemp(dir));
  exact_scene(xml, sizeof xml);
  double worst = stat_agreement(dir, xml, "cylinders", 32, 41, 0, 256, 8);
  th_rm_rf(dir);
  assert_true(worst < 4.5);
}

static void test_tessellated(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_cylinder_XXXXXX", xml[8192];
  assert_non_null(mkdtemp(dir));
  stat_blocks exact = {0}, mesh = {0};
  exact_scene(xml, sizeof xml);
  assert_int_equal(stat_render_xml(dir, xml, PC_METHOD_BDPT, 32, 43, 0, 256, 4, &exact, NULL), 0);
  mesh_scene(dir, xml, sizeof xml);
  assert_int_equal(stat_render_xml(dir, xml, PC_METHOD_BDPT, 32, 47, 0, 256, 4, &mesh, NULL), 0);
  double z = stat_largest_z(&exact, &mesh), se = 0, sum = 0, msum = 0;
  for (int b = 0; b < exact.nblocks; b++) {
    sum += stat_mean(&exact, b), msum += stat_mean(&mesh, b);
    se += stat_se(&exact, b) * stat_se(&exact, b) + stat_se(&mesh, b) * stat_se(&mesh, b);
  }
  printf("exact cylinders against %d-quad tubes, bdpt, 256 iterations: largest block difference %.2f standard errors over %d"
         " blocks; image means %.5f and %.5f (standard error of the difference %.5f)\n",
         SEGMENTS, z, exact.nblocks, sum / exact.nblocks, msum / exact.nblocks, sqrt(se) / exact.nblocks);
  assert_true(z < 4.5);
  assert_true(fabs(sum - msum) < 4.5 * sqrt(se));
  stat_free(&exact);
  stat_free(&mesh);
  th_rm_rf(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_agreement), cmocka_unit_test(test_tessellated)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
