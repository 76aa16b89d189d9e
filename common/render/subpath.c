/* subpath.c: light and eye sub-paths as pc_path_vertex arrays carrying their recursive MIS
 * quantities (path_vertex.h). Both sides share one random walk; Russian roulette uses the local
 * continuation probability q and folds it into the forward and reverse pdfs. */
#include "bidir.h"

pc_mis_counts pc_mis_counts_bdpt(const pc_render_settings *set, uint64_t n_light) {
  pc_mis_counts n;
  n.n_lt = (float)((double)n_light / ((double)set->width * (double)set->height));
  n.n_inner = 1.f;
  n.power = set->mis_heuristic == PC_MIS_POWER;
  return n;
}

/* Extends the sub-path v[0..nv-1] by tracing `dir` from its last vertex, whose sampling of dir
 * had pdfs pdf_fwd/pdf_rev (q included) and cosine cos_out; `beta` is the throughput carried
 * along dir. Stops at max_vertices. */
static int walk(pc_tctx *c, const pc_mis_counts *mc, pc_rng *rng, pc_path_vertex *v, int nv, int max_vertices,
                bool light_side, vec3 dir, vec3 beta, float pdf_fwd, float pdf_rev, bool delta, float cos_out,
                pc_emitter_hit_fn hit, void *user) {
  const pc_scene *s = c->scene;
  pc_transport mode = light_side ? PC_IMPORTANCE : PC_RADIANCE;
  while (nv < max_vertices) {
    const pc_path_vertex *prev = &v[nv - 1];
    vec3 o = v3_is_zero(prev->ng) ? prev->p : pc_offset_by(prev->p, prev->ng, dir, prev->eps);
    pc_hit h;
    c->rays++;
    bool escaped = !pc_scene_intersect(s, o, dir, INFINITY, &h);
    /* An eye ray that leaves the scene reaches the environment, a vertex at infinity. */
    if (escaped && (light_side || !hit || s->env_light < 0)) break;
    vec3 da;
    float d2, cos_in;
    if (escaped || prev->kind == PC_VTX_ENV) {
      /* Solid-angle measure at the environment's end of the edge (path_vertex.h). */
      da = v3_norm(dir);
      d2 = 1.f;
      cos_in = escaped ? 1.f : v3_absdot(h.ng, da);
    } else {
      /* The ray left from an offset origin: the MIS pdfs and the vertex's wo use the direction
       * between the stored vertices, as every connection to them does. */
      vec3 e = v3_sub(h.p, prev->p);
      d2 = v3_len2(e);
      if (!(d2 > 0.f)) break;
      da = v3_scale(e, 1.f / sqrtf(d2));
      cos_in = v3_absdot(h.ng, da);
    }
    /* A grazing hit has no usable area pdf (its reverse strategies would divide by ~0). */
    if (!(cos_in > 1e-6f)) break;
    if (prev->kind == PC_VTX_SURFACE) {
      cos_out = v3_absdot(prev->ng, da);
      if (!delta) {
        float pf, pr;
        pc_bsdf_pdfs_out(&prev->out, s->textures, &prev->sh, da, &pf, &pr);
        /* The offset origin turns the edge by about eps / distance. A lobe narrower than that
         * (a near-specular rough surface, e.g. roughdielectric alpha 1e-4) would find its own
         * sample impossible along the edge and lose the path: it keeps the sampled pdfs. */
        if (pf * prev->q >= 0.5f * pdf_fwd) {
          pdf_fwd = pf * prev->q;
          pdf_rev = pr * prev->q;
        }
        if (!(pdf_fwd > 0.f)) break;
      }
    } else if (prev->kind == PC_VTX_LIGHT && cos_out > 0.f) {
      cos_out = v3_dot(prev->ng, da);
      pdf_fwd = cos_out * PC_INV_PI;
      if (!(pdf_fwd > 0.f)) break;
    }
    pc_path_vertex *cur = &v[nv];
    if (escaped) {
      /* Reported but not kept: the environment is no connection endpoint. */
      const pc_light *l = &s->lights[s->env_light];
      *cur = (pc_path_vertex){.kind = PC_VTX_ENV, .p = prev->p, .wo = v3_neg(da), .beta = beta, .material = -1,
                              .light = s->env_light, .depth = nv + 1, .q = 1.f};
      pc_mis_extend(mc, prev, light_side, cur, pdf_fwd, pdf_rev, delta, cos_out, cos_in, d2);
      vec3 le = pc_env_le(l, da);
      if (!v3_is_zero(le)) hit(c, user, cur, cur->light, le);
      break;
    }
    const pc_shape *shape = &s->shapes[h.shape];
    const pc_material *m = &s->materials[shape->material];
    cur->kind = PC_VTX_SURFACE;
    cur->p = h.p;
    cur->ng = h.ng;
    cur->eps = h.eps;
    pc_shading_from_hit(&cur->sh, s, &h, v3_neg(da));
    cur->wo = v3_neg(da);
    pc_bsdf_out_make(&cur->out, m, s->textures, &cur->sh, cur->wo);
    cur->beta = beta;
    cur->material = shape->material;
    cur->light = shape->light;
    cur->depth = nv + 1;
    cur->q = pc_bsdf_out_continuation(&cur->out, m, s->textures, &cur->sh);
    cur->delta = pc_bsdf_out_is_delta(&cur->out, m);
    pc_mis_extend(mc, prev, light_side, cur, pdf_fwd, pdf_rev, delta, cos_out, cos_in, d2);
    nv++;
    if (hit && cur->light >= 0) {
      vec3 le = pc_light_le(&s->lights[cur->light], cur->ng, cur->wo);
      if (!v3_is_zero(le)) hit(c, user, cur, cur->light, le);
    }
    if (nv >= max_vertices) break;
    float q = cur->q;
    if (!(q > 0.f) || pc_rng_f(rng) >= q) break;
    pc_bsdf_sampled bs;
    float u0 = pc_rng_f(rng), u1 = pc_rng_f(rng), u2 = pc_rng_f(rng);
    if (!pc_bsdf_sample_out(&cur->out, s->textures, &cur->sh, u0, u1, u2, mode, &bs)) break;
    if (!(bs.pdf > 0.f) || v3_is_zero(bs.f)) break;
    beta = v3_mul(beta, v3_scale(bs.f, v3_absdot(bs.wi, cur->sh.sh.n) / (bs.pdf * q)));
    if (!v3_is_finite(beta) || v3_is_zero(beta)) break;
    /* Delta lobes keep the sampled lobe probabilities; smooth ones are re-evaluated along the
     * actual edge once it is known. */
    pdf_fwd = bs.pdf * q;
    pdf_rev = bs.pdf_rev * q;
    delta = bs.is_delta;
    dir = bs.wi;
  }
  return nv;
}

float pc_env_disk_pdf(const pc_scene *s) { return 1.f / (PC_PI * s->env_radius * s->env_radius); }

void pc_light_vertex_sample(const pc_scene *s, const pc_mis_counts *n, float u0, float u1, float u2, float u3,
                            pc_path_vertex *out) {
  float pick;
  int li = pc_light_choose(s, u0, &pick);
  const pc_light *l = &s->lights[li];
  out->material = -1;
  out->light = li;
  out->depth = 1;
  out->q = 1.f;
  out->delta = false;
  out->mis_far = 0.f;
  if (l->type == PC_LIGHT_ENV) {
    /* A direction, at infinity: its density is per unit solid angle (path_vertex.h). */
    float pdf;
    vec3 d = pc_env_sample(l, u1, u2, &pdf);
    float pa = pick * pdf;
    out->kind = PC_VTX_ENV;
    out->p = s->scene_center;
    out->ng = v3s(0.f);
    out->eps = 0.f;
    out->wo = v3_neg(d);
    out->beta = pa > 0.f ? v3_scale(pc_env_le(l, d), 1.f / pa) : v3s(0.f);
    out->mis_near = pa > 0.f ? pc_mis(n, 1.f / pa) : 0.f;
    return;
  }
  if (l->type == PC_LIGHT_DIRECTIONAL) {
    /* At infinity too, with its one direction: the Dirac factor cancels between strategies. */
    out->kind = PC_VTX_ENV;
    out->p = s->scene_center;
    out->ng = v3s(0.f);
    out->eps = 0.f;
    out->wo = l->direction;
    out->beta = v3_scale(l->irradiance, 1.f / pick);
    out->mis_near = pc_mis(n, 1.f / pick);
    return;
  }
  pc_light_point lp;
  pc_light_sample_point(s, l, u1, u2, u3, &lp);
  float pa = pick * lp.pdf_area; /* area pdf (point and spot lights: the choice, the delta cancels) */
  out->kind = PC_VTX_LIGHT;
  out->p = lp.p;
  out->ng = lp.n;
  out->eps = lp.eps;
  out->wo = v3s(0.f);
  /* A spot's profile enters with the emitted direction (pc_light_subpath, pc_connect). */
  out->beta = v3_scale(pc_light_is_delta_pos(l) ? l->intensity : l->radiance, 1.f / pa);
  out->mis_near = pc_mis(n, 1.f / pa);
}

/* A light sub-path from the environment or a directional light: the direction of v[0], from a
 * uniform point of the disk of radius R perpendicular to it, centred on the bounding sphere's
 * tangent plane behind the scene (pbrt-v3's infinite lights, Mitsuba's directional). */
static int env_subpath(pc_tctx *c, const pc_mis_counts *n, pc_rng *rng, pc_path_vertex *v) {
  const pc_scene *s = c->scene;
  vec3 w = v[0].wo;
  float u0 = pc_rng_f(rng), u1 = pc_rng_f(rng);
  if (v3_is_zero(v[0].beta) || c->max_segments < 2) return 1;
  float r = sqrtf(u0) * s->env_radius, phi = 2.f * PC_PI * u1;
  frame f = frame_from_normal(w);
  vec3 disk = v3_add(v3_scale(f.s, r * cosf(phi)), v3_scale(f.t, r * sinf(phi)));
  v[0].p = v3_add(v3_madd(s->scene_center, w, -s->env_radius), disk);
  float pdf_pos = pc_env_disk_pdf(s);
  vec3 beta = v3_scale(v[0].beta, 1.f / pdf_pos);
  /* A directional light cannot be hit: cos_out 0 removes the s=0 strategy, as for point lights. */
  float cos_out = s->lights[v[0].light].type == PC_LIGHT_DIRECTIONAL ? 0.f : 1.f;
  return walk(c, n, rng, v, 1, c->max_segments, true, w, beta, pdf_pos, 0.f, false, cos_out, NULL, NULL);
}

int pc_light_subpath(pc_tctx *c, const pc_mis_counts *n, uint64_t index, pc_path_vertex *v) {
  const pc_scene *s = c->scene;
  pc_rng rng = pc_rng_make(c->set->seed, c->iteration, PC_STREAM_LIGHT, index);
  float u0 = pc_rng_f(&rng), u1 = pc_rng_f(&rng), u2 = pc_rng_f(&rng), u3 = pc_rng_f(&rng);
  pc_light_vertex_sample(s, n, u0, u1, u2, u3, &v[0]);
  if (v[0].kind == PC_VTX_ENV) return env_subpath(c, n, &rng, v);
  const pc_light *l = &s->lights[v[0].light];
  float pdf_dir;
  u0 = pc_rng_f(&rng);
  u1 = pc_rng_f(&rng);
  vec3 dir = pc_light_sample_dir(l, v[0].ng, u0, u1, &pdf_dir);
  if (!(pdf_dir > 0.f) || c->max_segments < 2) return 1;
  /* A point or spot light cannot be hit by an eye path: cos_out 0 removes the s=0 strategy. */
  bool at_point = pc_light_is_delta_pos(l);
  float cos_out = at_point ? 0.f : v3_dot(v[0].ng, dir);
  vec3 beta = at_point ? v3_scale(v3_mul(v[0].beta, pc_light_profile(l, dir)), 1.f / pdf_dir)
                       : v3_scale(v[0].beta, cos_out / pdf_dir);
  if (v3_is_zero(beta)) return 1;
  return walk(c, n, &rng, v, 1, c->max_segments, true, dir, beta, pdf_dir, 0.f, false, cos_out, NULL, NULL);
}

int pc_eye_subpath(pc_tctx *c, const pc_mis_counts *n, pc_rng *rng, int x, int y, int max_vertices, pc_path_vertex *v,
                   pc_emitter_hit_fn hit, void *user) {
  const pc_camera *cam = &c->scene->camera;
  float u0 = pc_rng_f(rng), u1 = pc_rng_f(rng), px, py;
  float density = pc_camera_pixel_point(cam, x, y, u0, u1, &px, &py);
  vec3 d;
  pc_path_vertex *v0 = &v[0];
  v0->kind = PC_VTX_CAMERA;
  v0->p = pc_camera_sample_ray(cam, px, py, rng, &d);
  v0->ng = v3s(0.f);
  v0->eps = 0.f;
  v0->wo = v3s(0.f);
  v0->beta = v3s(1.f); /* We cos / pdf, per pixel */
  v0->material = -1;
  v0->light = -1;
  v0->depth = 1;
  v0->q = 1.f;
  v0->delta = false;
  v0->mis_near = v0->mis_far = 0.f;
  /* This pixel's eye strategies sample the direction with its filter's density (1 for the
   * pixel box); light tracing does not, which the MIS weights see through this pdf. */
  float pdf = pc_camera_dir_pdf(cam, d) * density;
  if (!(pdf > 0.f) || !isfinite(pdf)) return 1;
  /* The pinhole cannot be hit: cos_out 0. */
  return walk(c, n, rng, v, 1, max_vertices, false, d, v3s(1.f), pdf, 0.f, false, 0.f, hit, user);
}
