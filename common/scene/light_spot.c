/* light_spot.c: Mitsuba's `spot` emitter: a point light whose intensity falls linearly in
 * angle from the edge of its beam to its cutoff, with an optional texture projected over the
 * cone; light paths leave it uniformly over the cutoff cone (see light.h). */
#include "light.h"

void pc_spot_set_angles(pc_light *l, float cutoff_deg, float beam_deg) {
  l->cutoff = cutoff_deg * (PC_PI / 180.f);
  l->beam_width = beam_deg * (PC_PI / 180.f);
  l->cos_cutoff = cosf(l->cutoff);
  l->cos_beam = cosf(l->beam_width);
}

/* 1 - cos(cutoff) without the cancellation of narrow cones. */
static float one_minus_cos_cutoff(const pc_light *l) {
  float h = sinf(0.5f * l->cutoff);
  return 2.f * h * h;
}

vec3 pc_spot_falloff(const pc_light *l, vec3 w) {
  vec3 d = frame_to_local(&l->spot_frame, w);
  float c = d.z;
  if (c <= l->cos_cutoff) return v3s(0.f);
  vec3 r = v3s(1.f);
  if (l->spot_tex) {
    /* Mitsuba's projection: the cone's cross-section at unit distance spans uv [0, 1]^2. */
    float k = 0.5f / (d.z * tanf(l->cutoff));
    r = pc_texture_eval(l->spot_tex, (vec2){0.5f + d.x * k, 0.5f + d.y * k});
  }
  if (c >= l->cos_beam || !(l->cutoff > l->beam_width)) return r;
  float t = (l->cutoff - acosf(fminf(c, 1.f))) / (l->cutoff - l->beam_width);
  return v3_scale(r, fminf(fmaxf(t, 0.f), 1.f));
}

double pc_spot_solid_angle(const pc_light *l) {
  double g = l->cutoff, b = l->beam_width;
  /* 2 pi [ (1 - cos b) + int_b^g (g - t) / (g - b) sin t dt ] = 2 pi [1 - (sin g - sin b) / (g - b)] */
  if (g - b < 1e-6) return 2.0 * PC_PI * (1.0 - cos(g));
  return 2.0 * PC_PI * (1.0 - (sin(g) - sin(b)) / (g - b));
}

vec3 pc_spot_sample_dir(const pc_light *l, float u0, float u1, float *pdf) {
  float om = one_minus_cos_cutoff(l);
  float m = u0 * om; /* 1 - cos(theta), uniform in solid angle over the cone */
  float st = sqrtf(fmaxf(0.f, m * (2.f - m))), phi = 2.f * PC_PI * u1;
  *pdf = 1.f / (2.f * PC_PI * om);
  return frame_to_world(&l->spot_frame, v3(st * cosf(phi), st * sinf(phi), 1.f - m));
}

/* As Mitsuba's pdfDirection, the same for every direction: those outside the cone carry no
 * emission (the falloff is 0 there, so no connection asks), and a test of the cone here would
 * disagree with the falloff's, in float, for samples at its very edge. */
float pc_spot_pdf_dir(const pc_light *l, vec3 w) {
  (void)w;
  return 1.f / (2.f * PC_PI * one_minus_cos_cutoff(l));
}
