/* test_cylinder.c: Mitsuba's `cylinder` shape: placement from p0, p1, radius and toWorld as
 * Mitsuba composes them, the quadric's hits from outside, from inside and through the open
 * ends, Mitsuba's uv and tangents, the normal's side (flipNormals, a mirroring toWorld), area
 * sampling of an emitting one, instances and motion, and the refused placements. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "rng.h"
#include "scene.h"
#include "test_helpers_fs.h"

#define SENSOR "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>\n"

static void near3(vec3 a, vec3 b, float tol) {
  if (fabsf(a.x - b.x) > tol || fabsf(a.y - b.y) > tol || fabsf(a.z - b.z) > tol) {
    print_error("(%g %g %g) != (%g %g %g)\n", a.x, a.y, a.z, b.x, b.y, b.z);
    fail();
  }
}

static void near1(double a, double b, double tol) {
  if (!(fabs(a - b) <= tol)) {
    print_error("%.9g != %.9g\n", a, b);
    fail();
  }
}

/* Loads `body` as a scene (line 1 is <scene>) in a fresh folder; returns the loader's code. */
static int load(const char *body, pc_scene *s, pc_err *e) {
  char dir[] = "/tmp/pcbpt_cyl_XXXXXX", path[4096];
  assert_non_null(mkdtemp(dir));
  char *xml = malloc(strlen(body) + 64);
  sprintf(xml, "<scene version=\"0.6.0\">\n%s</scene>\n", body);
  assert_int_equal(th_write_str(dir, "scene.xml", xml), 0);
  free(xml);
  snprintf(path, sizeof path, "%s/scene.xml", dir);
  int rc = pc_scene_load(path, s, e);
  th_rm_rf(dir);
  return rc;
}

static void load_built(const char *body, pc_scene *s) {
  pc_err e = {0};
  int rc = load(body, s, &e);
  if (rc == 0) rc = pc_scene_build(s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
}

/* A tube from (1,2,3) to (1,2,5) of radius 0.5 (the axis +z, so Mitsuba's frame puts u = 0 at
 * +x and u = 1/4 at +y), a point light to make the scene renderable. */
static const char *tube =
    SENSOR "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"9\"/></emitter>\n"
    "<shape type=\"cylinder\"><point name=\"p0\" x=\"1\" y=\"2\" z=\"3\"/><point name=\"p1\" x=\"1\" y=\"2\" z=\"5\"/>"
    "<float name=\"radius\" value=\"0.5\"/>%s</shape>\n";

static void load_tube(const char *extra, pc_scene *s) {
  char body[2048];
  snprintf(body, sizeof body, tube, extra);
  load_built(body, s);
}

static void test_placement(void **state) {
  (void)state;
  pc_scene s;
  load_tube("", &s);
  const pc_shape *sh = &s.shapes[0];
  assert_int_equal(sh->kind, PC_SHAPE_CYLINDER);
  near3(sh->center, v3(1, 2, 3), 0);
  near3(sh->cyl_axes.n, v3(0, 0, 1), 0);
  near3(sh->cyl_axes.s, v3(1, 0, 0), 0);
  near3(sh->cyl_axes.t, v3(0, 1, 0), 0);
  near1(sh->radius, 0.5, 0);
  near1(sh->length, 2, 0);
  pc_scene_free(&s);

  /* Mitsuba's defaults (0,0,0)-(0,0,1), radius 1, then a scale along the axis that keeps it
   * circular and a rotation of the axis onto +x */
  pc_err e = {0};
  assert_int_equal(load(SENSOR "<shape type=\"cylinder\"><transform name=\"toWorld\"><scale x=\"0.2\" y=\"0.2\" z=\"3\"/>"
                               "<rotate y=\"1\" angle=\"90\"/><translate y=\"1\"/></transform></shape>\n",
                        &s, &e),
                   0);
  sh = &s.shapes[0];
  near3(sh->center, v3(0, 1, 0), 1e-6f);
  near3(sh->cyl_axes.n, v3(1, 0, 0), 1e-6f);
  near1(sh->radius, 0.2, 1e-6);
  near1(sh->length, 3, 1e-6);
  vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
  pc_shape_grow_bounds(sh, &lo, &hi);
  near3(lo, v3(0, 0.8f, -0.2f), 1e-6f);
  near3(hi, v3(3, 1.2f, 0.2f), 1e-6f);
  pc_scene_free(&s);
}

static void test_refused(void **state) {
  (void)state;
  const struct { const char *body, *want; } bad[] = {
      {"<shape type=\"cylinder\"><transform name=\"toWorld\"><scale x=\"2\"/></transform></shape>", "circular"},
      {"<shape type=\"cylinder\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"45\"/><scale y=\"3\"/></transform></shape>",
       "circular"},
      {"<shape type=\"cylinder\"><float name=\"radius\" value=\"0\"/></shape>", "radius"},
      {"<shape type=\"cylinder\"><point name=\"p1\" x=\"0\" y=\"0\" z=\"0\"/></shape>", "distinct"},
      {"<shape type=\"shapegroup\" id=\"g\"><shape type=\"cylinder\"/></shape><shape type=\"instance\"><ref id=\"g\"/>"
       "<transform name=\"toWorld\"><scale y=\"2\"/></transform></shape>",
       "holds a cylinder"},
      {"<shape type=\"cylinder\"><animation name=\"toWorld\"><transform time=\"0\"><scale x=\"2\"/></transform>"
       "<transform time=\"1\"/></animation></shape>",
       "uniformly"},
  };
  char body[2048];
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    pc_scene s;
    pc_err e = {0};
    snprintf(body, sizeof body, SENSOR "%s\n", bad[i].body);
    int rc = load(body, &s, &e);
    if (rc == 0 || !strstr(e.msg, bad[i].want) || !strstr(e.msg, "scene.xml:3:")) {
      print_error("case %zu: rc %d, '%s' (want '%s')\n", i, rc, e.msg, bad[i].want);
      fail();
    }
  }
}

static void test_hits(void **state) {
  (void)state;
  pc_scene s;
  load_tube("", &s);
  pc_hit h;
  /* from outside, toward +y: the near wall at y = 1.5, facing -y, u = 3/4 */
  assert_true(pc_scene_intersect(&s, v3(1, -5, 4), v3(0, 1, 0), INFINITY, &h));
  near1(h.t, 6.5, 1e-5);
  near3(h.p, v3(1, 1.5f, 4), 1e-6f);
  near3(h.ng, v3(0, -1, 0), 1e-6f);
  near3(h.ns, h.ng, 0);
  near1(h.uv.x, 0.75, 1e-6);
  near1(h.uv.y, 0.5, 1e-6);
  /* Mitsuba's dpdu = 2 pi r (-y, x, 0) in the tube's frame, dpdv = length along the axis */
  near3(h.dpdu, v3((float)M_PI, 0, 0), 1e-5f);
  near3(h.dpdv, v3(0, 0, 2), 1e-6f);
  near1(v3_dot(v3_norm(v3_cross(h.dpdu, h.dpdv)), h.ng), 1, 1e-6);
  assert_true(h.eps > 0.f && h.eps < 1e-4f);
  /* a ray that stops short of the wall */
  assert_false(pc_scene_intersect(&s, v3(1, -5, 4), v3(0, 1, 0), 6.4f, &h));
  /* from inside: the far wall, whose normal still points out (the ray meets its back) */
  assert_true(pc_scene_intersect(&s, v3(1, 2, 4), v3(1, 0, 0), INFINITY, &h));
  near1(h.t, 0.5, 1e-6);
  near3(h.ng, v3(1, 0, 0), 1e-6f);
  near1(h.uv.x, 0, 1e-6);
  /* along the axis through both open ends: nothing */
  assert_false(pc_scene_intersect(&s, v3(1, 2, 0), v3(0, 0, 1), INFINITY, &h));
  /* in through the open bottom, onto the inside of the wall at (1.5, 2, 3.5) */
  assert_true(pc_scene_intersect(&s, v3(1, 2, 0), v3(0.5f, 0, 3.5f), INFINITY, &h));
  near3(h.p, v3(1.5f, 2, 3.5f), 1e-5f);
  near1(h.uv.y, 0.25, 1e-5);
  assert_true(v3_dot(h.ng, v3(0.5f, 0, 3.5f)) > 0.f);
  /* past the top end, and through the tube's height where a far wall is missed at the top */
  assert_false(pc_scene_intersect(&s, v3(1, -5, 5.01f), v3(0, 1, 0), INFINITY, &h));
  assert_true(pc_scene_intersect(&s, v3(1, -5, 4.99f), v3(0, 1, 0), INFINITY, &h));
  /* the near side is below the bottom, the far side within: the far wall, from inside */
  assert_true(pc_scene_intersect(&s, v3(1, 0, 2), v3(0, 1, 0.5f), INFINITY, &h));
  near3(h.p, v3(1, 2.5f, 3.25f), 1e-5f);
  near3(h.ng, v3(0, 1, 0), 1e-5f);
  /* shadow rays: blocked through the tube, free beside it and through its open ends */
  assert_false(pc_scene_visible(&s, v3(1, -5, 4), v3s(0), 0.f, v3(1, 9, 4), v3s(0), 0.f));
  assert_true(pc_scene_visible(&s, v3(2, -5, 4), v3s(0), 0.f, v3(2, 9, 4), v3s(0), 0.f));
  assert_true(pc_scene_visible(&s, v3(1, 2, -1), v3s(0), 0.f, v3(1, 2, 9), v3s(0), 0.f));
  /* a segment that ends before the wall */
  assert_true(pc_scene_visible(&s, v3(1, -5, 4), v3s(0), 0.f, v3(1, 1.4f, 4), v3s(0), 0.f));
  pc_scene_free(&s);

  /* flipNormals turns the normal in; so does a mirroring toWorld (Mitsuba's cross(dpdu, dpdv)),
   * and both together turn it back out */
  const struct { const char *extra; float sign; } sides[] = {
      {"<boolean name=\"flipNormals\" value=\"true\"/>", -1},
      {"<transform name=\"toWorld\"><scale x=\"-1\"/><translate x=\"2\"/></transform>", -1},
      {"<boolean name=\"flipNormals\" value=\"true\"/><transform name=\"toWorld\"><scale x=\"-1\"/><translate x=\"2\"/></transform>",
       1},
  };
  for (size_t i = 0; i < sizeof sides / sizeof sides[0]; i++) {
    load_tube(sides[i].extra, &s);
    assert_true(pc_scene_intersect(&s, v3(1, -5, 4), v3(0, 1, 0), INFINITY, &h));
    near3(h.p, v3(1, 1.5f, 4), 1e-5f);
    near3(h.ng, v3(0, -sides[i].sign, 0), 1e-5f);
    pc_scene_free(&s);
  }
}

/* An emitting tube: its area and power, and points sampled on it: on the surface, uniform in
 * height and angle (moments), with the hit record's normal. */
static void test_emitter(void **state) {
  (void)state;
  pc_scene s;
  load_tube("<emitter type=\"area\"><rgb name=\"radiance\" value=\"2\"/></emitter>", &s);
  assert_int_equal(s.nlights, 2);
  const pc_light *l = &s.lights[s.shapes[0].light];
  near1(l->area, 2 * M_PI * 0.5 * 2, 1e-5);
  near1(l->power, M_PI * l->area * 2, 1e-4);
  pc_rng r = pc_rng_make(7, 0, 0, 0);
  enum { N = 20000 };
  double mz = 0, mz2 = 0, mx = 0, my = 0;
  for (int i = 0; i < N; i++) {
    pc_light_point lp;
    pc_light_sample_point(&s, l, pc_rng_f(&r), pc_rng_f(&r), pc_rng_f(&r), &lp);
    near1(lp.pdf_area, 1 / l->area, 1e-7);
    vec3 rel = v3_sub(lp.p, v3(1, 2, 3));
    near1(sqrt(rel.x * rel.x + rel.y * rel.y), 0.5, 1e-6);
    assert_true(rel.z >= 0.f && rel.z <= 2.f);
    near3(lp.n, v3_scale(v3(rel.x, rel.y, 0), 2), 1e-5f);
    pc_hit h;
    vec3 o = v3_madd(lp.p, lp.n, 1.f);
    assert_true(pc_scene_intersect(&s, o, v3_neg(lp.n), INFINITY, &h));
    near3(h.ng, lp.n, 1e-5f);
    mz += rel.z, mz2 += rel.z * rel.z, mx += rel.x, my += rel.y;
  }
  /* uniform on [0, 2]: mean 1, second moment 4/3; x and y have mean 0. Standard errors of the
   * means of N samples: sqrt(1/3 / N) = 0.0041, sqrt((16/5 - 16/9) / N) = 0.0084 and
   * sqrt(0.125 / N) = 0.0025; each checked to 5 of them */
  near1(mz / N, 1, 5 * 0.0041);
  near1(mz2 / N, 4. / 3, 5 * 0.0084);
  near1(mx / N, 0, 5 * 0.0025);
  near1(my / N, 0, 5 * 0.0025);
  pc_scene_free(&s);
}

static void test_instance_and_motion(void **state) {
  (void)state;
  pc_scene s;
  load_built(SENSOR "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"9\"/></emitter>\n"
                    "<shape type=\"shapegroup\" id=\"g\"><shape type=\"cylinder\"><float name=\"radius\" value=\"0.5\"/></shape></shape>\n"
                    "<shape type=\"instance\"><ref id=\"g\"/><transform name=\"toWorld\"><scale value=\"2\"/><translate x=\"5\"/></transform></shape>\n",
             &s);
  assert_int_equal(s.nshapes, 1);
  near3(s.shapes[0].center, v3(5, 0, 0), 1e-6f);
  near1(s.shapes[0].radius, 1, 1e-6);
  near1(s.shapes[0].length, 2, 1e-6);
  pc_hit h;
  assert_true(pc_scene_intersect(&s, v3(5, -5, 1), v3(0, 1, 0), INFINITY, &h));
  near1(h.t, 4, 1e-5);
  pc_scene_free(&s);

  /* a tube moving from x = 0 to x = 4 over the shutter */
  load_built("<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><float name=\"shutterOpen\" value=\"0\"/><float name=\"shutterClose\" value=\"1\"/></sensor>\n"
             "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"9\"/></emitter>\n"
             "<shape type=\"cylinder\"><float name=\"radius\" value=\"0.5\"/><animation name=\"toWorld\">"
             "<transform time=\"0\"/><transform time=\"1\"><translate x=\"4\"/></transform></animation></shape>\n",
             &s);
  pc_scene *view = NULL;
  pc_err e = {0};
  assert_int_equal(pc_scene_view_create(&s, &view, &e), 0);
  assert_int_equal(pc_scene_view_set_time(view, 0.5f, &e), 0);
  near3(view->shapes[0].center, v3(2, 0, 0), 1e-6f);
  assert_true(pc_scene_intersect(view, v3(2, -5, 0.5f), v3(0, 1, 0), INFINITY, &h));
  near1(h.t, 4.5, 1e-5);
  assert_false(pc_scene_intersect(view, v3(0, -5, 0.5f), v3(0, 1, 0), INFINITY, &h));
  pc_scene_view_destroy(view);
  pc_scene_free(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_placement), cmocka_unit_test(test_refused), cmocka_unit_test(test_hits),
                                     cmocka_unit_test(test_emitter), cmocka_unit_test(test_instance_and_motion)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
