/* image.c: the pc_image raster's lifetime, format detection by magic bytes for pc_image_read. */
#include "image_internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

void pc_image_free(pc_image *img) {
  if (!img) return;
  free(img->rgb);
  img->rgb = NULL;
  img->w = img->h = 0;
}

int pc_image_read(const char *path, int srgb_to_linear, pc_image *out, pc_err *e) {
  if (!path || !out) return pc_errf(e, PC_EINVAL, "pc_image_read: NULL argument");
  out->w = out->h = 0;
  out->rgb = NULL;
  FILE *f = fopen(path, "rb");
  if (!f) return pc_errf(e, PC_EIO, "%s: cannot open: %s", path, strerror(errno));
  unsigned char m[8];
  size_t n = fread(m, 1, sizeof m, f);
  int rerr = ferror(f);
  fclose(f);
  if (rerr) return pc_errf(e, PC_EIO, "%s: read error", path);

  static const unsigned char png_magic[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  static const unsigned char exr_magic[4] = {0x76, 0x2f, 0x31, 0x01};
  if (n >= 8 && memcmp(m, png_magic, 8) == 0) return pc_png_read(path, srgb_to_linear, out, e);
  if (n >= 3 && m[0] == 0xff && m[1] == 0xd8 && m[2] == 0xff)
    return pc_jpeg_read(path, srgb_to_linear, out, e);
  if (n >= 4 && memcmp(m, exr_magic, 4) == 0) return pc_exr_read_beauty(path, out, e);
  if ((n >= 7 && memcmp(m, "#?RADIA", 7) == 0) || (n >= 6 && memcmp(m, "#?RGBE", 6) == 0)) return pc_rgbe_read(path, out, e);
  return pc_errf(e, PC_EUNSUPPORTED, "%s: not a PNG, JPEG, OpenEXR or Radiance RGBE file", path);
}
