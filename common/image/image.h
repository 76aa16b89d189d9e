/* image.h: an RGB float raster and its files: PNG/JPEG/EXR/RGBE/PFM/PPM/BMP/TGA read (textures, references),
 * EXR write with named layers and header attributes, sRGB PNG preview. */
#ifndef PC_IMAGE_H
#define PC_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "error.h"

#define PC_IMAGE_MAX_DIM 32768

typedef struct pc_image {
  int w, h;
  float *rgb; /* w*h*3, row-major from the top-left; linear radiance/reflectance */
  /* Only from pc_image_read_bytes, for an 8-bit file (rgb then NULL): its samples as stored,
   * w*h*3, and lut8[b], the linear value of sample b. A quarter of the floats' memory. */
  uint8_t *rgb8;
  float *lut8;
} pc_image;

void pc_image_free(pc_image *img);
/* Sample k (0 .. 3*w*h-1) of either form. */
static inline float pc_image_sample(const pc_image *img, size_t k) {
  return img->rgb8 ? img->lut8[img->rgb8[k]] : img->rgb[k];
}

/* Reads a PNG, JPEG, EXR, Radiance RGBE .hdr, PFM, binary PPM or BMP (chosen by content, not
 * extension), or a TGA (by its .tga name: the format has no magic number). 8-bit formats
 * are converted from sRGB to linear when `srgb_to_linear`; EXR, RGBE and PFM are linear. For EXR the beauty R,G,B channels
 * are read. */
int pc_image_read(const char *path, int srgb_to_linear, pc_image *out, pc_err *e);
/* The same, but an 8-bit PNG, JPEG, PPM, BMP or TGA is kept in its bytes (rgb8 and lut8, rgb NULL); every
 * sample's value is the float pc_image_read gives for it. For textures, which may be many and
 * large. */
int pc_image_read_bytes(const char *path, int srgb_to_linear, pc_image *out, pc_err *e);

/* One named RGB layer of a multi-layer EXR. Name "" is the beauty (channels R,G,B). */
typedef struct pc_exr_layer {
  const char *name;
  const float *rgb; /* w*h*3 */
} pc_exr_layer;

/* A header attribute: a string, a double or a 64-bit count (stored as string or double). */
typedef struct pc_exr_attr {
  const char *name;
  enum { PC_ATTR_STRING, PC_ATTR_DOUBLE } type;
  const char *s;
  double d;
} pc_exr_attr;

/* Writes a single-part EXR (32-bit float, RLE compressed) with the layers' channels
 * "<layer>.R" etc. (beauty as plain R,G,B). Writes to a temporary file and renames, so a
 * reader never sees a partial file. */
int pc_exr_write(const char *path, int w, int h, const pc_exr_layer *layers, int nlayers,
                 const pc_exr_attr *attrs, int nattrs, pc_err *e);

/* The same with the pixels asked for a band of rows at a time, so that no whole image need
 * exist in floats: fill(user, y0, ny, rows, e) writes rows [y0, y0 + ny) of layer l, ny*w*3
 * floats of interleaved RGB, into rows[l] for every layer (named names[l], "" the beauty), and
 * returns PC_OK or an error (e set), which ends the write with no file. */
typedef int (*pc_exr_rows_fn)(void *user, int y0, int ny, float *const *rows, pc_err *e);
int pc_exr_write_rows(const char *path, int w, int h, const char *const *names, int nlayers, pc_exr_rows_fn fill,
                      void *user, const pc_exr_attr *attrs, int nattrs, pc_err *e);

/* Reads every layer of an EXR written by pc_exr_write (or any EXR with RGB channel triplets).
 * Returns layer names (malloc'd, "" for beauty) and images; caller frees with pc_exr_file_free. */
typedef struct pc_exr_file {
  int w, h, nlayers;
  char **names;
  pc_image *layers;
  int nattrs;
  char **attr_names;
  char **attr_values; /* attribute values printed as text */
} pc_exr_file;
int pc_exr_read_layers(const char *path, pc_exr_file *out, pc_err *e);
/* The same with only the first layer, the beauty when there is one (name ""), and every
 * attribute: what a render's summary and preview need, without the other layers' memory. */
int pc_exr_read_beauty_attrs(const char *path, pc_exr_file *out, pc_err *e);
void pc_exr_file_free(pc_exr_file *f);
/* The text of the attribute called name, or NULL. */
const char *pc_exr_attr_get(const pc_exr_file *f, const char *name);

/* 8-bit sRGB PNG of rgb * 2^exposure (clamped), atomically written. */
int pc_png_write_preview(const char *path, int w, int h, const float *rgb, float exposure, pc_err *e);

#endif
