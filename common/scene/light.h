/* light.h: emitters (area lights on any shape, point lights, and the environment: Mitsuba's
 * `constant` and lat-long `envmap`, at most one per scene), the power-proportional choice
 * among them, and every sampling routine and pdf the integrators need: sampling a point toward
 * a receiver (next-event estimation), sampling an emitted ray (light sub-paths), and the pdfs
 * of both for MIS. Area lights emit on the front side of their surface only (Mitsuba). */
#ifndef PC_LIGHT_H
#define PC_LIGHT_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "image.h"
#include "vecmath.h"

typedef enum { PC_LIGHT_AREA, PC_LIGHT_POINT, PC_LIGHT_ENV } pc_light_type;

typedef struct pc_light {
  pc_light_type type;
  vec3 radiance;      /* area: emitted radiance */
  vec3 intensity;     /* point: radiant intensity */
  vec3 position;      /* point */
  int shape;          /* area: index of its shape in the scene */
  /* area: triangles or an exact sphere, sampled uniformly by area */
  float area;
  float *tri_cdf;     /* ntris+1 entries, area CDF over the shape's triangles */
  uint32_t ntris;
  float power;        /* luminance of emitted flux, for light selection */
  /* env: radiance arriving from direction d (pointing away from the scene) is
   * radiance * scale * image(lat-long of d in env_frame); no image for `constant`. */
  pc_image env_img;
  float env_scale;
  frame env_frame;    /* the emitter's toWorld rotation: its local x, y, z axes in world space */
  float *env_row_cdf; /* h+1: rows by luminance times sin(theta) (Mitsuba's envmap tables) */
  float *env_col_cdf; /* h*(w+1): columns by luminance within each row */
  float env_norm;     /* pdf of pixel (x,y) per unit solid angle times sin(theta): lum * row weight * norm */
  float sampling_weight; /* Mitsuba's samplingWeight: scales power in the choice (0 is read as 1) */
} pc_light;

struct pc_scene;

/* A sampled point on a light. For a point light, n is zero and pdf_area is 1 (delta). */
typedef struct pc_light_point {
  vec3 p, n;
  float pdf_area;  /* area pdf of the point given this light (1 for point lights) */
  int shape, prim; /* the shape and primitive the point lies on (area lights) */
} pc_light_point;

/* Chooses a light proportionally to power; returns its index and sets *pdf. */
int pc_light_choose(const struct pc_scene *s, float u, float *pdf);
/* In a cumulative table cdf[0..n] (cdf[0] = 0): the smallest i with cdf[i+1] > u, so
 * zero-width entries are never chosen; u at or past the total (float rounding) falls back to
 * the last entry of non-zero width. */
int pc_cdf_find(const float *cdf, int n, float u);
float pc_light_choose_pdf(const struct pc_scene *s, int light);

/* Uniform point on the light by area. */
void pc_light_sample_point(const struct pc_scene *s, const pc_light *l, float u0, float u1, float u2,
                           pc_light_point *out);
/* Radiance emitted from a point of an area light with normal n toward direction w (zero on the
 * back side); point lights: intensity. */
vec3 pc_light_le(const pc_light *l, vec3 n, vec3 w);
/* Emission direction for a light sub-path: cosine-weighted about n (area), uniform sphere
 * (point). pdf is solid-angle. */
vec3 pc_light_sample_dir(const pc_light *l, vec3 n, float u0, float u1, float *pdf_dir);
float pc_light_pdf_dir(const pc_light *l, vec3 n, vec3 w);

/* The environment (light_env.c). Directions d point from the scene toward the environment;
 * light arriving from d travels along -d. Builds the sampling tables (envmap) and the power
 * for a scene of bounding radius `radius`; "what" names the emitter in messages. */
int pc_env_prepare(pc_light *l, float radius, const char *what, pc_err *e);
void pc_env_free(pc_light *l);
vec3 pc_env_le(const pc_light *l, vec3 d);
/* Samples d by the luminance of the environment (uniformly over the sphere for `constant`);
 * pdf per unit solid angle. */
vec3 pc_env_sample(const pc_light *l, float u1, float u2, float *pdf);
float pc_env_pdf(const pc_light *l, vec3 d);

#endif
