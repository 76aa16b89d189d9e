/* texture.c: texture lookups as Mitsuba 0.6 does them: constants, bitmaps (bilinear, repeat
 * wrap, uv (0,0) at the image's top-left as in Mitsuba) and the checkerboard, all after Mitsuba's
 * Texture2D mapping uv' = uv * scale + offset, and the `scale` texture's multiplier. */
#include "texture.h"

#include <stdlib.h>
#include <string.h>

static vec3 texel(const pc_image *img, int x, int y) {
  size_t k = 3 * ((size_t)y * (size_t)img->w + (size_t)x);
  if (img->rgb8) {
    const uint8_t *b = img->rgb8 + k;
    return v3(img->lut8[b[0]], img->lut8[b[1]], img->lut8[b[2]]);
  }
  const float *p = img->rgb + k;
  return v3(p[0], p[1], p[2]);
}

static bool has_pixels(const pc_image *img) { return (img->rgb || img->rgb8) && img->w > 0 && img->h > 0; }

static int wrap(int i, int n) {
  int r = i % n;
  return r < 0 ? r + n : r;
}

bool pc_bitmap_footprint(const pc_image *img, float u, float v, vec3 px[4], float *dx, float *dy) {
  if (!has_pixels(img)) return false;
  /* Repeat wrap first, so huge coordinates cannot overflow the integer conversion. */
  u -= floorf(u);
  v -= floorf(v);
  /* Texel centres sit at half-integer coordinates; image row 0 (the top of the file) is at
   * v = 0, as Mitsuba's MIPMap::evalBilinear (its OBJ loader flips vt, so OBJ files look as
   * their authors meant). */
  float x = u * (float)img->w - 0.5f, y = v * (float)img->h - 0.5f;
  float fx = floorf(x), fy = floorf(y);
  *dx = x - fx;
  *dy = y - fy;
  int x0 = wrap((int)fx, img->w), y0 = wrap((int)fy, img->h);
  int x1 = wrap(x0 + 1, img->w), y1 = wrap(y0 + 1, img->h);
  px[0] = texel(img, x0, y0);
  px[1] = texel(img, x1, y0);
  px[2] = texel(img, x0, y1);
  px[3] = texel(img, x1, y1);
  return true;
}

static vec3 bitmap_eval(const pc_image *img, float u, float v) {
  vec3 p[4];
  float dx, dy;
  if (!pc_bitmap_footprint(img, u, v, p, &dx, &dy)) return v3s(0.f);
  vec3 a = v3_add(v3_scale(p[0], 1.f - dx), v3_scale(p[1], dx));
  vec3 b = v3_add(v3_scale(p[2], 1.f - dx), v3_scale(p[3], dx));
  return v3_add(v3_scale(a, 1.f - dy), v3_scale(b, dy));
}

/* Parity of Mitsuba's (int)(c * 2): C++ truncates toward zero, so the cell around 0 is twice
 * as wide for negative coordinates; reproduced with truncf (no integer overflow). */
static int checker_parity(float c) {
  float t = truncf(c * 2.f);
  if (!isfinite(t)) return 0;
  return fmodf(fabsf(t), 2.f) != 0.f;
}

static vec3 unscaled_eval(const pc_texture *t, vec2 uv) {
  if (t->type == PC_TEX_CONST) return t->value;
  float u = uv.x * t->uscale + t->uoffset, v = uv.y * t->vscale + t->voffset;
  if (!isfinite(u) || !isfinite(v)) return v3s(0.f);
  if (t->type == PC_TEX_BITMAP) return bitmap_eval(&t->img, u, v);
  /* Mitsuba: x = 2 mod((int)(2u), 2) - 1, likewise y; x * y == 1 selects color0, i.e. equal
   * parities. */
  return checker_parity(u) == checker_parity(v) ? t->color0 : t->color1;
}

vec3 pc_texture_eval(const pc_texture *t, vec2 uv) {
  vec3 v = unscaled_eval(t, uv);
  return t->scaled ? v3_mul(v, t->scale) : v;
}

static vec3 unscaled_average(const pc_texture *t) {
  if (t->type == PC_TEX_CONST) return t->value;
  if (t->type == PC_TEX_CHECKER) return v3_scale(v3_add(t->color0, t->color1), 0.5f);
  const pc_image *img = &t->img;
  if (!has_pixels(img)) return v3s(0.f);
  double s[3] = {0, 0, 0};
  size_t n = (size_t)img->w * (size_t)img->h;
  for (size_t i = 0; i < n; i++)
    for (int c = 0; c < 3; c++) s[c] += pc_image_sample(img, 3 * i + c);
  return v3((float)(s[0] / n), (float)(s[1] / n), (float)(s[2] / n));
}

vec3 pc_texture_average(const pc_texture *t) {
  vec3 v = unscaled_average(t);
  return t->scaled ? v3_mul(v, t->scale) : v;
}

bool pc_texture_copy(const pc_texture *t, pc_texture *out) {
  *out = *t;
  if (t->type != PC_TEX_BITMAP) return true;
  out->img.rgb = NULL;
  out->img.rgb8 = NULL;
  out->img.lut8 = NULL;
  size_t n = 3 * (size_t)t->img.w * (size_t)t->img.h;
  if (t->img.rgb8) {
    out->img.rgb8 = malloc(n);
    out->img.lut8 = malloc(256 * sizeof *out->img.lut8);
    if (!out->img.rgb8 || !out->img.lut8) {
      pc_image_free(&out->img);
      return false;
    }
    memcpy(out->img.rgb8, t->img.rgb8, n);
    memcpy(out->img.lut8, t->img.lut8, 256 * sizeof *out->img.lut8);
    return true;
  }
  if (!t->img.rgb) return true;
  out->img.rgb = malloc(n * sizeof *out->img.rgb);
  if (!out->img.rgb) return false;
  memcpy(out->img.rgb, t->img.rgb, n * sizeof *out->img.rgb);
  return true;
}

static vec3 unscaled_maximum(const pc_texture *t) {
  if (t->type == PC_TEX_CONST) return t->value;
  if (t->type == PC_TEX_CHECKER) return v3_max(t->color0, t->color1);
  const pc_image *img = &t->img;
  vec3 m = v3s(0.f);
  for (size_t i = 0; has_pixels(img) && i < (size_t)img->w * (size_t)img->h; i++)
    m = v3_max(m, v3(pc_image_sample(img, 3 * i), pc_image_sample(img, 3 * i + 1), pc_image_sample(img, 3 * i + 2)));
  return m;
}

vec3 pc_texture_maximum(const pc_texture *t) {
  vec3 m = unscaled_maximum(t);
  return t->scaled ? v3_mul(m, t->scale) : m;
}

void pc_texture_free(pc_texture *t) {
  if (t->type == PC_TEX_BITMAP) pc_image_free(&t->img);
}
