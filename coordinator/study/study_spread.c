/* study_spread.c: a study repeated over --runs seeds: each method's median curve (with the
 * runs' min and max around it) on a common grid of times, and per layer the spread of the
 * runs' final errors and times to the target. The median curves are ordinary runs, so the
 * one-run table (study_table.c) summarises them as it summarises a single run. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "study.h"

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

/* Median of the finite values of v (reordered); NAN when none. */
double pc_study_median(double *v, int n, double *lo, double *hi) {
  int k = 0;
  for (int i = 0; i < n; i++)
    if (isfinite(v[i])) v[k++] = v[i];
  if (lo) *lo = NAN;
  if (hi) *hi = NAN;
  if (!k) return NAN;
  qsort(v, (size_t)k, sizeof *v, cmp_double);
  if (lo) *lo = v[0];
  if (hi) *hi = v[k - 1];
  return k % 2 ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
}

/* Run's metric field (0 relmse, 1 rmse, 2 l1) of slot at time t, log-log interpolated between
 * the snapshots around t, the last one a little past its time (a job stops a little after
 * its budget), NAN outside. */
static double field_of(const pc_study_snap *s, int slot, int field) {
  return field == 0 ? s->m[slot].relmse : field == 1 ? s->m[slot].rmse : s->m[slot].l1;
}

static double time_of(const pc_study_snap *s, bool wall) { return wall ? s->wall : s->seconds; }

static double at_time(const pc_study_run *r, int slot, int field, double t, bool wall) {
  for (int i = 0; i < r->nsnaps; i++) {
    const pc_study_snap *b = &r->snaps[i];
    double tb = time_of(b, wall), yb = field_of(b, slot, field);
    if (tb < t) continue;
    if (i == 0) return tb <= t * 1.0001 ? yb : NAN;
    const pc_study_snap *a = &r->snaps[i - 1];
    double ta = time_of(a, wall), ya = field_of(a, slot, field);
    if (tb == t) return yb;
    if (!(ta > 0) || !(ya > 0) || !(yb > 0) || tb <= ta) return NAN; /* no log-log line through them */
    double u = (log(t) - log(ta)) / (log(tb) - log(ta));
    return exp(log(ya) + u * (log(yb) - log(ya)));
  }
  if (r->nsnaps) {
    const pc_study_snap *l = &r->snaps[r->nsnaps - 1];
    if (t <= time_of(l, wall) * 1.05) return field_of(l, slot, field);
  }
  return NAN;
}

int pc_study_median_run(const pc_study_run *runs, int nruns, int npoints, double t_end, bool wall, pc_study_run *out,
                        pc_study_band band[PC_STUDY_NLAYERS], pc_err *e) {
  memset(out, 0, sizeof *out);
  if (nruns < 1 || npoints < 1) return pc_errf(e, PC_EINVAL, "study: no runs to summarise");
  out->method = runs[0].method;
  out->threads = runs[0].threads;
  out->workers = runs[0].workers;
  memcpy(out->layer_empty, runs[0].layer_empty, sizeof out->layer_empty);
  out->unlike = runs[0].unlike;
  memcpy(out->weights, runs[0].weights, sizeof out->weights);
  out->snaps = calloc((size_t)npoints, sizeof *out->snaps);
  double *v = malloc((size_t)nruns * sizeof *v);
  if (band) memset(band, 0, sizeof(pc_study_band) * PC_STUDY_NLAYERS);
  for (int s = 0; band && s < PC_STUDY_NLAYERS; s++) {
    band[s].t = calloc((size_t)npoints * 3, sizeof(double));
    band[s].lo = band[s].t ? band[s].t + npoints : NULL;
    band[s].hi = band[s].t ? band[s].t + 2 * npoints : NULL;
    if (!band[s].t) v = (free(v), NULL);
  }
  if (!out->snaps || !v) {
    free(v);
    pc_study_run_free(out);
    for (int s = 0; band && s < PC_STUDY_NLAYERS; s++) free(band[s].t);
    return pc_errf(e, PC_ENOMEM, "out of memory for the median curves");
  }
  for (int k = 0; k < npoints; k++) {
    double t = npoints == 1 ? t_end : t_end * pow(PC_STUDY_FIRST_FRACTION, (double)(npoints - 1 - k) / (npoints - 1));
    pc_study_snap *sn = &out->snaps[out->nsnaps];
    memset(sn, 0, sizeof *sn);
    sn->seconds = t;
    bool any = false;
    for (int slot = 0; slot < PC_STUDY_NLAYERS; slot++) {
      double lo = NAN, hi = NAN;
      for (int field = 0; field < 3; field++) {
        for (int r = 0; r < nruns; r++) v[r] = at_time(&runs[r], slot, field, t, wall);
        double med = pc_study_median(v, nruns, field == 0 ? &lo : NULL, field == 0 ? &hi : NULL);
        if (field == 0) sn->m[slot].relmse = med;
        else if (field == 1) sn->m[slot].rmse = med;
        else sn->m[slot].l1 = med;
      }
      if (slot == PC_STUDY_BEAUTY) any = isfinite(sn->m[slot].relmse);
      if (band) {
        band[slot].t[band[slot].n] = t;
        band[slot].lo[band[slot].n] = lo;
        band[slot].hi[band[slot].n] = hi;
      }
    }
    /* a time no run has reached yet is left out (the beauty is measured whenever any is) */
    if (!any) continue;
    out->nsnaps++;
    for (int s = 0; band && s < PC_STUDY_NLAYERS; s++) band[s].n++;
  }
  free(v);
  return PC_OK;
}

void pc_study_band_free(pc_study_band band[PC_STUDY_NLAYERS]) {
  for (int s = 0; s < PC_STUDY_NLAYERS; s++) {
    free(band[s].t);
    band[s].t = band[s].lo = band[s].hi = NULL;
    band[s].n = 0;
  }
}

/* Times to target of one method's runs, on the render-time or the wall axis. */
static void times_to(const pc_study_run *runs, int nruns, int slot, double target, bool wall, double *t) {
  for (int r = 0; r < nruns; r++) {
    pc_reach how;
    if (!wall) {
      t[r] = pc_study_time_to_error(&runs[r], slot, target, &how);
      continue;
    }
    pc_study_run w = runs[r];
    pc_study_snap *s = malloc((size_t)(w.nsnaps ? w.nsnaps : 1) * sizeof *s);
    if (!s) { t[r] = NAN; continue; }
    for (int i = 0; i < w.nsnaps; i++) {
      s[i] = runs[r].snaps[i];
      s[i].seconds = s[i].wall;
    }
    w.snaps = s;
    t[r] = pc_study_time_to_error(&w, slot, target, &how);
    free(s);
  }
}

void pc_study_spread_cell(const pc_study_run *runs, int nruns, const pc_study_run *first_runs, int slot, double target,
                          bool wall, double t_end, pc_study_spread *c) {
  double f[PC_STUDY_MAX_RUNS], t[PC_STUDY_MAX_RUNS], t0[PC_STUDY_MAX_RUNS], ratio[PC_STUDY_MAX_RUNS];
  if (nruns > PC_STUDY_MAX_RUNS) nruns = PC_STUDY_MAX_RUNS;
  memset(c, 0, sizeof *c);
  c->n = nruns;
  for (int r = 0; r < nruns; r++)
    f[r] = t_end > 0 ? at_time(&runs[r], slot, 0, t_end, false)
           : runs[r].nsnaps ? runs[r].snaps[runs[r].nsnaps - 1].m[slot].relmse : NAN;
  c->final_med = pc_study_median(f, nruns, &c->final_lo, &c->final_hi);
  times_to(runs, nruns, slot, target, wall, t);
  times_to(first_runs, nruns, slot, target, wall, t0);
  for (int r = 0; r < nruns; r++) {
    c->reached += isfinite(t[r]);
    ratio[r] = isfinite(t[r]) && t0[r] > 0 ? t[r] / t0[r] : NAN;
  }
  c->time_med = pc_study_median(t, nruns, &c->time_lo, &c->time_hi);
  c->ratio_med = pc_study_median(ratio, nruns, &c->ratio_lo, &c->ratio_hi);
}
