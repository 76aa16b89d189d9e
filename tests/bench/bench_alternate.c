/* bench_alternate.c: benchmark (not a test), issue 16's "PCBPT (K=1) time per iteration
 * against BDPT's" as a render sees it: both methods on the same scene in one process, on the
 * same threads, one iteration of each in turn, so that a load that comes and goes, the CPU's
 * clock and the memory's state fall on both alike. After one untimed iteration of each (the
 * first touch of their buffers), it prints each method's mean wall and CPU time per iteration
 * (pc_render_stats: the render threads' own clocks), how busy the threads were, the rays, and the
 * ratios. bench_pcbpt_cost.sh measures the same on one thread from whole processes.
 *   bench_alternate SCENE.xml [--iterations N] [--threads T] [render flags for the PCBPT side:
 *                   --pcbpt-k, --pcbpt-m, --width, --max-depth, ...]
 *   (defaults: 32 iterations each, every core, the scene's size, K = 1) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render.h"
#include "render_flags.h"
#include "scene.h"
#include "thread_pool.h"

enum { BDPT, PCBPT, NSIDES };

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: bench_alternate SCENE.xml [--iterations N] [--threads T] [render flags]\n");
    return 2;
  }
  pc_render_request req;
  pc_render_request_default(&req);
  req.set.pcbpt_k = 1;
  pc_err e = {0};
  long iterations = 32, threads = 0;
  for (int i = 2; i < argc; i++) {
    long *num = strcmp(argv[i], "--iterations") == 0 ? &iterations : strcmp(argv[i], "--threads") == 0 ? &threads : NULL;
    if (num && i + 1 < argc) {
      *num = strtol(argv[++i], NULL, 10);
      if (*num < (num == &threads ? 0 : 1) || *num > 100000) {
        fprintf(stderr, "bench_alternate: %s %s out of range\n", argv[i - 1], argv[i]);
        return 2;
      }
      continue;
    }
    if (pc_render_flag_parse(&req, argc, argv, &i, &e) <= 0) {
      fprintf(stderr, "bench_alternate: bad flag %s: %s\n", argv[i], e.msg);
      return 2;
    }
  }
  pc_scene scene = {0};
  pc_scene_load_opts lo;
  pc_render_request_load_opts(&req, &lo);
  pc_renderer *r[NSIDES] = {NULL, NULL};
  pc_film film[NSIDES] = {{0}, {0}};
  pc_render_stats st[NSIDES] = {{0}, {0}};
  int rc = pc_scene_load_with(argv[1], &lo, &scene, &e);
  if (!rc) {
    pc_render_request_apply_scene(&req, &scene);
    rc = pc_scene_build(&scene, &e);
  }
  for (int m = 0; m < NSIDES && !rc; m++) {
    pc_render_settings set = req.set;
    set.method = m == BDPT ? PC_METHOD_BDPT : PC_METHOD_PCBPT;
    rc = pc_renderer_create(&scene, &set, (int)threads, &r[m], &e);
    if (!rc) rc = pc_film_init(&film[m], set.width, set.height, set.strategy_layers, &e);
    if (!rc) rc = pc_render_iterations(r[m], 1000000, 1, &film[m], NULL, NULL, NULL, NULL, &e);
  }
  for (long it = 0; it < iterations && !rc; it++)
    for (int m = 0; m < NSIDES && !rc; m++) rc = pc_render_iterations(r[m], (uint64_t)it, 1, &film[m], &st[m], NULL, NULL, NULL, &e);
  if (rc) {
    fprintf(stderr, "bench_alternate: %s\n", e.msg);
    return 1;
  }
  int nthreads = pc_renderer_threads(r[BDPT]);
  printf("%s %dx%d max depth %d, %ld iterations each on %d thread%s (PCBPT K=%d M=%d):\n", argv[1], req.set.width,
         req.set.height, req.set.max_depth, iterations, nthreads, nthreads > 1 ? "s" : "", req.set.pcbpt_k, req.set.pcbpt_m);
  for (int m = 0; m < NSIDES; m++) {
    double n = (double)st[m].iterations;
    printf("  %-6s %8.2f ms wall, %8.2f ms CPU per iteration; threads busy %5.1f%%; phases (ms): paths %.2f, light "
           "tracing %.2f, PMF %.2f, connect %.2f; %.0fk rays\n",
           m == BDPT ? "bdpt" : "pcbpt", 1e3 * st[m].t_total / n, 1e3 * st[m].t_cpu / n,
           100 * st[m].t_cpu / (st[m].t_total * nthreads), 1e3 * st[m].t_paths / n, 1e3 * st[m].t_lt / n,
           1e3 * st[m].t_pmf / n, 1e3 * st[m].t_connect / n, 1e-3 * (double)st[m].rays / n);
  }
  printf("  pcbpt / bdpt: %.3f wall, %.3f CPU\n", st[PCBPT].t_total / st[BDPT].t_total, st[PCBPT].t_cpu / st[BDPT].t_cpu);
  for (int m = 0; m < NSIDES; m++) {
    pc_renderer_destroy(r[m]);
    pc_film_free(&film[m]);
  }
  pc_scene_free(&scene);
  return 0;
}
