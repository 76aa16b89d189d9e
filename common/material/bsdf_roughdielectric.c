/* bsdf_roughdielectric.c: Mitsuba 0.6's `roughdielectric` (Walter et al. 2007 with Mitsuba's
 * conventions): microfacet reflection and refraction through a rough interface, beckmann or
 * GGX (microfacet.h), the lobe chosen by the Fresnel reflectance at the sampled microfacet.
 * wo's side decides the relative index (eta = int/ext from the front, its inverse from the
 * back). Radiance transport scales refraction by 1/eta^2 of wo's side (the solid-angle
 * compression); importance transport does not, so f_radiance(wo, wi) = f_importance(wi, wo).
 * Sampled normals that face away from wo are rejected, so pdf is the density of the samples
 * the sampler returns. */
#include "bsdf_lobes.h"
#include "fresnel.h"
#include "microfacet.h"

/* The half vector of (wo, wi), on the front side, with eta of wo's side; false if none. A
 * refraction's half vector is computed from the outside direction whichever is wo, so that
 * (wo, wi) and (wi, wo) get the same one to the last bit. */
static bool half_vector(const pc_material *m, vec3 wo, vec3 wi, bool *reflect, float *eta, vec3 *h) {
  *reflect = wo.z * wi.z > 0.f;
  *eta = wo.z > 0.f ? pc_rel_eta(m) : 1.f / pc_rel_eta(m);
  vec3 out = wo.z > 0.f ? wo : wi, in = wo.z > 0.f ? wi : wo;
  vec3 v = *reflect ? v3_add(wo, wi) : v3_add(out, v3_scale(in, pc_rel_eta(m)));
  float len = v3_len(v);
  if (!(len > 0.f) || !(wo.z != 0.f && wi.z != 0.f)) return false;
  *h = v3_scale(v, (v.z < 0.f ? -1.f : 1.f) / len);
  /* The microfacet must face wo, and a refraction must cross it. */
  if (!(v3_dot(wo, *h) * wo.z > 0.f)) return false;
  return *reflect || v3_dot(wo, *h) * v3_dot(wi, *h) < 0.f;
}

/* Fresnel reflectance at the microfacet, computed so that (wo, wi) and (wi, wo) get the same
 * value to the last bit: a reflection's two cosines are equal (their mean is symmetric), a
 * refraction pair's reflectance is the same from both sides (taken from the outside one). */
static float fresnel_at(const pc_material *m, bool reflect, vec3 wo, float dot_o, float dot_i) {
  float c = reflect ? 0.5f * (dot_o + dot_i) : (wo.z > 0.f ? dot_o : dot_i);
  return pc_fresnel_dielectric(c, pc_rel_eta(m), NULL);
}

vec3 pc_roughdielectric_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  const pc_material *m = c->m;
  bool reflect;
  float eta;
  vec3 h;
  if (!half_vector(m, wo, wi, &reflect, &eta, &h)) return v3s(0.f);
  pc_microfacet mf = pc_mf_make_aniso(m->distribution, m->alpha, m->alpha_v);
  float d = pc_mf_d(&mf, h);
  if (d == 0.f) return v3s(0.f);
  float g = pc_mf_g1(&mf, wo, h) * pc_mf_g1(&mf, wi, h);
  float dot_o = v3_dot(wo, h), dot_i = v3_dot(wi, h);
  float f = fresnel_at(m, reflect, wo, dot_o, dot_i);
  if (reflect) return v3_scale(pc_tex(c, &m->specular), f * d * g / (4.f * fabsf(wo.z * wi.z)));
  float denom = dot_o + eta * dot_i;
  float t = (1.f - f) * d * g * eta * eta * fabsf(dot_o * dot_i) / fabsf(wo.z * wi.z * denom * denom);
  if (c->mode == PC_RADIANCE) t /= eta * eta;
  return v3_scale(pc_tex(c, &m->transmittance), t);
}

float pc_roughdielectric_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  const pc_material *m = c->m;
  bool reflect;
  float eta;
  vec3 h;
  if (!half_vector(m, wo, wi, &reflect, &eta, &h)) return 0.f;
  pc_microfacet mf = pc_mf_make_aniso(m->distribution, m->alpha, m->alpha_v);
  vec3 v = wo.z > 0.f ? wo : v3_neg(wo);
  float dot_o = v3_dot(wo, h), dot_i = v3_dot(wi, h);
  float f = fresnel_at(m, reflect, wo, dot_o, dot_i);
  /* Jacobian of the map from the microfacet normal to wi. */
  float dwh;
  if (reflect) {
    dwh = 1.f / (4.f * fabsf(dot_i));
  } else {
    float denom = dot_o + eta * dot_i;
    dwh = eta * eta * fabsf(dot_i) / (denom * denom);
  }
  return pc_mf_pdf(&mf, v, h) * (reflect ? f : 1.f - f) * dwh;
}

bool pc_roughdielectric_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  const pc_material *m = c->m;
  if (!(wo.z != 0.f)) return false;
  pc_microfacet mf = pc_mf_make_aniso(m->distribution, m->alpha, m->alpha_v);
  vec3 v = wo.z > 0.f ? wo : v3_neg(wo);
  vec3 h = pc_mf_sample(&mf, v, u1, u2);
  float dot_o = v3_dot(wo, h);
  if (!(dot_o * wo.z > 0.f)) return false;
  float cos_t, eta = pc_rel_eta(m);
  float f = pc_fresnel_dielectric(dot_o, eta, &cos_t);
  s->is_delta = false;
  if (u0 < f) {
    s->wi = v3_sub(v3_scale(h, 2.f * dot_o), wo);
    return s->wi.z * wo.z > 0.f;
  }
  if (cos_t == 0.f) return false;
  float scale = cos_t < 0.f ? 1.f / eta : eta; /* n_o / n_i across the microfacet */
  s->wi = v3_sub(v3_scale(h, dot_o * scale + cos_t), v3_scale(wo, scale));
  return s->wi.z * wo.z < 0.f;
}
