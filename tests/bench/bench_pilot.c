/* bench_pilot.c: benchmark (not a test) of how well `--method auto`'s pilot measures the
 * candidates (common/render/pilot.h, docs/auto.md).
 *   bench_pilot SCENE.xml [SIZE [PILOTS [ITERATIONS [THREADS]]]]   (defaults 128, 60, 14, 2)
 * Renders PILOTS batches of ITERATIONS iterations of the pilot's stage-1 candidates (BDPT, PCBPT
 * K = 1 and 2) and K = 1's stage-4 twin (the raised MIS count), all four on the same iterations
 * as the pilot renders them. Each batch is one pilot: pc_pilot_choose measures it, charged the
 * batch's CPU seconds. All batches together are the long render the pilot predicts: each
 * candidate's per-iteration relMSE against the mean of all four, and its CPU time. Prints the
 * long render's figures, then per candidate over the pilots the median of the pilot's relMSE
 * over K = 1's (with and without the twin), the spread of its log, how often it fell on the
 * long render's side of 1, and what the pilots chose. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pilot.h"
#include "render.h"
#include "render_flags.h"
#include "scene.h"
#include "study.h"

enum { NCAND = 4, BDPT = 0, K1 = 1, K2 = 2, TWIN = 3 };

static void fail(const pc_err *e) {
  fprintf(stderr, "bench_pilot: %s\n", e->msg);
  exit(1);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: bench_pilot SCENE.xml [SIZE [PILOTS [ITERATIONS [THREADS]]]]\n");
    return 2;
  }
  int size = argc > 2 ? atoi(argv[2]) : 128, pilots = argc > 3 ? atoi(argv[3]) : 60;
  int n = argc > 4 ? atoi(argv[4]) : 14, threads = argc > 5 ? atoi(argv[5]) : 2;
  if (size < 8 || size > 4096 || pilots < 2 || n < 2 || threads < 1) return 2;
  pc_err e = {0};
  pc_render_request req;
  pc_render_request_default(&req);
  pc_scene scene = {0};
  req.set.width = req.set.height = size;
  req.width_set = req.height_set = true;
  if (pc_scene_load(argv[1], &scene, &e)) fail(&e);
  pc_render_request_apply_scene(&req, &scene);
  if (pc_scene_build(&scene, &e)) fail(&e);
  static const char *names[NCAND] = {"bdpt", "pcbpt K=1", "pcbpt K=2", "pcbpt K=1 mis 4"};
  pc_pilot_candidate proto[NCAND];
  pc_renderer *r[NCAND];
  pc_film total[NCAND], batch;
  double cpu[NCAND] = {0};
  for (int c = 0; c < NCAND; c++) {
    memset(&proto[c], 0, sizeof proto[c]);
    proto[c].set = req.set;
    proto[c].set.method = c == BDPT ? PC_METHOD_BDPT : PC_METHOD_PCBPT;
    proto[c].set.pcbpt_k = c == K2 ? 2 : 1;
    if (c == TWIN) {
      proto[c].mis_raised = true;
      proto[c].set.mis_mode = PC_MIS_COUNT;
      proto[c].set.mis_count = PC_PILOT_RAISED_COUNT;
    }
    snprintf(proto[c].label, sizeof proto[c].label, "%s", names[c]);
    if (pc_renderer_create(&scene, &proto[c].set, threads, &r[c], &e) || pc_film_init(&total[c], size, size, 0, &e))
      fail(&e);
  }
  if (pc_film_init(&batch, size, size, 0, &e)) fail(&e);
  size_t nv = (size_t)size * size * 3;
  float *mean = malloc(nv * sizeof *mean), *var = malloc(nv * sizeof *var);
  double *ratio[2][NCAND], *rel[NCAND];
  for (int c = 0; c < NCAND; c++) {
    rel[c] = malloc((size_t)pilots * sizeof *rel[c]);
    for (int t = 0; t < 2; t++) ratio[t][c] = malloc((size_t)pilots * sizeof *ratio[t][c]);
  }
  int chose[2][NCAND] = {{0}};
  for (int b = 0; b < pilots; b++) {
    pc_pilot p = {0};
    for (int c = 0; c < NCAND; c++) {
      pc_film_clear(&batch);
      pc_render_stats st = {0};
      if (pc_render_iterations(r[c], (uint64_t)b * (uint64_t)n, (uint64_t)n, &batch, &st, NULL, NULL, NULL, &e)) fail(&e);
      if (pc_film_add(&total[c], &batch, &e)) fail(&e);
      cpu[c] += st.t_cpu;
      p.c[c] = proto[c];
      p.c[c].iterations = (uint64_t)n;
      p.c[c].seconds = st.t_total;
      p.c[c].cpu_seconds = st.t_cpu;
      p.c[c].own_relmse = -1;
      pc_film_beauty(&batch, mean);
      if (!pc_film_variance(&batch, var) || pc_pilot_keep_image(&p.c[c], size, size, mean, var, &e)) fail(&e);
    }
    /* with the twin (stage 4 ran), then stage 1 alone */
    for (int t = 0; t < 2; t++) {
      p.n = t == 0 ? NCAND : TWIN;
      pc_pilot_choose(&p);
      chose[t][p.best]++;
      for (int c = 0; c < p.n; c++) ratio[t][c][b] = p.c[c].relmse / p.c[K1].relmse;
      if (t == 0)
        for (int c = 0; c < NCAND; c++) rel[c][b] = p.c[c].relmse * n;
    }
    p.n = NCAND;
    pc_pilot_free(&p);
  }
  /* the long render: each candidate's per-iteration variance over every batch, against the mean
   * of all four */
  double truth[NCAND] = {0};
  double *m = calloc(nv, sizeof *m);
  for (int c = 0; c < NCAND; c++) {
    pc_film_beauty(&total[c], mean);
    for (size_t k = 0; k < nv; k++) m[k] += mean[k] / NCAND;
  }
  double its = (double)pilots * n;
  for (int c = 0; c < NCAND; c++) {
    if (!pc_film_variance(&total[c], var)) return 1;
    for (size_t k = 0; k < nv; k++) truth[c] += var[k] * its / (m[k] * m[k] + PC_RELMSE_EPS);
    truth[c] /= (double)nv;
  }
  printf("%s %dx%d, %d threads: %d pilots of %d iterations; the long render is all %.0f iterations of each\n", argv[1],
         size, size, threads, pilots, n, its);
  printf("%-16s %12s %10s %12s | %-34s | %-34s | %s\n", "candidate", "long relMSE", "CPU ms/it", "long eff/K=1",
         "pilot relMSE/K=1: med, sd log, side", "the same without the twin", "pilot relMSE x it (median)");
  for (int c = 0; c < NCAND; c++) {
    double eff = (truth[K1] * cpu[K1]) / (truth[c] * cpu[c]);
    printf("%-16s %12.4g %10.2f %12.3f |", names[c], truth[c], 1e3 * cpu[c] / its, eff);
    for (int t = 0; t < 2; t++) {
      if (c == K1 || (t == 1 && c == TWIN)) { /* K = 1 is the unit; stage 1 has no twin */
        printf(" %-34s |", "");
        continue;
      }
      double sl = 0, sl2 = 0;
      int side = 0;
      for (int b = 0; b < pilots; b++) {
        double l = log(ratio[t][c][b]);
        sl += l;
        sl2 += l * l;
        side += (ratio[t][c][b] > 1) == (truth[c] > truth[K1]);
      }
      double mu = sl / pilots, sd = sqrt(fmax(sl2 / pilots - mu * mu, 0));
      printf(" %8.3f %8.3f %6.0f%%%*s |", pc_study_median(ratio[t][c], pilots, NULL, NULL), sd, 100.0 * side / pilots, 9, "");
    }
    printf(" %.4g\n", pc_study_median(rel[c], pilots, NULL, NULL));
  }
  for (int t = 0; t < 2; t++) {
    printf("pilots chose (%s):", t ? "stage 1 alone" : "with the twin");
    for (int c = 0; c < NCAND; c++)
      if (chose[t][c]) printf(" %s %d", names[c], chose[t][c]);
    printf("\n");
  }
  for (int c = 0; c < NCAND; c++) {
    pc_renderer_destroy(r[c]);
    pc_film_free(&total[c]);
    free(rel[c]);
    for (int t = 0; t < 2; t++) free(ratio[t][c]);
  }
  pc_film_free(&batch);
  free(mean);
  free(var);
  free(m);
  pc_scene_free(&scene);
  return 0;
}
