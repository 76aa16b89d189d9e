/* connect.c: the one connection routine of the bidirectional methods (any light vertex with any
 * eye vertex, the camera included: s=1, t=1 and inner strategies alike), the s=0 weight of an
 * eye sub-path that hits an emitter, and the strategy-layer splat helper. The MIS weight uses the
 * per-vertex quantities of path_vertex.h: O(1) per connection. */
#include <time.h>

#include "bidir.h"

double pc_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void pc_film_queue_add_strategy(pc_film_queue *q, int strategy_layers, int layer, int s, int t, int x, int y, vec3 v) {
  pc_film_queue_add(q, layer, x, y, v);
  if (strategy_layers > 0 && s + t - 1 <= strategy_layers) {
    int l = pc_film_strategy_layer(q->film, s, t);
    if (l >= 0) pc_film_queue_add(q, l, x, y, v);
  }
}

/* Weight of a strategy whose own term is `own` (its count under the heuristic) given the sums of
 * the strategies on the light side (sl) and on the eye side (se) of its connection, each
 * relative to its pdf. */
static float weight_of(float own, float sl, float se) {
  float w = own / (own + sl + se);
  return w > 0.f && w <= 1.f ? w : 0.f; /* sl or se overflowed to Inf (or NaN): weight 0 */
}

float pc_lt_pixel_weight(const pc_mis_counts *n, const pc_connection *k, float density) {
  return weight_of(k->mis_own, pc_mis(n, density) * k->mis_eye, 0.f);
}

void pc_connect_nee(pc_tctx *c, const pc_mis_counts *n, pc_rng *rng, const pc_path_vertex *ev, int x, int y) {
  pc_connection k;
  pc_path_vertex lv;
  float u0 = pc_rng_f(rng), u1 = pc_rng_f(rng), u2 = pc_rng_f(rng), u3 = pc_rng_f(rng);
  pc_light_vertex_sample(c->scene, n, u0, u1, u2, u3, &lv);
  if (pc_connect(c, n, &lv, ev, c->weighted, &k))
    pc_tctx_add(c, PC_LAYER_NEE, 1, ev->depth, x, y, v3_scale(k.f, k.weight));
}

float pc_mis_weight_hit(const pc_scene *s, const pc_mis_counts *n, const pc_path_vertex *v, int light) {
  const pc_light *l = &s->lights[light];
  /* The light side would have sampled v as x_0 (choice by power, point by area) and emitted
   * toward v's predecessor with the cosine-weighted direction pdf; for the environment, v's
   * direction by pc_env_sample and v's predecessor from the disk. */
  float p_area, pdf_emit;
  if (v->kind == PC_VTX_ENV) {
    p_area = pc_light_choose_pdf(s, light) * pc_env_pdf(l, v3_neg(v->wo));
    pdf_emit = pc_env_disk_pdf(s);
  } else {
    p_area = pc_light_choose_pdf(s, light) / l->area;
    pdf_emit = fmaxf(0.f, v3_dot(v->ng, v->wo)) * PC_INV_PI;
  }
  int t = v->depth;
  float se = pc_mis_side(n, v, p_area, pdf_emit, pc_mis_count(n, 1, t - 1));
  return weight_of(pc_mis(n, pc_mis_count(n, 0, t)), 0.f, se);
}

bool pc_connect(pc_tctx *c, const pc_mis_counts *n, const pc_path_vertex *lv, const pc_path_vertex *ev, bool weighted,
                pc_connection *out) {
  return pc_connect_unoccluded(c, n, lv, ev, weighted, out) && pc_connect_visible(c, lv, ev);
}

bool pc_connect_visible(pc_tctx *c, const pc_path_vertex *lv, const pc_path_vertex *ev) {
  c->rays++;
  /* A vertex on the environment is at infinity in direction -lv->wo from the eye vertex. */
  if (lv->kind == PC_VTX_ENV) return pc_scene_escapes(c->scene, ev->p, ev->ng, ev->eps, v3_neg(lv->wo));
  return pc_scene_visible(c->scene, lv->p, lv->ng, lv->eps, ev->p, ev->ng, ev->eps);
}

bool pc_connect_unoccluded(pc_tctx *c, const pc_mis_counts *n, const pc_path_vertex *lv, const pc_path_vertex *ev,
                           bool weighted, pc_connection *out) {
  if (lv->delta || ev->delta) return false;
  const pc_scene *s = c->scene;
  bool env = lv->kind == PC_VTX_ENV;
  vec3 w; /* light vertex -> eye vertex */
  float d2;
  if (env) {
    w = lv->wo; /* at infinity: solid-angle measure, d2 = 1 (path_vertex.h) */
    d2 = 1.f;
  } else {
    vec3 d = v3_sub(ev->p, lv->p);
    d2 = v3_len2(d);
    if (!(d2 > 0.f)) return false;
    w = v3_scale(d, 1.f / sqrtf(d2));
  }
  vec3 we = v3_neg(w);

  /* Light end: emission or importance-transport BSDF, times the cosine; pdfs of continuing the
   * light sub-path toward ev (fwd) and of the reverse (toward lv's predecessor, given w). */
  vec3 fl;
  float cos_l, pdf_l_fwd, pdf_l_rev = 0.f;
  if (env) {
    /* A directional light is a Dirac in direction: it cannot be hit (cos_l 0, no s=0 strategy),
     * and a camera sees it in no pixel. */
    bool directional = s->lights[lv->light].type == PC_LIGHT_DIRECTIONAL;
    if (directional && ev->kind == PC_VTX_CAMERA) return false;
    fl = v3s(1.f);
    cos_l = directional ? 0.f : 1.f;
    pdf_l_fwd = pc_env_disk_pdf(s);
  } else if (lv->kind == PC_VTX_LIGHT) {
    const pc_light *l = &s->lights[lv->light];
    if (pc_light_is_delta_pos(l)) {
      fl = pc_light_profile(l, w); /* a spot's falloff; 1 for a point light */
      if (v3_is_zero(fl)) return false;
      cos_l = 0.f; /* cannot be hit: no s=0 strategy */
      pdf_l_fwd = pc_light_pdf_dir(l, lv->ng, w);
    } else {
      cos_l = v3_dot(lv->ng, w);
      if (!(cos_l > 0.f)) return false; /* back side or edge-on */
      fl = v3s(cos_l);
      pdf_l_fwd = cos_l * PC_INV_PI;
    }
  } else {
    fl = v3_scale(pc_bsdf_eval_pdfs_out(&lv->out, s->textures, &lv->sh, w, PC_IMPORTANCE, &pdf_l_fwd, &pdf_l_rev),
                  v3_absdot(w, lv->sh.sh.n));
    if (v3_is_zero(fl)) return false;
    cos_l = v3_absdot(w, lv->ng);
    pdf_l_fwd *= lv->q;
    pdf_l_rev *= lv->q;
  }

  /* Eye end: the camera (t=1: We * cos = its direction pdf) or a radiance-transport BSDF. */
  vec3 fe;
  float cos_e, pdf_e_fwd, pdf_e_rev = 0.f;
  if (ev->kind == PC_VTX_CAMERA) {
    const pc_camera *cam = &s->camera;
    if (!pc_camera_raster_from(cam, ev->p, we, &out->px, &out->py)) return false;
    pdf_e_fwd = pc_camera_dir_pdf(cam, we);
    fe = v3s(pdf_e_fwd);
    cos_e = 0.f; /* the pinhole cannot be hit */
  } else {
    fe = v3_scale(pc_bsdf_eval_pdfs_out(&ev->out, s->textures, &ev->sh, we, PC_RADIANCE, &pdf_e_fwd, &pdf_e_rev),
                  v3_absdot(w, ev->sh.sh.n));
    if (v3_is_zero(fe)) return false;
    cos_e = v3_absdot(w, ev->ng);
    pdf_e_fwd *= ev->q;
    pdf_e_rev *= ev->q;
  }

  vec3 f = v3_scale(v3_mul(v3_mul(lv->beta, fl), v3_mul(fe, ev->beta)), 1.f / d2);
  if (v3_is_zero(f) || !v3_is_finite(f)) return false;
  float weight = 1.f;
  if (weighted) {
    int sl = lv->depth, tl = ev->depth;
    /* Strategies with fewer light vertices: ev would sample lv (area pdf pdf_e_fwd cos_l / d2);
     * with more: lv would sample ev. */
    float sum_l = pc_mis_side(n, lv, pdf_e_fwd * cos_l / d2, pdf_l_rev, pc_mis_count(n, sl - 1, tl + 1));
    float sum_e = pc_mis_side(n, ev, pdf_l_fwd * cos_e / d2, pdf_e_rev, pc_mis_count(n, sl + 1, tl - 1));
    float own = pc_mis(n, pc_mis_count(n, sl, tl));
    weight = weight_of(own, sum_l, sum_e);
    if (weight == 0.f) return false;
    out->mis_own = own;
    out->mis_eye = sum_l; /* at the camera (t = 1) sum_e is 0: the pinhole cannot be hit */
  }
  out->f = f;
  out->weight = weight;
  return true;
}
