/* image_rgbe.c: Radiance RGBE (.hdr) images through Debian's stb_image (libstb-dev): the size
 * is checked from the header before any pixel is decoded. */
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>

#include "image_internal.h"

int pc_rgbe_read(const char *path, pc_image *out, pc_err *e) {
  int w, h, comp;
  if (!stbi_info(path, &w, &h, &comp))
    return pc_errf(e, PC_EPARSE, "%s: not a readable Radiance RGBE file: %s", path, stbi_failure_reason());
  if (w < 1 || h < 1 || w > PC_IMAGE_MAX_DIM || h > PC_IMAGE_MAX_DIM)
    return pc_errf(e, PC_ELIMIT, "%s: %dx%d pixels (at most %d on a side)", path, w, h, PC_IMAGE_MAX_DIM);
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
