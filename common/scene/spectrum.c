/* spectrum.c: spectra to RGB as Mitsuba 0.6's RGB mode converts them (see spectrum.h). The
 * integrals are exact for sampled spectra (both factors are linear between breakpoints, so
 * Simpson's rule is exact there) and converge to 1e-9 for Planck's law. */
#include "spectrum.h"

#include <math.h>
#include <stdlib.h>

static double cmf(int k, double l) {
  double x = (l - PC_CIE_MIN) / PC_CIE_STEP;
  if (x < 0 || x > PC_CIE_SAMPLES - 1) return 0;
  int i = (int)x;
  if (i >= PC_CIE_SAMPLES - 1) return pc_cie1931[k][PC_CIE_SAMPLES - 1];
  double t = x - i;
  return (1 - t) * pc_cie1931[k][i] + t * pc_cie1931[k][i + 1];
}

/* The integral of y-bar over 360..830 nm (trapezoids: y-bar is linear between samples). */
static double y_integral(void) {
  double s = 0;
  for (int i = 0; i + 1 < PC_CIE_SAMPLES; i++) s += 0.5 * PC_CIE_STEP * (pc_cie1931[1][i] + pc_cie1931[1][i + 1]);
  return s;
}

void pc_xyz_to_rgb(const double xyz[3], double rgb[3]) {
  double x = xyz[0], y = xyz[1], z = xyz[2];
  rgb[0] = 3.240479 * x - 1.537150 * y - 0.498535 * z;
  rgb[1] = -0.969256 * x + 1.875991 * y + 0.041556 * z;
  rgb[2] = 0.055648 * x - 0.204043 * y + 1.057311 * z;
}

static void finish(double xyz[3], double rgb[3]) {
  double norm = y_integral();
  for (int k = 0; k < 3; k++) xyz[k] /= norm;
  pc_xyz_to_rgb(xyz, rgb);
  for (int k = 0; k < 3; k++)
    if (rgb[k] < 0) rgb[k] = 0; /* Mitsuba's clampNegative */
}

typedef struct pl {
  const double *l, *v;
  int n;
} pl;

static double pl_eval(const pl *s, double x) {
  if (x < s->l[0] || x > s->l[s->n - 1]) return 0;
  int lo = 0, hi = s->n - 1;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (s->l[mid] <= x) lo = mid;
    else hi = mid;
  }
  double t = (x - s->l[lo]) / (s->l[hi] - s->l[lo]);
  return (1 - t) * s->v[lo] + t * s->v[hi];
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int pc_spectrum_sampled_rgb(const double *lambda, const double *value, int n, double rgb[3]) {
  if (n < 2 || n > PC_SPECTRUM_MAX_SAMPLES) return -1;
  for (int i = 1; i < n; i++)
    if (!(lambda[i] > lambda[i - 1])) return -1;
  double l[PC_SPECTRUM_MAX_SAMPLES + 2], v[PC_SPECTRUM_MAX_SAMPLES + 2];
  double avg = (lambda[n - 1] - lambda[0]) / (n - 1);
  int m = 0;
  if (value[0] != 0) l[m] = lambda[0] - avg, v[m++] = 0;
  for (int i = 0; i < n; i++) l[m] = lambda[i], v[m++] = value[i];
  if (value[n - 1] != 0) l[m] = lambda[n - 1] + avg, v[m++] = 0;
  pl s = {l, v, m};
  /* breakpoints: the CIE grid and the spectrum's own wavelengths inside 360..830 */
  double bp[PC_CIE_SAMPLES + PC_SPECTRUM_MAX_SAMPLES + 2];
  int nb = 0;
  for (int i = 0; i < PC_CIE_SAMPLES; i++) bp[nb++] = PC_CIE_MIN + PC_CIE_STEP * i;
  double hi = PC_CIE_MIN + PC_CIE_STEP * (PC_CIE_SAMPLES - 1);
  for (int i = 0; i < m; i++)
    if (l[i] > PC_CIE_MIN && l[i] < hi) bp[nb++] = l[i];
  qsort(bp, (size_t)nb, sizeof bp[0], cmp_double);
  double xyz[3] = {0, 0, 0};
  for (int i = 0; i + 1 < nb; i++) {
    double a = bp[i], b = bp[i + 1], c = 0.5 * (a + b);
    if (!(b > a)) continue;
    double sa = pl_eval(&s, a), sc = pl_eval(&s, c), sb = pl_eval(&s, b);
    for (int k = 0; k < 3; k++)
      xyz[k] += (b - a) / 6 * (sa * cmf(k, a) + 4 * sc * cmf(k, c) + sb * cmf(k, b));
  }
  finish(xyz, rgb);
  return 0;
}

double pc_blackbody(double kelvin, double lambda_nm) {
  const double c = 299792458, k = 1.3806488e-23, h = 6.62606957e-34; /* Mitsuba's constants */
  double l = lambda_nm * 1e-9;
  return (2 * h * c * c) * pow(l, -5.0) / ((exp((h / k) * c / (l * kelvin)) - 1.0) * 1e9);
}

void pc_spectrum_blackbody_rgb(double kelvin, double rgb[3]) {
  /* composite Simpson on each 5 nm CIE interval, where the colour matching functions are linear */
  enum { SUB = 32 };
  double xyz[3] = {0, 0, 0};
  for (int i = 0; i + 1 < PC_CIE_SAMPLES; i++) {
    double a = PC_CIE_MIN + PC_CIE_STEP * i, hstep = PC_CIE_STEP / SUB;
    for (int j = 0; j <= SUB; j++) {
      double x = a + j * hstep, w = (j == 0 || j == SUB) ? 1 : (j % 2 ? 4 : 2);
      double f = pc_blackbody(kelvin, x) * w * hstep / 3;
      /* the interval's own linear pieces (at x = a + 5 nm cmf() would use the next ones, which agree there) */
      for (int k = 0; k < 3; k++) xyz[k] += f * cmf(k, x);
    }
  }
  finish(xyz, rgb);
}
