/* integrator_lt.c: light tracing (t=1): every light vertex is connected to the camera and
 * splatted into the thread's splat film (layer lt), counted per light path. The lt method uses
 * it for every light path and adds s=0 for emitters seen directly, since path length 1 (the
 * emitter itself) is the one length light tracing shares with another strategy: those two are
 * combined by the balance/power heuristic with their counts (n=1 for s=0, n_lt for t=1); longer
 * light-traced paths have weight 1. BDPT uses the same splats with its full MIS weights. */
#include "bidir.h"

/* A connection to the camera added to every pixel whose filter reaches its raster point: each
 * pixel's measurement is its filter density there times the pixel box's, and its eye strategies'
 * pdfs scale the same way (pc_camera_pixel_point), so their share of the MIS weight does. */
static void splat_filtered(pc_tctx *c, const pc_connection *k, bool weighted, int s) {
  const pc_camera *cam = &c->scene->camera;
  int x0, y0, nx, ny;
  float wx[PC_CAMERA_FOOTPRINT_MAX], wy[PC_CAMERA_FOOTPRINT_MAX];
  pc_camera_footprint(cam, k->px, k->py, &x0, &nx, wx, &y0, &ny, wy);
  /* A footprint's pixels lie in a few short rows, so they go straight into the thread's splat
   * film (the rows fetched first) rather than through the queue, which pays for scattered adds. */
  pc_film *film = c->splat->film;
  int layers[2] = {PC_LAYER_LT, pc_film_strategy_layer(film, s, 1)}, nl = layers[1] >= 0 ? 2 : 1;
  for (int l = 0; l < nl; l++)
    for (int j = 0; j < ny; j++) {
      const double *row = film->layers[layers[l]].sum + 3 * ((size_t)(y0 + j) * film->w + x0);
      __builtin_prefetch(row, 1);
      __builtin_prefetch(row + 3 * nx - 1, 1);
    }
  for (int j = 0; j < ny; j++) {
    if (!(wy[j] > 0.f)) continue;
    for (int i = 0; i < nx; i++) {
      float density = wx[i] * wy[j];
      if (!(density > 0.f)) continue;
      float w = weighted ? pc_lt_pixel_weight(&c->counts, k, density) : 1.f;
      if (w == 0.f) continue;
      vec3 v = v3_scale(k->f, density * w);
      for (int l = 0; l < nl; l++) pc_film_add_sample(film, layers[l], x0 + i, y0 + j, v);
    }
  }
}

void pc_lt_splat(pc_tctx *c, const pc_path_vertex *lv, int nl, uint64_t index) {
  const pc_camera *cam = &c->scene->camera;
  /* a thin lens: each connection to the camera samples its own lens point */
  pc_rng lens = {0, 0};
  if (cam->aperture_radius > 0.f) lens = pc_rng_make(c->set->seed, c->iteration, PC_STREAM_LENS, index);
  pc_path_vertex eye = {0};
  eye.kind = PC_VTX_CAMERA;
  eye.p = cam->pos;
  eye.beta = v3s(1.f);
  eye.depth = 1;
  eye.material = eye.light = -1;
  bool lt_method = c->set->method == PC_METHOD_LT;
  bool pixel_box = pc_rfilter_is_pixel(&cam->filter);
  for (int i = 0; i < nl; i++) {
    /* The lt method weighs only path length 1 (against s=0); BDPT weighs every length. */
    bool weighted = c->weighted && (!lt_method || lv[i].depth == 1);
    if (cam->aperture_radius > 0.f) {
      float u1 = pc_rng_f(&lens), u2 = pc_rng_f(&lens);
      eye.p = pc_camera_lens_point(cam, u1, u2);
    }
    pc_connection k;
    if (!pc_connect(c, &c->counts, &lv[i], &eye, weighted, &k)) continue;
    if (pixel_box)
      pc_film_queue_add_strategy(c->splat, c->set->strategy_layers, PC_LAYER_LT, lv[i].depth, 1, (int)k.px, (int)k.py,
                                 v3_scale(k.f, k.weight));
    else
      splat_filtered(c, &k, weighted, lv[i].depth);
  }
}

void pc_lt_light_path(pc_tctx *c, uint64_t index) {
  bool timed = pc_timed(index);
  double t0 = pc_stamp(timed);
  int nl = pc_light_subpath(c, &c->counts, index, c->light_path);
  double t1 = pc_stamp(timed);
  pc_lt_splat(c, c->light_path, nl, index);
  if (timed) {
    c->t_paths += PC_TIMED_EVERY * (t1 - t0);
    c->t_lt += PC_TIMED_EVERY * (pc_seconds() - t1);
  }
}

void pc_emitter_hit(pc_tctx *c, void *user, const pc_path_vertex *v, int light, vec3 le) {
  const pc_pixel_target *h = user;
  float w = c->weighted ? pc_mis_weight_hit(c->scene, &c->counts, v, light) : 1.f;
  pc_tctx_add(c, PC_LAYER_PT, 0, v->depth, h->x, h->y, v3_scale(v3_mul(v->beta, le), w));
}

void pc_lt_pixel(pc_tctx *c, int x, int y) {
  uint64_t j = (uint64_t)y * (uint64_t)c->set->width + (uint64_t)x;
  bool timed = pc_timed(j);
  double t0 = pc_stamp(timed);
  pc_rng rng = pc_rng_make(c->set->seed, c->iteration, PC_STREAM_EYE, j);
  pc_pixel_target h = {x, y};
  pc_eye_subpath(c, &c->counts, &rng, x, y, 2, c->eye_path, pc_emitter_hit, &h);
  if (timed) c->t_paths += PC_TIMED_EVERY * (pc_seconds() - t0);
}
