/* microfacet.c: Beckmann and GGX distributions, Smith masking and normal sampling. */
#include "microfacet.h"

/* Mitsuba's Phong exponents along the two tangents. */
static float phong_exponent(float alpha) { return fmaxf(2.f / (alpha * alpha) - 2.f, 0.f); }

/* The exponent for the azimuth of m (interpolated by cos^2 and sin^2 phi when anisotropic). */
static float phong_exponent_at(const pc_microfacet *d, vec3 m) {
  float eu = phong_exponent(d->alpha), s2 = m.x * m.x + m.y * m.y;
  if (d->alpha_v == d->alpha || !(s2 > 1e-30f)) return eu;
  return (eu * m.x * m.x + phong_exponent(d->alpha_v) * m.y * m.y) / s2;
}

float pc_mf_d(const pc_microfacet *d, vec3 m) {
  if (!(m.z > 0.f)) return 0.f;
  float au = d->alpha, av = d->alpha_v, c2 = m.z * m.z;
  float e = (m.x * m.x / (au * au) + m.y * m.y / (av * av)) / c2;
  float r;
  if (d->type == PC_MF_PHONG) {
    float eu = phong_exponent(au), ev = phong_exponent(av);
    r = sqrtf((eu + 2.f) * (ev + 2.f)) * (0.5f * PC_INV_PI) * powf(m.z, phong_exponent_at(d, m));
  } else if (d->type == PC_MF_BECKMANN) {
    r = expf(-e) / (PC_PI * au * av * c2 * c2);
  } else {
    float root = (1.f + e) * c2;
    r = 1.f / (PC_PI * au * av * root * root);
  }
  /* Mitsuba flushes negligible values to zero; it also removes overflow. */
  return (isfinite(r) && r * m.z >= 1e-20f) ? r : 0.f;
}

float pc_mf_g1(const pc_microfacet *d, vec3 v, vec3 m) {
  if (!(v3_dot(v, m) * v.z > 0.f)) return 0.f;
  float sin2 = v.x * v.x + v.y * v.y;
  if (sin2 == 0.f) return 1.f;
  float tan_theta = sqrtf(sin2) / fabsf(v.z);
  /* The roughness seen along v's azimuth (Mitsuba's projectRoughness). */
  float alpha = d->alpha;
  if (d->alpha_v != d->alpha)
    alpha = sqrtf((v.x * v.x * d->alpha * d->alpha + v.y * v.y * d->alpha_v * d->alpha_v) / sin2);
  float g;
  if (d->type != PC_MF_GGX) { /* Beckmann's, which Mitsuba uses for Phong too */
    float a = 1.f / (alpha * tan_theta);
    if (a >= 1.6f) return 1.f;
    g = (3.535f * a + 2.181f * a * a) / (1.f + 2.276f * a + 2.577f * a * a);
  } else {
    float root = alpha * tan_theta;
    g = 2.f / (1.f + sqrtf(1.f + root * root));
  }
  return isfinite(g) ? g : 0.f;
}

static vec3 ggx_sample_visible(float au, float av, vec3 v, float u1, float u2) {
  /* Stretch to the hemisphere configuration of unit roughness. */
  vec3 vh = v3_norm(v3(au * v.x, av * v.y, v.z));
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
  return v3_norm(v3(au * nh.x, av * nh.y, fmaxf(0.f, nh.z)));
}

/* Phong: phi uniform (or Ashikhmin-Shirley's per-quadrant azimuth), cos theta = u1^(1/(e+2)). */
static vec3 phong_sample(const pc_microfacet *d, float u1, float u2) {
  float phi = 2.f * PC_PI * u2, e = phong_exponent(d->alpha);
  if (d->alpha_v != d->alpha) {
    float eu = e, ev = phong_exponent(d->alpha_v), k = sqrtf((eu + 2.f) / (ev + 2.f));
    int quadrant = u2 < 0.25f ? 0 : u2 < 0.5f ? 1 : u2 < 0.75f ? 2 : 3;
    static const float start[4] = {0.f, 0.5f, 0.5f, 1.f};
    float u = 4.f * fabsf(u2 - start[quadrant]);
    float q = atanf(k * tanf(PC_PI * u * 0.5f));
    phi = quadrant == 0 ? q : quadrant == 1 ? PC_PI - q : quadrant == 2 ? PC_PI + q : 2.f * PC_PI - q;
    float c = cosf(q), s = sinf(q);
    e = eu * c * c + ev * s * s;
  }
  float ct = powf(u1, 1.f / (e + 2.f)), st = sqrtf(fmaxf(0.f, 1.f - ct * ct));
  return v3(st * cosf(phi), st * sinf(phi), ct);
}

vec3 pc_mf_sample(const pc_microfacet *d, vec3 v, float u1, float u2) {
  if (d->type == PC_MF_GGX) return ggx_sample_visible(d->alpha, d->alpha_v, v, u1, u2);
  if (d->type == PC_MF_PHONG) return phong_sample(d, u1, u2);
  /* Beckmann: tan^2 theta = -alpha^2 log(1 - u1), phi uniform (Mitsuba's sampleAll); when
   * anisotropic, phi from the elliptical distribution and alpha^2 the roughness along it. */
  float phi = 2.f * PC_PI * u2, a2 = d->alpha * d->alpha;
  if (d->alpha_v != d->alpha) {
    phi = atanf(d->alpha_v / d->alpha * tanf(PC_PI + 2.f * PC_PI * u2)) + PC_PI * floorf(2.f * u2 + 0.5f);
    float cs = cosf(phi) / d->alpha, sn = sinf(phi) / d->alpha_v;
    a2 = 1.f / (cs * cs + sn * sn);
  }
  float tan2 = -a2 * logf(fmaxf(1.f - u1, 1e-30f));
  float c = 1.f / sqrtf(1.f + tan2), s = sqrtf(fmaxf(0.f, 1.f - c * c));
  return v3(s * cosf(phi), s * sinf(phi), c);
}

static float visible_of(vec3 v, vec3 m, float dm, float g1) {
  if (!(v.z > 0.f)) return 0.f;
  float dot = v3_dot(v, m);
  if (!(dot > 0.f)) return 0.f;
  return g1 * dot * dm / v.z;
}

float pc_mf_visible(const pc_microfacet *d, vec3 v, vec3 m) {
  if (!(v.z > 0.f && v3_dot(v, m) > 0.f)) return 0.f; /* D and G1 only where they count */
  return visible_of(v, m, pc_mf_d(d, m), pc_mf_g1(d, v, m));
}

float pc_mf_pdf(const pc_microfacet *d, vec3 v, vec3 m) {
  if (d->type == PC_MF_GGX) return pc_mf_visible(d, v, m);
  return pc_mf_d(d, m) * fmaxf(m.z, 0.f);
}

float pc_mf_pdf_of(const pc_microfacet *d, vec3 v, vec3 m, float dm, float g1) {
  if (d->type == PC_MF_GGX) return visible_of(v, m, dm, g1);
  return dm * fmaxf(m.z, 0.f);
}
