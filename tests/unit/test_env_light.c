/* test_env_light.c: the environment emitters of light_env.c: Mitsuba's lat-long orientation
 * (+y the top row, -z the image's left/right seam, +x a quarter across, toWorld rotating it),
 * bilinear lookup at texel centres, the sampling pdf integrating to 1 and agreeing with the
 * sampler (estimates of known integrals by importance sampling), and bad images refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "light.h"
#include "rng.h"

/* A `constant` environment of radiance k, not yet prepared. */
static pc_light env_base(float k) {
  pc_light l;
  memset(&l, 0, sizeof l);
  l.type = PC_LIGHT_ENV;
  l.radiance = v3s(k);
  l.env_scale = 1.f;
  l.env_frame = (frame){v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)};
  return l;
}

/* An envmap light over a w x h image whose texel (x, y) holds f(x, y) in every channel. */
static pc_light make_env(int w, int h, float (*f)(int, int)) {
  pc_light l = env_base(1.f);
  l.env_img.w = w;
  l.env_img.h = h;
  l.env_img.rgb = malloc(sizeof(float) * 3 * (size_t)w * h);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++)
      for (int c = 0; c < 3; c++) l.env_img.rgb[3 * (y * w + x) + c] = f(x, y);
  pc_err e = {0};
  assert_int_equal(pc_env_prepare(&l, 1.f, "test", &e), PC_OK);
  return l;
}

static float index_of(int x, int y) { return (float)(y * 8 + x + 1); }
static float bumpy(int x, int y) { return 0.05f + (float)((x * 7 + y * 13) % 11) + (x == 3 && y == 2 ? 400.f : 0.f); }

static vec3 uniform_sphere(pc_rng *r) {
  float z = 1.f - 2.f * pc_rng_f(r), phi = 2.f * PC_PI * pc_rng_f(r);
  float s = sqrtf(fmaxf(0.f, 1.f - z * z));
  return v3(s * cosf(phi), s * sinf(phi), z);
}

static void test_orientation(void **state) {
  (void)state;
  pc_light l = make_env(8, 4, index_of);
  /* Texel centres: u = (x + 0.5) / 8, v = (y + 0.5) / 4 <-> direction. +y is v = 0 (row 0 is
   * interpolated against itself by the clamp): the top row's mean is not needed, only that up
   * reads row 0 and down row 3. */
  float up = pc_env_le(&l, v3(0, 1, 0)).x, down = pc_env_le(&l, v3(0, -1, 0)).x;
  assert_true(up >= 1.f && up <= 8.f);
  assert_true(down >= 25.f && down <= 32.f);
  /* On the horizon (v = 0.5, between rows 1 and 2): -z is u = 0, the seam between columns 7
   * and 0; +x is u = 0.25 (between columns 1 and 2); +z is u = 0.5; -x is u = 0.75. */
  float rows12 = 0.5f * (index_of(0, 1) + index_of(0, 2)) - index_of(0, 0); /* row offset, 12.5 */
  assert_true(fabsf(pc_env_le(&l, v3(0, 0, -1)).x - (rows12 + 0.5f * (index_of(7, 0) + index_of(0, 0)))) < 1e-3f);
  assert_true(fabsf(pc_env_le(&l, v3(1, 0, 0)).x - (rows12 + 0.5f * (index_of(1, 0) + index_of(2, 0)))) < 1e-3f);
  assert_true(fabsf(pc_env_le(&l, v3(0, 0, 1)).x - (rows12 + 0.5f * (index_of(3, 0) + index_of(4, 0)))) < 1e-3f);
  assert_true(fabsf(pc_env_le(&l, v3(-1, 0, 0)).x - (rows12 + 0.5f * (index_of(5, 0) + index_of(6, 0)))) < 1e-3f);
  /* A texel centre reads the texel itself: column 2, row 1 at phi = 2pi * 2.5/8, theta = pi * 1.5/4. */
  float phi = 2.f * PC_PI * 2.5f / 8.f, th = PC_PI * 1.5f / 4.f;
  vec3 d = v3(sinf(th) * sinf(phi), cosf(th), -sinf(th) * cosf(phi));
  assert_true(fabsf(pc_env_le(&l, d).x - index_of(2, 1)) < 1e-3f);
  /* toWorld rotating 90 degrees about +y (x -> -z, z -> x): world +x now looks up local +z. */
  float before = pc_env_le(&l, v3(0, 0, 1)).x;
  l.env_frame = (frame){v3(0, 0, -1), v3(0, 1, 0), v3(1, 0, 0)};
  assert_true(fabsf(pc_env_le(&l, v3(1, 0, 0)).x - before) < 1e-4f);
  pc_env_free(&l);
}

/* The pdf integrates to 1 over the sphere, every sample's pdf is the pdf of its direction, and
 * importance-sampled estimates of the radiance's integral and of a cosine lobe match uniform
 * sampling (both with standard errors from the samples). */
static void test_sampling(void **state) {
  (void)state;
  pc_light l = make_env(16, 8, bumpy);
  pc_light c = env_base(2.f);
  pc_err e = {0};
  assert_int_equal(pc_env_prepare(&c, 1.f, "test", &e), PC_OK);
  const pc_light *lights[] = {&l, &c};
  for (int k = 0; k < 2; k++) {
    const pc_light *L = lights[k];
    pc_rng r = pc_rng_make(9, (uint64_t)k, PC_STREAM_MISC, 1);
    enum { N = 400000 };
    double pdf_int = 0, pdf_int2 = 0, uni[2] = {0}, uni2[2] = {0}, imp[2] = {0}, imp2[2] = {0};
    for (int i = 0; i < N; i++) {
      vec3 d = uniform_sphere(&r);
      double p = pc_env_pdf(L, d) * 4 * M_PI;
      pdf_int += p;
      pdf_int2 += p * p;
      double le = pc_env_le(L, d).x * 4 * M_PI, lobe = le * fmax(0.0, d.y + 0.3 * d.x);
      uni[0] += le, uni2[0] += le * le, uni[1] += lobe, uni2[1] += lobe * lobe;
      float pdf;
      vec3 s = pc_env_sample(L, pc_rng_f(&r), pc_rng_f(&r), &pdf);
      assert_true(fabsf(v3_len(s) - 1.f) < 1e-5f);
      assert_true(pdf == pc_env_pdf(L, s));
      if (!(pdf > 0.f)) continue;
      double w = pc_env_le(L, s).x / pdf, wl = w * fmax(0.0, s.y + 0.3 * s.x);
      imp[0] += w, imp2[0] += w * w, imp[1] += wl, imp2[1] += wl * wl;
    }
    double m = pdf_int / N, se = sqrt(fmax(pdf_int2 / N - m * m, 0) / N);
    printf("%s: integral of pdf %.5f +- %.5f\n", k ? "constant" : "envmap", m, se);
    assert_true(fabs(m - 1.0) < 4 * se + 1e-6);
    for (int j = 0; j < 2; j++) {
      double mu = uni[j] / N, su = sqrt(fmax(uni2[j] / N - mu * mu, 0) / N);
      double mi = imp[j] / N, si = sqrt(fmax(imp2[j] / N - mi * mi, 0) / N);
      printf("  %s: uniform %.4f +- %.4f, importance %.4f +- %.4f\n", j ? "cosine lobe" : "radiance", mu, su, mi, si);
      assert_true(fabs(mu - mi) < 4.5 * sqrt(su * su + si * si) + 1e-5 * fabs(mu));
    }
  }
  pc_env_free(&l);
}

static float black(int x, int y) { (void)x, (void)y; return 0.f; }
static float with_nan(int x, int y) { return x == 1 && y == 1 ? NAN : 1.f; }

static void test_refused(void **state) {
  (void)state;
  float (*bad[])(int, int) = {black, with_nan};
  for (int k = 0; k < 2; k++) {
    pc_light l = env_base(1.f);
    l.env_img.w = 4;
    l.env_img.h = 2;
    l.env_img.rgb = malloc(sizeof(float) * 24);
    for (int i = 0; i < 24; i++) l.env_img.rgb[i] = bad[k](i / 3 % 4, i / 12);
    pc_err e = {0};
    assert_int_equal(pc_env_prepare(&l, 1.f, "sky.exr", &e), PC_EINVAL);
    assert_non_null(strstr(e.msg, "sky.exr"));
    pc_env_free(&l);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_orientation),
      cmocka_unit_test(test_sampling),
      cmocka_unit_test(test_refused),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
