/* fresnel.c: dielectric and conductor Fresnel equations and the diffuse Fresnel reflectance. */
#include "fresnel.h"

#include <stddef.h>

float pc_fresnel_dielectric(float cos_i, float eta, float *cos_t) {
  cos_i = fminf(fmaxf(cos_i, -1.f), 1.f);
  if (!(eta > 0.f) || eta == 1.f || !isfinite(eta)) {
    if (cos_t) *cos_t = -cos_i;
    return 0.f;
  }
  /* Snell's law from whichever side cos_i says the light arrives on. */
  float scale = cos_i > 0.f ? 1.f / eta : eta;
  float cos_t2 = 1.f - (1.f - cos_i * cos_i) * scale * scale;
  if (cos_t2 <= 0.f) {
    if (cos_t) *cos_t = 0.f;
    return 1.f;
  }
  float ci = fabsf(cos_i), ct = sqrtf(cos_t2);
  /* The expressions are symmetric under swapping the two media up to sign, so the same form
   * serves both directions (as in Mitsuba's fresnelDielectricExt). */
  float rs = (ci - eta * ct) / (ci + eta * ct);
  float rp = (eta * ci - ct) / (eta * ci + ct);
  if (cos_t) *cos_t = cos_i > 0.f ? -ct : ct;
  float f = 0.5f * (rs * rs + rp * rp);
  return isfinite(f) ? fminf(f, 1.f) : 1.f;
}

/* Ratio that treats 0/0 (only reachable at grazing or for a perfect mirror) as total
 * reflection. */
static float ratio_or_one(float a, float b) { return b != 0.f ? a / b : 1.f; }

static float conductor1(float ci, float eta, float k) {
  float c2 = ci * ci, s2 = 1.f - c2, s4 = s2 * s2;
  float t1 = eta * eta - k * k - s2;
  float a2pb2 = sqrtf(fmaxf(t1 * t1 + 4.f * k * k * eta * eta, 0.f));
  float a = sqrtf(fmaxf(0.5f * (a2pb2 + t1), 0.f));
  float term1 = a2pb2 + c2, term2 = 2.f * a * ci;
  float rs = ratio_or_one(term1 - term2, term1 + term2);
  float term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
  float rp = rs * ratio_or_one(term3 - term4, term3 + term4);
  float f = 0.5f * (rp + rs);
  return isfinite(f) ? fminf(fmaxf(f, 0.f), 1.f) : 1.f;
}

vec3 pc_fresnel_conductor(float cos_i, vec3 eta, vec3 k) {
  float ci = fminf(fabsf(cos_i), 1.f);
  if (!(ci >= 0.f)) ci = 0.f;
  return v3(conductor1(ci, eta.x, k.x), conductor1(ci, eta.y, k.y), conductor1(ci, eta.z, k.z));
}

/* Composite Simpson over [a, b] of F(sqrt(x)); n even. */
static double simpson_fresnel(double a, double b, int n, float eta, int substitute) {
  double h = 1.0 / n, sum = 0;
  for (int i = 0; i <= n; i++) {
    double t = i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    /* With total internal reflection F has a square-root kink at the critical angle;
     * x = a + (b - a) t^2 turns it into a smooth integrand. */
    double x = substitute ? a + (b - a) * t * t : a + (b - a) * t;
    double jac = substitute ? 2 * (b - a) * t : (b - a);
    sum += w * jac * pc_fresnel_dielectric((float)sqrt(x), eta, NULL);
  }
  return sum * h / 3;
}

float pc_fresnel_diffuse_reflectance(float eta) {
  if (!(eta > 0.f) || !isfinite(eta)) return 0.f;
  if (eta >= 1.f) return (float)simpson_fresnel(0, 1, 512, eta, 0);
  /* Below x_c = cos^2 of the critical angle every direction is totally reflected. */
  double xc = 1.0 - (double)eta * eta;
  return (float)(xc + simpson_fresnel(xc, 1, 512, eta, 1));
}
