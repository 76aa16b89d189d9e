/* microfacet.h: the microfacet distributions of Mitsuba 0.6 (beckmann, its default, ggx and phong;
 * isotropic, or anisotropic with alphaU along the frame's s and alphaV along t) in a local
 * frame (normal = +z): D, Smith's masking G1 (Mitsuba's forms, with its
 * back-facing check: the exact one for GGX, Walter's rational approximation for Beckmann), and
 * sampling of microfacet normals with its density: GGX samples the distribution of visible
 * normals (Heitz 2018), Beckmann samples D(m) cos(theta_m) (Mitsuba's sampleVisible=false
 * path; the choice changes noise, not the image). */
#ifndef PC_MICROFACET_H
#define PC_MICROFACET_H

#include "vecmath.h"

/* PC_MF_PHONG: Mitsuba's "phong" (or "as"): the Phong distribution with exponent 2/alpha^2 - 2,
 * Ashikhmin-Shirley's when anisotropic; Beckmann's masking; sampled by D(m) cos(theta_m). */
typedef enum { PC_MF_GGX = 0, PC_MF_BECKMANN = 1, PC_MF_PHONG = 2 } pc_mf_type;

/* Mitsuba clamps roughness to this so that D stays finite. */
#define PC_MF_MIN_ALPHA 1e-4f

typedef struct pc_microfacet {
  pc_mf_type type;
  float alpha;   /* alphaU: roughness along the frame's first tangent; clamped to PC_MF_MIN_ALPHA */
  float alpha_v; /* alphaV: along the second (== alpha when isotropic) */
} pc_microfacet;

/* Mitsuba's anisotropic distributions (alphaU != alphaV); alpha_v <= 0 means isotropic. */
static inline pc_microfacet pc_mf_make_aniso(pc_mf_type type, float alpha_u, float alpha_v) {
  float u = alpha_u > PC_MF_MIN_ALPHA ? alpha_u : PC_MF_MIN_ALPHA;
  float v = alpha_v > 0.f ? (alpha_v > PC_MF_MIN_ALPHA ? alpha_v : PC_MF_MIN_ALPHA) : u;
  return (pc_microfacet){type, u, v};
}
static inline pc_microfacet pc_mf_make(pc_mf_type type, float alpha) { return pc_mf_make_aniso(type, alpha, 0.f); }

/* Normal distribution D(m); 0 for m below the horizon. */
float pc_mf_d(const pc_microfacet *d, vec3 m);
/* Smith masking of direction v for microfacet normal m; 0 when v sees m's back. */
float pc_mf_g1(const pc_microfacet *d, vec3 v, vec3 m);
/* A microfacet normal for the direction v (v.z > 0), distributed with density pc_mf_pdf. */
vec3 pc_mf_sample(const pc_microfacet *d, vec3 v, float u1, float u2);
/* Density of pc_mf_sample(v) with respect to the solid angle of m. */
float pc_mf_pdf(const pc_microfacet *d, vec3 v, vec3 m);
/* The distribution of normals visible from v: G1(v, m) max(0, v.m) D(m) / v.z. */
float pc_mf_visible(const pc_microfacet *d, vec3 v, vec3 m);
/* pc_mf_pdf(d, v, m) from dm = pc_mf_d(d, m) and g1 = pc_mf_g1(d, v, m) already computed, bit for
 * bit: a query that needs both directions' pdfs and the value takes D and G1 once each. */
float pc_mf_pdf_of(const pc_microfacet *d, vec3 v, vec3 m, float dm, float g1);

#endif
