/* bsdf_diffuse.c: Lambertian reflection (Mitsuba `diffuse`) and cosine-weighted sampling. */
#include "bsdf_lobes.h"

vec3 pc_sample_cosine_hemisphere(float u1, float u2) {
  vec2 d = pc_sample_concentric_disk(u1, u2);
  return v3(d.x, d.y, sqrtf(fmaxf(0.f, 1.f - d.x * d.x - d.y * d.y)));
}

vec3 pc_diffuse_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  return v3_scale(pc_tex(c, &c->m->reflectance), PC_INV_PI);
}

float pc_diffuse_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  (void)c;
  return (wo.z > 0.f && wi.z > 0.f) ? wi.z * PC_INV_PI : 0.f;
}

bool pc_diffuse_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  (void)c;
  (void)u0;
  if (!(wo.z > 0.f)) return false;
  s->wi = pc_sample_cosine_hemisphere(u1, u2);
  s->is_delta = false;
  return s->wi.z > 0.f;
}
