/* bench_variance.c: benchmark (not a test) of what the per-iteration layers beauty_sq and
 * beauty_max cost (docs/variance.md).
 *   bench_variance SCENE.xml [ITERATIONS [THREADS [with|without]]]     (defaults 8, 2)
 * Renders the scene (its own method and size) one iteration at a time, alternating a film with
 * beauty_sq and one without it (pc_film_init_stored without beauty_sq: the fold then skips the squares), so
 * both see the same machine load; prints the mean CPU time of an iteration of each and the
 * difference.
 * Then packs a 4-iteration delta with and without its last layer, beauty_max, and prints the
 * raw and zstd bytes of an upload.
 * Other load still disturbs CPU times (caches, memory bandwidth): the difference is only
 * meaningful against its printed spread. With `with` or `without` it renders only into that
 * film and prints nothing else: run both under `valgrind --tool=callgrind` and compare the
 * instructions collected, a figure no other load disturbs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render.h"
#include "render_flags.h"
#include "scene.h"
#include "wire_film.h"

/* CPU seconds of the whole process (every render thread): the work an iteration costs, much
 * less disturbed than wall time by other processes sharing the cores. */
static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Raw and compressed bytes of f's upload. */
static int upload_bytes(const pc_film *f, size_t *raw_n, size_t *z_n, pc_err *e) {
  uint8_t *raw = NULL, *z = NULL;
  int rc = pc_wire_film_pack(f, &raw, raw_n, e);
  if (!rc) rc = pc_wire_compress(raw, *raw_n, &z, z_n, e);
  free(raw);
  free(z);
  return rc;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: bench_variance SCENE.xml [ITERATIONS [THREADS [with|without]]]\n");
    return 2;
  }
  int n = argc > 2 ? atoi(argv[2]) : 8, threads = argc > 3 ? atoi(argv[3]) : 2;
  if (n < 2 || threads < 1) return 2;
  pc_err e = {0};
  pc_render_request req;
  pc_render_request_default(&req);
  pc_scene scene = {0};
  pc_renderer *r = NULL;
  pc_film with = {0}, without = {0};
  int rc = pc_scene_load(argv[1], &scene, &e);
  if (!rc) {
    pc_render_request_apply_scene(&req, &scene);
    rc = pc_scene_build(&scene, &e);
  }
  if (!rc) rc = pc_renderer_create(&scene, &req.set, threads, &r, &e);
  if (!rc) rc = pc_film_init(&with, req.set.width, req.set.height, 0, &e);
  if (!rc)
    rc = pc_film_init_stored(&without, req.set.width, req.set.height, 0,
                             PC_FILM_NORM(PC_NORM_EYE) | PC_FILM_NORM(PC_NORM_LIGHT), &e);
  if (rc) {
    fprintf(stderr, "bench_variance: %s\n", e.msg);
    return 1;
  }
  if (argc > 4) { /* one variant only, for instruction counts */
    if (strcmp(argv[4], "with") != 0 && strcmp(argv[4], "without") != 0) return 2;
    pc_film *f = strcmp(argv[4], "without") == 0 ? &without : &with;
    rc = pc_render_iterations(r, 0, (uint64_t)n, f, NULL, NULL, NULL, NULL, &e);
    if (rc) fprintf(stderr, "bench_variance: %s\n", e.msg);
    return rc ? 1 : 0;
  }
  /* both films render the same iterations (same index, so the same work): the paired
   * differences cancel most of the iteration-to-iteration variation */
  double t[2] = {0, 0}, d = 0, d2 = 0;
  for (int k = -1; k < n && !rc; k++) {
    double dt[2] = {0, 0};
    for (int j = 0; j < 2 && !rc; j++) {
      int which = (k + j) & 1; /* alternate which goes first */
      double t0 = now_s();
      rc = pc_render_iterations(r, (uint64_t)(k + 1), 1, which ? &without : &with, NULL, NULL, NULL, NULL, &e);
      dt[which] = now_s() - t0;
    }
    if (k < 0) continue; /* warm-up */
    t[0] += dt[0];
    t[1] += dt[1];
    d += dt[0] - dt[1];
    d2 += (dt[0] - dt[1]) * (dt[0] - dt[1]);
  }
  if (rc) {
    fprintf(stderr, "bench_variance: %s\n", e.msg);
    return 1;
  }
  double m0 = t[0] / n, m1 = t[1] / n, md = d / n, se = sqrt(fmax(d2 / n - md * md, 0) / (n - 1));
  printf("%s %s %dx%d, %d threads, %d iterations each: %.2f ms CPU with beauty_sq and beauty_max, %.2f ms without: "
         "%+.2f%% (+- %.2f%%, paired)\n",
         argv[1], pc_method_name(req.set.method), req.set.width, req.set.height, threads, n, 1e3 * m0, 1e3 * m1,
         100 * md / m1, 100 * se / m1);
  /* an upload: a delta of 4 iterations, with and without its beauty_max layer */
  pc_film delta = {0};
  size_t raw[2], z[2];
  rc = pc_film_init(&delta, req.set.width, req.set.height, 0, &e);
  if (!rc) rc = pc_render_iterations(r, 1000, 4, &delta, NULL, NULL, NULL, NULL, &e);
  if (!rc) rc = upload_bytes(&delta, &raw[0], &z[0], &e);
  if (!rc) {
    delta.nlayers--; /* the same film as an upload before beauty_max */
    rc = upload_bytes(&delta, &raw[1], &z[1], &e);
    delta.nlayers++;
  }
  if (rc) {
    fprintf(stderr, "bench_variance: %s\n", e.msg);
    return 1;
  }
  printf("upload of 4 iterations: %zu bytes raw, %zu zstd with beauty_max; %zu raw, %zu zstd without (%+.1f%%)\n", raw[0],
         z[0], raw[1], z[1], 100.0 * ((double)z[0] / (double)z[1] - 1));
  pc_film_free(&delta);
  pc_film_free(&with);
  pc_film_free(&without);
  pc_renderer_destroy(r);
  pc_scene_free(&scene);
  return 0;
}
