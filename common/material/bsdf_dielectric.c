/* bsdf_dielectric.c: Mitsuba's smooth `dielectric`: Fresnel-weighted choice between the delta
 * reflection and the delta refraction; and `thindielectric`, a thin pane: the same choice
 * between the mirror direction and passing straight through, with the reflectance summed over
 * the pane's internal reflections, R + T^2 R / (1 - R^2). For `dielectric` the side of wo
 * decides entering (eta = int/ext) or leaving. Radiance transport scales refraction by (eta_o / eta_i)^2 (the solid-angle
 * compression); importance transport does not, which makes it the adjoint. */
#include "bsdf_lobes.h"
#include "fresnel.h"

bool pc_dielectric_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  (void)u1;
  (void)u2;
  const pc_material *m = c->m;
  float eta = pc_rel_eta(m);
  if (!(wo.z != 0.f)) return false;
  float cos_t;
  float fr = pc_fresnel_dielectric(wo.z, eta, &cos_t);
  s->is_delta = true;
  if (u0 < fr) {
    s->wi = v3(-wo.x, -wo.y, wo.z);
    s->pdf = fr;
    s->pdf_rev = pc_fresnel_dielectric(s->wi.z, eta, NULL);
    s->f_cos = v3_scale(pc_tex(c, &m->specular), fr);
    return true;
  }
  if (cos_t == 0.f) return false;
  float inv = cos_t < 0.f ? 1.f / eta : eta; /* n_o / n_i */
  s->wi = v3(-inv * wo.x, -inv * wo.y, cos_t);
  s->pdf = 1.f - fr;
  s->pdf_rev = 1.f - pc_fresnel_dielectric(cos_t, eta, NULL);
  float scale = c->mode == PC_RADIANCE ? inv * inv : 1.f;
  s->f_cos = v3_scale(pc_tex(c, &m->transmittance), (1.f - fr) * scale);
  return true;
}

bool pc_thindielectric_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  (void)u1;
  (void)u2;
  const pc_material *m = c->m;
  float eta = pc_rel_eta(m);
  if (!(wo.z != 0.f)) return false;
  /* Both faces see the same |cos|, so the probabilities are the same in reverse. */
  float r = pc_fresnel_dielectric(fabsf(wo.z), eta, NULL), t = 1.f - r;
  if (r < 1.f) r += t * t * r / (1.f - r * r);
  s->is_delta = true;
  if (u0 < r) {
    s->wi = v3(-wo.x, -wo.y, wo.z);
    s->pdf = s->pdf_rev = r;
    s->f_cos = v3_scale(pc_tex(c, &m->specular), r);
    return true;
  }
  s->wi = v3_neg(wo);
  s->pdf = s->pdf_rev = 1.f - r;
  s->f_cos = v3_scale(pc_tex(c, &m->transmittance), 1.f - r);
  return !(r >= 1.f);
}
