/* image.c: the pc_image raster's lifetime, format detection by magic bytes (by name for TGA) for
 * pc_image_read. */
#include "image_internal.h"

#include "file_read.h"

#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

void pc_image_free(pc_image *img) {
  if (!img) return;
  free(img->rgb);
  free(img->rgb8);
  free(img->lut8);
  img->rgb = NULL;
  img->rgb8 = NULL;
  img->lut8 = NULL;
  img->w = img->h = 0;
}

void pc_image_lut8(int srgb_to_linear, float lut[256]) {
  for (int i = 0; i < 256; i++) lut[i] = srgb_to_linear ? pc_srgb_to_linear(i / 255.0f) : i / 255.0f;
}

static int read_image(const char *path, int srgb_to_linear, bool bytes, pc_image *out, pc_err *e) {
  if (!path || !out) return pc_errf(e, PC_EINVAL, "pc_image_read: NULL argument");
  memset(out, 0, sizeof *out);
  FILE *f = fopen(path, "rb");
  if (!f) return pc_errf(e, PC_EIO, "%s: cannot open: %s", path, strerror(errno));
  unsigned char m[48];
  size_t n = fread(m, 1, sizeof m, f);
  int rerr = ferror(f);
  fclose(f);
  if (rerr) return pc_errf(e, PC_EIO, "%s: read error", path);

  static const unsigned char png_magic[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  static const unsigned char exr_magic[4] = {0x76, 0x2f, 0x31, 0x01};
  if (n >= 8 && memcmp(m, png_magic, 8) == 0) return pc_png_read(path, srgb_to_linear, bytes, out, e);
  if (n >= 3 && m[0] == 0xff && m[1] == 0xd8 && m[2] == 0xff)
    return pc_jpeg_read(path, srgb_to_linear, bytes, out, e);
  if (n >= 4 && memcmp(m, exr_magic, 4) == 0) return pc_exr_read_beauty(path, out, e);
  if ((n >= 7 && memcmp(m, "#?RADIA", 7) == 0) || (n >= 6 && memcmp(m, "#?RGBE", 6) == 0)) return pc_rgbe_read(path, out, e);
  if (n >= 2 && m[0] == 'B' && m[1] == 'M') return pc_stb8_read(path, "BMP", srgb_to_linear, bytes, out, e);
  if (n >= 2 && m[0] == 'P' && m[1] == '6') return pc_stb8_read(path, "PPM", srgb_to_linear, bytes, out, e);
  if (n >= 2 && m[0] == 'P' && (m[1] == 'F' || m[1] == 'f')) return pc_pfm_read(path, out, e);
  /* TGA has no magic number: its name says it, as for Mitsuba */
  const char *dot = strrchr(path, '.');
  if (dot && strcasecmp(dot, ".tga") == 0) return pc_stb8_read(path, "TGA", srgb_to_linear, bytes, out, e);
  if (pc_is_lfs_pointer(m, n)) return pc_errf(e, PC_EINVAL, "%s: " PC_LFS_POINTER_ERROR, path);
  return pc_errf(e, PC_EUNSUPPORTED, "%s: not a PNG, JPEG, OpenEXR, Radiance RGBE, PFM, PPM (P6), BMP or TGA file", path);
}

int pc_image_read(const char *path, int srgb_to_linear, pc_image *out, pc_err *e) {
  return read_image(path, srgb_to_linear, false, out, e);
}

int pc_image_read_bytes(const char *path, int srgb_to_linear, pc_image *out, pc_err *e) {
  return read_image(path, srgb_to_linear, true, out, e);
}
