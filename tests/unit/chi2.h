/* chi2.h: Pearson's chi-square goodness-of-fit test as pbrt and Mitsuba use it to validate
 * sampling routines: cells with small expected counts are pooled, the p-value comes from the
 * regularized upper incomplete gamma function. Header-only, for tests. */
#ifndef PC_TEST_CHI2_H
#define PC_TEST_CHI2_H

#include <math.h>
#include <stdlib.h>

/* Q(a, x) = Gamma(a, x) / Gamma(a): series below a + 1, Lentz's continued fraction above
 * (Numerical Recipes 6.2). */
static double pc_gamma_q(double a, double x) {
  if (!(a > 0) || !(x >= 0)) return NAN;
  if (x == 0) return 1;
  double lg = -x + a * log(x) - lgamma(a);
  if (x < a + 1) {
    double ap = a, del = 1 / a, sum = del;
    for (int n = 0; n < 10000; n++) {
      ap += 1;
      del *= x / ap;
      sum += del;
      if (fabs(del) < fabs(sum) * 1e-15) break;
    }
    return 1 - sum * exp(lg);
  }
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 10000; i++) {
    double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (fabs(c) < tiny) c = tiny;
    d = 1 / d;
    double del = d * c;
    h *= del;
    if (fabs(del - 1) < 1e-15) break;
  }
  return exp(lg) * h;
}

typedef struct pc_chi2_cell { double obs, exp; } pc_chi2_cell;

static int pc_chi2_cmp(const void *a, const void *b) {
  double x = ((const pc_chi2_cell *)a)->exp, y = ((const pc_chi2_cell *)b)->exp;
  return (x > y) - (x < y);
}

/* p-value of observed vs expected counts over n cells (sorted in place). Cells expecting fewer
 * than 5 are pooled; a sample in a cell expecting exactly nothing gives p = 0. */
static double pc_chi2_test(pc_chi2_cell *cells, int n, double *stat_out, int *dof_out) {
  qsort(cells, (size_t)n, sizeof *cells, pc_chi2_cmp);
  double stat = 0, pobs = 0, pexp = 0;
  int dof = 0;
  for (int i = 0; i < n; i++) {
    double o = cells[i].obs, e = cells[i].exp;
    if (e <= 0) {
      if (o > 0) return 0;
      continue;
    }
    if (e < 5 || (pexp > 0 && pexp < 5)) {
      pobs += o;
      pexp += e;
      continue;
    }
    stat += (o - e) * (o - e) / e;
    dof++;
  }
  if (pexp > 0) {
    stat += (pobs - pexp) * (pobs - pexp) / pexp;
    dof++;
  }
  dof -= 1;
  if (stat_out) *stat_out = stat;
  if (dof_out) *dof_out = dof;
  if (dof <= 0) return 1;
  return pc_gamma_q(dof / 2.0, stat / 2.0);
}

#endif
