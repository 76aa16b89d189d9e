/* anim.c: Mitsuba 0.6's AnimatedTransform (libcore/track.cpp): keyframes decomposed as
 * appendTransform does, evaluated as its tracks' eval and TransformFunctor do. */
#include "anim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double det3(const double a[3][3]) {
  return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
         a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

/* The orthogonal factor of the polar decomposition A = Q P (Mitsuba takes U V^T of an SVD; the
 * factor is unique for a nonsingular A, and Higham's iteration Q <- (Q + Q^-T) / 2 reaches it). */
static bool polar_q(const double a[3][3], double q[3][3]) {
  memcpy(q, a, sizeof(double[3][3]));
  for (int it = 0; it < 100; it++) {
    double d = det3(q);
    if (!(fabs(d) > 1e-300) || !isfinite(d)) return false;
    double next[3][3], change = 0;
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) {
        /* (Q^-T)[r][c] = cofactor(r, c) / det */
        int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
        double cof = q[r1][c1] * q[r2][c2] - q[r1][c2] * q[r2][c1];
        next[r][c] = 0.5 * (q[r][c] + cof / d);
        change = fmax(change, fabs(next[r][c] - q[r][c]));
      }
    memcpy(q, next, sizeof next);
    if (change < 1e-14) return true;
  }
  return true; /* converged to rounding for any nonsingular A long before */
}

static void quat_from_rotation(const double m[3][3], double q[4]) {
  double tr = m[0][0] + m[1][1] + m[2][2];
  if (tr > 0) {
    double s = sqrt(tr + 1.0), f = 0.5 / s;
    q[3] = 0.5 * s;
    q[0] = (m[2][1] - m[1][2]) * f;
    q[1] = (m[0][2] - m[2][0]) * f;
    q[2] = (m[1][0] - m[0][1]) * f;
    return;
  }
  int i = 0;
  if (m[1][1] > m[0][0]) i = 1;
  if (m[2][2] > m[i][i]) i = 2;
  int j = (i + 1) % 3, k = (i + 2) % 3;
  double s = sqrt(m[i][i] - m[j][j] - m[k][k] + 1.0), f = s != 0 ? 0.5 / s : 0;
  q[i] = 0.5 * s;
  q[3] = (m[k][j] - m[j][k]) * f;
  q[j] = (m[j][i] + m[i][j]) * f;
  q[k] = (m[k][i] + m[i][k]) * f;
}

int pc_anim_append(pc_anim *a, double time, const mat4 *m, pc_err *e) {
  if (!isfinite(time)) return pc_errf(e, PC_EINVAL, "keyframe time is not finite");
  if (a->n >= PC_ANIM_MAX_KEYS) return pc_errf(e, PC_ELIMIT, "more than %d keyframes", PC_ANIM_MAX_KEYS);
  if (a->n == a->cap) {
    int cap = a->cap ? 2 * a->cap : 4;
    pc_keyframe *k = realloc(a->k, (size_t)cap * sizeof *k);
    if (!k) return pc_errf(e, PC_ENOMEM, "out of memory for keyframes");
    a->k = k, a->cap = cap;
  }
  double l[3][3], q[3][3];
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) l[r][c] = m->m[r][c];
  if (!polar_q(l, q)) return pc_errf(e, PC_EINVAL, "the keyframe at time %g is singular (a zero scale)", time);
  /* P = Q^T A; Mitsuba flips both factors when Q mirrors, so the rotation is proper */
  double sign = det3(q) < 0 ? -1.0 : 1.0;
  pc_keyframe *k = &a->k[a->n];
  k->time = time;
  for (int i = 0; i < 3; i++) {
    double p = 0;
    for (int r = 0; r < 3; r++) p += q[r][i] * l[r][i];
    k->s[i] = sign * p;
    k->t[i] = m->m[i][3];
  }
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) q[r][c] *= sign;
  quat_from_rotation(q, k->q);
  if (!isfinite(k->s[0] + k->s[1] + k->s[2] + k->t[0] + k->t[1] + k->t[2]))
    return pc_errf(e, PC_EINVAL, "the keyframe at time %g is not finite", time);
  a->n++;
  return PC_OK;
}

static int by_time(const void *x, const void *y) {
  double a = ((const pc_keyframe *)x)->time, b = ((const pc_keyframe *)y)->time;
  return (a > b) - (a < b);
}

int pc_anim_finish(pc_anim *a, pc_err *e) {
  if (a->n == 0) return pc_errf(e, PC_EINVAL, "an animation without keyframes");
  qsort(a->k, (size_t)a->n, sizeof *a->k, by_time);
  for (int i = 1; i < a->n; i++)
    if (a->k[i].time == a->k[i - 1].time) return pc_errf(e, PC_EINVAL, "two keyframes at time %g", a->k[i].time);
  return PC_OK;
}

bool pc_anim_is_static(const pc_anim *a) {
  for (int i = 1; i < a->n; i++) {
    const pc_keyframe *p = &a->k[0], *k = &a->k[i];
    /* q and -q are one rotation */
    double dq = fabs(p->q[0] * k->q[0] + p->q[1] * k->q[1] + p->q[2] * k->q[2] + p->q[3] * k->q[3]);
    for (int j = 0; j < 3; j++)
      if (p->t[j] != k->t[j] || p->s[j] != k->s[j]) return false;
    if (dq < 1.0 - 1e-12) return false;
  }
  return true;
}

static void slerp(const double q1[4], const double q2in[4], double t, double out[4]) {
  double q2[4], c = 0, n = 0;
  for (int i = 0; i < 4; i++) c += q1[i] * q2in[i];
  double sg = c < 0 ? -1.0 : 1.0; /* the short way */
  c *= sg;
  for (int i = 0; i < 4; i++) q2[i] = sg * q2in[i];
  if (c > 0.9995) {
    for (int i = 0; i < 4; i++) out[i] = q1[i] * (1 - t) + q2[i] * t, n += out[i] * out[i];
    for (int i = 0; i < 4; i++) out[i] /= sqrt(n);
    return;
  }
  double theta = acos(fmin(1.0, c)) * t, perp[4];
  for (int i = 0; i < 4; i++) perp[i] = q2[i] - q1[i] * c, n += perp[i] * perp[i];
  for (int i = 0; i < 4; i++) out[i] = q1[i] * cos(theta) + perp[i] / sqrt(n) * sin(theta);
}

mat4 pc_anim_eval(const pc_anim *a, double time) {
  if (a->n == 0) return mat4_identity();
  /* Mitsuba's track lookup: the first key at or after `time`, and the one before it */
  int hi = 0;
  while (hi < a->n && a->k[hi].time < time) hi++;
  int i0 = hi > 0 ? hi - 1 : 0, i1 = i0 + 1 < a->n ? i0 + 1 : a->n - 1;
  const pc_keyframe *k0 = &a->k[i0], *k1 = &a->k[i1];
  double f = 0.5;
  if (k0->time != k1->time) f = (fmax(k0->time, fmin(k1->time, time)) - k0->time) / (k1->time - k0->time);
  double t[3], s[3], q[4];
  for (int i = 0; i < 3; i++) {
    t[i] = k0->t[i] * (1 - f) + k1->t[i] * f;
    s[i] = k0->s[i] * (1 - f) + k1->s[i] * f;
  }
  slerp(k0->q, k1->q, f, q);
  double x = q[0], y = q[1], z = q[2], w = q[3];
  double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                    {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                    {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  /* Mitsuba skips a zero scale vector rather than collapse the shape */
  bool scale = s[0] != 0 || s[1] != 0 || s[2] != 0;
  mat4 m = mat4_identity();
  for (int row = 0; row < 3; row++) {
    for (int c = 0; c < 3; c++) m.m[row][c] = r[row][c] * (scale ? s[c] : 1.0);
    m.m[row][3] = t[row];
  }
  return m;
}

double pc_anim_max_scale(const pc_anim *a) {
  double s = 0;
  for (int i = 0; i < a->n; i++)
    for (int j = 0; j < 3; j++) s = fmax(s, fabs(a->k[i].s[j]));
  return s > 0 ? s : 1.0;
}

bool pc_anim_same_scale(const pc_anim *a) {
  for (int i = 1; i < a->n; i++)
    for (int j = 0; j < 3; j++)
      if (fabs(a->k[i].s[j] - a->k[0].s[j]) > 1e-6 * fmax(1.0, fabs(a->k[0].s[j]))) return false;
  return true;
}

void pc_anim_free(pc_anim *a) {
  free(a->k);
  memset(a, 0, sizeof *a);
}
