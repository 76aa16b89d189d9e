/* bsdf_lobes.h (private to the bsdf_*.c files): the per-material BSDF lobes in the local
 * shading frame (normal = +z). bsdf.c does everything that is common to all of them: the world
 * to local transform, the twosided flip, the light-leak test, the adjoint shading-normal
 * correction and the final finiteness guard.
 *
 * Lobe functions see local unit directions; opaque lobes return zeros unless both are above
 * the surface. eval and pdf cover non-delta lobes only; reflection lobes are reciprocal and the
 * same in both modes, refraction (roughdielectric) differs by the eta^2 of radiance transport
 * (c->mode). */
#ifndef PC_BSDF_LOBES_H
#define PC_BSDF_LOBES_H

#include "bsdf.h"

typedef struct pc_lobe_ctx {
  const pc_material *m;
  const pc_texture *texs;
  vec2 uv;
  pc_transport mode;
} pc_lobe_ctx;

/* What a lobe sampler produces. For a non-delta sample only wi is meaningful (bsdf.c evaluates
 * f and both pdfs, so sample, eval and pdf agree exactly); for a delta sample f_cos, pdf and
 * pdf_rev are set, with f_cos / pdf the sample weight (f times |cos wi|, without the shading
 * correction; bsdf.c divides by the cosine of the final world-space wi). */
typedef struct pc_lobe_sample {
  vec3 wi;
  vec3 f_cos;
  float pdf, pdf_rev;
  bool is_delta;
} pc_lobe_sample;

static inline vec3 pc_tex(const pc_lobe_ctx *c, const pc_tex_slot *s) {
  return pc_slot_eval(s, c->texs, c->uv);
}

/* The interface's relative index int/ext (1, an invisible interface, if it is not a number). */
static inline float pc_rel_eta(const pc_material *m) {
  float eta = m->int_ior / m->ext_ior;
  return (eta > 0.f && isfinite(eta)) ? eta : 1.f;
}

/* Mitsuba's specularSamplingWeight of plastic and ward: luminance of the average specular vs
 * diffuse reflectance. A textured slot contributes its `value`, which the scene loader sets to
 * the texture's average. */
static inline float pc_spec_weight(const pc_material *m) {
  float s = v3_luminance(m->specular.value), d = v3_luminance(m->reflectance.value);
  return (s + d > 0.f && isfinite(s + d)) ? s / (s + d) : 0.5f;
}

/* Mitsuba's reallocation of the specular-lobe probability (plastic, coating): the reflectance
 * refl toward wo, reweighted by spec_sampling_weight. */
static inline float pc_spec_prob(const pc_material *m, float refl) {
  float w = m->spec_sampling_weight;
  float num = refl * w, den = num + (1.f - refl) * (1.f - w);
  return den > 0.f ? num / den : 0.f;
}

/* Cosine-weighted hemisphere (Shirley-Chiu concentric map, as Mitsuba). */
vec3 pc_sample_cosine_hemisphere(float u1, float u2);

vec3 pc_diffuse_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_diffuse_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_diffuse_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);

bool pc_conductor_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
vec3 pc_roughconductor_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_roughconductor_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
/* _eval(wo, wi) with _pdf(wo, wi) in *pdf and _pdf(wi, wo) in *pdf_rev, bit for bit, sharing the
 * half vector and the microfacet terms between the three (likewise for roughplastic). */
vec3 pc_roughconductor_eval_pdfs(const pc_lobe_ctx *c, vec3 wo, vec3 wi, float *pdf, float *pdf_rev);
bool pc_roughconductor_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);

vec3 pc_plastic_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_plastic_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_plastic_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
vec3 pc_roughplastic_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_roughplastic_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
vec3 pc_roughplastic_eval_pdfs(const pc_lobe_ctx *c, vec3 wo, vec3 wi, float *pdf, float *pdf_rev);
bool pc_roughplastic_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
void pc_plastic_prepare(pc_material *m);

bool pc_dielectric_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
bool pc_thindielectric_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
vec3 pc_roughdielectric_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_roughdielectric_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_roughdielectric_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);

/* Rough dielectric transmittance into a layer seen from outside at cos theta (the
 * roughplastic table of pc_plastic_prepare, filled for m's distribution, alpha and index). */
void pc_rough_trans_prepare(pc_material *m);
float pc_rough_trans_in(const pc_material *m, float cos_theta);

/* A wrapper's view of the material it wraps (bsdf.c): the same lobes, turned over first if the
 * wrapped material is twosided and wo is behind. Delta lobes only from sample, as above. */
vec3 pc_nested_eval(const pc_lobe_ctx *c, const pc_material *inner, vec3 wo, vec3 wi);
float pc_nested_pdf(const pc_lobe_ctx *c, const pc_material *inner, vec3 wo, vec3 wi);
bool pc_nested_sample(const pc_lobe_ctx *c, const pc_material *inner, vec3 wo, float u0, float u1, float u2,
                      pc_lobe_sample *s);

void pc_coating_prepare(pc_material *m);
vec3 pc_coating_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_coating_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_coating_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
vec3 pc_roughcoating_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_roughcoating_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_roughcoating_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);

vec3 pc_ward_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_ward_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_ward_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);

vec3 pc_phong_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_phong_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_phong_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);

vec3 pc_roughdiffuse_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);

vec3 pc_difftrans_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_difftrans_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_difftrans_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
vec3 pc_mask_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_mask_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_mask_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);
/* blendbsdf and mixturebsdf */
vec3 pc_mix_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
float pc_mix_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi);
bool pc_mix_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s);

#endif
