/* bsdf_phong.c: Mitsuba's `phong`: the modified Phong model of Lafortune and Willems (a lobe
 * (n+2)/(2 pi) cos^n of the angle to the mirror direction, normalized so that at normal
 * incidence it reflects exactly specularReflectance) added to a Lambertian one. As in Mitsuba,
 * the lobe is picked with spec_sampling_weight, the specular lobe samples cos^n about the
 * mirror direction ((n+1)/(2 pi) cos^n per solid angle), and both lobes carry the
 * ensureEnergyConservation factor lobe_scale the loader computed. */
#include "bsdf_lobes.h"

static vec3 mirror(vec3 w) { return v3(-w.x, -w.y, w.z); }

vec3 pc_phong_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  const pc_material *m = c->m;
  vec3 f = v3_scale(pc_tex(c, &m->reflectance), PC_INV_PI);
  float cos_a = v3_dot(wi, mirror(wo));
  if (cos_a > 0.f)
    f = v3_add(f, v3_scale(pc_tex(c, &m->specular), (m->exponent + 2.f) * (0.5f * PC_INV_PI) * powf(cos_a, m->exponent)));
  return v3_scale(f, m->lobe_scale);
}

float pc_phong_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return 0.f;
  const pc_material *m = c->m;
  float cos_a = v3_dot(wi, mirror(wo)), spec = 0.f;
  if (cos_a > 0.f) spec = powf(cos_a, m->exponent) * (m->exponent + 1.f) * (0.5f * PC_INV_PI);
  float w = m->spec_sampling_weight;
  return w * spec + (1.f - w) * wi.z * PC_INV_PI;
}

bool pc_phong_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  if (!(wo.z > 0.f)) return false;
  s->is_delta = false;
  if (u0 >= c->m->spec_sampling_weight) {
    s->wi = pc_sample_cosine_hemisphere(u1, u2);
    return s->wi.z > 0.f;
  }
  float n = c->m->exponent, phi = 2.f * PC_PI * u1;
  float cos_a = powf(u2, 1.f / (n + 1.f)), sin_a = sqrtf(fmaxf(0.f, 1.f - powf(u2, 2.f / (n + 1.f))));
  frame r = frame_from_normal(mirror(wo));
  s->wi = frame_to_world(&r, v3(sin_a * cosf(phi), sin_a * sinf(phi), cos_a));
  return s->wi.z > 0.f;
}
