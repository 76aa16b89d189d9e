/* bsdf_coating.c: Mitsuba 0.6's `coating` and `roughcoating`: a dielectric layer (relative index
 * eta = intIOR / extIOR, absorption sigmaA over `thickness`) on top of any other material.
 *
 * The layer reflects on both sides: a delta mirror lobe with Fresnel reflectance (coating) or a
 * microfacet lobe (roughcoating, isotropic beckmann or ggx). Light it transmits is refracted
 * through the smooth interface (for roughcoating too: Mitsuba refracts with the macro normal
 * and attenuates by the rough transmittance instead), scattered once by the wrapped material
 * in the refracted directions, and refracted out:
 *   f(wo, wi) = T(wo) T(wi) A f_inner(wo', wi') / eta^2,  A = exp(-sigmaA d (1/|cos wo'| + 1/|cos wi'|))
 * T = 1 - Fresnel (coating) or the tabulated rough transmittance (roughcoating). The internal
 * reflections between the layer and what it covers are left out, as in Mitsuba (energy is lost,
 * never created). That expression is symmetric in (wo, wi) whenever f_inner is, so these
 * models are reciprocal and their importance transport is f_inner's own mode with the same
 * factors; Mitsuba's layers need no adjoint correction of their own. The lobe is chosen as
 * Mitsuba does: the layer's reflectance toward wo (Fresnel, or 1 - T for roughcoating)
 * reweighted by specularSamplingWeight = 1 / (1 + mean exp(-2 d sigmaA)). One difference from
 * Mitsuba: where roughcoating wraps a delta material, Mitsuba's sample weight leaves out the
 * probability of having chosen that lobe (its pdf() then counts only the delta); here the
 * weight divides by it, so that sampling stays unbiased. */
#include "bsdf_lobes.h"
#include "fresnel.h"
#include "microfacet.h"

void pc_coating_prepare(pc_material *m) {
  vec3 s = m->sigma_a.value; /* a texture's average (pc_scene_build), as Mitsuba's getAverage() */
  float d = m->thickness;
  float avg = (expf(-2.f * d * s.x) + expf(-2.f * d * s.y) + expf(-2.f * d * s.z)) / 3.f;
  m->spec_sampling_weight = isfinite(avg) ? 1.f / (avg + 1.f) : 0.5f;
  if (m->type == PC_MAT_ROUGHCOATING) pc_rough_trans_prepare(m);
}

/* Through the smooth interface, keeping the side: into the layer (eta) or out of it (1 / eta).
 * *r is the Fresnel reflectance (1 on total internal reflection). */
static vec3 refract_side(vec3 w, float eta, float *r) {
  float cos_t;
  *r = pc_fresnel_dielectric(fabsf(w.z), eta, &cos_t);
  float inv = 1.f / eta;
  return v3(inv * w.x, inv * w.y, w.z < 0.f ? -fabsf(cos_t) : fabsf(cos_t));
}

/* exp(-sigmaA d (1/|cos wo'| + 1/|cos wi'|)), per channel. */
static vec3 absorption(const pc_lobe_ctx *c, vec3 wo_in, vec3 wi_in) {
  vec3 s = v3_scale(pc_tex(c, &c->m->sigma_a), c->m->thickness);
  if (v3_is_zero(s)) return v3s(1.f);
  float path = 1.f / fabsf(wo_in.z) + 1.f / fabsf(wi_in.z);
  return v3(expf(-s.x * path), expf(-s.y * path), expf(-s.z * path));
}

/* The wrapped material's part, for transmittances t_o, t_i of the two crossings: the factors of
 * f (through *f) and the pdf's Jacobian from wi' to wi (through *jac); false if a crossing is
 * totally reflected. */
static bool inner_pair(const pc_lobe_ctx *c, vec3 wo, vec3 wi, vec3 *wo_in, vec3 *wi_in, float *ro, float *ri) {
  float eta = pc_rel_eta(c->m);
  *wo_in = refract_side(wo, eta, ro);
  *wi_in = refract_side(wi, eta, ri);
  return *ro < 1.f && *ri < 1.f && wo_in->z != 0.f && wi_in->z != 0.f;
}

static float jacobian(const pc_material *m, vec3 wi, vec3 wi_in) {
  float eta = pc_rel_eta(m);
  return fabsf(wi.z) / (eta * eta * fabsf(wi_in.z));
}

/* ---- coating: a smooth layer ---- */

vec3 pc_coating_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  vec3 wo_in, wi_in;
  float ro, ri;
  if (!c->m->inner || !inner_pair(c, wo, wi, &wo_in, &wi_in, &ro, &ri)) return v3s(0.f);
  float eta = pc_rel_eta(c->m);
  vec3 f = pc_nested_eval(c, c->m->inner, wo_in, wi_in);
  if (v3_is_zero(f)) return f;
  return v3_scale(v3_mul(f, absorption(c, wo_in, wi_in)), (1.f - ro) * (1.f - ri) / (eta * eta));
}

float pc_coating_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  vec3 wo_in, wi_in;
  float ro, ri;
  if (!c->m->inner || !inner_pair(c, wo, wi, &wo_in, &wi_in, &ro, &ri)) return 0.f;
  float ps = pc_spec_prob(c->m, ro);
  return (1.f - ps) * pc_nested_pdf(c, c->m->inner, wo_in, wi_in) * jacobian(c->m, wi, wi_in);
}

bool pc_coating_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  const pc_material *m = c->m;
  if (!(wo.z != 0.f) || !m->inner) return false;
  float eta = pc_rel_eta(m), ro;
  vec3 wo_in = refract_side(wo, eta, &ro);
  float ps = pc_spec_prob(m, ro);
  if (u0 < ps) {
    s->wi = v3(-wo.x, -wo.y, wo.z);
    s->is_delta = true;
    s->pdf = s->pdf_rev = ps; /* the mirror direction has the same |cos|, so the same Fresnel */
    s->f_cos = v3_scale(pc_tex(c, &m->specular), ro);
    return true;
  }
  if (ro >= 1.f) return false;
  pc_lobe_sample in = {0};
  if (!pc_nested_sample(c, m->inner, wo_in, (u0 - ps) / (1.f - ps), u1, u2, &in)) return false;
  float ri;
  vec3 wi = refract_side(in.wi, 1.f / eta, &ri);
  if (ri >= 1.f || wi.z == 0.f) return false;
  s->wi = wi;
  s->is_delta = in.is_delta;
  if (in.is_delta) {
    /* Discrete lobe probabilities: no solid-angle Jacobian; the round trip through the
     * interface leaves radiance unchanged apart from the two transmittances. */
    s->pdf = (1.f - ps) * in.pdf;
    s->pdf_rev = (1.f - pc_spec_prob(m, ri)) * in.pdf_rev; /* Fresnel is the same from both sides */
    s->f_cos = v3_scale(v3_mul(in.f_cos, absorption(c, wo_in, in.wi)), (1.f - ro) * (1.f - ri));
  }
  return true;
}

/* ---- roughcoating: a rough layer ---- */

static pc_microfacet layer_mf(const pc_material *m) { return pc_mf_make(m->distribution, m->alpha); }

/* Probability of the layer's own lobe for wo: its reflectance 1 - T(wo), reweighted. */
static float rough_spec_prob(const pc_material *m, vec3 wo) {
  return pc_spec_prob(m, 1.f - pc_rough_trans_in(m, fabsf(wo.z)));
}

/* Into the layer through the smooth interface (Mitsuba's refractTo); false on total internal
 * reflection. */
static bool refract_to(vec3 w, float inv_eta, vec3 *out) {
  float sin2 = inv_eta * inv_eta * (w.x * w.x + w.y * w.y);
  if (!(sin2 < 1.f)) return false;
  float ct = sqrtf(1.f - sin2);
  *out = v3(inv_eta * w.x, inv_eta * w.y, w.z > 0.f ? ct : -ct);
  return true;
}

/* The layer's microfacet reflection, on whichever side both directions lie (mirrored to the
 * front, where the distribution lives). */
static float rough_layer_f(const pc_material *m, vec3 wo, vec3 wi) {
  if (!(wo.z * wi.z > 0.f)) return 0.f;
  if (wo.z < 0.f) wo.z = -wo.z, wi.z = -wi.z;
  pc_microfacet mf = layer_mf(m);
  vec3 h = v3_norm(v3_add(wo, wi));
  float d = pc_mf_d(&mf, h);
  if (d == 0.f) return 0.f;
  float g = pc_mf_g1(&mf, wo, h) * pc_mf_g1(&mf, wi, h);
  return pc_fresnel_dielectric(v3_dot(wo, h), pc_rel_eta(m), NULL) * d * g / (4.f * wo.z * wi.z);
}

static float rough_layer_pdf(const pc_material *m, vec3 wo, vec3 wi) {
  if (!(wo.z * wi.z > 0.f)) return 0.f;
  if (wo.z < 0.f) wo.z = -wo.z, wi.z = -wi.z;
  pc_microfacet mf = layer_mf(m);
  vec3 h = v3_norm(v3_add(wo, wi));
  float dot = v3_dot(wo, h);
  return dot > 0.f ? pc_mf_pdf(&mf, wo, h) / (4.f * dot) : 0.f;
}

vec3 pc_roughcoating_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  const pc_material *m = c->m;
  vec3 f = v3_scale(pc_tex(c, &m->specular), rough_layer_f(m, wo, wi));
  float eta = pc_rel_eta(m);
  vec3 wo_in, wi_in;
  if (!m->inner || !refract_to(wo, 1.f / eta, &wo_in) || !refract_to(wi, 1.f / eta, &wi_in)) return f;
  vec3 fin = pc_nested_eval(c, m->inner, wo_in, wi_in);
  if (v3_is_zero(fin)) return f;
  float t = pc_rough_trans_in(m, fabsf(wo.z)) * pc_rough_trans_in(m, fabsf(wi.z)) / (eta * eta);
  return v3_add(f, v3_scale(v3_mul(fin, absorption(c, wo_in, wi_in)), t));
}

float pc_roughcoating_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  const pc_material *m = c->m;
  float ps = m->inner ? rough_spec_prob(m, wo) : 1.f;
  float pdf = ps * rough_layer_pdf(m, wo, wi);
  float eta = pc_rel_eta(m);
  vec3 wo_in, wi_in;
  if (m->inner && refract_to(wo, 1.f / eta, &wo_in) && refract_to(wi, 1.f / eta, &wi_in))
    pdf += (1.f - ps) * pc_nested_pdf(c, m->inner, wo_in, wi_in) * jacobian(m, wi, wi_in);
  return pdf;
}

bool pc_roughcoating_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  const pc_material *m = c->m;
  if (!(wo.z != 0.f)) return false;
  float ps = m->inner ? rough_spec_prob(m, wo) : 1.f;
  float eta = pc_rel_eta(m);
  s->is_delta = false;
  if (u0 < ps) {
    float side = wo.z < 0.f ? -1.f : 1.f;
    vec3 v = v3(wo.x, wo.y, wo.z * side);
    pc_microfacet mf = layer_mf(m);
    vec3 h = pc_mf_sample(&mf, v, u1, u2);
    vec3 wi = v3_sub(v3_scale(h, 2.f * v3_dot(v, h)), v);
    s->wi = v3(wi.x, wi.y, wi.z * side);
    return s->wi.z * wo.z > 0.f;
  }
  vec3 wo_in;
  if (!refract_to(wo, 1.f / eta, &wo_in)) return false;
  pc_lobe_sample in = {0};
  if (!pc_nested_sample(c, m->inner, wo_in, (u0 - ps) / (1.f - ps), u1, u2, &in)) return false;
  if (!refract_to(in.wi, eta, &s->wi)) return false;
  if (in.is_delta) {
    vec3 wi = s->wi;
    s->is_delta = true;
    s->pdf = (1.f - ps) * in.pdf;
    s->pdf_rev = (1.f - rough_spec_prob(m, wi)) * in.pdf_rev;
    float t = pc_rough_trans_in(m, fabsf(wo.z)) * pc_rough_trans_in(m, fabsf(wi.z));
    s->f_cos = v3_scale(v3_mul(in.f_cos, absorption(c, wo_in, in.wi)), t);
  }
  return true;
}
