/* cache_pixels.h: where PCBPT's importance-record eye paths start (Popov et al. sect. 6: a
 * fraction of W*H eye paths "using low discrepancy sampling to uniformly cover the screen").
 * A 2-d Hammersley set, rotated per iteration (Cranley-Patterson) so records of successive
 * iterations land on different pixels while each iteration's set stays evenly spread. */
#ifndef PC_CACHE_PIXELS_H
#define PC_CACHE_PIXELS_H

/* Number of cache eye paths for a W x H image: ceil(fraction * P), at least 1 and at most W * H
 * (fraction in (0, 1]), where P is the pixel count W * H up to PC_CACHE_FULL_PIXELS and grows
 * with its square root past that (P = sqrt(PC_CACHE_FULL_PIXELS * W * H)): more pixels of the
 * same view do not need proportionally more records (cache_pixels.c). */
#define PC_CACHE_FULL_PIXELS (128 * 128)
int pc_cache_path_count(float fraction, int w, int h);

/* Pixel of cache path i (0 <= i < n) of an n-point set; rx, ry in [0, 1) the iteration's
 * rotation. */
void pc_cache_pixel(int i, int n, int w, int h, float rx, float ry, int *x, int *y);

#endif
