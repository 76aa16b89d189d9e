/* texture.h: spatially varying RGB parameters (Mitsuba's spectrum/texture slots): a constant,
 * a bitmap (bilinear, wrapping) or a checkerboard, all looked up by texture coordinates. */
#ifndef PC_TEXTURE_H
#define PC_TEXTURE_H

#include <stdbool.h>

#include "image.h"
#include "vecmath.h"

typedef enum { PC_TEX_CONST, PC_TEX_BITMAP, PC_TEX_CHECKER } pc_tex_type;

typedef struct pc_texture {
  pc_tex_type type;
  vec3 value;              /* PC_TEX_CONST */
  pc_image img;            /* PC_TEX_BITMAP: owned, linear RGB */
  vec3 color0, color1;     /* PC_TEX_CHECKER (Mitsuba defaults 0.4 and 0.2) */
  float uscale, vscale;    /* uv' = uv * scale + offset (Mitsuba's Texture2D) */
  float uoffset, voffset;
  bool nearest;            /* PC_TEX_BITMAP: filterType nearest (Mitsuba's gradient is then 0) */
  bool scaled;             /* wrapped in Mitsuba's `scale` texture: every value times `scale` */
  vec3 scale;
} pc_texture;

/* A slot is either a constant or an index into the scene's texture array: keeps materials
 * plain data. */
typedef struct pc_tex_slot {
  int tex;      /* -1: use `value` */
  vec3 value;
} pc_tex_slot;

vec3 pc_texture_eval(const pc_texture *t, vec2 uv);
/* The four texels of a bilinear lookup at (u, v) (repeat wrap): px = {(x0,y0), (x1,y0), (x0,y1),
 * (x1,y1)} with image row y growing downward as v does (v = y / h), and the fractions dx, dy
 * toward x1, y1. False for an empty image. */
bool pc_bitmap_footprint(const pc_image *img, float u, float v, vec3 px[4], float *dx, float *dy);
static inline vec3 pc_slot_eval(const pc_tex_slot *s, const pc_texture *texs, vec2 uv) {
  return s->tex < 0 ? s->value : pc_texture_eval(&texs[s->tex], uv);
}
/* Mitsuba's getAverage(): the mean over the texture (for plastic's sampling weight, see
 * pc_material_prepare). */
vec3 pc_texture_average(const pc_texture *t);
/* Mitsuba's getMaximum(): the componentwise largest value (for ensureEnergyConservation). */
vec3 pc_texture_maximum(const pc_texture *t);
void pc_texture_free(pc_texture *t);
/* A deep copy (its own image); false if out of memory. */
bool pc_texture_copy(const pc_texture *t, pc_texture *out);

/* Mitsuba's evalGradient: d value / du in grad[0], d value / dv in grad[1], in the texture
 * coordinates that pc_texture_eval takes (texture_gradient.c). */
void pc_texture_gradient(const pc_texture *t, vec2 uv, vec3 grad[2]);

#endif
