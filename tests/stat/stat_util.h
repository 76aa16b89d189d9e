/* stat_util.h: helpers of the statistical tests: load a shipped scene with render overrides,
 * render independent iterations one by one, and reduce each to per-block means so a test can
 * compare estimators with standard errors measured from the iterations themselves. */
#ifndef PC_STAT_UTIL_H
#define PC_STAT_UTIL_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "film.h"
#include "render.h"
#include "render_flags.h"
#include "scene.h"
#include "../unit/test_helpers_fs.h"

/* Per-block statistics over iterations: block b of layer `layer` (-1 = beauty), channel mean
 * (luminance-free: the average of R, G and B). */
typedef struct stat_blocks {
  int bw, bh, nblocks;
  int n;            /* iterations accumulated */
  double *sum, *sum2;
} stat_blocks;

static inline char *stat_scene_path(const char *name) {
  const char *src = getenv("PCBPT_SOURCE_DIR");
  char *p = malloc(4096);
  snprintf(p, 4096, "%s/scenes/%s/scene.xml", src ? src : ".", name);
  return p;
}

/* Loads and builds scenes/<name>/scene.xml with the given settings overriding film size,
 * method and depth; returns 0 on success (prints the error otherwise). */
static inline int stat_load(const char *name, pc_render_request *req, pc_scene *scene) {
  char *path = stat_scene_path(name);
  pc_err e = {0};
  int rc = pc_scene_load(path, scene, &e);
  if (rc == 0) {
    pc_render_request_apply_scene(req, scene);
    rc = pc_scene_build(scene, &e);
  }
  if (rc != 0) fprintf(stderr, "stat_load %s: %s\n", path, e.msg);
  free(path);
  return rc;
}

/* Loads and builds the scene file `path` (with opts, NULL for none) for a request of `method`
 * at res x res with the given seed and the PCBPT settings the statistical tests share (M = 20
 * light paths, 5% cache pixels); returns 0 on success (prints the error otherwise). */
static inline int stat_load_file(const char *path, const pc_scene_load_opts *opts, pc_method method, int res, uint64_t seed,
                                 pc_render_request *req, pc_scene *scene) {
  pc_render_request_default(req);
  req->set.method = method;
  req->method_set = true;
  req->set.width = req->set.height = res;
  req->width_set = req->height_set = true;
  req->set.seed = seed;
  req->set.pcbpt_m = 20;
  req->set.cache_fraction = 0.05f;
  pc_err e = {0};
  int rc = pc_scene_load_with(path, opts, scene, &e);
  if (!rc) {
    pc_render_request_apply_scene(req, scene);
    rc = pc_scene_build(scene, &e);
  }
  if (rc) fprintf(stderr, "%s\n", e.msg);
  return rc;
}

/* Renders iterations [first, first+n) one at a time and accumulates block means of `layer`
 * (-1 = beauty) into st (block size bs x bs pixels). */
static inline int stat_render_blocks(const pc_scene *scene, const pc_render_settings *set, int threads, uint64_t first,
                                     int n, int layer, int bs, stat_blocks *st) {
  pc_err e = {0};
  pc_renderer *r = NULL;
  pc_film film;
  int rc = pc_film_init(&film, set->width, set->height, set->strategy_layers, &e);
  if (rc == 0) rc = pc_renderer_create(scene, set, threads, &r, &e);
  if (rc != 0) {
    fprintf(stderr, "stat_render_blocks: %s\n", e.msg);
    pc_film_free(&film);
    return rc;
  }
  st->bw = (set->width + bs - 1) / bs;
  st->bh = (set->height + bs - 1) / bs;
  st->nblocks = st->bw * st->bh;
  st->n = 0;
  st->sum = calloc((size_t)st->nblocks, sizeof(double));
  st->sum2 = calloc((size_t)st->nblocks, sizeof(double));
  float *img = malloc(sizeof(float) * 3 * (size_t)set->width * set->height);
  double *blk = malloc(sizeof(double) * (size_t)st->nblocks);
  int *cnt = malloc(sizeof(int) * (size_t)st->nblocks);
  for (int it = 0; it < n && rc == 0; it++) {
    pc_film_clear(&film);
    rc = pc_render_iterations(r, first + (uint64_t)it, 1, &film, NULL, NULL, NULL, NULL, &e);
    if (rc != 0) {
      fprintf(stderr, "stat_render_blocks: %s\n", e.msg);
      break;
    }
    if (layer < 0) pc_film_beauty(&film, img);
    else pc_film_layer_image(&film, layer, img);
    memset(blk, 0, sizeof(double) * (size_t)st->nblocks);
    memset(cnt, 0, sizeof(int) * (size_t)st->nblocks);
    for (int y = 0; y < set->height; y++)
      for (int x = 0; x < set->width; x++) {
        int b = (y / bs) * st->bw + x / bs;
        const float *p = img + 3 * ((size_t)y * set->width + x);
        blk[b] += (p[0] + p[1] + p[2]) / 3.0;
        cnt[b]++;
      }
    for (int b = 0; b < st->nblocks; b++) {
      double v = blk[b] / cnt[b];
      st->sum[b] += v;
      st->sum2[b] += v * v;
    }
    st->n++;
  }
  free(img);
  free(blk);
  free(cnt);
  pc_renderer_destroy(r);
  pc_film_free(&film);
  return rc;
}

static inline double stat_mean(const stat_blocks *st, int b) { return st->sum[b] / st->n; }
/* Standard error of the block mean, from the spread of the independent iterations. */
static inline double stat_se(const stat_blocks *st, int b) {
  double m = stat_mean(st, b);
  double var = (st->sum2[b] / st->n - m * m) * st->n / (st->n - 1);
  return sqrt(var > 0 ? var / st->n : 0);
}
/* The largest difference between two estimates' block means, in standard errors of the
 * difference (0 where both are exact and equal; blocks with no spread must agree exactly,
 * else the result is infinite). */
static inline double stat_largest_z(const stat_blocks *a, const stat_blocks *b) {
  double worst = 0;
  for (int k = 0; k < a->nblocks; k++) {
    double se = sqrt(stat_se(a, k) * stat_se(a, k) + stat_se(b, k) * stat_se(b, k));
    double d = fabs(stat_mean(a, k) - stat_mean(b, k)), z = se > 0 ? d / se : (d > 0 ? INFINITY : 0);
    if (z > worst) worst = z;
  }
  return worst;
}
static inline void stat_free(stat_blocks *st) {
  free(st->sum);
  free(st->sum2);
  memset(st, 0, sizeof *st);
}

/* The rest of a sensor (its frame and a 32x32 film) looking at a diffuse floor lit by a small
 * area light from above, for agreement tests to put their subject on. */
#define STAT_VIEW_OF_LIT_FLOOR \
  "<transform name=\"toWorld\"><lookat origin=\"0, 1, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>" \
  "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film></sensor>" \
  "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"3\"/><rotate x=\"1\" angle=\"-90\"/></transform>" \
  "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf></shape>" \
  "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale value=\"0.3\"/><rotate x=\"1\" angle=\"90\"/>" \
  "<translate y=\"2\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"20\"/></emitter></shape>"

/* A scene written as dir/scene.xml, rendered by `m` at res x res with the given seed and
 * maxDepth (0: the scene's) for `iterations` into st (blocks of bs); the scene is kept in *keep
 * when given, else freed. 0 on success. */
static inline int stat_render_xml(const char *dir, const char *xml, pc_method m, int res, uint64_t seed, int max_depth,
                                  int iterations, int bs, stat_blocks *st, pc_scene *keep) {
  char path[4200];
  snprintf(path, sizeof path, "%s/scene.xml", dir);
  if (th_write_str(dir, "scene.xml", xml)) return -1;
  pc_render_request req;
  pc_scene scene;
  int rc = stat_load_file(path, NULL, m, res, seed, &req, &scene);
  if (rc) return rc;
  if (max_depth) req.set.max_depth = max_depth;
  rc = stat_render_blocks(&scene, &req.set, 2, 0, iterations, -1, bs, st);
  if (keep) *keep = scene;
  else pc_scene_free(&scene);
  return rc;
}

/* Renders the scene with pt and with lt, bdpt, cbdpt and pcbpt (as stat_render_xml), prints
 * each one's largest block difference from pt as "<label> <method> vs pt: ...", and returns
 * the largest of them (infinite if a render fails). */
static inline double stat_agreement(const char *dir, const char *xml, const char *label, int res, uint64_t seed,
                                    int max_depth, int iterations, int bs) {
  stat_blocks ref = {0};
  if (stat_render_xml(dir, xml, PC_METHOD_PT, res, seed, max_depth, iterations, bs, &ref, NULL)) return INFINITY;
  const pc_method methods[] = {PC_METHOD_LT, PC_METHOD_BDPT, PC_METHOD_CBDPT, PC_METHOD_PCBPT};
  double worst = 0;
  for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
    stat_blocks st = {0};
    double mk = INFINITY;
    int lit = 0;
    if (!stat_render_xml(dir, xml, methods[k], res, seed, max_depth, iterations, bs, &st, NULL)) {
      mk = stat_largest_z(&ref, &st);
      for (int b = 0; b < st.nblocks; b++) lit += stat_mean(&st, b) > 0;
    }
    printf("%s %-5s vs pt: largest block difference %.2f standard errors over %d blocks (%d lit)\n", label,
           pc_method_name(methods[k]), mk, st.nblocks, lit);
    if (mk > worst) worst = mk;
    stat_free(&st);
  }
  stat_free(&ref);
  return worst;
}

#endif
