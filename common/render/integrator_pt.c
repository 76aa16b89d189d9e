/* integrator_pt.c: the path tracer: eye paths with BSDF sampling (s=0 when they hit an
 * emitter) and next-event estimation (s=1), combined by MIS. Russian roulette uses the local
 * continuation probability and is part of the BSDF sampling pdf, as in the bidirectional
 * integrators, so their s=0/s=1 weights agree with this one. */
#include "integrator.h"

/* Solid-angle pdf, as seen from `from`, with which next-event estimation picks the emitter
 * point p (normal n) of light `li`. */
static float nee_pdf(const pc_scene *s, int li, vec3 from, vec3 p, vec3 n) {
  const pc_light *l = &s->lights[li];
  vec3 d = v3_sub(from, p);
  float d2 = v3_len2(d);
  float cosl = v3_absdot(n, v3_scale(d, 1.f / sqrtf(d2)));
  if (!(cosl > 0.f)) return 0.f;
  return pc_light_choose_pdf(s, li) * (1.f / l->area) * d2 / cosl;
}

/* Next-event estimation at hit h (s=1): one light sample, MIS-weighted against BSDF sampling
 * (whose pdf includes the continuation q); the weighted contribution before the path's
 * throughput, zero when there is none. */
static vec3 nee(pc_tctx *c, pc_rng *rng, const pc_bsdf_out *o, const pc_shading *sh, const pc_hit *h, float q) {
  const pc_scene *s = c->scene;
  const pc_render_settings *set = c->set;
  float pick;
  int li = pc_light_choose(s, pc_rng_f(rng), &pick);
  const pc_light *l = &s->lights[li];
  float u0 = pc_rng_f(rng), u1 = pc_rng_f(rng), u2 = pc_rng_f(rng);
  vec3 wi, le, f;
  float pl; /* solid-angle pdf of wi; 0 for a point, spot or directional light (delta) */
  float pb, pb_rev; /* BSDF sampling's pdf of wi (without q), and of the reverse (unused) */
  float geo = 1.f; /* point or spot light: 1 / d^2; with the choice's pdf for every delta light */
  bool visible;
  if (l->type == PC_LIGHT_ENV) {
    wi = pc_env_sample(l, u1, u2, &pl);
    pl *= pick;
    if (!(pl > 0.f)) return v3s(0.f);
    le = pc_env_le(l, wi);
    f = pc_bsdf_eval_pdfs_out(o, s->textures, sh, wi, PC_RADIANCE, &pb, &pb_rev);
    if (v3_is_zero(le) || v3_is_zero(f)) return v3s(0.f);
    c->rays++;
    visible = pc_scene_escapes(s, h->p, h->ng, h->eps, wi);
  } else if (l->type == PC_LIGHT_DIRECTIONAL) {
    wi = v3_neg(l->direction);
    le = l->irradiance;
    pl = 0.f;
    geo = 1.f / pick;
    f = pc_bsdf_eval_pdfs_out(o, s->textures, sh, wi, PC_RADIANCE, &pb, &pb_rev);
    if (v3_is_zero(f)) return v3s(0.f);
    c->rays++;
    visible = pc_scene_escapes(s, h->p, h->ng, h->eps, wi);
  } else {
    pc_light_point lp;
    pc_light_sample_point(s, l, u0, u1, u2, &lp);
    vec3 to = v3_sub(lp.p, h->p);
    float d2 = v3_len2(to);
    if (!(d2 > 0.f)) return v3s(0.f);
    wi = v3_scale(to, 1.f / sqrtf(d2));
    le = pc_light_le(l, lp.n, v3_neg(wi));
    if (pc_light_is_delta_pos(l)) {
      pl = 0.f;
      geo = 1.f / (d2 * pick);
    } else {
      float cosl = v3_absdot(lp.n, wi);
      pl = pick * lp.pdf_area * d2 / cosl;
    }
    f = pc_bsdf_eval_pdfs_out(o, s->textures, sh, wi, PC_RADIANCE, &pb, &pb_rev);
    if (v3_is_zero(le) || v3_is_zero(f)) return v3s(0.f);
    c->rays++;
    visible = pc_scene_visible(s, h->p, h->ng, h->eps, lp.p, lp.n, lp.eps);
  }
  if (!visible) return v3s(0.f);
  float cosi = v3_absdot(wi, sh->sh.n), w = 1.f;
  if (pl > 0.f) {
    float a = pc_mis_term(set, pl), b = pc_mis_term(set, pb * q);
    w = a / (a + b);
    geo = 1.f / pl;
  }
  return v3_scale(v3_mul(f, le), cosi * geo * w);
}

void pc_pt_pixel(pc_tctx *c, int x, int y) {
  const pc_scene *s = c->scene;
  const pc_render_settings *set = c->set;
  pc_rng rng = pc_rng_make(set->seed, c->iteration, PC_STREAM_EYE, (uint64_t)y * (uint64_t)s->camera.width + (uint64_t)x);
  float u0 = pc_rng_f(&rng), u1 = pc_rng_f(&rng), px, py;
  pc_camera_pixel_point(&s->camera, x, y, u0, u1, &px, &py);
  vec3 d, o = pc_camera_sample_ray(&s->camera, px, py, &rng, &d);
  vec3 beta = v3s(1.f);
  float prev_pdf = 0.f; /* solid-angle pdf (with continuation) of the last BSDF sample */
  bool prev_delta = true; /* the camera cannot be reached by NEE: full weight at depth 1 */
  vec3 prev_p = o;
  for (int depth = 1; depth <= c->max_segments; depth++) {
    pc_hit h;
    c->rays++;
    if (!pc_scene_intersect(s, o, d, INFINITY, &h)) {
      /* The environment: NEE would have sampled this direction with pick * pdf. */
      if (s->env_light >= 0) {
        const pc_light *l = &s->lights[s->env_light];
        vec3 dn = v3_norm(d);
        vec3 le = pc_env_le(l, dn);
        float w = 1.f;
        if (!prev_delta) {
          float a = pc_mis_term(set, prev_pdf), b = pc_mis_term(set, pc_light_choose_pdf(s, s->env_light) * pc_env_pdf(l, dn));
          w = a / (a + b);
        }
        if (!v3_is_zero(le)) pc_tctx_add(c, PC_LAYER_PT, 0, depth + 1, x, y, v3_scale(v3_mul(beta, le), w));
      }
      break;
    }
    const pc_shape *shape = &s->shapes[h.shape];
    vec3 wo = v3_neg(d);
    if (shape->light >= 0) {
      vec3 le = pc_light_le(&s->lights[shape->light], h.ng, wo);
      if (!v3_is_zero(le)) {
        float w = 1.f;
        if (!prev_delta) {
          float pl = nee_pdf(s, shape->light, prev_p, h.p, h.ng);
          float a = pc_mis_term(set, prev_pdf), b = pc_mis_term(set, pl);
          w = a / (a + b);
        }
        pc_tctx_add(c, PC_LAYER_PT, 0, depth + 1, x, y, v3_scale(v3_mul(beta, le), w));
      }
    }
    if (depth >= c->max_segments) break;
    const pc_material *m = &s->materials[shape->material];
    pc_shading sh;
    pc_shading_from_hit(&sh, s, &h, wo);
    /* wo in the shading frame, once for the vertex's queries */
    pc_bsdf_out bo;
    pc_bsdf_out_make(&bo, m, s->textures, &sh, wo);
    float q = pc_bsdf_out_continuation(&bo, m, s->textures, &sh);

    if (!pc_bsdf_out_is_delta(&bo, m)) {
      vec3 v = nee(c, &rng, &bo, &sh, &h, q);
      if (!v3_is_zero(v)) pc_tctx_add(c, PC_LAYER_NEE, 1, depth + 1, x, y, v3_mul(beta, v));
    }

    if (!(q > 0.f) || pc_rng_f(&rng) >= q) break;
    pc_bsdf_sampled bs;
    float u0 = pc_rng_f(&rng), u1 = pc_rng_f(&rng), u2 = pc_rng_f(&rng);
    if (!pc_bsdf_sample_out(&bo, s->textures, &sh, u0, u1, u2, PC_RADIANCE, &bs)) break;
    if (!(bs.pdf > 0.f) || v3_is_zero(bs.f)) break;
    beta = v3_mul(beta, v3_scale(bs.f, v3_absdot(bs.wi, sh.sh.n) / (bs.pdf * q)));
    if (!v3_is_finite(beta)) break;
    prev_pdf = bs.pdf * q;
    prev_delta = bs.is_delta;
    prev_p = h.p;
    o = pc_offset_by(h.p, h.ng, bs.wi, h.eps);
    d = bs.wi;
  }
}
