/* test_cache_pixels.c: the cache eye paths' pixels are in the image, their count follows the
 * fraction, and they cover the image evenly (every cell of a coarse grid gets its share within
 * one point) for any rotation. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cache_pixels.h"

static void test_count(void **state) {
  (void)state;
  assert_int_equal(pc_cache_path_count(0.004f, 128, 128), 66);   /* every pixel counts up to 128x128 */
  assert_int_equal(pc_cache_path_count(0.004f, 256, 256), 132);  /* then the square root: 0.004 * 128 * 256 */
  assert_int_equal(pc_cache_path_count(0.004f, 1920, 1080), 738); /* 0.004 * sqrt(16384 * 2073600) = 737.3 */
  assert_int_equal(pc_cache_path_count(1.f, 200, 200), 25600);    /* sqrt(16384 * 40000) */
  assert_int_equal(pc_cache_path_count(1e-9f, 16, 16), 1);
  assert_int_equal(pc_cache_path_count(1.f, 16, 9), 144);
}

static void test_even_cover(void **state) {
  (void)state;
  const int w = 320, h = 240, n = 1024, g = 8; /* 8 x 8 cells of n/64 = 16 points */
  const float rot[3][2] = {{0.f, 0.f}, {0.37f, 0.81f}, {0.999f, 0.5f}};
  for (int r = 0; r < 3; r++) {
    int cells[8][8] = {{0}};
    for (int i = 0; i < n; i++) {
      int x, y;
      pc_cache_pixel(i, n, w, h, rot[r][0], rot[r][1], &x, &y);
      assert_true(x >= 0 && x < w && y >= 0 && y < h);
      cells[y * g / h][x * g / w]++;
    }
    for (int cy = 0; cy < g; cy++)
      for (int cx = 0; cx < g; cx++) assert_true(abs(cells[cy][cx] - n / (g * g)) <= 1);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_count), cmocka_unit_test(test_even_cover)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
