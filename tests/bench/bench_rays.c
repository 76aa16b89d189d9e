/* bench_rays.c: benchmark (not a test), the ray-tracing ceiling of issue 16: how fast Embree
 * alone traces the very rays a render traces. Renders N iterations of SCENE on one thread
 * recording every ray (pc_scene.ray_hook), renders them again without the hook for the
 * renderer's own time, then replays the recorded rays in their order through
 *   single  rtcIntersect1 / rtcOccluded1, one ray at a time (what the renderer calls);
 *   stream  rtcIntersect1M / rtcOccluded1M on runs of up to 256 consecutive rays of one kind;
 *   packet  rtcIntersect8 / rtcOccluded8 on runs of up to 8 consecutive rays of one kind
 * (best of 3 passes each, CPU time of the process), and prints each mode's Mrays/s, the
 * renderer's rays per second, and what share of the renderer's time the same rays take at
 * each mode's speed: with `single`, the share of the render that is Embree's traversal itself,
 * the rest being the renderer's own work. Every mode must find the same hits (it says so).
 *   bench_rays SCENE.xml [--iterations N] [render flags: --method, --width, --max-depth, ...]
 *   (defaults: 1 iteration, the scene's own method and size) */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render.h"
#include "render_flags.h"
#include "scene.h"

typedef struct ray_rec {
  float o[3], d[3], tfar;
  int shadow;
} ray_rec;

typedef struct ray_log {
  ray_rec *r;
  size_t n, cap;
  bool full;
} ray_log;

#define MAX_RAYS ((size_t)1 << 26) /* 2 GiB of records */

static void record(void *user, bool shadow, vec3 o, vec3 d, float tfar) {
  ray_log *l = user;
  if (l->n == l->cap) {
    size_t cap = l->cap ? 2 * l->cap : (size_t)1 << 16;
    ray_rec *r = cap <= MAX_RAYS ? realloc(l->r, cap * sizeof *r) : NULL;
    if (!r) { l->full = true; return; }
    l->r = r;
    l->cap = cap;
  }
  l->r[l->n++] = (ray_rec){{o.x, o.y, o.z}, {d.x, d.y, d.z}, tfar, shadow};
}

static double cpu_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void to_ray(const ray_rec *q, struct RTCRay *r) {
  r->org_x = q->o[0]; r->org_y = q->o[1]; r->org_z = q->o[2];
  r->dir_x = q->d[0]; r->dir_y = q->d[1]; r->dir_z = q->d[2];
  r->tnear = 0.f;
  r->tfar = q->tfar;
  r->time = 0.f;
  r->mask = 0xffffffffu;
  r->id = 0;
  r->flags = 0;
}

enum { SINGLE, STREAM, PACKET, NMODES };
static const char *mode_name[NMODES] = {"single (rtcIntersect1/rtcOccluded1)", "stream (rtcIntersect1M/rtcOccluded1M, 256)",
                                        "packet (rtcIntersect8/rtcOccluded8)"};

/* One pass over the log in mode m; returns how many rays hit (intersections) or are blocked. */
static size_t replay(RTCScene scn, const ray_log *l, int m) {
  enum { RUN = 256 };
  struct RTCRayHit hits[RUN];
  struct RTCRay rays[RUN];
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  size_t found = 0;
  for (size_t i = 0; i < l->n;) {
    int shadow = l->r[i].shadow;
    size_t cap = m == SINGLE ? 1 : m == STREAM ? RUN : 8, k = 0;
    while (k < cap && i + k < l->n && l->r[i + k].shadow == shadow) k++;
    if (m == PACKET) {
      int valid[8];
      for (size_t j = 0; j < 8; j++) valid[j] = j < k ? -1 : 0;
      if (shadow) {
        struct RTCRay8 p;
        for (size_t j = 0; j < 8; j++) {
          struct RTCRay r;
          to_ray(&l->r[i + (j < k ? j : 0)], &r);
          p.org_x[j] = r.org_x; p.org_y[j] = r.org_y; p.org_z[j] = r.org_z;
          p.dir_x[j] = r.dir_x; p.dir_y[j] = r.dir_y; p.dir_z[j] = r.dir_z;
          p.tnear[j] = 0.f; p.tfar[j] = r.tfar; p.time[j] = 0.f; p.mask[j] = ~0u; p.id[j] = 0; p.flags[j] = 0;
        }
        rtcOccluded8(valid, scn, &ctx, &p);
        for (size_t j = 0; j < k; j++) found += p.tfar[j] < 0.f;
      } else {
        struct RTCRayHit8 p;
        for (size_t j = 0; j < 8; j++) {
          struct RTCRay r;
          to_ray(&l->r[i + (j < k ? j : 0)], &r);
          p.ray.org_x[j] = r.org_x; p.ray.org_y[j] = r.org_y; p.ray.org_z[j] = r.org_z;
          p.ray.dir_x[j] = r.dir_x; p.ray.dir_y[j] = r.dir_y; p.ray.dir_z[j] = r.dir_z;
          p.ray.tnear[j] = 0.f; p.ray.tfar[j] = r.tfar; p.ray.time[j] = 0.f; p.ray.mask[j] = ~0u; p.ray.id[j] = 0;
          p.ray.flags[j] = 0;
          p.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
          p.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect8(valid, scn, &ctx, &p);
        for (size_t j = 0; j < k; j++) found += p.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID;
      }
    } else if (shadow) {
      for (size_t j = 0; j < k; j++) to_ray(&l->r[i + j], &rays[j]);
      if (m == SINGLE) rtcOccluded1(scn, &ctx, &rays[0]);
      else rtcOccluded1M(scn, &ctx, rays, (unsigned)k, sizeof rays[0]);
      for (size_t j = 0; j < k; j++) found += rays[j].tfar < 0.f;
    } else {
      for (size_t j = 0; j < k; j++) {
        to_ray(&l->r[i + j], &hits[j].ray);
        hits[j].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        hits[j].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      if (m == SINGLE) rtcIntersect1(scn, &ctx, &hits[0]);
      else rtcIntersect1M(scn, &ctx, hits, (unsigned)k, sizeof hits[0]);
      for (size_t j = 0; j < k; j++) found += hits[j].hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    i += k;
  }
  return found;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: bench_rays SCENE.xml [--iterations N] [render flags]\n");
    return 2;
  }
  pc_render_request req;
  pc_render_request_default(&req);
  pc_err e = {0};
  long iterations = 1;
  for (int i = 2; i < argc; i++) {
    if (strcmp(argv[i], "--iterations") == 0 && i + 1 < argc) {
      iterations = strtol(argv[++i], NULL, 10);
      if (iterations < 1 || iterations > 100000) { fprintf(stderr, "bench_rays: --iterations %s\n", argv[i]); return 2; }
      continue;
    }
    if (pc_render_flag_parse(&req, argc, argv, &i, &e) <= 0) {
      fprintf(stderr, "bench_rays: bad flag %s: %s\n", argv[i], e.msg);
      return 2;
    }
  }
  pc_scene scene = {0};
  pc_scene_load_opts lo;
  pc_render_request_load_opts(&req, &lo);
  pc_renderer *r = NULL;
  pc_film film = {0};
  ray_log log = {0};
  int rc = pc_scene_load_with(argv[1], &lo, &scene, &e);
  if (!rc) {
    pc_render_request_apply_scene(&req, &scene);
    rc = pc_scene_build(&scene, &e);
  }
  if (!rc) rc = pc_renderer_create(&scene, &req.set, 1, &r, &e);
  if (!rc) rc = pc_film_init(&film, req.set.width, req.set.height, 0, &e);
  /* an untimed iteration first (caches, the first iteration's allocations), then the
   * recorded ones, then the same iterations timed without the hook */
  if (!rc) rc = pc_render_iterations(r, 1000000, 1, &film, NULL, NULL, NULL, NULL, &e);
  scene.ray_hook = record;
  scene.ray_hook_user = &log;
  if (!rc) rc = pc_render_iterations(r, 0, (uint64_t)iterations, &film, NULL, NULL, NULL, NULL, &e);
  scene.ray_hook = NULL;
  double t_render = 0;
  if (!rc) {
    pc_film_clear(&film);
    double t0 = cpu_s();
    rc = pc_render_iterations(r, 0, (uint64_t)iterations, &film, NULL, NULL, NULL, NULL, &e);
    t_render = cpu_s() - t0;
  }
  if (!rc && log.full) rc = pc_errf(&e, PC_ELIMIT, "more than %zu rays: fewer iterations or a smaller image", MAX_RAYS);
  if (rc) {
    fprintf(stderr, "bench_rays: %s\n", e.msg);
    return 1;
  }
  size_t shadow = 0;
  for (size_t i = 0; i < log.n; i++) shadow += log.r[i].shadow != 0;
  printf("%s %s %dx%d max depth %d, %ld iteration%s on 1 thread: %zu rays (%.1f%% shadow rays), %.1f ms of CPU, "
         "%.2f Mrays/s in the renderer\n",
         argv[1], pc_method_name(req.set.method), req.set.width, req.set.height, req.set.max_depth, iterations,
         iterations > 1 ? "s" : "", log.n, 100.0 * (double)shadow / (double)(log.n ? log.n : 1), 1e3 * t_render,
         1e-6 * (double)log.n / t_render);
  size_t found[NMODES];
  for (int m = 0; m < NMODES; m++) {
    double best = INFINITY;
    for (int pass = 0; pass < 3; pass++) {
      double t0 = cpu_s();
      found[m] = replay((RTCScene)scene.rtc_scene, &log, m);
      double t = cpu_s() - t0;
      if (t < best) best = t;
    }
    printf("  %-44s %8.2f Mrays/s: the render's rays take %5.1f%% of its time at this speed\n", mode_name[m],
           1e-6 * (double)log.n / best, 100.0 * best / t_render);
  }
  if (found[STREAM] != found[SINGLE] || found[PACKET] != found[SINGLE])
    printf("  hits or blocked rays differ between the modes: single %zu, stream %zu, packet %zu\n", found[SINGLE],
           found[STREAM], found[PACKET]);
  else
    printf("  every mode: %zu of the rays hit or blocked\n", found[SINGLE]);
  free(log.r);
  pc_film_free(&film);
  pc_renderer_destroy(r);
  pc_scene_free(&scene);
  return 0;
}
