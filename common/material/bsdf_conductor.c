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

vec3 pc_roughconductor_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  const pc_material *m = c->m;
  pc_microfacet mf = pc_mf_make_aniso(m->distribution, m->alpha, m->alpha_v);
  vec3 h = v3_norm(v3_add(wo, wi));
  float d = pc_mf_d(&mf, h);
  if (d == 0.f) return v3s(0.f);
  float g = pc_mf_g1(&mf, wo, h) * pc_mf_g1(&mf, wi, h);
  vec3 fr = pc_fresnel_conductor(v3_dot(wo, h), m->eta, m->k);
  return v3_scale(v3_mul(pc_tex(c, &m->specular), fr), d * g / (4.f * wo.z * wi.z));
}

float pc_roughconductor_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return 0.f;
  pc_microfacet mf = pc_mf_make_aniso(c->m->distribution, c->m->alpha, c->m->alpha_v);
  vec3 h = v3_norm(v3_add(wo, wi));
  float dot = v3_dot(wo, h);
  if (!(dot > 0.f)) return 0.f;
  /* Jacobian of the reflection map h -> wi. */
  return pc_mf_pdf(&mf, wo, h) / (4.f * dot);
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
