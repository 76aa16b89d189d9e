/* cache_pixels.c: see cache_pixels.h. */
#include "cache_pixels.h"

#include <math.h>
#include <stdint.h>

/* Why the square root past 128x128: at 512x512 (2 threads, 60 s, estimated beauty relMSE, two
 * seeds) the records' count mattered per iteration only on ajar-door (0.004 of the pixels
 * 8.2-8.7 relMSE x iterations, 0.001 9.9-10.0, 0.00025 11.3-12.1), not on cornell-box (0.0811,
 * 0.0814, 0.0826) or open-room (0.224, 0.225, 0.227), while the R x V build and the lookups'
 * working set grow with R: at equal time 0.001 (this rule at 512x512) was 2-4% worse than
 * 0.004 on ajar-door and 10-13% better on cornell-box. */
int pc_cache_path_count(float fraction, int w, int h) {
  double total = (double)w * (double)h;
  double pixels = total <= PC_CACHE_FULL_PIXELS ? total : sqrt((double)PC_CACHE_FULL_PIXELS * total);
  double n = ceil((double)fraction * pixels);
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
