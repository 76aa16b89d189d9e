/* test_chart.c: the log-log line chart renders to PNG and SVG in a temporary folder; the PNG
 * decodes with pc_image_read at the requested size and is not blank; the SVG is an SVG; bad
 * sizes, missing data and unwritable paths are refused with a message. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "chart.h"
#include "image.h"
#include "test_helpers_fs.h"

typedef struct fixture {
  char dir[64];
  double t[12], a[12], b[12];
  pc_chart_series series[2];
  pc_chart chart;
} fixture;

static int setup(void **state) {
  fixture *f = calloc(1, sizeof *f);
  if (!f) return -1;
  snprintf(f->dir, sizeof f->dir, "/tmp/pcbpt-chart-XXXXXX");
  if (!mkdtemp(f->dir)) return -1;
  for (int i = 0; i < 12; i++) {
    f->t[i] = 0.05 * pow(2, i);
    f->a[i] = 0.3 / f->t[i];
    f->b[i] = 0.05 / f->t[i];
  }
  f->b[4] = 0; /* not on a log axis: skipped, the line breaks there */
  f->series[0] = (pc_chart_series){.name = "bdpt", .x = f->t, .y = f->a, .n = 12};
  f->series[1] = (pc_chart_series){.name = "pcbpt", .x = f->t, .y = f->b, .n = 12};
  f->chart = (pc_chart){.title = "cornell-box: beauty", .x_label = "render time (s)", .y_label = "relMSE",
                        .width = 640, .height = 480, .series = f->series, .nseries = 2};
  *state = f;
  return 0;
}

static int teardown(void **state) {
  fixture *f = *state;
  th_rm_rf(f->dir);
  free(f);
  return 0;
}

static off_t file_size(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 ? st.st_size : -1;
}

static void test_png_and_svg(void **state) {
  fixture *f = *state;
  pc_err e = {0};
  char png[128], svg[128];
  snprintf(png, sizeof png, "%s/chart.png", f->dir);
  snprintf(svg, sizeof svg, "%s/chart.svg", f->dir);
  assert_int_equal(pc_chart_write_png(&f->chart, png, &e), PC_OK);
  assert_int_equal(pc_chart_write_svg(&f->chart, svg, &e), PC_OK);
  assert_true(file_size(png) > 1000);
  assert_true(file_size(svg) > 1000);

  pc_image img = {0};
  assert_int_equal(pc_image_read(png, 0, &img, &e), PC_OK);
  assert_int_equal(img.w, 640);
  assert_int_equal(img.h, 480);
  /* White background with dark axes and coloured lines: some pixels are far from white. */
  size_t dark = 0, n = (size_t)img.w * img.h;
  for (size_t i = 0; i < n; i++)
    if (img.rgb[3 * i] + img.rgb[3 * i + 1] + img.rgb[3 * i + 2] < 1.5f) dark++;
  assert_true(dark > 500 && dark < n / 2);
  pc_image_free(&img);

  char *text = th_read(svg, NULL);
  assert_non_null(text);
  assert_non_null(strstr(text, "<svg"));
  free(text);
}

static void test_empty_chart_draws_axes(void **state) {
  fixture *f = *state;
  pc_err e = {0};
  char png[128];
  snprintf(png, sizeof png, "%s/empty.png", f->dir);
  pc_chart c = {.title = "nothing", .width = 200, .height = 150};
  assert_int_equal(pc_chart_write_png(&c, png, &e), PC_OK);
  pc_image img = {0};
  assert_int_equal(pc_image_read(png, 0, &img, &e), PC_OK);
  assert_int_equal(img.w, 200);
  pc_image_free(&img);
}

static void test_refusals(void **state) {
  fixture *f = *state;
  pc_err e = {0};
  char png[128];
  snprintf(png, sizeof png, "%s/bad.png", f->dir);
  pc_chart c = f->chart;
  c.width = 10;
  assert_int_equal(pc_chart_write_png(&c, png, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "chart size"));
  pc_chart_series s = {.name = "x", .x = NULL, .y = f->a, .n = 3};
  c = f->chart;
  c.series = &s;
  c.nseries = 1;
  assert_int_equal(pc_chart_write_svg(&c, png, &e), PC_EINVAL);
  assert_int_equal(file_size(png), -1);
  char nodir[160];
  snprintf(nodir, sizeof nodir, "%s/no/such/dir/c.png", f->dir);
  assert_int_equal(pc_chart_write_png(&f->chart, nodir, &e), PC_EIO);
  assert_non_null(strstr(e.msg, "c.png"));
  snprintf(nodir, sizeof nodir, "%s/no/such/dir/c.svg", f->dir);
  assert_int_not_equal(pc_chart_write_svg(&f->chart, nodir, &e), PC_OK);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_png_and_svg, setup, teardown),
      cmocka_unit_test_setup_teardown(test_empty_chart_draws_axes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_refusals, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
