/* vecmath.h: the small-vector algebra every module uses: vec3 (points, directions, RGB),
 * 4x4 affine transforms, orthonormal frames. Header-only so the compiler inlines it. */
#ifndef PC_VECMATH_H
#define PC_VECMATH_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#define PC_PI 3.14159265358979323846f
#define PC_INV_PI 0.31830988618379067154f

typedef struct vec3 { float x, y, z; } vec3;
typedef struct vec2 { float x, y; } vec2;

static inline vec3 v3(float x, float y, float z) { return (vec3){x, y, z}; }
static inline vec3 v3s(float s) { return (vec3){s, s, s}; }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v3_div(vec3 a, vec3 b) { return v3(a.x / b.x, a.y / b.y, a.z / b.z); }
static inline vec3 v3_scale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_neg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
static inline vec3 v3_madd(vec3 a, vec3 b, float s) { return v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s); }
static inline float v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline float v3_absdot(vec3 a, vec3 b) { return fabsf(v3_dot(a, b)); }
static inline vec3 v3_cross(vec3 a, vec3 b) {
  return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v3_len2(vec3 a) { return v3_dot(a, a); }
static inline float v3_len(vec3 a) { return sqrtf(v3_dot(a, a)); }
static inline vec3 v3_norm(vec3 a) {
  float l = v3_len(a);
  return l > 0.f ? v3_scale(a, 1.f / l) : a;
}
static inline float v3_maxc(vec3 a) { return fmaxf(a.x, fmaxf(a.y, a.z)); }
static inline vec3 v3_min(vec3 a, vec3 b) { return v3(fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)); }
static inline vec3 v3_max(vec3 a, vec3 b) { return v3(fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)); }
static inline float v3_minc(vec3 a) { return fminf(a.x, fminf(a.y, a.z)); }
/* max of two floats known not to be NaN: one maxss, where fmaxf is a libm call (its NaN rule
 * keeps the compiler from inlining it without -ffinite-math-only). */
static inline float pc_maxf(float a, float b) { return a > b ? a : b; }
static inline float v3_maxabs(vec3 a) { return pc_maxf(fabsf(a.x), pc_maxf(fabsf(a.y), fabsf(a.z))); }
static inline float v3_luminance(vec3 c) { return 0.212671f * c.x + 0.715160f * c.y + 0.072169f * c.z; }
/* Rec. 709 luminance in double precision, rounded coefficients: what images are measured in
 * (the film's trace of single iterations, a study's tails and strategy shares). */
static inline double pc_luminance709(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
/* The two tests below read the bits: written with && over float compares they were three
 * compare-and-branch pairs each (with the branches for NaN's parity flag); this way a
 * cornell-box BDPT eye pass executes 0.8% fewer instructions. A float is +-0 iff its bits
 * shifted out of the sign are 0, and finite iff its exponent bits are not all set. */
static inline uint32_t pc_float_bits(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return u;
}
static inline bool v3_is_zero(vec3 a) { return ((pc_float_bits(a.x) | pc_float_bits(a.y) | pc_float_bits(a.z)) << 1) == 0; }
static inline bool v3_is_finite(vec3 a) {
  uint32_t e = 0x7f800000u;
  /* bitwise & on purpose: no branch per component */
  int fx = (pc_float_bits(a.x) & e) != e, fy = (pc_float_bits(a.y) & e) != e, fz = (pc_float_bits(a.z) & e) != e;
  return (fx & fy & fz) != 0;
}
static inline float v3_get(vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }

/* Orthonormal frame (s, t, n); local coordinates have n as +z. */
typedef struct frame { vec3 s, t, n; } frame;

/* Duff et al. 2017, "Building an orthonormal basis, revisited": branch-free and continuous. */
static inline frame frame_from_normal(vec3 n) {
  float sign = copysignf(1.f, n.z);
  float a = -1.f / (sign + n.z);
  float b = n.x * n.y * a;
  frame f;
  f.s = v3(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x);
  f.t = v3(b, sign + n.y * n.y * a, -n.y);
  f.n = n;
  return f;
}
/* Mitsuba's Frame(n) (coordinateSystem in its libcore/util.cpp): its tangents are where Mitsuba
 * puts u = 0 on a cylinder, and s is the up it gives a <lookat> that names none. */
static inline frame frame_mitsuba(vec3 n) {
  vec3 t;
  if (fabsf(n.x) > fabsf(n.y)) {
    float inv = 1.f / sqrtf(n.x * n.x + n.z * n.z);
    t = v3(n.z * inv, 0.f, -n.x * inv);
  } else {
    float inv = 1.f / sqrtf(n.y * n.y + n.z * n.z);
    t = v3(0.f, n.z * inv, -n.y * inv);
  }
  return (frame){v3_cross(t, n), t, n};
}
static inline vec3 frame_to_local(const frame *f, vec3 v) {
  return v3(v3_dot(v, f->s), v3_dot(v, f->t), v3_dot(v, f->n));
}
static inline vec3 frame_to_world(const frame *f, vec3 v) {
  return v3_add(v3_add(v3_scale(f->s, v.x), v3_scale(f->t, v.y)), v3_scale(f->n, v.z));
}

/* Row-major 4x4 matrix: m[r][c]; points are column vectors (p' = M p). */
typedef struct mat4 { double m[4][4]; } mat4;

static inline mat4 mat4_identity(void) {
  mat4 r = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
  return r;
}
static inline mat4 mat4_mul(const mat4 *a, const mat4 *b) {
  mat4 r;
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      double s = 0;
      for (int k = 0; k < 4; k++) s += a->m[i][k] * b->m[k][j];
      r.m[i][j] = s;
    }
  return r;
}
static inline vec3 mat4_point(const mat4 *a, vec3 p) {
  double x = a->m[0][0] * p.x + a->m[0][1] * p.y + a->m[0][2] * p.z + a->m[0][3];
  double y = a->m[1][0] * p.x + a->m[1][1] * p.y + a->m[1][2] * p.z + a->m[1][3];
  double z = a->m[2][0] * p.x + a->m[2][1] * p.y + a->m[2][2] * p.z + a->m[2][3];
  double w = a->m[3][0] * p.x + a->m[3][1] * p.y + a->m[3][2] * p.z + a->m[3][3];
  if (w != 1.0 && w != 0.0) { x /= w; y /= w; z /= w; }
  return v3((float)x, (float)y, (float)z);
}
static inline vec3 mat4_vector(const mat4 *a, vec3 v) {
  return v3((float)(a->m[0][0] * v.x + a->m[0][1] * v.y + a->m[0][2] * v.z),
            (float)(a->m[1][0] * v.x + a->m[1][1] * v.y + a->m[1][2] * v.z),
            (float)(a->m[2][0] * v.x + a->m[2][1] * v.y + a->m[2][2] * v.z));
}
/* Transforms a normal by the inverse transpose; `inv` is the inverse of the transform. */
static inline vec3 mat4_normal(const mat4 *inv, vec3 n) {
  return v3((float)(inv->m[0][0] * n.x + inv->m[1][0] * n.y + inv->m[2][0] * n.z),
            (float)(inv->m[0][1] * n.x + inv->m[1][1] * n.y + inv->m[2][1] * n.z),
            (float)(inv->m[0][2] * n.x + inv->m[1][2] * n.y + inv->m[2][2] * n.z));
}
/* General inverse by Gauss-Jordan with partial pivoting; returns false when singular. */
bool mat4_inverse(const mat4 *a, mat4 *out);

/* A point of the unit disk from a uniform sample of [0,1)^2 by Shirley's concentric map, which
 * keeps strata compact (cosine-weighted hemisphere sampling and the thin lens use it). */
vec2 pc_sample_concentric_disk(float u1, float u2);

#endif
