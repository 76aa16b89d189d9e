/* microfacet.c: GGX distribution, Smith masking and visible-normal sampling. */
#include "microfacet.h"

float pc_ggx_d(float alpha, vec3 m) {
  if (!(m.z > 0.f)) return 0.f;
  float a2 = alpha * alpha, c2 = m.z * m.z;
  float root = c2 + (m.x * m.x + m.y * m.y) / a2;
  float d = 1.f / (PC_PI * a2 * root * root);
  /* Mitsuba flushes negligible values to zero; it also removes overflow. */
  return (isfinite(d) && d * m.z >= 1e-20f) ? d : 0.f;
}

float pc_ggx_g1(float alpha, vec3 v, vec3 m) {
  if (!(v3_dot(v, m) * v.z > 0.f)) return 0.f;
  float sin2 = v.x * v.x + v.y * v.y;
  if (sin2 == 0.f) return 1.f;
  float at2 = alpha * alpha * sin2 / (v.z * v.z); /* (alpha tan theta)^2 */
  float g = 2.f / (1.f + sqrtf(1.f + at2));
  return isfinite(g) ? g : 0.f;
}

vec3 pc_ggx_sample_visible(float alpha, vec3 v, float u1, float u2) {
  /* Stretch to the hemisphere configuration of unit roughness. */
  vec3 vh = v3_norm(v3(alpha * v.x, alpha * v.y, v.z));
  float len2 = vh.x * vh.x + vh.y * vh.y;
  vec3 t1 = len2 > 0.f ? v3_scale(v3(-vh.y, vh.x, 0.f), 1.f / sqrtf(len2)) : v3(1.f, 0.f, 0.f);
  vec3 t2 = v3_cross(vh, t1);
  /* Uniform point on the projected disk, warped to the visible half of it. */
  float r = sqrtf(u1), phi = 2.f * PC_PI * u2;
  float p1 = r * cosf(phi), p2 = r * sinf(phi);
  float s = 0.5f * (1.f + vh.z);
  p2 = (1.f - s) * sqrtf(fmaxf(0.f, 1.f - p1 * p1)) + s * p2;
  vec3 nh = v3_add(v3_add(v3_scale(t1, p1), v3_scale(t2, p2)),
                   v3_scale(vh, sqrtf(fmaxf(0.f, 1.f - p1 * p1 - p2 * p2))));
  return v3_norm(v3(alpha * nh.x, alpha * nh.y, fmaxf(0.f, nh.z)));
}

float pc_ggx_pdf_visible(float alpha, vec3 v, vec3 m) {
  if (!(v.z > 0.f)) return 0.f;
  float dot = v3_dot(v, m);
  if (!(dot > 0.f)) return 0.f;
  return pc_ggx_g1(alpha, v, m) * dot * pc_ggx_d(alpha, m) / v.z;
}
