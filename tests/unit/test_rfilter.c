/* test_rfilter.c: Mitsuba's box, tent and gaussian filters as pixel measurements (rfilter.h).
 * The steps against Mitsuba's definitions recomputed here in double (31 steps per radius, the
 * value at each step's start, normalized to integrate to 1); a pixel's mass over the film
 * against the steps integrated here; eye samples drawn from a pixel's filter, inside the film
 * and at its edges, by a chi-square test over the steps with the pdf returned checked against
 * the filter over its mass; the splat footprint's pixels and weights against the same; and the
 * pixel box recognised, a zeroed filter included, with radii out of range refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "camera.h"
#include "chi2.h"
#include "rng.h"

/* Mitsuba's filter functions, in double. */
static double mitsuba_eval(pc_rfilter_type type, double radius, double stddev, double x) {
  switch (type) {
  case PC_RFILTER_BOX: return fabs(x) <= radius ? 1 : 0;
  case PC_RFILTER_TENT: return fmax(0, 1 - fabs(x / radius));
  case PC_RFILTER_GAUSSIAN: {
    double a = -1 / (2 * stddev * stddev);
    return fmax(0, exp(a * x * x) - exp(a * radius * radius));
  }
  }
  return 0;
}

/* The normalized step function of Mitsuba's table at x. */
static double step_fn(pc_rfilter_type type, double radius, double stddev, double x) {
  double sum = 0;
  for (int i = 0; i < 31; i++) sum += mitsuba_eval(type, radius, stddev, radius * i / 31);
  sum *= 2 * radius / 31;
  int i = (int)(fabs(x) * 31 / radius);
  return i < 31 ? mitsuba_eval(type, radius, stddev, radius * i / 31) / sum : 0;
}

/* The step function's integral over [a, b], by its steps. */
static double step_integral(pc_rfilter_type type, double radius, double stddev, double a, double b) {
  double h = radius / 31, total = 0;
  for (int k = 0; k < 62; k++) {
    double lo = fmax(a, -radius + k * h), hi = fmin(b, -radius + (k + 1) * h);
    if (hi > lo) total += (hi - lo) * step_fn(type, radius, stddev, -radius + (k + 0.5) * h);
  }
  return total;
}

typedef struct kind {
  pc_rfilter_type type;
  float param;          /* box radius, gaussian stddev */
  double radius, stddev; /* what Mitsuba makes of it */
} kind;

static const kind kinds[] = {
    {PC_RFILTER_TENT, 0.f, 1.0, 0},
    {PC_RFILTER_GAUSSIAN, 0.5f, 2.0, 0.5},
    {PC_RFILTER_GAUSSIAN, 0.3f, 1.2, 0.3},
    {PC_RFILTER_BOX, 1.3f, 1.30001, 0},
};
#define NKINDS (int)(sizeof kinds / sizeof kinds[0])

static void test_tables(void **state) {
  (void)state;
  for (int k = 0; k < NKINDS; k++) {
    const kind *q = &kinds[k];
    pc_rfilter f;
    assert_true(pc_rfilter_make(&f, q->type, q->param));
    assert_false(pc_rfilter_is_pixel(&f));
    assert_true(fabs(f.radius - q->radius) < 1e-5);
    for (double x = -q->radius - 0.1; x <= q->radius + 0.1; x += 0.0123) {
      double want = step_fn(q->type, q->radius, q->stddev, x);
      assert_true(fabs(pc_rfilter_value(&f, (float)x) - want) < 1e-5 * (1 + want));
    }
    /* a pixel's mass over a 10-pixel film: 1 inside, the film's share of it at the edges */
    for (double c = 0.5; c < 10; c += 1) {
      double want = step_integral(q->type, q->radius, q->stddev, -c, 10 - c);
      assert_true(fabs(pc_rfilter_mass(&f, (float)c, 10.f) - want) < 1e-5);
      if (c > q->radius && c < 10 - q->radius) assert_true(fabs(want - 1) < 1e-9);
    }
  }
  pc_rfilter f;
  memset(&f, 0, sizeof f);
  assert_true(pc_rfilter_is_pixel(&f));
  assert_true(pc_rfilter_make(&f, PC_RFILTER_BOX, 0.5f));
  assert_true(pc_rfilter_is_pixel(&f));
  assert_false(pc_rfilter_make(&f, PC_RFILTER_BOX, 0.f));
  assert_false(pc_rfilter_make(&f, PC_RFILTER_BOX, 4.5f));
  assert_false(pc_rfilter_make(&f, PC_RFILTER_GAUSSIAN, 1.1f)); /* radius 4.4 */
  assert_false(pc_rfilter_make(&f, PC_RFILTER_GAUSSIAN, -0.5f));
  assert_false(pc_rfilter_make(&f, PC_RFILTER_GAUSSIAN, NAN));
}

/* Samples of the pixel centred at c on a film of `extent` pixels, binned by the steps (cut at
 * the film's edges), against the step function over the pixel's mass. */
static void check_sampling(const kind *q, float c, float extent) {
  pc_rfilter f;
  assert_true(pc_rfilter_make(&f, q->type, q->param));
  double h = q->radius / 31, lo = fmax(-c, -q->radius), hi = fmin(extent - c, q->radius);
  double mass = step_integral(q->type, q->radius, q->stddev, lo, hi);
  enum { N = 200000 };
  pc_chi2_cell cells[62];
  for (int k = 0; k < 62; k++) {
    double a = fmax(lo, -q->radius + k * h), b = fmin(hi, -q->radius + (k + 1) * h);
    cells[k].obs = 0;
    cells[k].exp = b > a ? N * step_integral(q->type, q->radius, q->stddev, a, b) / mass : 0;
  }
  pc_rng rng = pc_rng_make(7, 1, 2, (uint64_t)(c * 10));
  for (int i = 0; i < N; i++) {
    float pdf, x = pc_rfilter_sample(&f, c, extent, pc_rng_f(&rng), &pdf);
    double d = (double)x - c;
    assert_true(x >= 0.f && x <= extent);
    assert_true(fabs(d) <= q->radius);
    int k = (int)floor((d + q->radius) / h);
    if (k > 61) k = 61;
    if (k < 0) k = 0;
    cells[k].obs++;
    /* the pdf is the filter over the mass, but where the point sits on a step's boundary */
    double want = step_fn(q->type, q->radius, q->stddev, d) / mass;
    if (fabs(pdf - want) > 1e-4 * want) {
      double e = 1e-4 * h, below = step_fn(q->type, q->radius, q->stddev, d - e) / mass,
             above = step_fn(q->type, q->radius, q->stddev, d + e) / mass;
      assert_true(fabs(pdf - below) < 1e-4 * below || fabs(pdf - above) < 1e-4 * above);
    }
  }
  double stat;
  int dof;
  double p = pc_chi2_test(cells, 62, &stat, &dof);
  printf("filter %d (%g): pixel centre %.1f of %.0f: chi2 %.1f on %d dof, p = %.3f\n", (int)q->type, (double)q->param,
         (double)c, (double)extent, stat, dof, p);
  assert_true(p > 1e-3);
}

static void test_sampling(void **state) {
  (void)state;
  for (int k = 0; k < NKINDS; k++) {
    check_sampling(&kinds[k], 5.5f, 12.f); /* inside */
    check_sampling(&kinds[k], 0.5f, 12.f); /* the film's first pixel */
    check_sampling(&kinds[k], 11.5f, 12.f);
    check_sampling(&kinds[k], 0.5f, 1.f);  /* a film one pixel wide */
  }
}

/* The splat footprint: every pixel whose filter reaches the point, with its weight there. */
static void test_footprint(void **state) {
  (void)state;
  pc_camera cam;
  memset(&cam, 0, sizeof cam);
  cam.width = 9, cam.height = 5;
  for (int k = 0; k < NKINDS; k++) {
    const kind *q = &kinds[k];
    assert_true(pc_rfilter_make(&cam.filter, q->type, q->param));
    pc_rng rng = pc_rng_make(3, 4, 5, (uint64_t)k);
    for (int i = 0; i < 2000; i++) {
      float px = 9.f * pc_rng_f(&rng), py = 5.f * pc_rng_f(&rng);
      int x0, y0, nx, ny;
      float wx[PC_CAMERA_FOOTPRINT_MAX], wy[PC_CAMERA_FOOTPRINT_MAX];
      pc_camera_footprint(&cam, px, py, &x0, &nx, wx, &y0, &ny, wy);
      for (int x = 0; x < 9; x++) {
        double want = step_fn(q->type, q->radius, q->stddev, px - (x + 0.5)) /
                      step_integral(q->type, q->radius, q->stddev, -(x + 0.5), 9 - (x + 0.5));
        double got = x >= x0 && x < x0 + nx ? wx[x - x0] : 0;
        assert_true(fabs(got - want) < 1e-4 * (1 + want));
      }
      for (int y = 0; y < 5; y++) {
        double want = step_fn(q->type, q->radius, q->stddev, py - (y + 0.5)) /
                      step_integral(q->type, q->radius, q->stddev, -(y + 0.5), 5 - (y + 0.5));
        double got = y >= y0 && y < y0 + ny ? wy[y - y0] : 0;
        assert_true(fabs(got - want) < 1e-4 * (1 + want));
      }
    }
  }
  /* the pixel box: a sample of pixel (x, y) is x + u0, y + u1 with density 1 */
  memset(&cam.filter, 0, sizeof cam.filter);
  float px, py;
  assert_true(pc_camera_pixel_point(&cam, 3, 2, 0.25f, 0.75f, &px, &py) == 1.f);
  assert_true(px == 3.25f && py == 2.75f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tables),
      cmocka_unit_test(test_sampling),
      cmocka_unit_test(test_footprint),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
