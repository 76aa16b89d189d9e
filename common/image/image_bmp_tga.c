/* image_bmp_tga.c: BMP and Truevision TGA textures, which Mitsuba 0.6's bitmap reads too (a
 * published pool scene's textures are BMP), through Debian's stb_image (libstb-dev) as 8-bit
 * RGB. stb decodes a file that ends early as if zeros followed, so the size in the header is
 * checked against what the file can hold before any pixel is decoded. */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <stb_image.h>

#include "image_internal.h"

/* The most pixels a byte of either format encodes: a 1-bit BMP holds 8; a TGA run-length
 * packet, one byte of count and one of a colour-mapped pixel, 128 pixels in 2 bytes. */
#define PIXELS_PER_BYTE 64.0

static uint32_t le(const unsigned char *b, int n) {
  uint32_t v = 0;
  for (int i = n - 1; i >= 0; i--) v = v << 8 | b[i];
  return v;
}

/* The bytes an uncompressed file needs for its pixels (0 when it is compressed or the header is
 * too short to tell: then only the PIXELS_PER_BYTE bound holds). */
static double uncompressed_bytes(const char *path, bool bmp, int w, int h) {
  unsigned char b[34]; /* a BMP's info header to biCompression */
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  size_t n = fread(b, 1, sizeof b, f);
  fclose(f);
  if (bmp) {
    if (n < 34) return 0;
    uint32_t offset = le(b + 10, 4), bpp = le(b + 28, 2), compression = le(b + 30, 4);
    if (compression != 0 && compression != 3) return 0; /* BI_RGB or BI_BITFIELDS */
    double stride = (double)(((uint64_t)w * bpp + 31) / 32 * 4);
    return offset + stride * h;
  }
  if (n < 18) return 0;
  unsigned type = b[2], idlen = b[0], cmap_len = (unsigned)le(b + 5, 2), cmap_bits = b[7], bpp = b[16];
  if (type != 1 && type != 2 && type != 3) return 0; /* 9, 10, 11: run-length */
  return 18.0 + idlen + (b[1] ? cmap_len * ((cmap_bits + 7) / 8.0) : 0) + (double)w * h * ((bpp + 7) / 8);
}

int pc_bmp_tga_read(const char *path, const char *format, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e) {
  int w, h, comp;
  if (!stbi_info(path, &w, &h, &comp))
    return pc_errf(e, PC_EPARSE, "%s: not a readable %s file: %s", path, format, stbi_failure_reason());
  if (w < 1 || h < 1 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(e, PC_ELIMIT, "%s: %dx%d pixels (at most %d on a side)", path, w, h, PC_IMAGE_MAX_DIM);
  struct stat st;
  if (stat(path, &st) != 0) return pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  if ((double)w * (double)h > PIXELS_PER_BYTE * (double)st.st_size + 1024.0)
    return pc_errf(e, PC_EPARSE, "%s: a %dx%d %s image cannot fit in %lld bytes (truncated?)", path, w, h, format,
                   (long long)st.st_size);
  double need = uncompressed_bytes(path, format[0] == 'B', w, h);
  if (need > (double)st.st_size)
    return pc_errf(e, PC_EPARSE, "%s: a %dx%d %s image needs %.0f bytes, the file has %lld (truncated)", path, w, h,
                   format, need, (long long)st.st_size);
  unsigned char *px = stbi_load(path, &w, &h, &comp, 3);
  if (!px) return pc_errf(e, PC_EIMAGE, "%s: cannot decode the %s file: %s", path, format, stbi_failure_reason());
  size_t n = (size_t)w * (size_t)h * 3;
  float *lut = malloc(256 * sizeof *lut);
  if (lut) pc_image_lut8(srgb_to_linear, lut);
  if (lut && bytes) {
    out->rgb8 = malloc(n);
    if (out->rgb8) memcpy(out->rgb8, px, n);
  } else if (lut) {
    out->rgb = malloc(n * sizeof *out->rgb);
    for (size_t i = 0; out->rgb && i < n; i++) out->rgb[i] = lut[px[i]];
  }
  stbi_image_free(px);
  if (!lut || !(bytes ? (void *)out->rgb8 : (void *)out->rgb)) {
    free(lut);
    pc_image_free(out);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory for %dx%d pixels", path, w, h);
  }
  if (bytes) out->lut8 = lut;
  else free(lut);
  out->w = w;
  out->h = h;
  return PC_OK;
}
