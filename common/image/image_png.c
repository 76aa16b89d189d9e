/* image_png.c: PNG through libpng: reading any PNG (8/16-bit gray, gray+alpha, RGB, RGBA,
 * palette) into a linear float raster, and writing the 8-bit sRGB preview of a render.
 * libpng reports errors by longjmp; the jumping functions keep every resource they own in a
 * struct reached through a pointer, so nothing they change is lost across the jump. */
#include "image_internal.h"

#include <errno.h>
#include <png.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct png_msg {
  char text[256];
} png_msg;

static void on_png_error(png_structp png, png_const_charp msg) {
  png_msg *m = png_get_error_ptr(png);
  snprintf(m->text, sizeof m->text, "%s", msg);
  png_longjmp(png, 1);
}

/* Warnings (bad ancillary chunks, ignored gamma, ...) do not make an image unusable. */
static void on_png_warning(png_structp png, png_const_charp msg) {
  (void)png;
  (void)msg;
}

typedef struct png_reader {
  const char *path;
  int srgb_to_linear;
  bool keep8; /* an 8-bit image in rgb8/lut8 */
  pc_err *e;
  png_msg msg;
  FILE *f;
  png_structp png;
  png_infop info;
  png_bytep pixels;
  png_bytepp rows;
  pc_image img;
} png_reader;

/* One decoded row of `channels` samples of `bytes` bytes into w linear RGB floats. */
static void png_row_to_rgb(const png_byte *src, float *dst, png_uint_32 w, int channels, int bytes,
                           const float *lut, int srgb_to_linear) {
  for (png_uint_32 x = 0; x < w; x++, src += channels * bytes, dst += 3) {
    for (int c = 0; c < 3; c++) {
      if (bytes == 1) {
        dst[c] = lut[src[c]];
      } else {
        /* PNG samples are big-endian on disk and libpng keeps them so. */
        float v = (float)((src[2 * c] << 8) | src[2 * c + 1]) / 65535.0f;
        dst[c] = srgb_to_linear ? pc_srgb_to_linear(v) : v;
      }
    }
  }
}

/* One decoded row of 8-bit samples, its first three channels as they are. */
static void png_row_to_bytes(const png_byte *src, uint8_t *dst, png_uint_32 w, int channels) {
  for (png_uint_32 x = 0; x < w; x++, src += channels, dst += 3) memcpy(dst, src, 3);
}

/* Runs under the caller's setjmp: returns a code for errors found here, longjmps for
 * errors libpng finds. */
static int png_decode(png_reader *r) {
  png_init_io(r->png, r->f);
  png_read_info(r->png, r->info);
  png_uint_32 w, h;
  int depth, ctype;
  png_get_IHDR(r->png, r->info, &w, &h, &depth, &ctype, NULL, NULL, NULL);
  if (w == 0 || h == 0 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(r->e, PC_ELIMIT, "%s: PNG size %lux%lu outside 1..%d", r->path,
                   (unsigned long)w, (unsigned long)h, PC_IMAGE_MAX_DIM);

  if (ctype == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(r->png);
  if (ctype == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(r->png);
  if (!(ctype & PNG_COLOR_MASK_COLOR)) png_set_gray_to_rgb(r->png);
  int passes = png_set_interlace_handling(r->png);
  png_read_update_info(r->png, r->info);

  int channels = png_get_channels(r->png, r->info);
  int bytes = png_get_bit_depth(r->png, r->info) == 16 ? 2 : 1;
  size_t rowbytes = png_get_rowbytes(r->png, r->info);
  if ((channels != 3 && channels != 4) || rowbytes != (size_t)w * channels * bytes)
    return pc_errf(r->e, PC_EIMAGE, "%s: unexpected PNG pixel layout", r->path);

  /* An interlaced image's rows are complete only after its last pass, so it is decoded whole;
   * any other row by row, without a second copy of the image in its file's samples. */
  size_t buffered = passes > 1 ? h : 1;
  bool keep8 = r->keep8 && bytes == 1;
  r->pixels = malloc(rowbytes * buffered);
  r->rows = malloc(sizeof *r->rows * buffered);
  if (keep8) {
    r->img.rgb8 = malloc(3 * (size_t)w * h);
    r->img.lut8 = malloc(256 * sizeof *r->img.lut8);
  } else {
    r->img.rgb = malloc(sizeof(float) * 3 * (size_t)w * h);
  }
  if (!r->pixels || !r->rows || !(keep8 ? r->img.rgb8 && r->img.lut8 : r->img.rgb != NULL))
    return pc_errf(r->e, PC_ENOMEM, "%s: out of memory for a %lux%lu PNG", r->path,
                   (unsigned long)w, (unsigned long)h);
  for (size_t y = 0; y < buffered; y++) r->rows[y] = r->pixels + rowbytes * y;
  float lut[256];
  pc_image_lut8(r->srgb_to_linear, lut);
  if (keep8) memcpy(r->img.lut8, lut, sizeof lut);
  if (passes > 1) png_read_image(r->png, r->rows);
  for (png_uint_32 y = 0; y < h; y++) {
    if (passes == 1) png_read_row(r->png, r->rows[0], NULL);
    const png_byte *src = r->rows[passes > 1 ? y : 0];
    if (keep8) png_row_to_bytes(src, r->img.rgb8 + (size_t)y * w * 3, w, channels);
    else png_row_to_rgb(src, r->img.rgb + (size_t)y * w * 3, w, channels, bytes, lut, r->srgb_to_linear);
  }
  png_read_end(r->png, NULL);
  r->img.w = (int)w;
  r->img.h = (int)h;
  return PC_OK;
}

static uint32_t be32(const unsigned char *b) {
  return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3];
}

/* The bytes of image data the file holds: its IDAT chunks' lengths, each cut at the end of
 * the file. Walks the chunk headers from the signature (ending at IEND, the file's end or a
 * header that cannot be one; libpng reports what is wrong with the file). */
static uint64_t png_idat_bytes(FILE *f) {
  if (fseek(f, 0, SEEK_END) != 0) return 0;
  long size = ftell(f);
  uint64_t sum = 0;
  for (long pos = 8; size >= 0 && pos + 8 <= size;) {
    unsigned char hdr[8];
    if (fseek(f, pos, SEEK_SET) != 0 || fread(hdr, 1, sizeof hdr, f) != sizeof hdr) break;
    uint32_t len = be32(hdr);
    if (len > 0x7fffffffu) break; /* PNG's limit: not a chunk */
    long data = pos + 8, left = size - data;
    if (memcmp(hdr + 4, "IDAT", 4) == 0) sum += (uint64_t)(len < (uint64_t)left ? len : left);
    if (memcmp(hdr + 4, "IEND", 4) == 0) break;
    pos = data + (long)len + 4;
  }
  return sum;
}

/* libpng's png_read_info parses every chunk up to the first IDAT before returning the size,
 * so the size limit is first checked here on the IHDR, which PNG requires at a fixed place.
 * And a header may claim far more pixels than the file's data holds (a cut file, or a
 * forged one): deflate expands at most 1032:1, so the rows (their filter bytes left out)
 * must fit in 1032 times the IDAT bytes, or the file is refused before its image is
 * allocated. */
static int png_precheck_size(FILE *f, const char *path, pc_err *e) {
  unsigned char b[26];
  if (fread(b, 1, sizeof b, f) == sizeof b && memcmp(b + 12, "IHDR", 4) == 0) {
    uint32_t w = be32(b + 16), h = be32(b + 20);
    if (w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
      return pc_errf(e, PC_ELIMIT, "%s: PNG size %lux%lu exceeds %d", path, (unsigned long)w,
                     (unsigned long)h, PC_IMAGE_MAX_DIM);
    static const int samples[7] = {1, 0, 3, 1, 2, 0, 4}; /* per colour type; 0: not one */
    int depth = b[24], ctype = b[25];
    if (ctype < 7 && samples[ctype] > 0 && depth >= 1 && depth <= 16) {
      uint64_t row = ((uint64_t)w * (uint64_t)(samples[ctype] * depth) + 7) / 8;
      uint64_t idat = png_idat_bytes(f);
      if (row * h > 1032 * idat)
        return pc_errf(e, PC_EIMAGE,
                       "%s: bad PNG: its header claims %lux%lu pixels, more than its %llu bytes of "
                       "image data can hold (a cut or damaged file)",
                       path, (unsigned long)w, (unsigned long)h, (unsigned long long)idat);
    }
  }
  if (fseek(f, 0, SEEK_SET) != 0) return pc_errf(e, PC_EIO, "%s: cannot seek", path);
  return PC_OK;
}

int pc_png_read(const char *path, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e) {
  png_reader *r = calloc(1, sizeof *r);
  if (!r) return pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  r->path = path;
  r->srgb_to_linear = srgb_to_linear;
  r->keep8 = bytes;
  r->e = e;
  int rc;
  r->f = fopen(path, "rb");
  if (!r->f) {
    rc = pc_errf(e, PC_EIO, "%s: cannot open: %s", path, strerror(errno));
    goto done;
  }
  if ((rc = png_precheck_size(r->f, path, e))) goto done;
  r->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &r->msg, on_png_error, on_png_warning);
  r->info = r->png ? png_create_info_struct(r->png) : NULL;
  if (!r->info) {
    rc = pc_errf(e, PC_ENOMEM, "%s: cannot create a libpng reader", path);
    goto done;
  }
  if (setjmp(png_jmpbuf(r->png))) {
    /* libpng says only "Read Error" when the file is cut short. */
    rc = pc_errf(e, PC_EIMAGE, "%s: bad PNG: %s", path,
                 feof(r->f) ? "file ends early" : r->msg.text);
    goto done;
  }
  rc = png_decode(r);
done:
  if (r->png) png_destroy_read_struct(&r->png, r->info ? &r->info : NULL, NULL);
  if (r->f) fclose(r->f);
  free(r->pixels);
  free(r->rows);
  if (rc == PC_OK) *out = r->img;
  else pc_image_free(&r->img);
  free(r);
  return rc;
}

typedef struct png_writer {
  png_msg msg;
  FILE *f;
  png_structp png;
  png_infop info;
  const uint8_t *pixels;
  int w, h;
} png_writer;

static void png_encode(png_writer *wr) {
  png_init_io(wr->png, wr->f);
  png_set_IHDR(wr->png, wr->info, (png_uint_32)wr->w, (png_uint_32)wr->h, 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB_gAMA_and_cHRM(wr->png, wr->info, PNG_sRGB_INTENT_PERCEPTUAL);
  /* A preview, written after every render while the user waits. A 512x512 render's: 55 ms at
   * libpng's defaults (deflate level 6, each row's filter chosen among five), 19.5 ms at level 1
   * with the Up filter alone, for a file 9% larger (530 KB against 484 KB). */
  png_set_compression_level(wr->png, 1);
  png_set_filter(wr->png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
  png_write_info(wr->png, wr->info);
  for (int y = 0; y < wr->h; y++) png_write_row(wr->png, wr->pixels + (size_t)y * wr->w * 3);
  png_write_end(wr->png, NULL);
}

static uint8_t to_srgb8(float v) {
  if (!(v > 0.0f)) v = 0.0f; /* also NaN */
  if (v > 1.0f) v = 1.0f;
  return (uint8_t)(pc_linear_to_srgb(v) * 255.0f + 0.5f);
}

int pc_png_write_preview(const char *path, int w, int h, const float *rgb, float exposure,
                         pc_err *e) {
  if (!path || !rgb) return pc_errf(e, PC_EINVAL, "pc_png_write_preview: NULL argument");
  if (w <= 0 || h <= 0 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(e, PC_ELIMIT, "%s: preview size %dx%d outside 1..%d", path, w, h,
                   PC_IMAGE_MAX_DIM);
  float scale = exp2f(exposure);
  if (!isfinite(scale) || scale <= 0.0f)
    return pc_errf(e, PC_EINVAL, "%s: exposure %g out of range", path, (double)exposure);
  char tmp[4096];
  int rc = pc_file_tmp_path(path, tmp, sizeof tmp, e);
  if (rc) return rc;

  size_t n = (size_t)w * h * 3;
  uint8_t *pixels = malloc(n);
  png_writer *wr = calloc(1, sizeof *wr);
  if (!pixels || !wr) {
    free(pixels);
    free(wr);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory for a %dx%d preview", path, w, h);
  }
  for (size_t i = 0; i < n; i++) pixels[i] = to_srgb8(rgb[i] * scale);
  wr->pixels = pixels;
  wr->w = w;
  wr->h = h;

  wr->f = fopen(tmp, "wb");
  if (!wr->f) {
    rc = pc_errf(e, PC_EIO, "%s: cannot create: %s", tmp, strerror(errno));
    goto done;
  }
  wr->png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &wr->msg, on_png_error, on_png_warning);
  wr->info = wr->png ? png_create_info_struct(wr->png) : NULL;
  if (!wr->info) {
    rc = pc_errf(e, PC_ENOMEM, "%s: cannot create a libpng writer", path);
    goto done;
  }
  if (setjmp(png_jmpbuf(wr->png))) {
    rc = pc_errf(e, PC_EIMAGE, "%s: PNG write failed: %s", path, wr->msg.text);
    goto done;
  }
  png_encode(wr);
  rc = PC_OK;
done:
  if (wr->png) png_destroy_write_struct(&wr->png, wr->info ? &wr->info : NULL);
  if (wr->f && fclose(wr->f) != 0 && rc == PC_OK)
    rc = pc_errf(e, PC_EIO, "%s: write error: %s", tmp, strerror(errno));
  if (wr->f) {
    if (rc == PC_OK) rc = pc_file_commit(tmp, path, e);
    else unlink(tmp);
  }
  free(pixels);
  free(wr);
  return rc;
}
