/* light_env.c: the environment emitters with Mitsuba 0.6's conventions: `constant` (one
 * radiance from every direction) and `envmap` (a lat-long image: direction v in the emitter's
 * frame maps to u = atan2(v.x, -v.z) / 2pi (repeating), v = acos(v.y) / pi (row 0 at the top,
 * +y), looked up bilinearly at texel centres and times `scale`). Sampling follows Mitsuba's
 * envmap: a row by luminance times sin(theta) at the row's centre, a column by luminance, a
 * uniform point inside the pixel; the pdf is therefore piecewise constant per pixel over
 * (phi, theta), divided by sin(theta) for solid angle. */
#include <stdlib.h>

#include "light.h"

/* Envmaps above this many pixels are refused (their tables alone would pass 128 MiB). */
#define PC_ENV_MAX_PIXELS ((size_t)1 << 25)

static inline float luminance_at(const pc_image *img, int x, int y) {
  const float *p = img->rgb + 3 * ((size_t)y * (size_t)img->w + (size_t)x);
  float l = v3_luminance(v3(p[0], p[1], p[2]));
  return l > 0.f ? l : 0.f; /* negative texels (bad EXRs) never get probability */
}

int pc_env_prepare(pc_light *l, float radius, const char *what, pc_err *e) {
  const pc_image *img = &l->env_img;
  float area = PC_PI * radius * radius;
  if (!(radius > 0.f) || !isfinite(area))
    return pc_errf(e, PC_EINVAL, "%s: the scene's bounding sphere has radius %g", what, (double)radius);
  if (img->w == 0) {
    /* Flux into the scene's cross-section times pi: a rough match to an area light's irradiance
     * at the scene's scale, used only to choose among emitters. */
    l->power = PC_PI * area * v3_luminance(v3_scale(l->radiance, l->env_scale));
    return PC_OK;
  }
  int w = img->w, h = img->h;
  if ((size_t)w * (size_t)h > PC_ENV_MAX_PIXELS)
    return pc_errf(e, PC_ELIMIT, "%s: %dx%d pixels is over the limit of %zu", what, w, h, PC_ENV_MAX_PIXELS);
  free(l->env_row_cdf);
  free(l->env_col_cdf);
  l->env_row_cdf = malloc(sizeof(float) * ((size_t)h + 1));
  l->env_col_cdf = malloc(sizeof(float) * (size_t)h * ((size_t)w + 1));
  if (!l->env_row_cdf || !l->env_col_cdf) return pc_errf(e, PC_ENOMEM, "%s: out of memory for the sampling tables", what);
  double row_sum = 0.0;
  l->env_row_cdf[0] = 0.f;
  for (int y = 0; y < h; y++) {
    float *col = l->env_col_cdf + (size_t)y * ((size_t)w + 1);
    double col_sum = 0.0;
    col[0] = 0.f;
    for (int x = 0; x < w; x++) {
      const float *t = img->rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
      if (!isfinite(t[0]) || !isfinite(t[1]) || !isfinite(t[2]))
        return pc_errf(e, PC_EINVAL, "%s: texel (%d, %d) is NaN or infinite", what, x, y);
      col_sum += luminance_at(img, x, y);
      col[x + 1] = (float)col_sum;
    }
    for (int x = 1; x <= w; x++) col[x] = col_sum > 0.0 ? (float)(col[x] / col_sum) : 0.f;
    row_sum += col_sum * sin((y + 0.5) * PC_PI / h);
    l->env_row_cdf[y + 1] = (float)row_sum;
  }
  if (!(row_sum > 0.0) || !isfinite(row_sum))
    return pc_errf(e, PC_EINVAL, "%s: the image is black", what);
  for (int y = 1; y <= h; y++) l->env_row_cdf[y] = (float)(l->env_row_cdf[y] / row_sum);
  l->env_row_cdf[h] = 1.f;
  l->env_norm = (float)(1.0 / (row_sum * (2.0 * PC_PI / w) * (PC_PI / h)));
  /* Mean radiance over the sphere, as for `constant`. */
  double mean = row_sum * (2.0 * PC_PI / w) * (PC_PI / h) / (4.0 * PC_PI);
  l->power = (float)(PC_PI * area * mean * l->env_scale * v3_luminance(l->radiance));
  return PC_OK;
}

void pc_env_free(pc_light *l) {
  pc_image_free(&l->env_img);
  free(l->env_row_cdf);
  free(l->env_col_cdf);
  l->env_row_cdf = l->env_col_cdf = NULL;
}

/* Lat-long coordinates (u in [0,1), v in [0,1]) of world direction d. */
static void latlong(const pc_light *l, vec3 d, float *u, float *v) {
  vec3 q = frame_to_local(&l->env_frame, d);
  float len = v3_len(q);
  float cy = len > 0.f ? q.y / len : 1.f;
  float uu = atan2f(q.x, -q.z) * (0.5f * PC_INV_PI);
  if (uu < 0.f) uu += 1.f;
  if (!(uu < 1.f)) uu = 0.f; /* -0 + 1 rounding, NaN */
  *u = uu;
  *v = acosf(fminf(1.f, fmaxf(-1.f, cy))) * PC_INV_PI;
}

static vec3 texel(const pc_image *img, int x, int y) {
  x %= img->w;
  if (x < 0) x += img->w;
  y = y < 0 ? 0 : (y >= img->h ? img->h - 1 : y);
  const float *p = img->rgb + 3 * ((size_t)y * (size_t)img->w + (size_t)x);
  return v3(p[0], p[1], p[2]);
}

vec3 pc_env_le(const pc_light *l, vec3 d) {
  vec3 k = v3_scale(l->radiance, l->env_scale);
  const pc_image *img = &l->env_img;
  if (img->w == 0) return k;
  float u, v;
  latlong(l, d, &u, &v);
  /* Mitsuba's evalBilinear: texel centres at half-integers, u repeats, v clamps. */
  float fx = u * img->w - 0.5f, fy = v * img->h - 0.5f;
  float x0 = floorf(fx), y0 = floorf(fy);
  float tx = fx - x0, ty = fy - y0;
  int ix = (int)x0, iy = (int)y0;
  vec3 a = v3_add(v3_scale(texel(img, ix, iy), 1.f - tx), v3_scale(texel(img, ix + 1, iy), tx));
  vec3 b = v3_add(v3_scale(texel(img, ix, iy + 1), 1.f - tx), v3_scale(texel(img, ix + 1, iy + 1), tx));
  vec3 r = v3_mul(k, v3_add(v3_scale(a, 1.f - ty), v3_scale(b, ty)));
  return v3(fmaxf(r.x, 0.f), fmaxf(r.y, 0.f), fmaxf(r.z, 0.f));
}

vec3 pc_env_sample(const pc_light *l, float u1, float u2, float *pdf) {
  const pc_image *img = &l->env_img;
  if (img->w == 0) {
    float z = 1.f - 2.f * u1, r = sqrtf(fmaxf(0.f, 1.f - z * z)), phi = 2.f * PC_PI * u2;
    *pdf = 0.25f * PC_INV_PI;
    return v3(r * cosf(phi), r * sinf(phi), z);
  }
  int w = img->w, h = img->h;
  int y = pc_cdf_find(l->env_row_cdf, h, u1);
  float r0 = l->env_row_cdf[y], r1 = l->env_row_cdf[y + 1];
  float fy = r1 > r0 ? fminf(fmaxf((u1 - r0) / (r1 - r0), 0.f), 1.f) : 0.5f;
  const float *col = l->env_col_cdf + (size_t)y * ((size_t)w + 1);
  int x = pc_cdf_find(col, w, u2);
  float c0 = col[x], c1 = col[x + 1];
  float fx = c1 > c0 ? fminf(fmaxf((u2 - c0) / (c1 - c0), 0.f), 1.f) : 0.5f;
  float phi = 2.f * PC_PI * ((float)x + fx) / (float)w, theta = PC_PI * ((float)y + fy) / (float)h;
  float st = sinf(theta);
  vec3 q = v3(st * sinf(phi), cosf(theta), -st * cosf(phi));
  vec3 d = v3_norm(frame_to_world(&l->env_frame, q));
  /* The pdf of the direction as pc_env_pdf computes it, so both agree to the last bit. */
  *pdf = pc_env_pdf(l, d);
  return d;
}

float pc_env_pdf(const pc_light *l, vec3 d) {
  const pc_image *img = &l->env_img;
  if (img->w == 0) return 0.25f * PC_INV_PI;
  float u, v;
  latlong(l, d, &u, &v);
  int w = img->w, h = img->h;
  int x = (int)(u * w), y = (int)(v * h);
  x = x < 0 ? 0 : (x >= w ? w - 1 : x);
  y = y < 0 ? 0 : (y >= h ? h - 1 : y);
  float st = sinf(v * PC_PI);
  if (!(st > 0.f)) return 0.f;
  float row_weight = sinf(((float)y + 0.5f) * PC_PI / (float)h);
  float p = luminance_at(img, x, y) * row_weight * l->env_norm / st;
  return isfinite(p) ? p : 0.f;
}
