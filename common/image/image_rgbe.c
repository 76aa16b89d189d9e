/* image_rgbe.c: Radiance RGBE (.hdr) images through Debian's stb_image (libstb-dev): the size
 * is checked from the header, and against what the file can hold, and the run-length
 * scanlines' structure is walked, before any pixel is decoded. */
#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <stb_image.h>

#include "image_internal.h"

/* Skips the header as stb reads it: lines up to one that is empty as a C string (its first
 * byte a newline or a NUL: stb keeps a line in a C string), then the resolution line. */
static bool skip_header(FILE *f) {
  int c;
  bool line_start = true, empty = false, end_seen = false;
  while ((c = getc(f)) != EOF) {
    if (line_start) empty = c == '\n' || c == '\0';
    line_start = c == '\n';
    if (c != '\n') continue;
    if (end_seen) return true; /* the end of the resolution line */
    end_seen = empty;
  }
  return false;
}

/* stb_image (Debian 12's) loops forever on a run-length scanline where a count byte is 0, and
 * reads zeros past the end of the file, so a corrupt or truncated file of a few bytes hangs it
 * (fuzz_files: 67 bytes). This walks the scanlines as stbi__hdr_load does and returns the
 * first (from 1) where it would hang, 0 where stb ends on its own: a complete image, one of
 * flat pixels (bounded by the size check), or an error stb reports itself. */
static int rle_hang_line(FILE *f, int w, int h) {
  if (!skip_header(f) || w < 8 || w >= 32768) return 0;
  for (int j = 0; j < h; j++) {
    int c1 = getc(f), c2 = getc(f), len = getc(f);
    if (c1 != 2 || c2 != 2 || len == EOF || (len & 0x80)) return 0; /* flat from here on */
    int lo = getc(f);
    if (lo == EOF || (len << 8 | lo) != w) return 0; /* stb: "invalid decoded scanline length" */
    for (int k = 0; k < 4; k++)
      for (int i = 0; i < w;) {
        int count = getc(f);
        if (count == EOF || count == 0) return j + 1;
        if (count > 128) {
          count -= 128;
          if (getc(f) == EOF) return j + 1;
        } else if (count <= w - i && fseek(f, count, SEEK_CUR) != 0) {
          return j + 1;
        }
        if (count > w - i) return 0; /* stb: "bad RLE data" */
        i += count;
      }
  }
  return 0;
}

int pc_rgbe_read(const char *path, pc_image *out, pc_err *e) {
  int w, h, comp;
  if (!stbi_info(path, &w, &h, &comp))
    return pc_errf(e, PC_EPARSE, "%s: not a readable Radiance RGBE file: %s", path, stbi_failure_reason());
  if (w < 1 || h < 1 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(e, PC_ELIMIT, "%s: %dx%d pixels (at most %d on a side)", path, w, h, PC_IMAGE_MAX_DIM);
  /* stb_image decodes a file that ends early as if zeros followed, so a 53-byte header that
   * claims 30000x30000 pixels took minutes and 12 GB. What stb decodes packs at most 127 pixels'
   * component in 2 bytes (a run of its scanline encoding): under 16 pixels a byte. */
  struct stat st;
  if (stat(path, &st) != 0) return pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  if ((double)w * (double)h > 16.0 * (double)st.st_size)
    return pc_errf(e, PC_EPARSE, "%s: a %dx%d Radiance RGBE image cannot fit in %lld bytes (truncated?)", path, w, h,
                   (long long)st.st_size);
  FILE *f = fopen(path, "rb");
  if (!f) return pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  int bad = rle_hang_line(f, w, h);
  fclose(f);
  if (bad) return pc_errf(e, PC_EPARSE, "%s: corrupt or truncated run-length data in scanline %d", path, bad);
  float *px = stbi_loadf(path, &w, &h, &comp, 3);
  if (!px) return pc_errf(e, PC_EPARSE, "%s: cannot decode the Radiance RGBE file: %s", path, stbi_failure_reason());
  size_t n = (size_t)w * (size_t)h * 3;
  out->rgb = malloc(n * sizeof(float));
  if (!out->rgb) {
    stbi_image_free(px);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory for %dx%d pixels", path, w, h);
  }
  memcpy(out->rgb, px, n * sizeof(float));
  stbi_image_free(px);
  out->w = w;
  out->h = h;
  return PC_OK;
}
