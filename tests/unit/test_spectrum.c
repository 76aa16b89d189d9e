/* test_spectrum.c: spectra to RGB as Mitsuba 0.6's RGB mode converts them, checked against
 * integrals computed here another way (a dense midpoint rule with its own interpolation and
 * its own Planck's law) and against the CIE chromaticities of the Planckian locus; and the
 * scene syntax that uses them. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <sys/stat.h>

#include "scene.h"
#include "spectrum.h"
#include "test_helpers_fs.h"

/* Mitsuba's Rec. 709 RGB -> XYZ (Spectrum::toXYZ). */
static void rgb_to_xyz(const double rgb[3], double xyz[3]) {
  xyz[0] = 0.412453 * rgb[0] + 0.357580 * rgb[1] + 0.180423 * rgb[2];
  xyz[1] = 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
  xyz[2] = 0.019334 * rgb[0] + 0.119193 * rgb[1] + 0.950227 * rgb[2];
}

static double table(int k, double l) {
  double x = (l - 360.0) / 5.0;
  if (x < 0 || x > 94) return 0;
  int i = (int)floor(x);
  if (i == 94) return pc_cie1931[k][94];
  return pc_cie1931[k][i] + (x - i) * (pc_cie1931[k][i + 1] - pc_cie1931[k][i]);
}

/* XYZ of f by the midpoint rule at 0.002 nm, normalised by the same rule's integral of y. */
static void xyz_midpoint(double (*f)(double, const void *), const void *ud, double xyz[3]) {
  double s[3] = {0, 0, 0}, ny = 0, h = 0.002;
  for (double l = 360 + h / 2; l < 830; l += h) {
    double v = f(l, ud);
    for (int k = 0; k < 3; k++) s[k] += v * table(k, l) * h;
    ny += table(1, l) * h;
  }
  for (int k = 0; k < 3; k++) xyz[k] = s[k] / ny;
}

typedef struct sampled {
  int n;
  double l[8], v[8];
} sampled;

/* Linear between the samples, zero one average spacing past a non-zero end (written apart
 * from spectrum.c on purpose). */
static double sampled_eval(double x, const void *ud) {
  const sampled *s = ud;
  double sp = (s->l[s->n - 1] - s->l[0]) / (s->n - 1);
  double l[10], v[10];
  int m = 0;
  if (s->v[0] != 0) l[m] = s->l[0] - sp, v[m++] = 0;
  for (int i = 0; i < s->n; i++) l[m] = s->l[i], v[m++] = s->v[i];
  if (s->v[s->n - 1] != 0) l[m] = s->l[s->n - 1] + sp, v[m++] = 0;
  for (int i = 0; i + 1 < m; i++)
    if (x >= l[i] && x <= l[i + 1]) return v[i] + (x - l[i]) / (l[i + 1] - l[i]) * (v[i + 1] - v[i]);
  return 0;
}

static double planck(double l_nm, const void *ud) {
  double t = *(const double *)ud, h = 6.62607015e-34, c = 2.99792458e8, k = 1.380649e-23, l = l_nm * 1e-9;
  return 2 * h * c * c / (l * l * l * l * l) / expm1(h * c / (l * k * t)) * 1e-9;
}

static void expect_rgb_of_xyz(const double rgb[3], const double xyz[3], double rel) {
  double want[3];
  pc_xyz_to_rgb(xyz, want);
  for (int k = 0; k < 3; k++) {
    double w = want[k] < 0 ? 0 : want[k];
    if (fabs(rgb[k] - w) > rel * (fabs(w) + 1e-3)) {
      print_error("channel %d: %.9g, expected %.9g\n", k, rgb[k], w);
      fail();
    }
  }
}

static void test_sampled(void **state) {
  (void)state;
  static const sampled cases[] = {
      {4, {400, 500, 600, 700}, {0, 8, 15.6, 18.4}},      /* a published emitter (zero-extended at 800 nm) */
      {4, {400, 500, 600, 700}, {0.78, 0.78, 0.78, 0.78}}, /* a published reflectance, both ends extended */
      {2, {380, 800}, {1, 1}},
      {3, {300, 550, 900}, {0.2, 0.9, 0.1}},             /* beyond the CIE range on both sides */
      {2, {540, 560}, {0, 3}},                           /* narrow */
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    double rgb[3], xyz[3];
    assert_int_equal(pc_spectrum_sampled_rgb(cases[i].l, cases[i].v, cases[i].n, rgb), 0);
    xyz_midpoint(sampled_eval, &cases[i], xyz);
    expect_rgb_of_xyz(rgb, xyz, 1e-6);
  }
  /* equal energy over the whole range: Y equals the value */
  double l[2] = {300, 900}, v[2] = {0.5, 0.5}, rgb[3], xyz[3];
  assert_int_equal(pc_spectrum_sampled_rgb(l, v, 2, rgb), 0);
  rgb_to_xyz(rgb, xyz);
  assert_true(fabs(xyz[1] - 0.5) < 1e-5);
  /* refused: too few, not increasing */
  assert_int_equal(pc_spectrum_sampled_rgb(l, v, 1, rgb), -1);
  double dl[2] = {500, 500};
  assert_int_equal(pc_spectrum_sampled_rgb(dl, v, 2, rgb), -1);
}

static void test_blackbody(void **state) {
  (void)state;
  /* chromaticities of the Planckian locus (CIE 15: illuminant A at 2856 K; 6504 K) */
  static const struct { double t, x, y; } locus[] = {{2856, 0.44757, 0.40745}, {6504, 0.31352, 0.32363}};
  for (size_t i = 0; i < 2; i++) {
    double rgb[3], xyz[3], want[3];
    pc_spectrum_blackbody_rgb(locus[i].t, rgb);
    rgb_to_xyz(rgb, xyz);
    double sum = xyz[0] + xyz[1] + xyz[2];
    if (fabs(xyz[0] / sum - locus[i].x) > 2e-3 || fabs(xyz[1] / sum - locus[i].y) > 2e-3) {
      print_error("%g K: x %.5f y %.5f\n", locus[i].t, xyz[0] / sum, xyz[1] / sum);
      fail();
    }
    /* and the absolute values against an independent integral of Planck's law */
    xyz_midpoint(planck, &locus[i].t, want);
    expect_rgb_of_xyz(rgb, want, 1e-5);
  }
}

static void test_scene_syntax(void **state) {
  (void)state;
  char dir[] = "/tmp/pcbpt_spectrum_XXXXXX";
  assert_non_null(mkdtemp(dir));
  const char *xml =
      "<scene version=\"0.6.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>"
      "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"400:0.78, 500:0.78, 600:0.78, 700:0.78\"/></bsdf>"
      "<bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\".65 .65 .47\"/></bsdf>"
      "<shape type=\"cube\"><emitter type=\"area\"><blackbody name=\"radiance\" temperature=\"5000K\" scale=\"2e-4\"/></emitter></shape>"
      "<shape type=\"cube\"><emitter type=\"area\"><spectrum name=\"radiance\" value=\"31250\"/></emitter></shape>"
      "</scene>";
  assert_int_equal(th_write_str(dir, "s.xml", xml), 0);
  char path[128];
  snprintf(path, sizeof path, "%s/s.xml", dir);
  pc_scene s;
  pc_err e = {0};
  int rc = pc_scene_load(path, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  double l[4] = {400, 500, 600, 700}, v[4] = {0.78, 0.78, 0.78, 0.78}, rgb[3];
  pc_spectrum_sampled_rgb(l, v, 4, rgb);
  vec3 r = s.materials[0].reflectance.value;
  assert_true(fabsf(r.x - (float)rgb[0]) < 1e-6f && fabsf(r.y - (float)rgb[1]) < 1e-6f && fabsf(r.z - (float)rgb[2]) < 1e-6f);
  r = s.materials[1].reflectance.value;
  assert_true(r.x == 0.65f && r.z == 0.47f);
  pc_spectrum_blackbody_rgb(5000, rgb);
  vec3 le = s.lights[0].radiance;
  assert_true(fabs(le.x - 2e-4 * rgb[0]) < 1e-6 * fabs(le.x) && fabs(le.z - 2e-4 * rgb[2]) < 1e-6 * fabs(le.z));
  assert_true(s.lights[1].radiance.y == 31250.f);
  pc_scene_free(&s);
  th_rm_rf(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_sampled), cmocka_unit_test(test_blackbody),
                                     cmocka_unit_test(test_scene_syntax)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
