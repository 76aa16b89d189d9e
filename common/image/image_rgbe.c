/* image_rgbe.c: Radiance RGBE (.hdr) images through Debian's stb_image (libstb-dev): the size
 * is checked from the header, and against what the file can hold, before any pixel is
 * decoded. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <stb_image.h>

#include "image_internal.h"

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
