/* vecmath.c: the parts of vecmath.h too large to inline. */
#include "vecmath.h"

bool mat4_inverse(const mat4 *a, mat4 *out) {
  double m[4][8];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      m[i][j] = a->m[i][j];
      m[i][j + 4] = i == j ? 1.0 : 0.0;
    }
  for (int c = 0; c < 4; c++) {
    int piv = c;
    for (int r = c + 1; r < 4; r++)
      if (fabs(m[r][c]) > fabs(m[piv][c])) piv = r;
    if (!(fabs(m[piv][c]) > 1e-300)) return false;
    if (piv != c)
      for (int j = 0; j < 8; j++) {
        double t = m[c][j];
        m[c][j] = m[piv][j];
        m[piv][j] = t;
      }
    double inv = 1.0 / m[c][c];
    for (int j = 0; j < 8; j++) m[c][j] *= inv;
    for (int r = 0; r < 4; r++) {
      if (r == c) continue;
      double f = m[r][c];
      if (f != 0.0)
        for (int j = 0; j < 8; j++) m[r][j] -= f * m[c][j];
    }
  }
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) out->m[i][j] = m[i][j + 4];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++)
      if (!isfinite(out->m[i][j])) return false;
  return true;
}

vec2 pc_sample_concentric_disk(float u1, float u2) {
  float a = 2.f * u1 - 1.f, b = 2.f * u2 - 1.f, r, phi;
  if (a == 0.f && b == 0.f) return (vec2){0.f, 0.f};
  if (a * a > b * b) {
    r = a;
    phi = (PC_PI / 4.f) * (b / a);
  } else {
    r = b;
    phi = (PC_PI / 2.f) - (PC_PI / 4.f) * (a / b);
  }
  return (vec2){r * cosf(phi), r * sinf(phi)};
}
