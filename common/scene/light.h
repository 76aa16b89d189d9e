/* light.h: emitters (area lights on any shape, point and spot lights, Mitsuba's distant
 * `directional` light, and the environment: Mitsuba's `constant` and lat-long `envmap`, at most
 * one per scene), the power-proportional choice
 * among them, and every sampling routine and pdf the integrators need: sampling a point toward
 * a receiver (next-event estimation), sampling an emitted ray (light sub-paths), and the pdfs
 * of both for MIS. Area lights emit on the front side of their surface only (Mitsuba). */
#ifndef PC_LIGHT_H
#define PC_LIGHT_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "image.h"
#include "texture.h"
#include "vecmath.h"

/* Point and spot lights sit at one point (a delta in position): they cannot be hit and their
 * sampled point has area pdf 1; a spot only adds a directional profile (light_spot.c). A
 * directional light is a delta in direction, at infinity like the environment: it cannot be
 * hit either, and its light paths start on the environment's disk. */
typedef enum { PC_LIGHT_AREA, PC_LIGHT_POINT, PC_LIGHT_SPOT, PC_LIGHT_ENV, PC_LIGHT_DIRECTIONAL } pc_light_type;

typedef struct pc_light {
  pc_light_type type;
  vec3 radiance;      /* area: emitted radiance */
  vec3 intensity;     /* point, spot: radiant intensity (a spot's, at the centre of its beam) */
  vec3 position;      /* point, spot */
  vec3 irradiance;    /* directional: power per unit area across its direction (Mitsuba's) */
  vec3 direction;     /* directional: the unit direction its light travels */
  int shape;          /* area: index of its shape in the scene */
  /* area: triangles, an exact sphere or cylinder, sampled uniformly by area */
  float area;
  float *tri_cdf;     /* ntris+1 entries, area CDF over the shape's triangles */
  vec3 *tri_n;        /* ntris unit normals of its triangles (emitters do not move), bit for bit
                         what sampling a point would compute: its cross product and division
                         were 1-3% of a BDPT profile */
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
  /* spot (Mitsuba's `spot`): shines along spot_frame.n (its local +z); full intensity within
   * beam_width of the axis, falling linearly in angle to 0 at cutoff (radians, beam <= cutoff);
   * an optional texture (owned) projected over the cone's tangent plane. */
  frame spot_frame;
  float cutoff, beam_width, cos_cutoff, cos_beam;
  pc_texture *spot_tex;
} pc_light;

static inline bool pc_light_is_delta_pos(const pc_light *l) {
  return l->type == PC_LIGHT_POINT || l->type == PC_LIGHT_SPOT;
}

/* Whether no eye path can reach the light by scattering: only connections sample it. */
static inline bool pc_light_is_delta(const pc_light *l) {
  return pc_light_is_delta_pos(l) || l->type == PC_LIGHT_DIRECTIONAL;
}

struct pc_scene;

/* A sampled point on a light. For a point or spot light, n is zero and pdf_area is 1 (delta). */
typedef struct pc_light_point {
  vec3 p, n;
  float pdf_area;  /* area pdf of the point given this light (1 for point and spot lights) */
  float eps;       /* its ray offset (scene.h, PC_OFFSET_RELATIVE), from the primitive it lies on */
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
 * back side); point and spot lights: intensity times pc_light_profile. */
vec3 pc_light_le(const pc_light *l, vec3 n, vec3 w);
/* The directional factor of a point or spot light toward unit direction w: 1 for a point light,
 * the spot's falloff (times its texture) for a spot. */
vec3 pc_light_profile(const pc_light *l, vec3 w);
/* Emission direction for a light sub-path: cosine-weighted about n (area), uniform sphere
 * (point), uniform over the cutoff cone (spot, as Mitsuba). pdf is solid-angle. */
vec3 pc_light_sample_dir(const pc_light *l, vec3 n, float u0, float u1, float *pdf_dir);
float pc_light_pdf_dir(const pc_light *l, vec3 n, vec3 w);
/* Releases what a light owns (environment tables and image, a spot's texture). */
void pc_light_free(pc_light *l);

/* Spots (light_spot.c). Sets the derived cosines; cutoff and beam width in degrees. */
void pc_spot_set_angles(pc_light *l, float cutoff_deg, float beam_deg);
/* The falloff toward unit world direction w: 1 within the beam, (cutoff - angle) / (cutoff -
 * beam) between beam and cutoff, 0 at and beyond the cutoff; times the texture if any. */
vec3 pc_spot_falloff(const pc_light *l, vec3 w);
/* The integral over directions of the falloff without texture (steradians): the spot's flux
 * is intensity times this. */
double pc_spot_solid_angle(const pc_light *l);
/* Uniform over the cutoff cone; its pdf per unit solid angle (the same for every w). */
vec3 pc_spot_sample_dir(const pc_light *l, float u0, float u1, float *pdf);
float pc_spot_pdf_dir(const pc_light *l, vec3 w);

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
