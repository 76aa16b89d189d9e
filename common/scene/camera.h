/* camera.h: Mitsuba's `perspective` (pinhole) and `thinlens` sensors: ray generation, the
 * importance function We and its pdfs, and the t=1 connection (sampling the camera from a scene
 * point) that light tracing needs. A thin lens is a pinhole whose rays leave a uniformly sampled
 * point of a disk toward the point of the plane in focus the pinhole ray would reach; the
 * direction pdf from a lens point is then the pinhole's, and the lens area cancels between We
 * and the lens pdf, so every method treats both alike but for the lens point. Camera space follows Mitsuba: +z forward, +y up, +x to the LEFT of the image
 * (so toWorld from <lookat> renders unmirrored). */
#ifndef PC_CAMERA_H
#define PC_CAMERA_H

#include <stdbool.h>

#include "rfilter.h"
#include "rng.h"
#include "vecmath.h"

typedef struct pc_camera {
  mat4 to_world;       /* camera to world: rigid, or (a still sensor) as near rigid as Mitsuba accepts */
  vec3 pos, dir, right, up; /* derived: world position, forward, image-right, image-up (unit; at
                               most 1e-3 off orthogonal for a near-rigid still sensor) */
  int width, height;
  float fov_deg;       /* along fov_axis */
  char fov_axis;       /* 'x', 'y', 'd' (diagonal), 's' (smaller), 'l' (larger) */
  float aperture_radius; /* thinlens: world-space lens radius; 0 for the pinhole */
  float focus_distance;  /* thinlens: distance along dir of the plane in focus */
  /* Mitsuba's clip range along dir (nearClip, farClip): pcbpt does not clip, and the probe of
   * pc_scene_probe_backs counts what the camera sees outside it */
  float near_clip, far_clip;
  pc_rfilter filter; /* the film's reconstruction filter: a pixel's measurement (rfilter.h) */
  /* derived by pc_camera_prepare */
  float tan_half_x, tan_half_y; /* half extents of the image plane at distance 1 */
  float image_area;             /* area of the image plane at distance 1 */
  /* The rows of the inverse of the frame (right | up | dir), which take a world direction to its
   * image-plane coordinates, and 1 / |its determinant|; (right, up, dir) and 1 where the frame is
   * orthonormal, so that a rigid camera computes exactly what a transpose does. */
  vec3 inv_right, inv_up, inv_dir;
  float inv_det;
} pc_camera;

void pc_camera_prepare(pc_camera *c);

/* Primary ray through raster position (px, py) in [0,W)x[0,H), (0,0) the top-left corner. */
vec3 pc_camera_ray_dir(const pc_camera *c, float px, float py);

/* A point of the lens from a uniform sample of [0,1)^2 (the pinhole: pos). */
vec3 pc_camera_lens_point(const pc_camera *c, float u1, float u2);
/* The direction of the ray from lens point `lens` through raster position (px, py) (the
 * pinhole: pc_camera_ray_dir). */
vec3 pc_camera_lens_dir(const pc_camera *c, vec3 lens, float px, float py);
/* The primary ray through raster position (px, py): returns its origin and sets *dir. A thin
 * lens draws its lens point from rng; the pinhole draws nothing. */
vec3 pc_camera_sample_ray(const pc_camera *c, float px, float py, pc_rng *rng, vec3 *dir);
/* Raster position of direction dir leaving lens point `lens` (the pinhole: pc_camera_raster). */
bool pc_camera_raster_from(const pc_camera *c, vec3 lens, vec3 dir, float *px, float *py);
/* Raster position of a world direction from the camera; false if outside the image or behind. */
bool pc_camera_raster(const pc_camera *c, vec3 dir, float *px, float *py);

/* The raster point of pixel (x, y)'s eye sample from u0, u1 in [0, 1), drawn from the pixel's
 * filter weight; returns that weight there (its raster-area pdf: 1 for the pixel box, whose
 * point is (x + u0, y + u1)). The eye strategies' camera pdf, pc_camera_dir_pdf's, is per pixel
 * and scales by it. */
float pc_camera_pixel_point(const pc_camera *c, int x, int y, float u0, float u1, float *px, float *py);

/* The pixels a light-tracing splat at raster point (px, py) reaches under a filter that is not
 * the pixel box: columns *x0 .. *x0 + *nx - 1 and rows *y0 .. *y0 + *ny - 1 with the 1-D weights
 * wx and wy (pixel (x, y)'s weight at the point is wx * wy, 0 for some). */
#define PC_CAMERA_FOOTPRINT_MAX ((int)(2.f * PC_RFILTER_MAX_RADIUS) + 2)
void pc_camera_footprint(const pc_camera *c, float px, float py, int *x0, int *nx, float wx[PC_CAMERA_FOOTPRINT_MAX], int *y0,
                         int *ny, float wy[PC_CAMERA_FOOTPRINT_MAX]);

/* Importance We(dir) for a world direction leaving the camera, normalised so that
 * integrating We * cos over the image solid angle gives 1 per pixel-count unit:
 * We = 1 / (A * cos^4) with A the image-plane area at distance 1 (0 outside the image); in
 * general the direction pdf over cos, cos = dot(dir, c->dir) being the cosine the connections
 * use. */
float pc_camera_we(const pc_camera *c, vec3 dir);
/* Solid-angle pdf of generating `dir` by uniform raster sampling: 1 / (A cos^3). */
float pc_camera_pdf_dir(const pc_camera *c, vec3 dir);
/* The same for a direction known to lie in the image: 1 / (A cos^3) with cos the direction's
 * depth along dir, and for a sheared frame 1 / (A |det| k^3), k its depth in the frame's own
 * coordinates (the solid angle of image-plane area dA at direction w is |det| k^3 dA). */
static inline float pc_camera_dir_pdf(const pc_camera *c, vec3 dir) {
  float k = v3_dot(dir, c->inv_dir);
  return c->inv_det / (c->image_area * k * k * k);
}

#endif
