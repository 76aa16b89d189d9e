/* bsdf_conductor.c: Mitsuba's `conductor` (smooth mirror, delta lobe) and `roughconductor`
 * (beckmann or GGX, microfacet.h). Shadowing is Mitsuba 0.6's separable Smith form
 * G = G1(wo, m) G1(wi, m); Fresnel is the exact conductor formula per RGB channel, times
 * specularReflectance. */
#include "bsdf_lobes.h"
#include "fresnel.h"
#include "microfacet.h"

bool pc_conductor_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  (void)u0;
  (void)u1;
  (void)u2;
  if (!(wo.z > 0.f)) return false;
  const pc_material *m = c->m;
  vec3 fr = pc_fresnel_conductor(wo.z, m->eta, m->k);
  s->wi = v3(-wo.x, -wo.y, wo.z);
  s->is_delta = true;
  s->pdf = s->pdf_rev = 1.f;
  s->f_cos = v3_mul(pc_tex(c, &m->specular), fr);
  return true;
}

/* The value for the half vector h of (wo, wi), given D(h) > 0 and the masking g. */
static vec3 value(const pc_lobe_ctx *c, vec3 wo, vec3 wi, vec3 h, float d, float g) {
  const pc_material *m = c->m;
  vec3 fr = pc_fresnel_conductor(v3_dot(wo, h), m->eta, m->k);
  return v3_scale(v3_mul(pc_tex(c, &m->specular), fr), d * g / (4.f * wo.z * wi.z));
}

/* The pdf of sampling wi from wo through h (Jacobian of the reflection map h -> wi), from D(h)
 * and G1(wo, h). */
static float pdf_of(const pc_microfacet *mf, vec3 wo, vec3 h, float d, float g1) {
  float dot = v3_dot(wo, h);
  return dot > 0.f ? pc_mf_pdf_of(mf, wo, h, d, g1) / (4.f * dot) : 0.f;
}

vec3 pc_roughconductor_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  const pc_material *m = c->m;
  pc_microfacet mf = pc_mf_make_aniso(m->distribution, m->alpha, m->alpha_v);
  vec3 h = v3_norm(v3_add(wo, wi));
  float d = pc_mf_d(&mf, h);
  if (d == 0.f) return v3s(0.f);
  return value(c, wo, wi, h, d, pc_mf_g1(&mf, wo, h) * pc_mf_g1(&mf, wi, h));
}

float pc_roughconductor_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return 0.f;
  pc_microfacet mf = pc_mf_make_aniso(c->m->distribution, c->m->alpha, c->m->alpha_v);
  vec3 h = v3_norm(v3_add(wo, wi));
  if (!(v3_dot(wo, h) > 0.f)) return 0.f; /* (pdf_of's own test, before D and G1 are taken) */
  return pdf_of(&mf, wo, h, pc_mf_d(&mf, h), pc_mf_g1(&mf, wo, h));
}

vec3 pc_roughconductor_eval_pdfs(const pc_lobe_ctx *c, vec3 wo, vec3 wi, float *pdf, float *pdf_rev) {
  *pdf = *pdf_rev = 0.f;
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  const pc_material *m = c->m;
  pc_microfacet mf = pc_mf_make_aniso(m->distribution, m->alpha, m->alpha_v);
  vec3 h = v3_norm(v3_add(wo, wi)); /* (wi, wo)'s too: the sum is the same either way round */
  float d = pc_mf_d(&mf, h), go = pc_mf_g1(&mf, wo, h), gi = pc_mf_g1(&mf, wi, h);
  *pdf = pdf_of(&mf, wo, h, d, go);
  *pdf_rev = pdf_of(&mf, wi, h, d, gi);
  return d == 0.f ? v3s(0.f) : value(c, wo, wi, h, d, go * gi);
}

bool pc_roughconductor_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  (void)u0;
  if (!(wo.z > 0.f)) return false;
  pc_microfacet mf = pc_mf_make_aniso(c->m->distribution, c->m->alpha, c->m->alpha_v);
  vec3 h = pc_mf_sample(&mf, wo, u1, u2);
  s->wi = v3_sub(v3_scale(h, 2.f * v3_dot(wo, h)), wo);
  s->is_delta = false;
  return s->wi.z > 0.f;
}
