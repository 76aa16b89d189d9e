/* texture_gradient.c: Mitsuba 0.6's Texture::evalGradient, what the bumpmap BSDF reads its
 * displacement slopes from. A bitmap gives the exact derivative of its bilinear interpolation
 * at full resolution (Mitsuba's evalGradientBilinear), zero with filterType nearest; every
 * other 2D texture (the checkerboard) a forward difference with Mitsuba's Epsilon in its scaled
 * coordinates; a constant zero. All after the uv scale (chain rule) and the `scale`
 * texture's multiplier. */
#include "texture.h"

/* Mitsuba's Epsilon in single precision, the step of its forward differences. */
#define PC_TEX_GRAD_EPS 1e-4f

/* d/du and d/dv of the bilinear lookup, in the texture's own (offset and scaled) coordinates. */
static void bitmap_gradient(const pc_image *img, float u, float v, vec3 g[2]) {
  vec3 p[4];
  float dx, dy;
  g[0] = g[1] = v3s(0.f);
  if (!pc_bitmap_footprint(img, u, v, p, &dx, &dy)) return;
  /* x = u w - 1/2 and y = v h - 1/2. */
  vec3 du = v3_add(v3_scale(v3_sub(p[1], p[0]), 1.f - dy), v3_scale(v3_sub(p[3], p[2]), dy));
  vec3 row0 = v3_add(v3_scale(p[0], 1.f - dx), v3_scale(p[1], dx));
  vec3 row1 = v3_add(v3_scale(p[2], 1.f - dx), v3_scale(p[3], dx));
  g[0] = v3_scale(du, (float)img->w);
  g[1] = v3_scale(v3_sub(row1, row0), (float)img->h);
}

void pc_texture_gradient(const pc_texture *t, vec2 uv, vec3 grad[2]) {
  grad[0] = grad[1] = v3s(0.f);
  if (t->type == PC_TEX_CONST) return;
  float u = uv.x * t->uscale + t->uoffset, v = uv.y * t->vscale + t->voffset;
  if (!isfinite(u) || !isfinite(v)) return;
  if (t->type == PC_TEX_BITMAP) {
    if (!t->nearest) bitmap_gradient(&t->img, u, v, grad);
  } else {
    /* Texture2D's forward difference, on the unscaled value of the texture at the shifted
     * texture coordinates (pc_texture_eval applies the mapping again, so undo it). */
    pc_texture plain = *t;
    plain.uscale = plain.vscale = 1.f;
    plain.uoffset = plain.voffset = 0.f;
    plain.scaled = false;
    vec3 f = pc_texture_eval(&plain, (vec2){u, v});
    vec3 fu = pc_texture_eval(&plain, (vec2){u + PC_TEX_GRAD_EPS, v});
    vec3 fv = pc_texture_eval(&plain, (vec2){u, v + PC_TEX_GRAD_EPS});
    grad[0] = v3_scale(v3_sub(fu, f), 1.f / PC_TEX_GRAD_EPS);
    grad[1] = v3_scale(v3_sub(fv, f), 1.f / PC_TEX_GRAD_EPS);
  }
  grad[0] = v3_scale(grad[0], t->uscale);
  grad[1] = v3_scale(grad[1], t->vscale);
  if (t->scaled) {
    grad[0] = v3_mul(grad[0], t->scale);
    grad[1] = v3_mul(grad[1], t->scale);
  }
}
