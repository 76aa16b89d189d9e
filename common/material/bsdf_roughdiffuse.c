/* bsdf_roughdiffuse.c: Mitsuba's `roughdiffuse`: Oren and Nayar's rough Lambertian model, in
 * Mitsuba's exact variant: the full model with its interreflection term (Oren and Nayar 1994,
 * eq. 30 and 31), or the qualitative one with useFastApprox; alpha is a Beckmann-style RMS slope
 * converted to Oren-Nayar's sigma by 1/sqrt(2). Mitsuba samples it as a Lambertian (bsdf.c
 * reuses the diffuse sampler and pdf). The value is symmetric in the two directions. */
#include "bsdf_lobes.h"

/* Mitsuba's Epsilon below which the azimuth difference is taken as undefined (cos 0). */
#define ON_EPSILON 1e-4f

static float sin_theta(vec3 w) { return sqrtf(fmaxf(0.f, 1.f - w.z * w.z)); }

/* cos(phi_o - phi_i) from the components, 0 where either azimuth is undefined. */
static float cos_phi_diff(vec3 a, vec3 b, float sa, float sb) {
  if (!(sa > ON_EPSILON && sb > ON_EPSILON)) return 0.f;
  float ca = fminf(fmaxf(a.x / sa, -1.f), 1.f), sa_ = fminf(fmaxf(a.y / sa, -1.f), 1.f);
  float cb = fminf(fmaxf(b.x / sb, -1.f), 1.f), sb_ = fminf(fmaxf(b.y / sb, -1.f), 1.f);
  return ca * cb + sa_ * sb_;
}

vec3 pc_roughdiffuse_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (!(wo.z > 0.f && wi.z > 0.f)) return v3s(0.f);
  float sigma = c->m->alpha * (float)(1.0 / 1.4142135623730951), s2 = sigma * sigma;
  float so = sin_theta(wo), si = sin_theta(wi), cpd = cos_phi_diff(wo, wi, so, si);
  /* alpha is the larger polar angle, beta the smaller */
  float sin_alpha, sin_beta, tan_beta;
  if (wo.z > wi.z) {
    sin_alpha = si, sin_beta = so, tan_beta = so / wo.z;
  } else {
    sin_alpha = so, sin_beta = si, tan_beta = si / wi.z;
  }
  vec3 rho = pc_tex(c, &c->m->reflectance);
  if (c->m->fast_approx) {
    float a = 1.f - 0.5f * s2 / (s2 + 0.33f), b = 0.45f * s2 / (s2 + 0.09f);
    return v3_scale(rho, PC_INV_PI * (a + b * fmaxf(cpd, 0.f) * sin_alpha * tan_beta));
  }
  float to = acosf(fminf(fmaxf(wo.z, -1.f), 1.f)), ti = acosf(fminf(fmaxf(wi.z, -1.f), 1.f));
  float alpha = fmaxf(to, ti), beta = fminf(to, ti);
  float tmp = s2 / (s2 + 0.09f), tmp2 = (4.f * PC_INV_PI * PC_INV_PI) * alpha * beta, tmp3 = 2.f * beta * PC_INV_PI;
  float c1 = 1.f - 0.5f * s2 / (s2 + 0.33f), c2 = 0.45f * tmp, c3 = 0.125f * tmp * tmp2 * tmp2,
        c4 = 0.17f * s2 / (s2 + 0.13f);
  c2 *= cpd > 0.f ? sin_alpha : sin_alpha - tmp3 * tmp3 * tmp3;
  float tan_half = (sin_alpha + sin_beta) /
                   (sqrtf(fmaxf(0.f, 1.f - sin_alpha * sin_alpha)) + sqrtf(fmaxf(0.f, 1.f - sin_beta * sin_beta)));
  vec3 single = v3_scale(rho, c1 + cpd * c2 * tan_beta + (1.f - fabsf(cpd)) * c3 * tan_half);
  vec3 twice = v3_scale(v3_mul(rho, rho), c4 * (1.f - cpd * tmp3 * tmp3));
  return v3_scale(v3_add(single, twice), PC_INV_PI);
}
