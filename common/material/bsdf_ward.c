/* bsdf_ward.c: Mitsuba's `ward`: a Ward specular lobe (one of its three normalizations, see
 * pc_ward_variant; isotropic) added to a Lambertian one. As in Mitsuba, the lobe is picked with
 * spec_sampling_weight, the specular lobe samples Ward's half-vector density and the pdf is the
 * mixture of both; the specular value is dropped below 1e-10 where Mitsuba drops it. */
#include "bsdf_lobes.h"

static float ward_spec(const pc_material *m, vec3 wo, vec3 wi) {
  vec3 h = v3_add(wo, wi); /* unnormalized, as the balanced normalization needs it */
  float a2 = m->alpha * m->alpha, f1;
  switch (m->ward) {
  case PC_WARD_ORIGINAL: f1 = 1.f / (4.f * PC_PI * a2 * sqrtf(wo.z * wi.z)); break;
  case PC_WARD_DUER: f1 = 1.f / (4.f * PC_PI * a2 * wo.z * wi.z); break;
  default: f1 = v3_dot(h, h) / (PC_PI * a2 * (h.z * h.z) * (h.z * h.z)); break;
  }
  float v = f1 * expf(-(h.x * h.x + h.y * h.y) / (a2 * h.z * h.z));
  return v > 1e-10f ? v : 0.f;
}

/* Ward's half-vector density exp(-tan^2 / a^2) / (pi a^2 cos^3), per solid angle of wi. */
static float ward_spec_pdf(const pc_material *m, vec3 wo, vec3 wi) {
  vec3 h = v3_norm(v3_add(wo, wi));
  float a2 = m->alpha * m->alpha, hw = v3_dot(h, wo);
  if (!(h.z > 0.f && hw > 0.f)) return 0.f;
  return expf(-(h.x * h.x + h.y * h.y) / (a2 * h.z * h.z)) / (4.f * PC_PI * a2 * hw * h.z * h.z * h.z);
}

vec3 pc_ward_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  return v3_add(v3_scale(pc_tex(c, &c->m->specular), ward_spec(c->m, wo, wi)),
                v3_scale(pc_tex(c, &c->m->reflectance), PC_INV_PI));
}

float pc_ward_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return 0.f;
  float w = c->m->spec_sampling_weight;
  return w * ward_spec_pdf(c->m, wo, wi) + (1.f - w) * wi.z * PC_INV_PI;
}

bool pc_ward_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  if (!(wo.z > 0.f)) return false;
  s->is_delta = false;
  if (u0 >= c->m->spec_sampling_weight) {
    s->wi = pc_sample_cosine_hemisphere(u1, u2);
    return s->wi.z > 0.f;
  }
  float tan_h = c->m->alpha * sqrtf(-logf(1.f - u1)), phi = 2.f * PC_PI * u2;
  float cos_h = 1.f / sqrtf(1.f + tan_h * tan_h), sin_h = tan_h * cos_h;
  vec3 h = v3(sin_h * cosf(phi), sin_h * sinf(phi), cos_h);
  s->wi = v3_sub(v3_scale(h, 2.f * v3_dot(wo, h)), wo);
  return s->wi.z > 0.f;
}
