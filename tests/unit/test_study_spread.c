/* test_study_spread.c: the summaries of a study's several runs (study_spread.c). On curves
 * that are power laws (relMSE = a / t, exact under log-log interpolation) sampled at
 * different times per run: the median curve and its band are the median, min and max of
 * a_r / t at each grid time, times no run reached are left out, and the time to a target is
 * a_r / target per run with its median, range and per-run ratios to another method's runs.
 * A chart with a band draws; half a band is refused. A bar chart draws each part in its colour
 * and refuses values that are not fractions. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <cairo.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "chart.h"
#include "study.h"

static void test_median(void **state) {
  (void)state;
  double lo, hi;
  double a[] = {3, NAN, 1, 2};
  assert_true(pc_study_median(a, 4, &lo, &hi) == 2);
  assert_true(lo == 1 && hi == 3);
  double b[] = {4, 1, 3, 2};
  assert_true(pc_study_median(b, 4, &lo, &hi) == 2.5);
  double c[] = {NAN, NAN};
  assert_true(isnan(pc_study_median(c, 2, &lo, &hi)) && isnan(lo) && isnan(hi));
}

/* relMSE of every layer = a / t at n snapshots from t0, doubling. */
static void power_run(pc_study_run *r, double a, double t0, int n) {
  memset(r, 0, sizeof *r);
  r->snaps = calloc((size_t)n, sizeof *r->snaps);
  assert_non_null(r->snaps);
  r->nsnaps = n;
  for (int i = 0; i < n; i++) {
    double t = t0 * pow(2, i);
    r->snaps[i].seconds = t;
    r->snaps[i].wall = 2 * t;
    for (int s = 0; s < PC_STUDY_NLAYERS; s++) r->snaps[i].m[s].relmse = r->snaps[i].m[s].rmse = r->snaps[i].m[s].l1 = a / t;
  }
}

static void test_median_run(void **state) {
  (void)state;
  pc_study_run runs[3], med;
  const double a[3] = {1, 2, 4};
  power_run(&runs[0], a[0], 0.5, 6);   /* 0.5 .. 16 */
  power_run(&runs[1], a[1], 0.25, 7);  /* 0.25 .. 16 */
  power_run(&runs[2], a[2], 1, 5);     /* 1 .. 16 */
  pc_study_band band[PC_STUDY_NLAYERS];
  pc_err e = {0};
  assert_int_equal(pc_study_median_run(runs, 3, 9, 16, false, &med, band, &e), PC_OK);
  /* grid 16 * (1/64)^((8-k)/8): 0.25 .. 16; only run 1 reaches 0.25 and 0.42 ... */
  assert_true(med.nsnaps == 9);
  assert_int_equal(band[0].n, med.nsnaps);
  for (int i = 0; i < med.nsnaps; i++) {
    double t = med.snaps[i].seconds, want[3], n = 0;
    for (int r = 0; r < 3; r++) {
      double first = runs[r].snaps[0].seconds;
      if (t >= first * 0.9999) want[(int)n++] = a[r] / t;
    }
    double m = n == 3 ? want[1] : n == 2 ? 0.5 * (want[0] + want[1]) : want[0];
    assert_true(fabs(med.snaps[i].m[PC_STUDY_BEAUTY].relmse / m - 1) < 1e-9);
    assert_true(fabs(band[PC_STUDY_BEAUTY].lo[i] / want[0] - 1) < 1e-9);
    assert_true(fabs(band[PC_STUDY_BEAUTY].hi[i] / want[(int)n - 1] - 1) < 1e-9);
  }
  pc_study_run_free(&med);
  pc_study_band_free(band);
  /* on the wall axis (twice the render time here) the same curves, at twice the times */
  assert_int_equal(pc_study_median_run(runs, 3, 5, 32, true, &med, NULL, &e), PC_OK);
  assert_true(fabs(med.snaps[med.nsnaps - 1].m[0].relmse / (2 / 16.0) - 1) < 1e-9);
  pc_study_run_free(&med);
  /* a time before every run's first snapshot is left out */
  assert_int_equal(pc_study_median_run(&runs[2], 1, 9, 16, false, &med, NULL, &e), PC_OK);
  assert_int_equal(med.nsnaps, 6); /* the grid 16 * 64^((k-8)/8) from 1.19 on */
  pc_study_run_free(&med);
  for (int r = 0; r < 3; r++) pc_study_run_free(&runs[r]);
}

static void test_spread_cell(void **state) {
  (void)state;
  pc_study_run m[3], base[3];
  const double a[3] = {1, 2, 4}, b[3] = {2, 8, 4};
  for (int r = 0; r < 3; r++) {
    power_run(&m[r], a[r], 0.0625, 9);    /* to 16 */
    power_run(&base[r], b[r], 0.0625, 9);
  }
  pc_study_spread c;
  pc_study_spread_cell(m, 3, base, PC_STUDY_BEAUTY, 0.5, false, 0, &c);
  assert_int_equal(c.n, 3);
  assert_int_equal(c.reached, 3);
  assert_true(fabs(c.time_med - 4) < 1e-9 && fabs(c.time_lo - 2) < 1e-9 && fabs(c.time_hi - 8) < 1e-9);
  assert_true(fabs(c.final_med - 2 / 16.0) < 1e-12);
  /* per-run ratios a_r / b_r: 0.5, 0.25, 1 */
  assert_true(fabs(c.ratio_med - 0.5) < 1e-9 && fabs(c.ratio_lo - 0.25) < 1e-9 && fabs(c.ratio_hi - 1) < 1e-9);
  /* at a budget of 15 s, which every run's last snapshot (16 s) passes: each run's error
   * there, a_r / 15 on these power-law curves, not its last snapshot's a_r / 16 */
  pc_study_spread_cell(m, 3, base, PC_STUDY_BEAUTY, 0.5, false, 15, &c);
  assert_true(fabs(c.final_med - 2 / 15.0) < 1e-12 && fabs(c.final_lo - 1 / 15.0) < 1e-12 &&
              fabs(c.final_hi - 4 / 15.0) < 1e-12);
  /* a target one run never reaches (its final is 4/16) */
  pc_study_spread_cell(m, 3, base, PC_STUDY_BEAUTY, 0.2, false, 0, &c);
  assert_int_equal(c.reached, 2);
  for (int r = 0; r < 3; r++) {
    pc_study_run_free(&m[r]);
    pc_study_run_free(&base[r]);
  }
}

static void test_band_chart(void **state) {
  (void)state;
  double x[4] = {1, 2, 4, 8}, y[4] = {1, 0.5, 0.25, 0.125}, lo[4], hi[4];
  for (int i = 0; i < 4; i++) lo[i] = 0.5 * y[i], hi[i] = 2 * y[i];
  pc_chart_series s = {.name = "pcbpt", .x = x, .y = y, .n = 4, .lo = lo, .hi = hi};
  pc_chart c = {.title = "band", .width = 320, .height = 240, .series = &s, .nseries = 1};
  char path[] = "/tmp/pcbpt-band-XXXXXX.svg";
  int fd = mkstemps(path, 4);
  assert_true(fd >= 0);
  pc_err e = {0};
  assert_int_equal(pc_chart_write_svg(&c, path, &e), PC_OK);
  s.hi = NULL;
  assert_int_not_equal(pc_chart_write_svg(&c, path, &e), PC_OK);
  assert_non_null(strstr(e.msg, "half a band"));
  remove(path);
}

/* Whether a pixel of the PNG's column x has colour rgb (0..255), within 2 per channel. */
static bool column_has(cairo_surface_t *img, int x, int r, int g, int b) {
  const unsigned char *d = cairo_image_surface_get_data(img);
  int stride = cairo_image_surface_get_stride(img), h = cairo_image_surface_get_height(img);
  for (int y = 0; y < h; y++) {
    uint32_t px = *(const uint32_t *)(d + (size_t)y * stride + 4 * (size_t)x);
    int pr = px >> 16 & 255, pg = px >> 8 & 255, pb = px & 255;
    if (abs(pr - r) <= 2 && abs(pg - g) <= 2 && abs(pb - b) <= 2) return true;
  }
  return false;
}

/* Stacked bars: a bar all of the first part and one all of the fourth show the first and fourth
 * colours across the plot's middle column, and no other part's; values that are no fraction
 * and too many parts are refused. */
static void test_bar_chart(void **state) {
  (void)state;
  const char *rows[2] = {"pt", "pcbpt"}, *parts[4] = {"pt", "nee", "lt", "inner"};
  double v[8] = {1, 0, 0, 0, 0, 0, 0, 1};
  pc_chart_bars b = {.rows = rows, .parts = parts, .value = v, .nrows = 2, .nparts = 4};
  pc_chart c = {.title = "shares", .x_label = "share", .width = 400, .height = 220, .bars = &b};
  char path[] = "/tmp/pcbpt-bars-XXXXXX.png";
  int fd = mkstemps(path, 4);
  assert_true(fd >= 0);
  close(fd);
  pc_err e = {0};
  assert_int_equal(pc_chart_write_png(&c, path, &e), PC_OK);
  cairo_surface_t *img = cairo_image_surface_create_from_png(path);
  assert_int_equal(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
  cairo_surface_flush(img);
  int x = 300; /* right of the labels, left of the plot's end */
  assert_true(column_has(img, x, 0, 114, 178));   /* Okabe-Ito blue: part 1 */
  assert_true(column_has(img, x, 204, 121, 167)); /* reddish purple: part 4 */
  assert_false(column_has(img, x, 213, 94, 0));   /* vermillion: part 2, empty */
  assert_false(column_has(img, x, 0, 158, 115));  /* bluish green: part 3, empty */
  cairo_surface_destroy(img);
  v[1] = NAN;
  assert_int_not_equal(pc_chart_write_png(&c, path, &e), PC_OK);
  assert_non_null(strstr(e.msg, "not a fraction"));
  v[1] = 0;
  b.nparts = PC_CHART_MAX_PARTS + 1;
  assert_int_not_equal(pc_chart_write_png(&c, path, &e), PC_OK);
  assert_non_null(strstr(e.msg, "bad bars"));
  remove(path);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_median),
      cmocka_unit_test(test_median_run),
      cmocka_unit_test(test_spread_cell),
      cmocka_unit_test(test_band_chart),
      cmocka_unit_test(test_bar_chart),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
