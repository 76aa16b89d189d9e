/* image_jpeg.c: JPEG reading through libjpeg into a linear float raster. libjpeg's default
 * error handler calls exit(); ours longjmps back instead, and treats libjpeg's warnings
 * (premature end of data, corrupt entropy data) as errors, because libjpeg would otherwise
 * pad a truncated file with gray and report success. A header's size is not trusted with
 * memory: the image grows as its scanlines decode, and a progressive image, whose coefficients
 * libjpeg holds whole, is refused where they would outweigh its file past any real image's
 * ratio (a forged or damaged header). */
#include "image_internal.h"

#include <errno.h>
#include <jpeglib.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct jpeg_reader {
  struct jpeg_error_mgr jerr; /* first, so libjpeg's err pointer is also ours */
  jmp_buf jump;
  char msg[JMSG_LENGTH_MAX];
  struct jpeg_decompress_struct cinfo;
  int created;
  const char *path;
  int srgb_to_linear;
  bool keep8; /* the samples in rgb8/lut8 */
  pc_err *e;
  FILE *f;
  long file_bytes;
  JSAMPLE *row;
  pc_image img;
} jpeg_reader;

static void on_jpeg_error(j_common_ptr cinfo) {
  jpeg_reader *r = (jpeg_reader *)cinfo->err;
  r->jerr.format_message(cinfo, r->msg);
  longjmp(r->jump, 1);
}

static void on_jpeg_message(j_common_ptr cinfo, int level) {
  if (level < 0) on_jpeg_error(cinfo); /* level -1 is a warning; >= 0 are trace messages */
}

/* Runs under the caller's setjmp. */
static int jpeg_decode(jpeg_reader *r) {
  jpeg_create_decompress(&r->cinfo);
  r->created = 1;
  jpeg_stdio_src(&r->cinfo, r->f);
  jpeg_read_header(&r->cinfo, TRUE);
  JDIMENSION w = r->cinfo.image_width, h = r->cinfo.image_height;
  if (w == 0 || h == 0 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(r->e, PC_ELIMIT, "%s: JPEG size %ux%u outside 1..%d", r->path, (unsigned)w,
                   (unsigned)h, PC_IMAGE_MAX_DIM);
  if (r->cinfo.progressive_mode) {
    /* 128 bytes per 8x8 block of every component (at most full resolution each); the file
     * holds at least a byte per 1024 of them, or the image is far flatter than any texture */
    uint64_t blocks = ((uint64_t)w + 7) / 8 * (((uint64_t)h + 7) / 8) * (uint64_t)r->cinfo.num_components;
    uint64_t need = 128 * blocks, allowed = ((uint64_t)64 << 20) + 1024 * (uint64_t)r->file_bytes;
    if (need > allowed)
      return pc_errf(r->e, PC_EIMAGE,
                     "%s: bad JPEG: a progressive %ux%u image in %ld bytes (decoding it would take "
                     "%llu MB; a damaged or forged header)",
                     r->path, (unsigned)w, (unsigned)h, r->file_bytes, (unsigned long long)(need >> 20));
  }
  r->cinfo.out_color_space = JCS_RGB;
  jpeg_start_decompress(&r->cinfo);
  if (r->cinfo.output_components != 3 || r->cinfo.output_width != w ||
      r->cinfo.output_height != h)
    return pc_errf(r->e, PC_EIMAGE, "%s: unexpected JPEG output layout", r->path);

  r->row = malloc((size_t)w * 3);
  if (!r->row) return pc_errf(r->e, PC_ENOMEM, "%s: out of memory for a %ux%u JPEG", r->path, (unsigned)w, (unsigned)h);
  float lut[256];
  pc_image_lut8(r->srgb_to_linear, lut);
  if (r->keep8) {
    if (!(r->img.lut8 = malloc(sizeof lut)))
      return pc_errf(r->e, PC_ENOMEM, "%s: out of memory for a %ux%u JPEG", r->path, (unsigned)w, (unsigned)h);
    memcpy(r->img.lut8, lut, sizeof lut);
  }
  size_t rows_held = 0, row_samples = (size_t)w * 3, sample = r->keep8 ? 1 : sizeof(float);
  void **held = r->keep8 ? (void **)&r->img.rgb8 : (void **)&r->img.rgb;
  while (r->cinfo.output_scanline < h) {
    size_t y = r->cinfo.output_scanline;
    if (y == rows_held) {
      /* doubling from ~1 MB: a file cut short fails at its first missing data, having taken at
       * most twice what it decoded */
      size_t more = rows_held ? rows_held : (1u << 20) / (sample * row_samples) + 1;
      if (more > h - rows_held) more = h - rows_held;
      void *grown = realloc(*held, sample * row_samples * (rows_held + more));
      if (!grown)
        return pc_errf(r->e, PC_ENOMEM, "%s: out of memory for a %ux%u JPEG", r->path, (unsigned)w,
                       (unsigned)h);
      *held = grown;
      rows_held += more;
    }
    JSAMPROW rows[1] = {r->row};
    if (jpeg_read_scanlines(&r->cinfo, rows, 1) != 1)
      return pc_errf(r->e, PC_EIMAGE, "%s: JPEG data ends early", r->path);
    if (r->keep8) {
      memcpy(r->img.rgb8 + y * row_samples, r->row, row_samples);
    } else {
      float *dst = r->img.rgb + y * row_samples;
      for (size_t i = 0; i < row_samples; i++) dst[i] = lut[r->row[i]];
    }
  }
  jpeg_finish_decompress(&r->cinfo);
  r->img.w = (int)w;
  r->img.h = (int)h;
  return PC_OK;
}

int pc_jpeg_read(const char *path, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e) {
  jpeg_reader *r = calloc(1, sizeof *r);
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
  if (fseek(r->f, 0, SEEK_END) != 0 || (r->file_bytes = ftell(r->f)) < 0 || fseek(r->f, 0, SEEK_SET) != 0) {
    rc = pc_errf(e, PC_EIO, "%s: cannot seek: %s", path, strerror(errno));
    goto done;
  }
  r->cinfo.err = jpeg_std_error(&r->jerr);
  r->jerr.error_exit = on_jpeg_error;
  r->jerr.emit_message = on_jpeg_message;
  if (setjmp(r->jump)) {
    rc = pc_errf(e, PC_EIMAGE, "%s: bad JPEG: %s", path, r->msg);
    goto done;
  }
  rc = jpeg_decode(r);
done:
  if (r->created) jpeg_destroy_decompress(&r->cinfo);
  if (r->f) fclose(r->f);
  free(r->row);
  if (rc == PC_OK) *out = r->img;
  else pc_image_free(&r->img);
  free(r);
  return rc;
}
