/* camera.c: the perspective and thin-lens sensors (Mitsuba conventions, see camera.h). */
#include "camera.h"

void pc_camera_prepare(pc_camera *c) {
  const mat4 *m = &c->to_world;
  vec3 left = v3_norm(v3((float)m->m[0][0], (float)m->m[1][0], (float)m->m[2][0]));
  c->up = v3_norm(v3((float)m->m[0][1], (float)m->m[1][1], (float)m->m[2][1]));
  c->dir = v3_norm(v3((float)m->m[0][2], (float)m->m[1][2], (float)m->m[2][2]));
  c->pos = v3((float)m->m[0][3], (float)m->m[1][3], (float)m->m[2][3]);
  c->right = v3_neg(left);
  float w = (float)c->width, h = (float)c->height;
  float t = tanf(0.5f * c->fov_deg * PC_PI / 180.f);
  char axis = c->fov_axis;
  if (axis == 's') axis = w <= h ? 'x' : 'y';
  if (axis == 'l') axis = w >= h ? 'x' : 'y';
  if (axis == 'y') {
    c->tan_half_y = t;
    c->tan_half_x = t * w / h;
  } else if (axis == 'd') {
    float diag = sqrtf(w * w + h * h);
    c->tan_half_x = t * w / diag;
    c->tan_half_y = t * h / diag;
  } else {
    c->tan_half_x = t;
    c->tan_half_y = t * h / w;
  }
  c->image_area = 4.f * c->tan_half_x * c->tan_half_y;
  float skew = pc_maxf(fabsf(v3_dot(c->right, c->up)), pc_maxf(fabsf(v3_dot(c->right, c->dir)), fabsf(v3_dot(c->up, c->dir))));
  if (skew < 1e-6f) {
    c->inv_right = c->right, c->inv_up = c->up, c->inv_dir = c->dir;
    c->inv_det = 1.f;
    return;
  }
  /* a near-rigid matrix of a published scene, used as Mitsuba uses it (not squared up): the
     raster position of a direction inverts the ray of that position exactly, so every strategy
     sees the same image */
  vec3 a = v3_cross(c->up, c->dir), b = v3_cross(c->dir, c->right), n = v3_cross(c->right, c->up);
  float det = v3_dot(c->right, a);
  c->inv_right = v3_scale(a, 1.f / det);
  c->inv_up = v3_scale(b, 1.f / det);
  c->inv_dir = v3_scale(n, 1.f / det);
  c->inv_det = 1.f / fabsf(det);
}

vec3 pc_camera_ray_dir(const pc_camera *c, float px, float py) {
  float x = (2.f * px / (float)c->width - 1.f) * c->tan_half_x;
  float y = (1.f - 2.f * py / (float)c->height) * c->tan_half_y;
  return v3_norm(v3_add(c->dir, v3_add(v3_scale(c->right, x), v3_scale(c->up, y))));
}

bool pc_camera_raster(const pc_camera *c, vec3 dir, float *px, float *py) {
  float cz = v3_dot(dir, c->inv_dir);
  if (!(cz > 0.f)) return false;
  float x = v3_dot(dir, c->inv_right) / cz / c->tan_half_x;
  float y = v3_dot(dir, c->inv_up) / cz / c->tan_half_y;
  float rx = (x + 1.f) * 0.5f * (float)c->width;
  float ry = (1.f - y) * 0.5f * (float)c->height;
  if (!(rx >= 0.f && rx < (float)c->width && ry >= 0.f && ry < (float)c->height)) return false;
  *px = rx;
  *py = ry;
  return true;
}

float pc_camera_we(const pc_camera *c, vec3 dir) {
  float px, py;
  if (!pc_camera_raster(c, dir, &px, &py)) return 0.f;
  float k = v3_dot(dir, c->inv_dir), cz = v3_dot(dir, c->dir);
  return c->inv_det / (c->image_area * k * k * k * cz);
}

float pc_camera_pdf_dir(const pc_camera *c, vec3 dir) {
  float px, py;
  if (!pc_camera_raster(c, dir, &px, &py)) return 0.f;
  return pc_camera_dir_pdf(c, dir);
}

vec3 pc_camera_lens_point(const pc_camera *c, float u1, float u2) {
  if (!(c->aperture_radius > 0.f)) return c->pos;
  vec2 d = pc_sample_concentric_disk(u1, u2);
  float r = c->aperture_radius;
  return v3_add(c->pos, v3_add(v3_scale(c->right, r * d.x), v3_scale(c->up, r * d.y)));
}

vec3 pc_camera_lens_dir(const pc_camera *c, vec3 lens, float px, float py) {
  vec3 d = pc_camera_ray_dir(c, px, py);
  if (!(c->aperture_radius > 0.f)) return d;
  vec3 focus = v3_madd(c->pos, d, c->focus_distance / v3_dot(d, c->inv_dir));
  return v3_norm(v3_sub(focus, lens));
}

bool pc_camera_raster_from(const pc_camera *c, vec3 lens, vec3 dir, float *px, float *py) {
  if (!(c->aperture_radius > 0.f)) return pc_camera_raster(c, dir, px, py);
  float cz = v3_dot(dir, c->inv_dir);
  if (!(cz > 0.f)) return false;
  /* the lens lies in the plane of right and up through pos: the ray meets the plane in focus at
   * depth focus_distance (in the frame's own coordinates), where the pinhole ray of the same
   * pixel meets it too */
  vec3 focus = v3_madd(lens, dir, c->focus_distance / cz);
  return pc_camera_raster(c, v3_sub(focus, c->pos), px, py);
}

vec3 pc_camera_sample_ray(const pc_camera *c, float px, float py, pc_rng *rng, vec3 *dir) {
  vec3 o = c->pos;
  if (c->aperture_radius > 0.f) {
    float u1 = pc_rng_f(rng), u2 = pc_rng_f(rng);
    o = pc_camera_lens_point(c, u1, u2);
  }
  *dir = pc_camera_lens_dir(c, o, px, py);
  return o;
}

float pc_camera_pixel_point(const pc_camera *c, int x, int y, float u0, float u1, float *px, float *py) {
  if (pc_rfilter_is_pixel(&c->filter)) {
    *px = (float)x + u0;
    *py = (float)y + u1;
    return 1.f;
  }
  float pdf_x, pdf_y;
  *px = pc_rfilter_sample(&c->filter, (float)x + 0.5f, (float)c->width, u0, &pdf_x);
  *py = pc_rfilter_sample(&c->filter, (float)y + 0.5f, (float)c->height, u1, &pdf_y);
  return pdf_x * pdf_y;
}

/* The pixels of one axis whose filter reaches p, and their weights at p. */
static int footprint_1d(const pc_rfilter *f, float p, int extent, int *first, float *w) {
  /* from the first centre past p - radius to the last before p + radius (one more is 0) */
  float from = p - 0.5f - f->radius, to = p - 0.5f + f->radius;
  int lo = from > 0.f ? (int)from : 0, hi = to > 0.f ? (int)to + 1 : 0;
  if (hi > extent - 1) hi = extent - 1;
  if (hi - lo + 1 > PC_CAMERA_FOOTPRINT_MAX) hi = lo + PC_CAMERA_FOOTPRINT_MAX - 1;
  int n = 0;
  for (int i = lo; i <= hi; i++) {
    float centre = (float)i + 0.5f;
    float v = pc_rfilter_value(f, p - centre);
    w[n++] = v > 0.f ? v / pc_rfilter_mass(f, centre, (float)extent) : 0.f;
  }
  *first = lo;
  return n;
}

void pc_camera_footprint(const pc_camera *c, float px, float py, int *x0, int *nx, float wx[PC_CAMERA_FOOTPRINT_MAX], int *y0,
                         int *ny, float wy[PC_CAMERA_FOOTPRINT_MAX]) {
  *nx = footprint_1d(&c->filter, px, c->width, x0, wx);
  *ny = footprint_1d(&c->filter, py, c->height, y0, wy);
}
