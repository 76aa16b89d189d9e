/* rfilter.c: Mitsuba's reconstruction filters as tabulated steps, their integral over the film
 * and sampling from it (rfilter.h). The tables are made as Mitsuba's ReconstructionFilter::
 * configure makes them, in floats, so that a pixel weighs its samples as Mitsuba's does. */
#include "rfilter.h"

static float filter_eval(pc_rfilter_type type, float radius, float param, float x) {
  switch (type) {
  case PC_RFILTER_BOX: return fabsf(x) <= radius ? 1.f : 0.f;
  case PC_RFILTER_TENT: return fmaxf(0.f, 1.f - fabsf(x / radius));
  case PC_RFILTER_GAUSSIAN: {
    float alpha = -1.f / (2.f * param * param);
    return fmaxf(0.f, expf(alpha * x * x) - expf(alpha * radius * radius));
  }
  }
  return 0.f;
}

bool pc_rfilter_make(pc_rfilter *out, pc_rfilter_type type, float param) {
  pc_rfilter made, *f = &made; /* out changes only on success */
  float radius = type == PC_RFILTER_BOX ? param + 1e-5f : type == PC_RFILTER_TENT ? 1.f : 4.f * param;
  if (!(radius > 1e-5f) || !(radius <= PC_RFILTER_MAX_RADIUS + 1e-5f)) return false;
  f->type = type;
  f->radius = radius;
  float value[PC_RFILTER_STEPS], sum = 0.f; /* Mitsuba's m_values: |x| in [i step, (i + 1) step) */
  for (int i = 0; i < PC_RFILTER_STEPS; i++) {
    value[i] = filter_eval(type, radius, param, (radius * (float)i) / PC_RFILTER_STEPS);
    if (!(value[i] > 0.f)) return false;
    sum += value[i];
  }
  sum *= 2 * radius / PC_RFILTER_STEPS;
  f->step = radius / PC_RFILTER_STEPS;
  f->scale = PC_RFILTER_STEPS / radius;
  double c = 0.0;
  f->cdf[0] = 0.f;
  for (int k = 0; k < 2 * PC_RFILTER_STEPS; k++) {
    f->across[k] = value[k < PC_RFILTER_STEPS ? PC_RFILTER_STEPS - 1 - k : k - PC_RFILTER_STEPS] * (1.f / sum);
    c += (double)f->across[k] * f->step;
    f->cdf[k + 1] = (float)c;
    f->inv_width[k] = 1.f / (f->across[k] * f->step);
  }
  for (int g = 0, k = 0; g < 64; g++) {
    float t = f->cdf[2 * PC_RFILTER_STEPS] * (float)g / 64.f;
    while (k < 2 * PC_RFILTER_STEPS - 1 && f->cdf[k + 1] <= t) k++;
    f->guide[g] = (unsigned char)k;
  }
  *out = made;
  return true;
}

bool pc_rfilter_is_pixel(const pc_rfilter *f) {
  return f->type == PC_RFILTER_BOX && (f->radius == 0.f || fabsf(f->radius - 0.5f) < 1e-4f);
}

/* The filter's integral from -radius to t. */
static float cdf_at(const pc_rfilter *f, float t) {
  float x = (t + f->radius) / f->step;
  if (!(x > 0.f)) return 0.f;
  if (x >= 2 * PC_RFILTER_STEPS) return f->cdf[2 * PC_RFILTER_STEPS];
  int k = (int)x;
  return f->cdf[k] + (x - (float)k) * f->across[k] * f->step;
}

float pc_rfilter_mass_cut(const pc_rfilter *f, float c, float extent) { return cdf_at(f, extent - c) - cdf_at(f, -c); }

float pc_rfilter_sample(const pc_rfilter *f, float c, float extent, float u, float *pdf) {
  float lo = -c, hi = extent - c, g0 = 0.f, z = f->cdf[2 * PC_RFILTER_STEPS];
  if (lo > -f->radius || hi < f->radius) { /* the film cuts the filter */
    g0 = cdf_at(f, lo);
    z = cdf_at(f, hi) - g0;
  }
  float t = g0 + u * z;
  /* the step holding t: cdf[a] <= t < cdf[a + 1] (the last one for t at the very top) */
  int g = (int)(t * (64.f / f->cdf[2 * PC_RFILTER_STEPS]));
  int a = f->guide[g < 0 ? 0 : g > 63 ? 63 : g];
  while (a > 0 && f->cdf[a] > t) a--; /* the guide's index rounded up */
  while (a < 2 * PC_RFILTER_STEPS - 1 && f->cdf[a + 1] <= t) a++;
  float v = f->across[a];
  float d = -f->radius + ((float)a + (t - f->cdf[a]) * f->inv_width[a]) * f->step;
  d = fminf(fmaxf(d, fmaxf(lo, -f->radius)), fminf(hi, f->radius));
  *pdf = v / z;
  return c + d;
}
