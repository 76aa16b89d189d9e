/* integrator_bdpt.c: bidirectional path tracing (Veach 1997) with recursive MIS weights
 * (path_vertex.h). Pairing: the eye path of pixel j (j = y*W + x) is connected, for the inner
 * strategies (s>=2, t>=2), to light path j mod N_L of the same iteration; that light path's
 * light tracing (t=1) is done here too when j < N_L, so each light path splats exactly once.
 * Light paths j >= W*H (N_L > W*H) are only light traced (render.c). s=1 uses a fresh light
 * sample per eye vertex from the pixel's own stream, as the path tracer does. */
#include "bidir.h"

void pc_bdpt_pixel(pc_tctx *c, int x, int y) {
  const pc_render_settings *set = c->set;
  const pc_mis_counts *n = &c->counts;
  uint64_t j = (uint64_t)y * (uint64_t)set->width + (uint64_t)x;
  int maxs = c->max_segments;
  bool timed = pc_timed(j);
  double t0 = pc_stamp(timed);
  int nl = pc_light_subpath(c, n, j % c->n_light, c->light_path);
  double t1 = pc_stamp(timed);
  if (j < c->n_light) pc_lt_splat(c, c->light_path, nl, j);
  double t2 = pc_stamp(timed);
  pc_rng rng = pc_rng_make(set->seed, c->iteration, PC_STREAM_EYE, j);
  pc_pixel_target h = {x, y};
  int ne = pc_eye_subpath(c, n, &rng, x, y, maxs + 1, c->eye_path, pc_emitter_hit, &h);
  double t3 = pc_stamp(timed);
  for (int t = 2; t <= ne && t <= maxs; t++) {
    const pc_path_vertex *ev = &c->eye_path[t - 1];
    if (ev->delta) continue;
    pc_connect_nee(c, n, &rng, ev, x, y);
    pc_connection k;
    for (int s = 2; s <= nl && s + t - 1 <= maxs; s++)
      if (pc_connect(c, n, &c->light_path[s - 1], ev, c->weighted, &k))
        pc_tctx_add(c, PC_LAYER_INNER, s, t, x, y, v3_scale(k.f, k.weight));
  }
  if (timed) {
    c->t_paths += PC_TIMED_EVERY * ((t1 - t0) + (t3 - t2));
    c->t_lt += PC_TIMED_EVERY * (t2 - t1);
    c->t_connect += PC_TIMED_EVERY * (pc_seconds() - t3);
  }
}
