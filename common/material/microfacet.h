/* microfacet.h: the isotropic GGX microfacet distribution in a local frame (normal = +z):
 * D, Smith's masking G1 (Mitsuba 0.6's form, with its back-facing check) and Heitz's 2018
 * sampling of the distribution of visible normals. */
#ifndef PC_MICROFACET_H
#define PC_MICROFACET_H

#include "vecmath.h"

/* Mitsuba clamps roughness to this so that D stays finite. */
#define PC_GGX_MIN_ALPHA 1e-4f

static inline float pc_ggx_alpha(float alpha) {
  return alpha > PC_GGX_MIN_ALPHA ? alpha : PC_GGX_MIN_ALPHA;
}

/* Normal distribution D(m); 0 for m below the horizon. */
float pc_ggx_d(float alpha, vec3 m);
/* Smith masking of direction v for microfacet normal m; 0 when v sees m's back. */
float pc_ggx_g1(float alpha, vec3 v, vec3 m);
/* A microfacet normal distributed as the normals visible from v (v.z > 0):
 * D_v(m) = G1(v, m) max(0, v.m) D(m) / v.z. */
vec3 pc_ggx_sample_visible(float alpha, vec3 v, float u1, float u2);
/* Density of pc_ggx_sample_visible with respect to the solid angle of m. */
float pc_ggx_pdf_visible(float alpha, vec3 v, vec3 m);

#endif
