/* image_stb8.c: BMP, Truevision TGA and binary PPM (P6) textures, which Mitsuba 0.6's bitmap
 * reads too (a published pool scene's textures are BMP), through Debian's stb_image (libstb-dev)
 * as 8-bit RGB. stb decodes a BMP or TGA that ends early as if zeros followed, so the size in
 * the header is checked against what the file can hold before any pixel is decoded. */
#include <ctype.h>
#include <limits.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>

#include "file_read.h"
#include "image_internal.h"

/* The most pixels a byte of either format encodes: a 1-bit BMP holds 8; a TGA run-length
 * packet, one byte of count and one of a colour-mapped pixel, 128 pixels in 2 bytes. */
#define PIXELS_PER_BYTE 64.0

static uint32_t le(const unsigned char *b, int n) {
  uint32_t v = 0;
  for (int i = n - 1; i >= 0; i--) v = v << 8 | b[i];
  return v;
}

/* A P6 header's length: four words (P6, width, height, maximum value), each after whitespace
 * and comments from '#' to the end of the line, and one byte of whitespace after the last. */
static double ppm_header_bytes(const unsigned char *b, size_t n) {
  size_t i = 0;
  for (int word = 0; word < 4; word++) {
    while (i < n && (isspace(b[i]) || b[i] == '#'))
      if (b[i++] == '#')
        while (i < n && b[i] != '\n') i++;
    while (i < n && !isspace(b[i])) i++;
  }
  return (double)i + 1;
}

/* The bytes an uncompressed file needs for its pixels (0 when it is compressed or the header is
 * too short to tell: then only the PIXELS_PER_BYTE bound holds). */
static double uncompressed_bytes(const unsigned char *b, size_t n, char format, int w, int h) {
  if (format == 'P') return ppm_header_bytes(b, n) + 3.0 * w * h;
  if (format == 'B') {
    if (n < 34) return 0; /* the info header to biCompression */
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

/* Checks the header's size against the file's n bytes, then decodes. */
static int decode(const char *path, const char *format, const unsigned char *file, size_t n, int srgb_to_linear,
                  bool bytes, pc_image *out, pc_err *e) {
  int w, h, comp;
  if (!stbi_info_from_memory(file, (int)n, &w, &h, &comp))
    return pc_errf(e, PC_EPARSE, "%s: not a readable %s file: %s", path, format, stbi_failure_reason());
  if (w < 1 || h < 1 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(e, PC_ELIMIT, "%s: %dx%d pixels (at most %d on a side)", path, w, h, PC_IMAGE_MAX_DIM);
  if ((double)w * (double)h > PIXELS_PER_BYTE * (double)n + 1024.0)
    return pc_errf(e, PC_EPARSE, "%s: a %dx%d %s image cannot fit in %zu bytes (truncated?)", path, w, h, format, n);
  /* Mitsuba reads a PPM's samples above 255 as 16-bit words in the machine's byte order (the
     format's is big-endian), so no image of such a file agrees with it */
  if (format[0] == 'P' && stbi_is_16_bit_from_memory(file, (int)n))
    return pc_errf(e, PC_EUNSUPPORTED, "%s: a 16-bit PPM (maximum value above 255): only 8-bit ones are read", path);
  double need = uncompressed_bytes(file, n, format[0], w, h);
  if (need > (double)n)
    return pc_errf(e, PC_EPARSE, "%s: a %dx%d %s image needs %.0f bytes, the file has %zu (truncated)", path, w, h,
                   format, need, n);
  unsigned char *px = stbi_load_from_memory(file, (int)n, &w, &h, &comp, 3);
  if (!px) return pc_errf(e, PC_EIMAGE, "%s: cannot decode the %s file: %s", path, format, stbi_failure_reason());
  size_t ns = (size_t)w * (size_t)h * 3;
  float lut[256];
  pc_image_lut8(srgb_to_linear, lut);
  if (bytes) {
    out->rgb8 = malloc(ns);
    out->lut8 = malloc(sizeof lut);
    if (out->rgb8 && out->lut8) {
      memcpy(out->rgb8, px, ns);
      memcpy(out->lut8, lut, sizeof lut);
    }
  } else if ((out->rgb = malloc(ns * sizeof *out->rgb))) {
    for (size_t i = 0; i < ns; i++) out->rgb[i] = lut[px[i]];
  }
  stbi_image_free(px);
  if (bytes ? !out->rgb8 || !out->lut8 : !out->rgb) {
    pc_image_free(out);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory for %dx%d pixels", path, w, h);
  }
  out->w = w;
  out->h = h;
  return PC_OK;
}

int pc_stb8_read(const char *path, const char *format, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e) {
  char *file;
  size_t n;
  /* stb takes the length as an int */
  int rc = pc_file_read(path, INT_MAX, &file, &n, e);
  if (rc) return rc;
  rc = decode(path, format, (const unsigned char *)file, n, srgb_to_linear, bytes, out, e);
  free(file);
  return rc;
}
