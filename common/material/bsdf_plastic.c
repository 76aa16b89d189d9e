/* bsdf_plastic.c: Mitsuba's `plastic` (delta specular coating over a diffuse base with internal
 * scattering) and `roughplastic` (beckmann or GGX coating; the diffuse base is attenuated by the rough
 * interface's transmittance, tabulated here in pc_plastic_prepare instead of Mitsuba's shipped
 * data files). Lobe selection follows Mitsuba: the Fresnel (or rough) reflectance toward wo,
 * reweighted by spec_sampling_weight. */
#include <stddef.h>

#include "bsdf_lobes.h"
#include "fresnel.h"
#include "microfacet.h"

/* The diffuse base with its internal multiple reflections summed (Mitsuba's `nonlinear` keeps
 * the per-channel geometric series; otherwise the linear approximation). */
static vec3 base_albedo(const pc_lobe_ctx *c, float fdr) {
  vec3 d = pc_tex(c, &c->m->reflectance);
  if (c->m->nonlinear)
    return v3(d.x / fmaxf(1.f - d.x * fdr, 1e-6f), d.y / fmaxf(1.f - d.y * fdr, 1e-6f),
              d.z / fmaxf(1.f - d.z * fdr, 1e-6f));
  return v3_scale(d, 1.f / fmaxf(1.f - fdr, 1e-6f));
}

vec3 pc_plastic_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  float eta = pc_rel_eta(c->m);
  float fi = pc_fresnel_dielectric(wo.z, eta, NULL), fo = pc_fresnel_dielectric(wi.z, eta, NULL);
  return v3_scale(base_albedo(c, c->m->fdr_int), (1.f - fi) * (1.f - fo) * PC_INV_PI / (eta * eta));
}

float pc_plastic_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return 0.f;
  float ps = pc_spec_prob(c->m, pc_fresnel_dielectric(wo.z, pc_rel_eta(c->m), NULL));
  return (1.f - ps) * wi.z * PC_INV_PI;
}

bool pc_plastic_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  if (!(wo.z > 0.f)) return false;
  float eta = pc_rel_eta(c->m);
  float fi = pc_fresnel_dielectric(wo.z, eta, NULL);
  float ps = pc_spec_prob(c->m, fi);
  if (u0 < ps) {
    s->wi = v3(-wo.x, -wo.y, wo.z);
    s->is_delta = true;
    s->pdf = ps;
    s->pdf_rev = pc_spec_prob(c->m, pc_fresnel_dielectric(s->wi.z, eta, NULL));
    s->f_cos = v3_scale(pc_tex(c, &c->m->specular), fi);
    return true;
  }
  s->wi = pc_sample_cosine_hemisphere(u1, u2);
  s->is_delta = false;
  return s->wi.z > 0.f;
}

/* Table node i holds cos theta = (i / (N - 1))^2: denser toward grazing, where the
 * transmittance changes fastest. */
static float table_cos(int i) {
  float t = (float)i / (PC_PLASTIC_TABLE - 1);
  return t * t;
}

/* Linear interpolation in the table of rough transmittance vs cos theta. */
float pc_rough_trans_in(const pc_material *m, float cos_theta) {
  float x = sqrtf(fminf(fmaxf(cos_theta, 0.f), 1.f)) * (PC_PLASTIC_TABLE - 1);
  int i = (int)x;
  if (i >= PC_PLASTIC_TABLE - 1) return m->rough_trans_in[PC_PLASTIC_TABLE - 1];
  float t = x - (float)i;
  return (1.f - t) * m->rough_trans_in[i] + t * m->rough_trans_in[i + 1];
}

/* The value for the half vector h of (wo, wi), from D(h), the masking g (read only where D > 0)
 * and the transmittances t_o, t_i into the base along wo and wi. */
static vec3 rough_value(const pc_lobe_ctx *c, vec3 wo, vec3 wi, vec3 h, float d, float g, float t_o, float t_i) {
  const pc_material *m = c->m;
  float eta = pc_rel_eta(m), spec = 0.f;
  if (d > 0.f) spec = pc_fresnel_dielectric(v3_dot(wo, h), eta, NULL) * d * g / (4.f * wo.z * wi.z);
  float diff = t_o * t_i * PC_INV_PI / (eta * eta);
  vec3 base = base_albedo(c, 1.f - m->rough_trans_avg_int);
  return v3_add(v3_scale(pc_tex(c, &m->specular), spec), v3_scale(base, diff));
}

/* The pdf of sampling wi from wo (coating or base, by the coating's reflectance 1 - t_o), from
 * D(h) and G1(wo, h). */
static float rough_pdf(const pc_material *m, const pc_microfacet *mf, vec3 wo, vec3 wi, vec3 h, float d, float g1,
                       float t_o) {
  float ps = pc_spec_prob(m, 1.f - t_o);
  float dot = v3_dot(wo, h), spec = 0.f;
  if (dot > 0.f) spec = pc_mf_pdf_of(mf, wo, h, d, g1) / (4.f * dot);
  return ps * spec + (1.f - ps) * wi.z * PC_INV_PI;
}

vec3 pc_roughplastic_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  const pc_material *m = c->m;
  pc_microfacet mf = pc_mf_make(m->distribution, m->alpha);
  vec3 h = v3_norm(v3_add(wo, wi));
  float d = pc_mf_d(&mf, h), g = d > 0.f ? pc_mf_g1(&mf, wo, h) * pc_mf_g1(&mf, wi, h) : 0.f;
  return rough_value(c, wo, wi, h, d, g, pc_rough_trans_in(m, wo.z), pc_rough_trans_in(m, wi.z));
}

float pc_roughplastic_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return 0.f;
  const pc_material *m = c->m;
  pc_microfacet mf = pc_mf_make(m->distribution, m->alpha);
  vec3 h = v3_norm(v3_add(wo, wi));
  return rough_pdf(m, &mf, wo, wi, h, pc_mf_d(&mf, h), pc_mf_g1(&mf, wo, h), pc_rough_trans_in(m, wo.z));
}

vec3 pc_roughplastic_eval_pdfs(const pc_lobe_ctx *c, vec3 wo, vec3 wi, float *pdf, float *pdf_rev) {
  *pdf = *pdf_rev = 0.f;
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  const pc_material *m = c->m;
  pc_microfacet mf = pc_mf_make(m->distribution, m->alpha);
  vec3 h = v3_norm(v3_add(wo, wi)); /* (wi, wo)'s too: the sum is the same either way round */
  float d = pc_mf_d(&mf, h), go = pc_mf_g1(&mf, wo, h), gi = pc_mf_g1(&mf, wi, h);
  float t_o = pc_rough_trans_in(m, wo.z), t_i = pc_rough_trans_in(m, wi.z);
  *pdf = rough_pdf(m, &mf, wo, wi, h, d, go, t_o);
  *pdf_rev = rough_pdf(m, &mf, wi, wo, h, d, gi, t_i);
  return rough_value(c, wo, wi, h, d, go * gi, t_o, t_i);
}

bool pc_roughplastic_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  if (!(wo.z > 0.f)) return false;
  const pc_material *m = c->m;
  if (u0 < pc_spec_prob(m, 1.f - pc_rough_trans_in(m, wo.z))) {
    pc_microfacet mf = pc_mf_make(m->distribution, m->alpha);
    vec3 h = pc_mf_sample(&mf, wo, u1, u2);
    s->wi = v3_sub(v3_scale(h, 2.f * v3_dot(wo, h)), wo);
  } else {
    s->wi = pc_sample_cosine_hemisphere(u1, u2);
  }
  s->is_delta = false;
  return s->wi.z > 0.f;
}

/* Transmittance of a rough dielectric interface (the material's distribution, separable Smith) for light arriving at
 * cos theta = mu, defined as Mitsuba's precomputed tables define it: the integral of the
 * roughdielectric transmission lobe, E[(1 - F(wo.m)) G1(wt, m)] over visible normals m with wt
 * the refracted direction. Energy lost to masking therefore counts as neither reflected nor
 * transmitted. Deterministic midpoint rule on the sampler's unit square, each normal weighted
 * by the visible-normal density over the sampler's (1 for GGX). */
#define PC_RT_GRID 24
static float rough_transmittance(const pc_microfacet *mf, float eta, float mu) {
  mu = fminf(fmaxf(mu, 1e-4f), 1.f);
  vec3 wo = v3(sqrtf(fmaxf(0.f, 1.f - mu * mu)), 0.f, mu);
  double sum = 0;
  for (int i = 0; i < PC_RT_GRID; i++)
    for (int j = 0; j < PC_RT_GRID; j++) {
      vec3 h = pc_mf_sample(mf, wo, (i + 0.5f) / PC_RT_GRID, (j + 0.5f) / PC_RT_GRID);
      float pdf = pc_mf_pdf(mf, wo, h);
      if (!(pdf > 0.f)) continue;
      float weight = mf->type == PC_MF_GGX ? 1.f : pc_mf_visible(mf, wo, h) / pdf;
      float dot = v3_dot(wo, h), cos_t;
      float fr = pc_fresnel_dielectric(dot, eta, &cos_t);
      if (fr >= 1.f) continue;
      float scale = cos_t < 0.f ? 1.f / eta : eta;
      vec3 wt = v3_sub(v3_scale(h, dot * scale + cos_t), v3_scale(wo, scale));
      if (wt.z < 0.f) sum += weight * (1.f - fr) * pc_mf_g1(mf, wt, h);
    }
  return (float)(sum / (PC_RT_GRID * PC_RT_GRID));
}

void pc_plastic_prepare(pc_material *m) {
  float eta = pc_rel_eta(m);
  m->fdr_int = pc_fresnel_diffuse_reflectance(1.f / eta);
  m->spec_sampling_weight = pc_spec_weight(m);
  if (m->type == PC_MAT_ROUGHPLASTIC) pc_rough_trans_prepare(m);
}

void pc_rough_trans_prepare(pc_material *m) {
  float eta = pc_rel_eta(m);
  pc_microfacet mf = pc_mf_make(m->distribution, m->alpha);
  for (int i = 0; i < PC_PLASTIC_TABLE; i++)
    m->rough_trans_in[i] = rough_transmittance(&mf, eta, table_cos(i));
  /* Cosine-weighted average from inside: mean of T(sqrt(x)) for x uniform in [0, 1]. */
  double avg = 0;
  for (int i = 0; i < PC_PLASTIC_TABLE; i++)
    avg += rough_transmittance(&mf, 1.f / eta, sqrtf((i + 0.5f) / PC_PLASTIC_TABLE));
  m->rough_trans_avg_int = (float)(avg / PC_PLASTIC_TABLE);
}
