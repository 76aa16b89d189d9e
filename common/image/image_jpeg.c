/* image_jpeg.c: JPEG reading through libjpeg into a linear float raster. libjpeg's default
 * error handler calls exit(); ours longjmps back instead, and treats libjpeg's warnings
 * (premature end of data, corrupt entropy data) as errors, because libjpeg would otherwise
 * pad a truncated file with gray and report success. */
#include "image_internal.h"

#include <errno.h>
#include <jpeglib.h>
#include <setjmp.h>
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
  pc_err *e;
  FILE *f;
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
  r->cinfo.out_color_space = JCS_RGB;
  jpeg_start_decompress(&r->cinfo);
  if (r->cinfo.output_components != 3 || r->cinfo.output_width != w ||
      r->cinfo.output_height != h)
    return pc_errf(r->e, PC_EIMAGE, "%s: unexpected JPEG output layout", r->path);

  r->row = malloc((size_t)w * 3);
  r->img.rgb = malloc(sizeof(float) * 3 * (size_t)w * h);
  if (!r->row || !r->img.rgb)
    return pc_errf(r->e, PC_ENOMEM, "%s: out of memory for a %ux%u JPEG", r->path, (unsigned)w,
                   (unsigned)h);
  float lut[256];
  for (int i = 0; i < 256; i++)
    lut[i] = r->srgb_to_linear ? pc_srgb_to_linear(i / 255.0f) : i / 255.0f;
  while (r->cinfo.output_scanline < h) {
    float *dst = r->img.rgb + (size_t)r->cinfo.output_scanline * w * 3;
    JSAMPROW rows[1] = {r->row};
    if (jpeg_read_scanlines(&r->cinfo, rows, 1) != 1)
      return pc_errf(r->e, PC_EIMAGE, "%s: JPEG data ends early", r->path);
    for (size_t i = 0; i < (size_t)w * 3; i++) dst[i] = lut[r->row[i]];
  }
  jpeg_finish_decompress(&r->cinfo);
  r->img.w = (int)w;
  r->img.h = (int)h;
  return PC_OK;
}

int pc_jpeg_read(const char *path, int srgb_to_linear, pc_image *out, pc_err *e) {
  jpeg_reader *r = calloc(1, sizeof *r);
  if (!r) return pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  r->path = path;
  r->srgb_to_linear = srgb_to_linear;
  r->e = e;
  int rc;
  r->f = fopen(path, "rb");
  if (!r->f) {
    rc = pc_errf(e, PC_EIO, "%s: cannot open: %s", path, strerror(errno));
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
