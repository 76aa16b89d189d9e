/* bsdf_mix.c: Mitsuba 0.6's `difftrans`, and the BSDFs that combine others: `mask`, `blendbsdf`
 * and `mixturebsdf`.
 *
 * difftrans: f = transmittance / pi between the two sides, nothing on the same side; sampled
 * cosine-weighted on the far side.
 *
 * mask: opacity a (spectrum or texture): a * f_inner, plus a Dirac pass-through toward -wo of
 * weight 1 - a (Mitsuba's null component: an index-matched interface, so the surface still
 * blocks shadow rays, as in Mitsuba's path integrator). The nested material is sampled with
 * probability P = luminance(a), the pass-through otherwise, as in Mitsuba.
 *
 * blendbsdf: (1 - w) f_0 + w f_1 with w the weight texture's channel average clamped to [0, 1];
 * mixturebsdf: sum w_k f_k with constant weights (scaled to sum to 1 when they exceed it and
 * ensureEnergyConservation, Mitsuba's default, holds), component k chosen with probability
 * w_k / sum w. eval and pdf are the weighted sums over the components' smooth lobes; a sampled
 * delta lobe keeps its own discrete probability times that of its component (the Dirac factors
 * cancel in every ratio, as for plastic's specular lobe). Where two components have delta lobes
 * in the same direction (a mixture of a conductor and a dielectric), each is a lobe of its own:
 * the sum over lobes is still the expected value, and delta vertices are never connected. */
#include "bsdf_lobes.h"

/* ---- difftrans ---- */

vec3 pc_difftrans_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z * wi.z < 0.f)) return v3s(0.f);
  return v3_scale(pc_tex(c, &c->m->transmittance), PC_INV_PI);
}

float pc_difftrans_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  (void)c;
  return wo.z * wi.z < 0.f ? fabsf(wi.z) * PC_INV_PI : 0.f;
}

bool pc_difftrans_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  (void)c;
  (void)u0;
  if (!(wo.z != 0.f)) return false;
  s->wi = pc_sample_cosine_hemisphere(u1, u2);
  if (wo.z > 0.f) s->wi.z = -s->wi.z;
  s->is_delta = false;
  return s->wi.z != 0.f;
}

/* ---- mask ---- */

/* Mitsuba's probability of sampling the nested material: the opacity's luminance. */
static float mask_prob(vec3 opacity) {
  float p = v3_luminance(opacity);
  return p > 0.f ? fminf(p, 1.f) : 0.f;
}

vec3 pc_mask_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!c->m->inner) return v3s(0.f);
  vec3 f = pc_nested_eval(c, c->m->inner, wo, wi);
  return v3_is_zero(f) ? f : v3_mul(f, pc_tex(c, &c->m->weight));
}

float pc_mask_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!c->m->inner) return 0.f;
  float p = mask_prob(pc_tex(c, &c->m->weight));
  return p > 0.f ? p * pc_nested_pdf(c, c->m->inner, wo, wi) : 0.f;
}

bool pc_mask_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  if (!(wo.z != 0.f) || !c->m->inner) return false;
  vec3 a = pc_tex(c, &c->m->weight);
  float p = mask_prob(a);
  if (u0 < p) {
    pc_lobe_sample in = {0};
    if (!pc_nested_sample(c, c->m->inner, wo, u0 / p, u1, u2, &in)) return false;
    *s = in;
    if (in.is_delta) {
      s->pdf = p * in.pdf;
      s->pdf_rev = p * in.pdf_rev;
      s->f_cos = v3_mul(in.f_cos, a);
    }
    return true;
  }
  /* Straight through: f |cos| = 1 - a, the same probability seen from either side. */
  s->wi = v3_neg(wo);
  s->is_delta = true;
  s->pdf = s->pdf_rev = 1.f - p;
  s->f_cos = v3_sub(v3s(1.f), a);
  return true;
}

/* ---- blendbsdf and mixturebsdf ---- */

/* The components' weights in f (w) and sampling probabilities (p) at this point; the count. */
static int mix_weights(const pc_lobe_ctx *c, float *w, float *p) {
  const pc_material *m = c->m;
  if (m->type == PC_MAT_BLEND) {
    vec3 t = pc_tex(c, &m->weight);
    float b = (t.x + t.y + t.z) / 3.f;
    b = b > 0.f ? fminf(b, 1.f) : 0.f; /* (NaN too) */
    w[0] = p[0] = 1.f - b;
    w[1] = p[1] = b;
    return 2;
  }
  for (int k = 0; k < m->nmix; k++) w[k] = m->mix_w[k], p[k] = m->mix_p[k];
  return m->nmix;
}

vec3 pc_mix_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  float w[PC_MIX_MAX], p[PC_MIX_MAX];
  int n = mix_weights(c, w, p);
  vec3 f = v3s(0.f);
  for (int k = 0; k < n; k++)
    if (w[k] > 0.f && c->m->mix[k]) f = v3_add(f, v3_scale(pc_nested_eval(c, c->m->mix[k], wo, wi), w[k]));
  return f;
}

float pc_mix_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  float w[PC_MIX_MAX], p[PC_MIX_MAX];
  int n = mix_weights(c, w, p);
  float pdf = 0.f;
  for (int k = 0; k < n; k++)
    if (p[k] > 0.f && c->m->mix[k]) pdf += p[k] * pc_nested_pdf(c, c->m->mix[k], wo, wi);
  return pdf;
}

bool pc_mix_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  float w[PC_MIX_MAX], p[PC_MIX_MAX];
  int n = mix_weights(c, w, p), k = 0;
  float lo = 0.f;
  /* The component whose interval of [0, 1) holds u0 (skipping empty ones); u0 reused inside it. */
  while (k < n - 1 && (u0 >= lo + p[k] || !(p[k] > 0.f))) lo += p[k++];
  if (!(p[k] > 0.f) || !c->m->mix[k]) return false;
  float u = fminf((u0 - lo) / p[k], 0x1.fffffep-1f);
  pc_lobe_sample in = {0};
  if (!pc_nested_sample(c, c->m->mix[k], wo, u > 0.f ? u : 0.f, u1, u2, &in)) return false;
  *s = in;
  if (in.is_delta) {
    s->pdf = p[k] * in.pdf;
    s->pdf_rev = p[k] * in.pdf_rev;
    s->f_cos = v3_scale(in.f_cos, w[k]);
  }
  return true;
}
