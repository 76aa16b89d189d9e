/* cache_pixels.c: see cache_pixels.h. */
#include "cache_pixels.h"

#include <math.h>
#include <stdint.h>

int pc_cache_path_count(float fraction, int w, int h) {
  double total = (double)w * (double)h;
  double n = ceil((double)fraction * total);
  if (!(n >= 1.0)) return 1;
  return n > total ? (int)total : (int)n;
}

/* Van der Corput radical inverse in base 2, exact in double for 32-bit i. */
static double radical_inverse2(uint32_t i) {
  i = (i << 16) | (i >> 16);
  i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
  i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
  i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
  i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
  return (double)i * 0x1p-32;
}

static int to_pixel(double u, int size) {
  int p = (int)(u * size);
  return p < 0 ? 0 : (p >= size ? size - 1 : p);
}

void pc_cache_pixel(int i, int n, int w, int h, float rx, float ry, int *x, int *y) {
  double u = ((double)i + 0.5) / (double)n + rx, v = radical_inverse2((uint32_t)i) + ry;
  u -= floor(u);
  v -= floor(v);
  *x = to_pixel(u, w);
  *y = to_pixel(v, h);
}
