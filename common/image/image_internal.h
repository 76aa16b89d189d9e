/* image_internal.h: what the image codecs (image.c, image_png.c, image_jpeg.c, image_exr.c, image_stb8.c,
 * image_pfm.c)
 * share with each other and nobody else: per-format readers and the sRGB transfer functions. */
#ifndef PC_IMAGE_INTERNAL_H
#define PC_IMAGE_INTERNAL_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>

#include "file_replace.h"
#include "image.h"

/* bytes: an 8-bit image is kept in rgb8/lut8 (pc_image_read_bytes). */
int pc_png_read(const char *path, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e);
int pc_jpeg_read(const char *path, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e);
/* The linear value of each 8-bit sample: lut[i] = i / 255, through the sRGB EOTF when asked. */
void pc_image_lut8(int srgb_to_linear, float lut[256]);
/* BMP, TGA or PPM (format names which: "BMP", "TGA", "PPM"), 8-bit, as pc_png_read. */
int pc_stb8_read(const char *path, const char *format, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e);
/* Radiance RGBE (.hdr, "#?RADIANCE" or "#?RGBE"): linear. */
int pc_rgbe_read(const char *path, pc_image *out, pc_err *e);
/* Portable float map (PF, or Pf for grey): linear, as Mitsuba reads it. */
int pc_pfm_read(const char *path, pc_image *out, pc_err *e);
/* The beauty R,G,B, or the first RGB triplet when the file has no plain R,G,B. */
int pc_exr_read_beauty(const char *path, pc_image *out, pc_err *e);

/* Exact piecewise sRGB EOTF / OETF (IEC 61966-2-1) on [0,1]. */
static inline float pc_srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}
static inline float pc_linear_to_srgb(float v) {
  return v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
}

#endif
