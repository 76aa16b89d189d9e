/* study_files.c: what an equal-time study leaves on disk besides the images: study.csv (one row
 * per method, snapshot and layer), study.json (settings, curves and the summary table) and the
 * relMSE-against-time charts. Text files are written to a temporary name and renamed, so a
 * reader never sees half a file. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "chart.h"
#include "text_out.h"
#include "study.h"

typedef struct out_file {
  FILE *f;
  char tmp[4096];
  const char *path;
} out_file;

static int out_open(out_file *o, const char *path, pc_err *e) {
  o->path = path;
  int n = snprintf(o->tmp, sizeof o->tmp, "%s.tmp.%ld", path, (long)getpid());
  if (n < 0 || (size_t)n >= sizeof o->tmp) return pc_errf(e, PC_EINVAL, "%s: path too long", path);
  if (!(o->f = fopen(o->tmp, "w"))) return pc_errf(e, PC_EIO, "%s: cannot create: %s", o->tmp, strerror(errno));
  return PC_OK;
}

static int out_commit(out_file *o, pc_err *e) {
  bool bad = ferror(o->f) != 0;
  if (fclose(o->f) != 0) bad = true;
  if (bad) {
    unlink(o->tmp);
    return pc_errf(e, PC_EIO, "%s: write error", o->path);
  }
  if (rename(o->tmp, o->path) != 0) {
    int err = errno;
    unlink(o->tmp);
    return pc_errf(e, PC_EIO, "%s: cannot rename into place: %s", o->path, strerror(err));
  }
  return PC_OK;
}

int pc_study_write_csv(const char *path, const pc_study_run *runs, int nruns, const pc_study_ref *ref, pc_err *e) {
  out_file o;
  int rc = out_open(&o, path, e);
  if (rc != PC_OK) return rc;
  fprintf(o.f, "method,snapshot,seconds,iterations,layer,relmse,rmse,l1,workers,run,worker_seconds,wall_seconds\n");
  for (int r = 0; r < nruns; r++)
    for (int s = 0; s < runs[r].nsnaps; s++)
      for (int slot = 0; slot < PC_STUDY_NLAYERS; slot++) {
        if (!pc_study_ref_has(ref, slot)) continue;
        const pc_study_snap *sn = &runs[r].snaps[s];
        fprintf(o.f, "%s,%d,%.6f,%llu,%s,%.9g,%.9g,%.9g,%d,%d,%.6f,%.6f\n", runs[r].method.name, s,
                sn->seconds, (unsigned long long)sn->iterations, pc_study_layer_name(slot), sn->m[slot].relmse,
                sn->m[slot].rmse, sn->m[slot].l1, runs[r].workers, runs[r].run + 1, sn->worker_seconds, sn->wall);
      }
  return out_commit(&o, e);
}

static const char *reach_name(pc_reach r) {
  switch (r) {
  case PC_REACH_INTERPOLATED: return "interpolated";
  case PC_REACH_BY_FIRST: return "by_first_snapshot";
  case PC_REACH_NEVER: return "not_reached";
  case PC_REACH_EXCLUDED: return "layer_empty";
  case PC_REACH_UNLIKE: return "weighted_unlike_reference";
  }
  return "?";
}

/* The final image's heavy tails (study.h), null when it cannot tell. */
static void json_tails(FILE *f, const pc_study_tails *t) {
  if (!t->known) {
    fputs("null", f);
    return;
  }
  fprintf(f, "{\"iterations\": %llu, \"lit_fraction_of_mean\": %g, \"pixels\": %zu, \"max_over_mean_p50\": ",
          (unsigned long long)t->iterations, PC_STUDY_TAILS_LIT, t->pixels);
  pc_json_number(f, t->p50);
  fputs(", \"max_over_mean_p99\": ", f);
  pc_json_number(f, t->p99);
  fputs(", \"max_over_mean_max\": ", f);
  pc_json_number(f, t->max);
  fprintf(f, ", \"max_pixel\": [%d, %d]}", t->max_x, t->max_y);
}

/* The per-iteration error's distribution (film_trace.h), null when the image has none. */
static void json_iteration_errors(FILE *f, const pc_study_tails *t) {
  if (!t->iter_known) {
    fputs("null", f);
    return;
  }
  const pc_iteration_errors *ie = &t->iter;
  fprintf(f, "{\"iterations\": %u, \"grid\": %d, \"worst_iteration\": %u", ie->n, PC_TRACE_GRID, ie->worst);
  const char *names[] = {"mean", "p50", "p90", "p99", "max", "top1_percent_share"};
  double v[] = {ie->mean, ie->p50, ie->p90, ie->p99, ie->max, ie->top1};
  for (int i = 0; i < 6; i++) {
    fprintf(f, ", \"%s\": ", names[i]);
    pc_json_number(f, v[i]);
  }
  fputs(", \"tail\": [", f);
  for (int k = 0; k < ie->ntail; k++) {
    if (k) fputs(", ", f);
    pc_json_number(f, ie->tail[k]);
  }
  fputs("]}", f);
}

/* Which strategies carry the final image (study.h), null when it cannot tell. */
static void json_shares(FILE *f, const pc_study_shares *sh) {
  if (!sh->known) {
    fputs("null", f);
    return;
  }
  fputc('{', f);
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) {
    fprintf(f, "%s\"%s\": ", l ? ", " : "", pc_study_layer_name(1 + l));
    pc_json_number(f, sh->share[l]);
  }
  fputc('}', f);
}

static void json_runs(FILE *f, const pc_study_run *runs, int nruns, const pc_study_ref *ref) {
  fputs("  \"methods\": [\n", f);
  for (int r = 0; r < nruns; r++) {
    const pc_study_run *run = &runs[r];
    const pc_study_snap *last = run->nsnaps ? &run->snaps[run->nsnaps - 1] : NULL;
    fprintf(f, "    {\"method\": \"%s\", \"workers\": %d, \"run\": %d, \"seed\": %llu, \"ranges_rerun\": %u, "
               "\"group_wall_seconds\": %.6f, \"threads\": %d, \"iterations\": %llu, \"render_seconds\": ",
            run->method.name, run->workers, run->run + 1, (unsigned long long)run->seed, run->ranges_rerun,
            run->group_wall, run->threads, last ? (unsigned long long)last->iterations : 0ULL);
    pc_json_number(f, last ? last->seconds : NAN);
    fprintf(f, ", \"rays\": %llu, \"exr\": \"%s.exr\", \"png\": \"%s.png\", \"empty_layers\": [",
            (unsigned long long)run->stats.rays, run->method.name, run->method.name);
    for (int slot = 0, k = 0; slot < PC_STUDY_NLAYERS; slot++)
      if (run->layer_empty[slot]) fprintf(f, "%s\"%s\"", k++ ? ", " : "", pc_study_layer_name(slot));
    fputs("], \"unlike_layers\": [", f);
    for (int slot = 0, k = 0; slot < PC_STUDY_NLAYERS; slot++)
      if (run->unlike && slot != PC_STUDY_BEAUTY) fprintf(f, "%s\"%s\"", k++ ? ", " : "", pc_study_layer_name(slot));
    fputs("], \"weights\": ", f);
    if (run->weights[0]) pc_json_string(f, run->weights);
    else fputs("null", f);
    if (run->auto_report[0]) {
      fputs(", \"auto\": ", f);
      pc_json_string(f, run->auto_report);
    }
    fputs(",\n     \"tails\": ", f);
    json_tails(f, &run->tails);
    fputs(",\n     \"iteration_errors\": ", f);
    json_iteration_errors(f, &run->tails);
    fputs(",\n     \"shares\": ", f);
    json_shares(f, &run->shares);
    fputs(",\n     \"snapshots\": [\n", f);
    for (int s = 0; s < run->nsnaps; s++) {
      const pc_study_snap *sn = &run->snaps[s];
      fprintf(f, "       {\"seconds\": %.6f, \"worker_seconds\": %.6f, \"wall_seconds\": %.6f, \"iterations\": %llu, "
                 "\"layers\": {",
              sn->seconds, sn->worker_seconds, sn->wall, (unsigned long long)sn->iterations);
      for (int slot = 0, k = 0; slot < PC_STUDY_NLAYERS; slot++) {
        if (!pc_study_ref_has(ref, slot)) continue;
        fprintf(f, "%s\"%s\": {\"relmse\": ", k++ ? ", " : "", pc_study_layer_name(slot));
        pc_json_number(f, sn->m[slot].relmse);
        fputs(", \"rmse\": ", f);
        pc_json_number(f, sn->m[slot].rmse);
        fputs(", \"l1\": ", f);
        pc_json_number(f, sn->m[slot].l1);
        fputc('}', f);
      }
      fprintf(f, "}}%s\n", s + 1 < run->nsnaps ? "," : "");
    }
    fprintf(f, "     ]}%s\n", r + 1 < nruns ? "," : "");
  }
  fputs("  ],\n", f);
}

static void json_table(FILE *f, const pc_study_table *t) {
  fputs("  \"table\": [\n", f);
  for (int row = 0; row < t->nlayers; row++) {
    fprintf(f, "    {\"layer\": \"%s\", \"target_relmse\": ", pc_study_layer_name(t->slot[row]));
    pc_json_number(f, t->target[row]);
    fprintf(f, ", \"target_from\": \"%s\", \"rows\": [\n", t->target_given[row] ? "--target-error" : "worst final relmse");
    for (int m = 0; m < t->nmethods; m++) {
      const pc_study_cell *c = &t->cell[row][m];
      fprintf(f, "      {\"method\": \"%s\", \"final_relmse\": ", t->name[m]);
      pc_json_number(f, c->final_relmse);
      fprintf(f, ", \"relmse_ratio_to_%s\": ", t->name[0]);
      pc_json_number(f, c->relmse_ratio);
      fputs(", \"time_to_target\": ", f);
      pc_json_number(f, c->time);
      fprintf(f, ", \"reached\": \"%s\", \"time_ratio_to_%s\": ", reach_name(c->reach), t->name[0]);
      pc_json_number(f, c->time_ratio);
      fprintf(f, "}%s\n", m + 1 < t->nmethods ? "," : "");
    }
    fprintf(f, "    ]}%s\n", row + 1 < t->nlayers ? "," : "");
  }
  fputs("  ],\n  \"headline\": [", f);
  for (int m = 1; m < t->nmethods; m++) {
    char line[512];
    pc_study_headline(t, m, line, sizeof line);
    if (m > 1) fputs(", ", f);
    pc_json_string(f, line);
  }
  fputs("]\n", f);
}

int pc_study_write_json(const char *path, const pc_study_info *info, const pc_study_run *runs, int nruns,
                        const pc_study_ref *ref, const pc_study_table *t, pc_err *e) {
  out_file o;
  int rc = out_open(&o, path, e);
  if (rc != PC_OK) return rc;
  FILE *f = o.f;
  fputs("{\n  \"scene\": ", f);
  pc_json_string(f, info->scene_path);
  fputs(", \"scene_name\": ", f);
  pc_json_string(f, info->scene_name);
  fputs(", \"reference\": ", f);
  if (info->reference_path) pc_json_string(f, info->reference_path);
  else fputs("null", f);
  /* where the errors come from: a reference, or each image's own iterations (docs/variance.md) */
  fprintf(f, ", \"errors\": \"%s\"", info->reference_path ? "measured" : "estimated");
  fprintf(f, ",\n  \"seconds\": %.6g, \"width\": %d, \"height\": %d, \"seed\": %llu, \"max_snapshots\": %d,\n",
          info->seconds, info->width, info->height, (unsigned long long)info->seed, info->max_snaps);
  /* the table and the charts: the median curves of this farm size over the runs */
  fprintf(f, "  \"farm\": ");
  if (info->host) pc_json_string(f, info->host);
  else fputs("\"embedded\"", f);
  fprintf(f, ", \"table_workers\": %d, \"runs\": %d, \"time\": \"worker_seconds / workers\",\n", info->workers,
          info->runs);
  json_runs(f, runs, nruns, ref);
  json_table(f, t);
  fputs("}\n", f);
  return out_commit(&o, e);
}

/* <dir>/<leaf>.png and <dir>/<leaf>.svg of the same chart. */
static int write_png_and_svg(const pc_chart *c, const char *dir, const char *leaf, pc_err *e) {
  char path[4096];
  int rc = PC_OK;
  for (int k = 0; k < 2 && rc == PC_OK; k++) {
    int n = snprintf(path, sizeof path, "%s/%s.%s", dir, leaf, k ? "svg" : "png");
    if (n < 0 || (size_t)n >= sizeof path) rc = pc_errf(e, PC_EINVAL, "%s: path too long", dir);
    else rc = k ? pc_chart_write_svg(c, path, e) : pc_chart_write_png(c, path, e);
  }
  return rc;
}

int pc_study_write_chart(const char *dir, const pc_study_info *info, const pc_study_run *runs, int nruns, int slot,
                         const pc_study_band *const *bands, pc_err *e) {
  pc_chart_series series[PC_STUDY_MAX_METHODS];
  double *xy = calloc((size_t)nruns * 2 * PC_STUDY_MAX_SNAPSHOTS, sizeof *xy);
  if (!xy) return pc_errf(e, PC_ENOMEM, "out of memory for the chart");
  int ns = 0;
  for (int r = 0; r < nruns; r++) {
    if (pc_study_excluded(&runs[r], slot)) continue;
    double *x = xy + (size_t)ns * 2 * PC_STUDY_MAX_SNAPSHOTS, *y = x + PC_STUDY_MAX_SNAPSHOTS;
    for (int s = 0; s < runs[r].nsnaps; s++) {
      x[s] = runs[r].snaps[s].seconds;
      y[s] = runs[r].snaps[s].m[slot].relmse;
    }
    series[ns] = (pc_chart_series){.name = runs[r].method.name, .x = x, .y = y, .n = runs[r].nsnaps};
    /* the band's points are the median curve's (both leave out the times no run reached) */
    if (bands && bands[r] && bands[r][slot].n == runs[r].nsnaps) {
      series[ns].lo = bands[r][slot].lo;
      series[ns].hi = bands[r][slot].hi;
    }
    ns++;
  }
  char title[512];
  char xlabel[128] = "render time (s)";
  if (info->workers > 0)
    snprintf(xlabel, sizeof xlabel, "render time on %d worker%s (worker-seconds / %d)", info->workers,
             info->workers > 1 ? "s" : "", info->workers);
  snprintf(title, sizeof title, "%s: %s relMSE against render time%s%s", info->scene_name, pc_study_layer_name(slot),
           info->reference_path ? "" : " (estimated, no reference)",
           info->runs > 1 ? " (median, min-max shaded)" : "");
  pc_chart c = {.title = title, .x_label = xlabel,
                .y_label = info->reference_path ? "relMSE" : "estimated relMSE", .width = 800, .height = 560,
                .series = series, .nseries = ns};
  char leaf[64];
  snprintf(leaf, sizeof leaf, "study_%s", pc_study_layer_name(slot));
  int rc = write_png_and_svg(&c, dir, leaf, e);
  free(xy);
  return rc;
}

int pc_study_write_shares_chart(const char *dir, const pc_study_info *info, const pc_study_run *runs, int nmethods,
                                bool *written, pc_err *e) {
  *written = false;
  bool per_run = info->runs <= PC_STUDY_SHARE_BARS_RUNS;
  enum { MAX_BARS = PC_STUDY_MAX_METHODS * PC_STUDY_SHARE_BARS_RUNS };
  char label[MAX_BARS][96];
  const char *rows[MAX_BARS];
  double value[MAX_BARS * PC_LAYER_STD_COUNT];
  int n = 0;
  for (int m = 0; m < nmethods; m++) {
    double mean[PC_LAYER_STD_COUNT] = {0};
    int known = 0;
    for (int r = 0; r < info->runs; r++) {
      const pc_study_run *run = &runs[(size_t)r * (size_t)nmethods + (size_t)m];
      if (!run->shares.known) continue;
      known++;
      for (int l = 0; l < PC_LAYER_STD_COUNT; l++) mean[l] += run->shares.share[l];
      if (!per_run) continue;
      snprintf(label[n], sizeof label[n], info->runs > 1 ? "%s, run %d" : "%s", run->method.name, r + 1);
      for (int l = 0; l < PC_LAYER_STD_COUNT; l++) value[n * PC_LAYER_STD_COUNT + l] = fmax(0, run->shares.share[l]);
      n++;
    }
    if (per_run || !known) continue;
    snprintf(label[n], sizeof label[n], "%s, mean of %d runs", runs[m].method.name, known);
    for (int l = 0; l < PC_LAYER_STD_COUNT; l++) value[n * PC_LAYER_STD_COUNT + l] = fmax(0, mean[l] / known);
    n++;
  }
  if (n == 0) return PC_OK;
  for (int i = 0; i < n; i++) rows[i] = label[i];
  static const char *const parts[PC_LAYER_STD_COUNT] = {"pt: emitter hits (s=0)", "nee (s=1)", "lt (t=1)",
                                                        "inner (s,t>=2)"};
  pc_chart_bars bars = {.rows = rows, .parts = parts, .value = value, .nrows = n, .nparts = PC_LAYER_STD_COUNT};
  char title[512];
  snprintf(title, sizeof title, "%s: strategies carrying the final images (share of the mean luminance)",
           info->scene_name);
  pc_chart c = {.title = title, .x_label = "share of the image's mean luminance", .width = 800,
                .height = 150 + 30 * n, .bars = &bars};
  int rc = write_png_and_svg(&c, dir, "study_shares", e);
  *written = rc == PC_OK;
  return rc;
}

int pc_study_write_iterations_chart(const char *dir, const pc_study_info *info, const pc_study_run *runs, int nmethods,
                                    bool *written, pc_err *e) {
  *written = false;
  pc_chart_series series[PC_STUDY_MAX_METHODS];
  double x[PC_STUDY_MAX_METHODS][PC_TRACE_TAIL_MAX], y[PC_STUDY_MAX_METHODS][PC_TRACE_TAIL_MAX];
  double v[PC_STUDY_MAX_RUNS];
  int ns = 0;
  for (int m = 0; m < nmethods && m < PC_STUDY_MAX_METHODS; m++) {
    int np = 0;
    for (int k = 0; k < PC_TRACE_TAIL_MAX; k++) {
      int nv = 0;
      for (int r = 0; r < info->runs && r < PC_STUDY_MAX_RUNS; r++) {
        const pc_study_tails *t = &runs[(size_t)r * (size_t)nmethods + (size_t)m].tails;
        if (t->iter_known && k < t->iter.ntail && t->iter.mean > 0) v[nv++] = t->iter.tail[k] / t->iter.mean;
      }
      if (nv == 0) break;
      x[ns][np] = pc_study_median(v, nv, NULL, NULL);
      y[ns][np++] = ldexp(1.0, -(k + 1));
    }
    if (np == 0) continue;
    series[ns] = (pc_chart_series){.name = runs[m].method.name, .x = x[ns], .y = y[ns], .n = np};
    ns++;
  }
  if (ns == 0) return PC_OK;
  char title[512];
  snprintf(title, sizeof title, "%s: tail of the per-iteration error (%dx%d blocks%s)", info->scene_name, PC_TRACE_GRID,
           PC_TRACE_GRID, info->runs > 1 ? ", median of the runs" : "");
  pc_chart c = {.title = title, .x_label = "error of one iteration / mean error of an iteration",
                .y_label = "fraction of iterations above", .width = 800, .height = 560, .series = series, .nseries = ns};
  int rc = write_png_and_svg(&c, dir, "study_iterations", e);
  *written = rc == PC_OK;
  return rc;
}
