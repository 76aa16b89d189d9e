/* study_table.c: the summary of an equal-time study: per layer and method, the final relMSE and
 * its ratio to the first method's, and the render time each method needs to reach a target
 * relMSE (interpolated in log-log between snapshots) with its ratio to the first method's. */
#include <math.h>
#include <string.h>

#include "study.h"

double pc_study_time_to_error(const pc_study_run *run, int slot, double target, pc_reach *how) {
  if (pc_study_excluded(run, slot)) {
    *how = run->layer_empty[slot] ? PC_REACH_EXCLUDED : PC_REACH_UNLIKE;
    return NAN;
  }
  for (int i = 0; i < run->nsnaps; i++) {
    double ei = run->snaps[i].m[slot].relmse, ti = run->snaps[i].seconds;
    if (!(ei <= target)) continue;
    if (i == 0) {
      *how = PC_REACH_BY_FIRST;
      return ti;
    }
    *how = PC_REACH_INTERPOLATED;
    double ep = run->snaps[i - 1].m[slot].relmse, tp = run->snaps[i - 1].seconds;
    /* ep > target >= ei; an exact zero error has no logarithm: take the snapshot's time. */
    if (!(ei > 0) || !(tp > 0)) return ti;
    double u = (log(target) - log(ep)) / (log(ei) - log(ep));
    return exp(log(tp) + u * (log(ti) - log(tp)));
  }
  *how = PC_REACH_NEVER;
  return NAN;
}

static double final_relmse(const pc_study_run *r, int slot) {
  return r->nsnaps ? r->snaps[r->nsnaps - 1].m[slot].relmse : NAN;
}

void pc_study_table_build(const pc_study_run *runs, int nruns, const pc_study_ref *ref, int headline_slot,
                          double target_error, pc_study_table *t) {
  memset(t, 0, sizeof *t);
  t->nmethods = nruns;
  for (int m = 0; m < nruns; m++) t->name[m] = runs[m].method.name;
  for (int slot = 0; slot < PC_STUDY_NLAYERS; slot++) {
    if (!pc_study_ref_has(ref, slot)) continue;
    int row = t->nlayers++;
    t->slot[row] = slot;
    if (slot == headline_slot) t->headline = row;
    double target = -INFINITY;
    if (slot == headline_slot && target_error > 0) {
      target = target_error;
      t->target_given[row] = true;
    } else {
      for (int m = 0; m < nruns; m++)
        if (!pc_study_excluded(&runs[m], slot)) target = fmax(target, final_relmse(&runs[m], slot));
    }
    t->target[row] = isfinite(target) ? target : NAN;
    for (int m = 0; m < nruns; m++) {
      pc_study_cell *c = &t->cell[row][m];
      c->final_relmse = final_relmse(&runs[m], slot);
      c->time = pc_study_time_to_error(&runs[m], slot, t->target[row], &c->reach);
      const pc_study_cell *c0 = &t->cell[row][0];
      bool comparable = !pc_study_excluded(&runs[m], slot) && !pc_study_excluded(&runs[0], slot);
      c->relmse_ratio = comparable && c0->final_relmse > 0 ? c->final_relmse / c0->final_relmse : NAN;
      c->time_ratio = c0->time > 0 ? c->time / c0->time : NAN; /* NAN propagates from unreached */
    }
  }
}

static const char *method_name(const pc_study_table *t, int m) { return t->name[m]; }

static bool left_out(const pc_study_cell *c) { return c->reach == PC_REACH_EXCLUDED || c->reach == PC_REACH_UNLIKE; }

static const char *left_out_why(const pc_study_cell *c) {
  return c->reach == PC_REACH_EXCLUDED ? "  (layer empty)" : c->reach == PC_REACH_UNLIKE ? "  (weighted unlike the reference)" : "";
}

static bool is_bound(const pc_study_table *t, int row, int m) {
  return t->cell[row][m].reach == PC_REACH_BY_FIRST || t->cell[row][0].reach == PC_REACH_BY_FIRST;
}

void pc_study_table_print(FILE *f, const pc_study_table *t) {
  char ratio_hdr[32];
  snprintf(ratio_hdr, sizeof ratio_hdr, "vs %s", method_name(t, 0));
  fprintf(f, "%-7s %-6s %13s %10s %12s %13s %10s\n", "layer", "method", "final relMSE", ratio_hdr, "target", "time to target",
          ratio_hdr);
  for (int row = 0; row < t->nlayers; row++)
    for (int m = 0; m < t->nmethods; m++) {
      const pc_study_cell *c = &t->cell[row][m];
      char ratio[32] = "-", time[32] = "-", tratio[32] = "-";
      if (isfinite(c->relmse_ratio)) snprintf(ratio, sizeof ratio, "%.2fx", c->relmse_ratio);
      if (c->reach == PC_REACH_NEVER) snprintf(time, sizeof time, "not reached");
      else if (!left_out(c)) snprintf(time, sizeof time, "%s%.3g s", c->reach == PC_REACH_BY_FIRST ? "<=" : "", c->time);
      if (isfinite(c->time_ratio)) snprintf(tratio, sizeof tratio, "%s%.2fx", is_bound(t, row, m) ? "~" : "", c->time_ratio);
      fprintf(f, "%-7s %-6s %13.4e %10s %12.4e %13s %10s%s\n", pc_study_layer_name(t->slot[row]), method_name(t, m),
              c->final_relmse, ratio, t->target[row], time, tratio, left_out_why(c));
    }
}

void pc_study_headline(const pc_study_table *t, int m, char *buf, size_t size) {
  int row = t->headline;
  const pc_study_cell *c = &t->cell[row][m], *c0 = &t->cell[row][0];
  const char *a = method_name(t, m), *b = method_name(t, 0), *layer = pc_study_layer_name(t->slot[row]);
  size_t n = 0;
  if (isfinite(c->relmse_ratio)) {
    int k = snprintf(buf, size, "%s/%s %s relMSE %.2fx; ", a, b, layer, c->relmse_ratio);
    n = k > 0 && (size_t)k < size ? (size_t)k : 0;
  }
  if (left_out(c) || left_out(c0)) {
    const pc_study_cell *out = left_out(c) ? c : c0;
    if (out->reach == PC_REACH_EXCLUDED)
      snprintf(buf + n, size - n, "%s leaves the %s layer empty: no time comparison", out == c ? a : b, layer);
    else
      snprintf(buf + n, size - n, "%s weighs the %s layer's strategies unlike the reference: no time comparison",
               out == c ? a : b, layer);
  } else if (!isfinite(c->time_ratio))
    snprintf(buf + n, size - n, "%s does not reach %s relMSE %.3g within the budget", c->reach == PC_REACH_NEVER ? a : b,
             layer, t->target[row]);
  else
    snprintf(buf + n, size - n, "%s needs %s%.2fx %s time than %s to reach %s relMSE %.3g%s", a,
             is_bound(t, row, m) ? "~" : "", c->time_ratio >= 1 ? c->time_ratio : 1 / c->time_ratio,
             c->time_ratio >= 1 ? "more" : "less", b, layer, t->target[row],
             is_bound(t, row, m) ? " (reached by the first snapshot: a bound only)" : "");
}
