/* light.h: emitters (area lights on any shape, point lights), the power-proportional choice
 * among them, and every sampling routine and pdf the integrators need: sampling a point toward
 * a receiver (next-event estimation), sampling an emitted ray (light sub-paths), and the pdfs
 * of both for MIS. Area lights emit on the front side of their surface only (Mitsuba). */
#ifndef PC_LIGHT_H
#define PC_LIGHT_H

#include <stdbool.h>
#include <stdint.h>

#include "vecmath.h"

typedef enum { PC_LIGHT_AREA, PC_LIGHT_POINT } pc_light_type;

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

#endif
