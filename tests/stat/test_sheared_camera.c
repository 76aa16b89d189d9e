/* test_sheared_camera.c: a camera frame that is not orthogonal (Mitsuba accepts a matrix rigid
 * to 1e-3; this one leans its up axis by 0.15 toward the view and 0.1 toward the left, so that
 * any error shows) renders the same image in every method: pt's rays, light tracing's and BDPT's
 * t=1 connections (raster position, We, direction pdf) and the MIS weights must all use the same
 * frame. A pinhole and a thin lens over a lit floor with a sphere; lt, bdpt, cbdpt and pcbpt
 * against pt, block by block within 4.5 standard errors measured from the iterations (fixed
 * seeds). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define RES 32
#define ITERATIONS 384
#define BLOCK 8

/* Leans the loaded camera's up axis (its matrix's second column). */
static void shear(pc_camera *c) {
  for (int r = 0; r < 3; r++) c->to_world.m[r][1] += 0.15 * c->to_world.m[r][2] + 0.1 * c->to_world.m[r][0];
  pc_camera_prepare(c);
}

static int render(const char *path, pc_method m, stat_blocks *st) {
  pc_render_request req;
  pc_scene scene;
  int rc = stat_load_file(path, NULL, m, RES, 59, &req, &scene);
  if (rc) return rc;
  shear(&scene.camera);
  if (!(fabsf(scene.camera.inv_det - 1.f) > 0.005f)) {
    pc_scene_free(&scene);
    return -1;
  }
  rc = stat_render_blocks(&scene, &req.set, 2, 0, ITERATIONS, -1, BLOCK, st);
  pc_scene_free(&scene);
  return rc;
}

static void agreement(const char *sensor, const char *label) {
  char dir[] = "/tmp/pcbpt_shear_XXXXXX", xml[4096], path[4200];
  assert_non_null(mkdtemp(dir));
  snprintf(xml, sizeof xml,
           "<scene version=\"0.6.0\"><integrator type=\"path\"><integer name=\"maxDepth\" value=\"4\"/></integrator>%s"
           STAT_VIEW_OF_LIT_FLOOR
           "<shape type=\"sphere\"><point name=\"center\" x=\"0.4\" y=\"0.4\" z=\"-0.5\"/><float name=\"radius\" value=\"0.4\"/>"
           "<bsdf type=\"roughplastic\"><float name=\"alpha\" value=\"0.2\"/></bsdf></shape></scene>",
           sensor);
  assert_int_equal(th_write_str(dir, "scene.xml", xml), 0);
  snprintf(path, sizeof path, "%s/scene.xml", dir);
  stat_blocks ref = {0};
  assert_int_equal(render(path, PC_METHOD_PT, &ref), 0);
  const pc_method methods[] = {PC_METHOD_LT, PC_METHOD_BDPT, PC_METHOD_CBDPT, PC_METHOD_PCBPT};
  double worst = 0;
  for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
    stat_blocks st = {0};
    assert_int_equal(render(path, methods[k], &st), 0);
    double z = stat_largest_z(&ref, &st);
    printf("%s %-5s vs pt: largest block difference %.2f standard errors over %d blocks\n", label, pc_method_name(methods[k]),
           z, st.nblocks);
    if (z > worst) worst = z;
    stat_free(&st);
  }
  stat_free(&ref);
  th_rm_rf(dir);
  assert_true(worst < 4.5);
}

static void test_pinhole(void **state) {
  (void)state;
  agreement("<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>", "sheared pinhole");
}

static void test_thin_lens(void **state) {
  (void)state;
  agreement("<sensor type=\"thinlens\"><float name=\"fov\" value=\"60\"/><float name=\"apertureRadius\" value=\"0.15\"/>"
            "<float name=\"focusDistance\" value=\"2\"/>",
            "sheared thin lens");
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_pinhole), cmocka_unit_test(test_thin_lens)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
