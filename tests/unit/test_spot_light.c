/* test_spot_light.c: Mitsuba's `spot` emitter: the loader's reading of its parameters (defaults,
 * lookat frame, refusals), the falloff on the axis, in the beam, across the transition and at
 * and beyond the cutoff, the cone sampling against its pdf (chi-square), and its flux
 * (pc_spot_solid_angle against quadrature and against the sampled estimate; the scene's power). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "chi2.h"
#include "rng.h"
#include "scene.h"
#include "test_helpers_fs.h"

static const char *head =
    "<scene version=\"0.6.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>"
    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor>"
    "<shape type=\"rectangle\"/>";

/* Loads head + body + </scene> from a temporary folder; returns the loader's code. */
static int load_body(const char *body, pc_scene *s, pc_err *e) {
  char dir[] = "/tmp/pcbpt_spot_XXXXXX", path[256], *xml = malloc(strlen(head) + strlen(body) + 16);
  assert_non_null(mkdtemp(dir));
  sprintf(xml, "%s%s</scene>", head, body);
  assert_int_equal(th_write_str(dir, "scene.xml", xml), 0);
  free(xml);
  snprintf(path, sizeof path, "%s/scene.xml", dir);
  memset(s, 0, sizeof *s);
  int rc = pc_scene_load(path, s, e);
  th_rm_rf(dir);
  return rc;
}

static const pc_light *only_spot(const pc_scene *s) {
  assert_int_equal(s->nlights, 1);
  assert_int_equal(s->lights[0].type, PC_LIGHT_SPOT);
  return &s->lights[0];
}

static void test_parse(void **state) {
  (void)state;
  pc_scene s;
  pc_err e = {0};
  /* Defaults: intensity 1, cutoff 20 degrees, beam 3/4 of it; at the origin along +z. */
  assert_int_equal(load_body("<emitter type=\"spot\"/>", &s, &e), PC_OK);
  const pc_light *l = only_spot(&s);
  assert_float_equal(l->cutoff, 20.0 * M_PI / 180, 1e-6);
  assert_float_equal(l->beam_width, 15.0 * M_PI / 180, 1e-6);
  assert_float_equal(l->intensity.x, 1, 0);
  assert_float_equal(l->spot_frame.n.z, 1, 1e-6);
  assert_float_equal(v3_len(l->position), 0, 0);
  pc_scene_free(&s);
  /* lookat: at origin, toward target; the default beam follows a given cutoff. */
  assert_int_equal(load_body("<emitter type=\"spot\"><transform name=\"toWorld\"><lookat origin=\"1, 2, 3\" target=\"1, 2, 0\" "
                             "up=\"0, 1, 0\"/></transform><rgb name=\"intensity\" value=\"2, 3, 4\"/>"
                             "<float name=\"cutoffAngle\" value=\"40\"/><float name=\"samplingWeight\" value=\"2\"/></emitter>",
                             &s, &e),
                   PC_OK);
  l = only_spot(&s);
  assert_float_equal(l->position.x, 1, 1e-6);
  assert_float_equal(l->position.y, 2, 1e-6);
  assert_float_equal(l->position.z, 3, 1e-6);
  assert_float_equal(l->spot_frame.n.z, -1, 1e-6);
  assert_float_equal(l->beam_width, 30.0 * M_PI / 180, 1e-6);
  assert_float_equal(l->intensity.z, 4, 0);
  assert_float_equal(l->sampling_weight, 2, 0);
  pc_scene_free(&s);
  /* A projected checkerboard is kept; a constant one has no effect (Mitsuba). */
  assert_int_equal(load_body("<emitter type=\"spot\"><texture name=\"texture\" type=\"checkerboard\"/></emitter>", &s, &e), PC_OK);
  assert_non_null(only_spot(&s)->spot_tex);
  pc_scene_free(&s);
  assert_int_equal(load_body("<emitter type=\"spot\"><rgb name=\"texture\" value=\"0.2\"/></emitter>", &s, &e), PC_OK);
  assert_null(only_spot(&s)->spot_tex);
  pc_scene_free(&s);
  /* Refusals, each one line naming the file, line and what is wrong. */
  static const char *const bad[][2] = {
      {"<emitter type=\"spot\"><float name=\"beamWidth\" value=\"30\"/></emitter>", "beamWidth must lie in [0, cutoffAngle]"},
      {"<emitter type=\"spot\"><float name=\"cutoffAngle\" value=\"0\"/></emitter>", "cutoffAngle must lie in (0, 180]"},
      {"<emitter type=\"spot\"><float name=\"cutoffAngle\" value=\"200\"/></emitter>", "cutoffAngle must lie in (0, 180]"},
      {"<emitter type=\"spot\"><rgb name=\"intensity\" value=\"0\"/></emitter>", "'intensity' must be positive"},
      {"<emitter type=\"spot\"><transform name=\"toWorld\"><scale value=\"2\"/></transform></emitter>", "not modelled by pcbpt"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    e.msg[0] = 0;
    if (load_body(bad[i][0], &s, &e) == PC_OK) {
      fprintf(stderr, "loaded: %s\n", bad[i][0]);
      fail();
    }
    if (!strstr(e.msg, bad[i][1]) || !strstr(e.msg, "scene.xml:1: emitter 'spot'") || strchr(e.msg, '\n')) {
      fprintf(stderr, "%s\n -> %s\n", bad[i][0], e.msg);
      fail();
    }
  }
}

/* A spot along an oblique axis (cutoff 40, beam 25 degrees). */
static pc_light make_spot(vec3 axis, float cutoff, float beam) {
  pc_light l;
  memset(&l, 0, sizeof l);
  l.type = PC_LIGHT_SPOT;
  l.intensity = v3(2, 3, 4);
  l.spot_frame = frame_from_normal(v3_norm(axis));
  pc_spot_set_angles(&l, cutoff, beam);
  return l;
}

/* The unit direction at angle `deg` from the axis. */
static vec3 at_angle(const pc_light *l, float deg, float phi) {
  float t = deg * (float)M_PI / 180.f;
  return frame_to_world(&l->spot_frame, v3(sinf(t) * cosf(phi), sinf(t) * sinf(phi), cosf(t)));
}

static void test_falloff(void **state) {
  (void)state;
  pc_light l = make_spot(v3(0.3f, -1.f, 0.4f), 40.f, 25.f);
  static const struct { float deg, expect; } cases[] = {
      {0, 1}, {10, 1}, {24.9f, 1}, {25.5f, 14.5f / 15}, {32.5f, 0.5f}, {37, 3.f / 15}, {39.9f, 0.1f / 15}, {40.1f, 0}, {60, 0}, {179, 0}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
    for (float phi = 0; phi < 6.2f; phi += 0.9f) {
      vec3 w = at_angle(&l, cases[i].deg, phi);
      vec3 f = pc_spot_falloff(&l, w);
      assert_float_equal(f.x, cases[i].expect, 2e-4);
      assert_float_equal(f.y, f.x, 0);
      /* emitted intensity toward w; a point light's profile is 1 */
      assert_float_equal(pc_light_le(&l, v3s(0), w).z, 4 * cases[i].expect, 1e-3);
      assert_float_equal(pc_light_pdf_dir(&l, v3s(0), w), 1 / (2 * M_PI * (1 - cos(40 * M_PI / 180))), 1e-4);
    }
  /* Beam equal to the cutoff: a hard edge (a published scene uses 4.5 and 4.5). */
  pc_light h = make_spot(v3(0, 0, 1), 4.5f, 4.5f);
  assert_float_equal(pc_spot_falloff(&h, at_angle(&h, 4.4f, 0)).x, 1, 0);
  assert_float_equal(pc_spot_falloff(&h, at_angle(&h, 4.6f, 0)).x, 0, 0);
  assert_float_equal(pc_spot_solid_angle(&h), 2 * M_PI * (1 - cos(4.5 * M_PI / 180)), 1e-9);
  /* A projected checkerboard (Mitsuba's colours 0.4 and 0.2 on cells of 1/2 in uv): the axis
   * sits at uv (0.5, 0.5), a cell corner; a direction toward +x and +y lies in the cell of color0. */
  pc_texture tex = {.type = PC_TEX_CHECKER, .color0 = v3s(0.4f), .color1 = v3s(0.2f), .uscale = 1, .vscale = 1};
  l.spot_tex = &tex;
  assert_float_equal(pc_spot_falloff(&l, at_angle(&l, 20, (float)M_PI / 4)).x, 0.4f, 1e-6);
  assert_float_equal(pc_spot_falloff(&l, at_angle(&l, 20, 3 * (float)M_PI / 4)).x, 0.2f, 1e-6);
  assert_float_equal(pc_spot_falloff(&l, at_angle(&l, 32.5f, (float)M_PI / 4)).x, 0.2f, 1e-5); /* 0.4 times 1/2 */
  assert_float_equal(pc_spot_falloff(&l, at_angle(&l, 45, (float)M_PI / 4)).x, 0, 0);
}

static void test_sampling(void **state) {
  (void)state;
  const float cutoffs[] = {1.f, 20.f, 40.f, 90.f, 150.f};
  for (size_t k = 0; k < sizeof cutoffs / sizeof cutoffs[0]; k++) {
    pc_light l = make_spot(v3(-0.2f, 0.5f, 1.f), cutoffs[k], 0.5f * cutoffs[k]);
    double cc = cos(cutoffs[k] * M_PI / 180), pdf_expect = 1 / (2 * M_PI * (1 - cc));
    enum { NT = 10, NP = 12, N = 200000 };
    pc_chi2_cell cells[NT * NP];
    for (int i = 0; i < NT * NP; i++) cells[i] = (pc_chi2_cell){0, (double)N / (NT * NP)};
    pc_rng rng = pc_rng_make(5, k, 0, 0);
    double flux = 0;
    int edge = 0;
    for (int i = 0; i < N; i++) {
      float pdf;
      vec3 w = pc_light_sample_dir(&l, v3s(0), pc_rng_f(&rng), pc_rng_f(&rng), &pdf);
      assert_float_equal(v3_len(w), 1, 1e-5);
      assert_float_equal(pdf, pdf_expect, 1e-4 * pdf_expect);
      assert_float_equal(pc_light_pdf_dir(&l, v3s(0), w), pdf, 1e-4 * pdf);
      vec3 d = frame_to_local(&l.spot_frame, w);
      edge += d.z < l.cos_cutoff - 1e-6f; /* inside the cone up to float rounding */
      /* equal solid angles: 1 - cos theta uniform on [0, 1 - cos cutoff], phi uniform */
      int a = (int)((1 - (double)d.z) / (1 - cc) * NT), b = (int)((atan2(d.y, d.x) + M_PI) / (2 * M_PI) * NP);
      a = a < 0 ? 0 : a >= NT ? NT - 1 : a;
      b = b < 0 ? 0 : b >= NP ? NP - 1 : b;
      cells[a * NP + b].obs++;
      flux += pc_spot_falloff(&l, w).x / pdf;
    }
    double stat, p = pc_chi2_test(cells, NT * NP, &stat, NULL);
    /* The flux per unit intensity three ways: closed form, midpoint quadrature in theta, and the
     * sampled estimate (falloff / pdf). */
    double g = cutoffs[k] * M_PI / 180, quad = 0;
    int nq = 200000;
    for (int i = 0; i < nq; i++) {
      double th = (i + 0.5) * g / nq;
      quad += pc_spot_falloff(&l, at_angle(&l, (float)(th * 180 / M_PI), 0)).x * 2 * M_PI * sin(th) * g / nq;
    }
    double closed = pc_spot_solid_angle(&l);
    printf("cutoff %5.1f: chi2 p = %.3f; solid angle closed %.6g, quadrature %.6g, sampled %.6g\n", cutoffs[k], p, closed, quad,
           flux / N);
    assert_true(p > 0.001);
    assert_int_equal(edge, 0);
    assert_float_equal(quad, closed, 1e-4 * closed);
    assert_float_equal(flux / N, closed, 3e-3 * closed);
  }
}

static void test_power(void **state) {
  (void)state;
  pc_scene s;
  pc_err e = {0};
  assert_int_equal(load_body("<emitter type=\"spot\"><rgb name=\"intensity\" value=\"3\"/><float name=\"cutoffAngle\" "
                             "value=\"30\"/><float name=\"beamWidth\" value=\"10\"/></emitter>"
                             "<emitter type=\"point\"><rgb name=\"intensity\" value=\"1\"/></emitter>",
                             &s, &e),
                   PC_OK);
  assert_int_equal(pc_scene_build(&s, &e), PC_OK);
  double g = 30 * M_PI / 180, b = 10 * M_PI / 180, omega = 2 * M_PI * (1 - (sin(g) - sin(b)) / (g - b));
  assert_float_equal(s.lights[0].power, 3 * omega, 1e-5 * 3 * omega);
  /* chosen by power against the point light's 4 pi */
  assert_float_equal(pc_light_choose_pdf(&s, 0), 3 * omega / (3 * omega + 4 * M_PI), 1e-5);
  pc_scene_free(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_parse), cmocka_unit_test(test_falloff), cmocka_unit_test(test_sampling),
                                     cmocka_unit_test(test_power)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
