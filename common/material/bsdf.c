/* bsdf.c: the material-independent half of every BSDF query: world <-> shading frame, the
 * `twosided` flip, Veach's light-leak rule, the adjoint shading-normal correction for
 * importance transport, dispatch to the lobes (bsdf_*.c), Russian-roulette probabilities and
 * a last guard so that no NaN or Inf ever leaves. */
#include "bsdf.h"

#include "bsdf_lobes.h"

void pc_material_prepare(pc_material *m) {
  if (m->type == PC_MAT_PLASTIC || m->type == PC_MAT_ROUGHPLASTIC) pc_plastic_prepare(m);
  if (m->type == PC_MAT_WARD || m->type == PC_MAT_PHONG) m->spec_sampling_weight = pc_spec_weight(m);
  if (m->type == PC_MAT_COATING || m->type == PC_MAT_ROUGHCOATING) pc_coating_prepare(m);
}

bool pc_bsdf_is_delta(const pc_material *m) {
  switch (m->type) {
  case PC_MAT_CONDUCTOR:
  case PC_MAT_DIELECTRIC:
  case PC_MAT_THINDIELECTRIC: return true;
  case PC_MAT_BUMPMAP:
  case PC_MAT_COATING: /* its own lobe is a delta; all are if the wrapped ones are */
  case PC_MAT_MASK: /* the pass-through is a delta too */
    return m->inner && pc_bsdf_is_delta(m->inner);
  case PC_MAT_BLEND:
  case PC_MAT_MIXTURE:
    for (int k = 0; k < m->nmix; k++)
      if (!m->mix[k] || !pc_bsdf_is_delta(m->mix[k])) return false;
    return m->nmix > 0;
  default: return false;
  }
}

/* What a material says of a property of the materials it is made of: it has it, it does not,
 * or it wraps one (`nested`) that answers. Mixes answer for any of theirs. */
typedef enum { HAS_NOT, HAS, HAS_IF_WRAPPED } has_answer;

static bool material_has(const pc_material *materials, int n, int i, has_answer (*ask)(const pc_material *)) {
  if (i < 0 || i >= n) return false;
  const pc_material *m = &materials[i];
  /* a nested material is always read before its parent: the index falls, so this ends */
  if (m->type == PC_MAT_BLEND || m->type == PC_MAT_MIXTURE) {
    for (int k = 0; k < m->nmix && k < PC_MIX_MAX; k++)
      if (m->mix_nested[k] < i && material_has(materials, n, m->mix_nested[k], ask)) return true;
    return false;
  }
  switch (ask(m)) {
  case HAS: return true;
  case HAS_IF_WRAPPED: return m->nested < i && material_has(materials, n, m->nested, ask);
  default: return false;
  }
}

static has_answer delta_lobe(const pc_material *m) {
  switch (m->type) {
  case PC_MAT_CONDUCTOR:
  case PC_MAT_DIELECTRIC:
  case PC_MAT_THINDIELECTRIC:
  case PC_MAT_PLASTIC:
  case PC_MAT_COATING:
  case PC_MAT_MASK: return HAS;
  case PC_MAT_BUMPMAP:
  case PC_MAT_ROUGHCOATING: return HAS_IF_WRAPPED;
  default: return HAS_NOT;
  }
}

bool pc_material_has_delta(const pc_material *materials, int n, int i) {
  return material_has(materials, n, i, delta_lobe);
}

static has_answer caustic_surface(const pc_material *m) {
  switch (m->type) {
  case PC_MAT_CONDUCTOR:
  case PC_MAT_DIELECTRIC:
  case PC_MAT_THINDIELECTRIC:
  case PC_MAT_ROUGHDIELECTRIC: return HAS;
  case PC_MAT_BUMPMAP:
  case PC_MAT_COATING: /* its coat does not count; what it coats may */
  case PC_MAT_ROUGHCOATING:
  case PC_MAT_MASK: return HAS_IF_WRAPPED;
  default: return HAS_NOT;
  }
}

bool pc_material_casts_caustics(const pc_material *materials, int n, int i) {
  return material_has(materials, n, i, caustic_surface);
}

static has_answer lit_behind(const pc_material *m) {
  if (m->twosided) return HAS;
  switch (m->type) {
  case PC_MAT_DIELECTRIC:
  case PC_MAT_ROUGHDIELECTRIC:
  case PC_MAT_THINDIELECTRIC:
  case PC_MAT_DIFFTRANS:
  case PC_MAT_MASK: return HAS; /* what is behind shows through */
  case PC_MAT_BUMPMAP:
  case PC_MAT_COATING:
  case PC_MAT_ROUGHCOATING: return HAS_IF_WRAPPED;
  default: return HAS_NOT;
  }
}

bool pc_material_shows_behind(const pc_material *materials, int n, int i) {
  return material_has(materials, n, i, lit_behind);
}

static bool is_dielectric(const pc_material *m) {
  return m->type == PC_MAT_DIELECTRIC || m->type == PC_MAT_ROUGHDIELECTRIC || m->type == PC_MAT_THINDIELECTRIC;
}

/* Mitsuba's twosided wrapper turns the frame over when wo is behind it; the dielectrics have
 * their own notion of both sides. */
static bool flips(const pc_material *m, float so) {
  return m->twosided && !is_dielectric(m) && so < 0.f;
}

static vec3 lobe_eval(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  switch (c->m->type) {
  case PC_MAT_DIFFUSE: return pc_diffuse_eval(c, wo, wi);
  case PC_MAT_ROUGHCONDUCTOR: return pc_roughconductor_eval(c, wo, wi);
  case PC_MAT_PLASTIC: return pc_plastic_eval(c, wo, wi);
  case PC_MAT_ROUGHPLASTIC: return pc_roughplastic_eval(c, wo, wi);
  case PC_MAT_ROUGHDIELECTRIC: return pc_roughdielectric_eval(c, wo, wi);
  case PC_MAT_WARD: return pc_ward_eval(c, wo, wi);
  case PC_MAT_PHONG: return pc_phong_eval(c, wo, wi);
  case PC_MAT_ROUGHDIFFUSE: return pc_roughdiffuse_eval(c, wo, wi);
  case PC_MAT_COATING: return pc_coating_eval(c, wo, wi);
  case PC_MAT_ROUGHCOATING: return pc_roughcoating_eval(c, wo, wi);
  case PC_MAT_DIFFTRANS: return pc_difftrans_eval(c, wo, wi);
  case PC_MAT_MASK: return pc_mask_eval(c, wo, wi);
  case PC_MAT_BLEND:
  case PC_MAT_MIXTURE: return pc_mix_eval(c, wo, wi);
  case PC_MAT_CONDUCTOR:
  case PC_MAT_DIELECTRIC:
  case PC_MAT_THINDIELECTRIC:
  case PC_MAT_BUMPMAP: break;
  }
  return v3s(0.f);
}

static float lobe_pdf(const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  switch (c->m->type) {
  case PC_MAT_DIFFUSE: return pc_diffuse_pdf(c, wo, wi);
  case PC_MAT_ROUGHCONDUCTOR: return pc_roughconductor_pdf(c, wo, wi);
  case PC_MAT_PLASTIC: return pc_plastic_pdf(c, wo, wi);
  case PC_MAT_ROUGHPLASTIC: return pc_roughplastic_pdf(c, wo, wi);
  case PC_MAT_ROUGHDIELECTRIC: return pc_roughdielectric_pdf(c, wo, wi);
  case PC_MAT_WARD: return pc_ward_pdf(c, wo, wi);
  case PC_MAT_PHONG: return pc_phong_pdf(c, wo, wi);
  case PC_MAT_ROUGHDIFFUSE: return pc_diffuse_pdf(c, wo, wi); /* Mitsuba samples it as Lambertian */
  case PC_MAT_COATING: return pc_coating_pdf(c, wo, wi);
  case PC_MAT_ROUGHCOATING: return pc_roughcoating_pdf(c, wo, wi);
  case PC_MAT_DIFFTRANS: return pc_difftrans_pdf(c, wo, wi);
  case PC_MAT_MASK: return pc_mask_pdf(c, wo, wi);
  case PC_MAT_BLEND:
  case PC_MAT_MIXTURE: return pc_mix_pdf(c, wo, wi);
  case PC_MAT_CONDUCTOR:
  case PC_MAT_DIELECTRIC:
  case PC_MAT_THINDIELECTRIC:
  case PC_MAT_BUMPMAP: break;
  }
  return 0.f;
}

static bool lobe_sample(const pc_lobe_ctx *c, vec3 wo, float u0, float u1, float u2, pc_lobe_sample *s) {
  switch (c->m->type) {
  case PC_MAT_DIFFUSE: return pc_diffuse_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_CONDUCTOR: return pc_conductor_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_ROUGHCONDUCTOR: return pc_roughconductor_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_PLASTIC: return pc_plastic_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_ROUGHPLASTIC: return pc_roughplastic_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_DIELECTRIC: return pc_dielectric_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_ROUGHDIELECTRIC: return pc_roughdielectric_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_THINDIELECTRIC: return pc_thindielectric_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_WARD: return pc_ward_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_PHONG: return pc_phong_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_ROUGHDIFFUSE: return pc_diffuse_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_COATING: return pc_coating_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_ROUGHCOATING: return pc_roughcoating_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_DIFFTRANS: return pc_difftrans_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_MASK: return pc_mask_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_BLEND:
  case PC_MAT_MIXTURE: return pc_mix_sample(c, wo, u0, u1, u2, s);
  case PC_MAT_BUMPMAP: break;
  }
  return false;
}

/* A wrapped material's lobes, as its wrapper sees them (local directions of the shared frame):
 * turned over if it is twosided and wo is behind. */
static pc_lobe_ctx nested_ctx(const pc_lobe_ctx *c, const pc_material *inner) {
  pc_lobe_ctx n = *c;
  n.m = inner;
  return n;
}

vec3 pc_nested_eval(const pc_lobe_ctx *c, const pc_material *inner, vec3 wo, vec3 wi) {
  pc_lobe_ctx n = nested_ctx(c, inner);
  if (pc_bsdf_is_delta(inner)) return v3s(0.f);
  if (flips(inner, wo.z)) wo.z = -wo.z, wi.z = -wi.z;
  return lobe_eval(&n, wo, wi);
}

float pc_nested_pdf(const pc_lobe_ctx *c, const pc_material *inner, vec3 wo, vec3 wi) {
  pc_lobe_ctx n = nested_ctx(c, inner);
  if (pc_bsdf_is_delta(inner)) return 0.f;
  if (flips(inner, wo.z)) wo.z = -wo.z, wi.z = -wi.z;
  return lobe_pdf(&n, wo, wi);
}

bool pc_nested_sample(const pc_lobe_ctx *c, const pc_material *inner, vec3 wo, float u0, float u1, float u2,
                      pc_lobe_sample *s) {
  pc_lobe_ctx n = nested_ctx(c, inner);
  float zsign = flips(inner, wo.z) ? -1.f : 1.f;
  wo.z *= zsign;
  if (!lobe_sample(&n, wo, u0, u1, u2, s)) return false;
  s->wi.z *= zsign;
  return true;
}

/* A query's directions as the lobes see them: both turned over if twosided says so for wo. */
static inline void orient(const pc_material *m, vec3 *wo, vec3 *wi) {
  if (flips(m, wo->z)) {
    wo->z = -wo->z;
    wi->z = -wi->z;
  }
}

/* What every evaluation ends with: the adjoint correction of importance transport, and no NaN
 * or Inf out. */
static inline vec3 finish_eval(vec3 f, vec3 wo, vec3 wi, float go, float gi, pc_transport mode) {
  if (mode == PC_IMPORTANCE) f = v3_scale(f, pc_adjoint_correction(wo.z, wi.z, go, gi));
  return v3_is_finite(f) ? f : v3s(0.f);
}

/* A query's local directions and geometric cosines (go, gi: sign irrelevant, only products used)
 * travel as separate values, never bundled in a struct: GCC kept such a bundle in memory and
 * read it back with loads wider or narrower than the stores that had just formed it, which
 * cannot forward (a stall of a dozen cycles per query). */
static vec3 eval_local(const pc_material *m, const pc_texture *texs, const pc_shading *sh, vec3 wo, vec3 wi, float go,
                       float gi, pc_transport mode) {
  pc_lobe_ctx c = {m, texs, sh->uv, mode};
  return finish_eval(lobe_eval(&c, wo, wi), wo, wi, go, gi, mode);
}

static inline float finish_pdf(float pdf) { return (isfinite(pdf) && pdf > 0.f) ? pdf : 0.f; }

static float pdf_local(const pc_material *m, const pc_texture *texs, const pc_shading *sh, vec3 wo, vec3 wi) {
  pc_lobe_ctx c = {m, texs, sh->uv, PC_RADIANCE};
  return finish_pdf(lobe_pdf(&c, wo, wi));
}

/* Mitsuba's bumpmap answers zero for a direction on different sides of the frame before and
 * after bump mapping. Mitsuba tests only the direction its queries sample; here both directions
 * are tested, which keeps the BSDF reciprocal (so light tracing and the bidirectional methods
 * converge to the path tracer's image). The two differ only where the camera-side direction
 * crosses between the two frames, grazing to the bumped surface. */
static bool bump_side(const pc_shading *sh, vec3 w) { return v3_dot(w, sh->nb) * v3_dot(w, sh->sh.n) > 0.f; }

/* The material a query from wo evaluates: a bumpmap's wrapped one (the shading frame is already
 * the bumped one, see pc_shading_make), or NULL where every query is zero. */
static const pc_material *unwrap(const pc_material *m, const pc_shading *sh, vec3 wo) {
  if (m->type != PC_MAT_BUMPMAP) return m; /* (a twosided bumpmap's frame is on wo's side already) */
  if (!m->inner || m->inner->type == PC_MAT_BUMPMAP || !bump_side(sh, wo)) return NULL;
  return m->inner;
}

void pc_bsdf_out_make(pc_bsdf_out *o, const pc_material *m, const pc_texture *texs, const pc_shading *sh, vec3 wo) {
  o->m = unwrap(m, sh, wo);
  o->bump = o->m && o->m != m;
  o->delta = o->m && pc_bsdf_is_delta(o->m);
  o->local = frame_to_local(&sh->sh, wo);
  o->g = v3_dot(wo, sh->ng);
  o->albedo = o->m && o->m->type == PC_MAT_DIFFUSE ? pc_slot_eval(&o->m->reflectance, texs, sh->uv) : v3s(0.f);
  o->diffuse = o->m && o->m->type == PC_MAT_DIFFUSE && !o->bump;
  o->flip = o->m && flips(o->m, o->local.z);
}

/* lobe_eval for o's material: a diffuse one from o's albedo, as pc_diffuse_eval computes it. */
static inline vec3 out_lobe_eval(const pc_bsdf_out *o, const pc_lobe_ctx *c, vec3 wo, vec3 wi) {
  if (o->m->type != PC_MAT_DIFFUSE) return lobe_eval(c, wo, wi);
  return wo.z > 0.f && wi.z > 0.f ? v3_scale(o->albedo, PC_INV_PI) : v3s(0.f);
}

/* eval_local for o's material. */
static inline vec3 out_eval_local(const pc_bsdf_out *o, const pc_texture *texs, const pc_shading *sh, vec3 wo, vec3 wi,
                                  float gi, pc_transport mode) {
  if (o->m->type != PC_MAT_DIFFUSE) return eval_local(o->m, texs, sh, wo, wi, o->g, gi, mode);
  return finish_eval(out_lobe_eval(o, NULL, wo, wi), wo, wi, o->g, gi, mode);
}

/* The microfacet lobes that are zero for every pair on two sides of the shading frame: a pair
 * on one side turns over as a whole, so the reverse of a pair, as the plain queries turn it
 * over, is the swapped pair, and value and both pdfs come from one call that takes the half
 * vector, D and G1 once (lobe_eval_pdfs). Diffuse, the same kind, has shortcuts of its own. */
static inline bool microfacet_reflection(const pc_material *m) {
  return m->type == PC_MAT_ROUGHCONDUCTOR || m->type == PC_MAT_ROUGHPLASTIC;
}

/* lobe_eval(wo, wi) with lobe_pdf(wo, wi) and lobe_pdf(wi, wo). */
static vec3 lobe_eval_pdfs(const pc_lobe_ctx *c, vec3 wo, vec3 wi, float *pdf, float *pdf_rev) {
  switch (c->m->type) {
  case PC_MAT_ROUGHCONDUCTOR: return pc_roughconductor_eval_pdfs(c, wo, wi, pdf, pdf_rev);
  case PC_MAT_ROUGHPLASTIC: return pc_roughplastic_eval_pdfs(c, wo, wi, pdf, pdf_rev);
  default:
    *pdf = lobe_pdf(c, wo, wi);
    *pdf_rev = lobe_pdf(c, wi, wo);
    return lobe_eval(c, wo, wi);
  }
}

/* wi in the shading frame (li) and its geometric cosine (gi), with o's wo not yet turned over;
 * false where every query of the pair, either way round, is zero (a bumpmap's wi on different
 * sides of its two frames, or the sides of the shading and geometric normals disagree). The
 * turning over (orient) stays with the callers: folded in here, with four callers, this was no
 * longer inlined and its results went back through memory (2-3% of a cornell-box BDPT profile). */
static inline bool out_local(const pc_bsdf_out *o, const pc_shading *sh, vec3 wi, vec3 *li, float *gi) {
  if (!o->m || o->delta || (o->bump && !bump_side(sh, wi))) return false;
  *li = frame_to_local(&sh->sh, wi);
  *gi = v3_dot(wi, sh->ng);
  return pc_sides_agree(o->local.z, li->z, o->g, *gi);
}

vec3 pc_bsdf_eval(const pc_material *m, const pc_texture *texs, const pc_shading *sh,
                  vec3 wo, vec3 wi, pc_transport mode) {
  pc_bsdf_out o;
  pc_bsdf_out_make(&o, m, texs, sh, wo);
  vec3 li;
  float gi;
  if (!out_local(&o, sh, wi, &li, &gi)) return v3s(0.f);
  vec3 lo = o.local;
  orient(o.m, &lo, &li);
  return out_eval_local(&o, texs, sh, lo, li, gi, mode);
}

float pc_bsdf_pdf(const pc_material *m, const pc_texture *texs, const pc_shading *sh,
                  vec3 wo, vec3 wi) {
  pc_bsdf_out o;
  pc_bsdf_out_make(&o, m, texs, sh, wo);
  vec3 li;
  float gi;
  if (!out_local(&o, sh, wi, &li, &gi)) return 0.f;
  vec3 lo = o.local;
  orient(o.m, &lo, &li);
  return pdf_local(o.m, texs, sh, lo, li);
}

/* A diffuse pair's pdfs both ways, without the lobe dispatch (a pair on one side turns over as
 * a whole, so the swapped pair's orientation is the pair's; a pair on two sides has pdfs 0
 * either way). */
static inline void diffuse_pdfs(vec3 wo, vec3 wi, float *pdf, float *pdf_rev) {
  *pdf = pc_diffuse_pdf(NULL, wo, wi);
  *pdf_rev = pc_diffuse_pdf(NULL, wi, wo);
}

/* Both pdfs of the pair (o's wo, li), qo and qi the pair turned over as the lobes see it; a
 * diffuse pair, the commonest query, by diffuse_pdfs. */
static inline void pdfs_local(const pc_bsdf_out *o, const pc_texture *texs, const pc_shading *sh, vec3 li, vec3 qo,
                              vec3 qi, float *pdf, float *pdf_rev) {
  if (o->m->type == PC_MAT_DIFFUSE) {
    diffuse_pdfs(qo, qi, pdf, pdf_rev);
  } else {
    *pdf = pdf_local(o->m, texs, sh, qo, qi);
    vec3 ro = li, ri = o->local;
    orient(o->m, &ro, &ri);
    *pdf_rev = pdf_local(o->m, texs, sh, ro, ri);
  }
}

void pc_bsdf_pdfs_out(const pc_bsdf_out *o, const pc_texture *texs, const pc_shading *sh, vec3 wi, float *pdf,
                      float *pdf_rev) {
  vec3 li;
  float gi;
  *pdf = *pdf_rev = 0.f;
  if (!out_local(o, sh, wi, &li, &gi)) return;
  vec3 qo = o->local, qi = li;
  orient(o->m, &qo, &qi);
  pdfs_local(o, texs, sh, li, qo, qi, pdf, pdf_rev);
}

/* pc_bsdf_eval_pdfs_out for a microfacet_reflection material, kept out of line: inlined, its
 * set-up was hoisted above the diffuse path (cornell-box's eval_pdfs_out +11% instructions). */
__attribute__((noinline)) static vec3 eval_pdfs_microfacet(const pc_bsdf_out *o, const pc_texture *texs,
                                                           const pc_shading *sh, vec3 wi, pc_transport mode,
                                                           float *pdf, float *pdf_rev) {
  vec3 li;
  float gi, p, p_rev;
  *pdf = *pdf_rev = 0.f;
  if (!out_local(o, sh, wi, &li, &gi)) return v3s(0.f);
  vec3 qo = o->local, qi = li;
  orient(o->m, &qo, &qi);
  pc_lobe_ctx c = {o->m, texs, sh->uv, mode}; /* (no such lobe's pdf reads the mode) */
  vec3 f = lobe_eval_pdfs(&c, qo, qi, &p, &p_rev);
  *pdf = finish_pdf(p);
  *pdf_rev = finish_pdf(p_rev);
  return finish_eval(f, qo, qi, o->g, gi, mode);
}

vec3 pc_bsdf_eval_pdfs_out_general(const pc_bsdf_out *o, const pc_texture *texs, const pc_shading *sh, vec3 wi,
                                   pc_transport mode, float *pdf, float *pdf_rev) {
  if (o->m && microfacet_reflection(o->m)) return eval_pdfs_microfacet(o, texs, sh, wi, mode, pdf, pdf_rev);
  vec3 li;
  float gi;
  *pdf = *pdf_rev = 0.f;
  if (!out_local(o, sh, wi, &li, &gi)) return v3s(0.f);
  vec3 qo = o->local, qi = li;
  orient(o->m, &qo, &qi);
  /* A diffuse pair through the surface: value and both pdfs are 0 (pc_diffuse_eval and _pdf),
   * as the full query would find; PCBPT's connections to its stored vertices end here often. */
  if (o->m->type == PC_MAT_DIFFUSE && !(qo.z > 0.f && qi.z > 0.f)) return v3s(0.f);
  pdfs_local(o, texs, sh, li, qo, qi, pdf, pdf_rev);
  return out_eval_local(o, texs, sh, qo, qi, gi, mode);
}

bool pc_bsdf_sample(const pc_material *m, const pc_texture *texs, const pc_shading *sh,
                    vec3 wo, float u0, float u1, float u2, pc_transport mode, pc_bsdf_sampled *out) {
  pc_bsdf_out o;
  pc_bsdf_out_make(&o, m, texs, sh, wo);
  return pc_bsdf_sample_out(&o, texs, sh, u0, u1, u2, mode, out);
}

bool pc_bsdf_sample_out(const pc_bsdf_out *o, const pc_texture *texs, const pc_shading *sh, float u0, float u1,
                        float u2, pc_transport mode, pc_bsdf_sampled *out) {
  const pc_material *m = o->m;
  *out = (pc_bsdf_sampled){0};
  if (!m) return false;
  vec3 lo = o->local;
  float go = o->g;
  float zsign = flips(m, lo.z) ? -1.f : 1.f;
  lo.z *= zsign;
  pc_lobe_ctx c = {m, texs, sh->uv, mode};
  pc_lobe_sample s = {0};
  if (!lobe_sample(&c, lo, u0, u1, u2, &s)) return false;
  vec3 wi = v3_norm(frame_to_world(&sh->sh, v3(s.wi.x, s.wi.y, s.wi.z * zsign)));
  float gi = v3_dot(wi, sh->ng);
  /* Continue from wi as eval and pdf will see it, so that they agree with this sample to the
   * last bit. */
  s.wi = frame_to_local(&sh->sh, wi);
  s.wi.z *= zsign;
  if (!pc_sides_agree(lo.z, s.wi.z, go, gi) || (o->bump && !bump_side(sh, wi))) return false;
  vec3 f;
  if (s.is_delta) {
    f = v3_scale(s.f_cos, 1.f / fabsf(s.wi.z));
  } else {
    if (m->type == PC_MAT_DIFFUSE) {
      diffuse_pdfs(lo, s.wi, &s.pdf, &s.pdf_rev);
      f = out_lobe_eval(o, &c, lo, s.wi);
    } else {
      f = lobe_eval_pdfs(&c, lo, s.wi, &s.pdf, &s.pdf_rev);
    }
  }
  if (mode == PC_IMPORTANCE) f = v3_scale(f, pc_adjoint_correction(lo.z, s.wi.z, go, gi));
  if (!v3_is_finite(f) || v3_is_zero(f) || !(s.pdf > 0.f) || !isfinite(s.pdf) ||
      !isfinite(s.pdf_rev) || !v3_is_finite(wi))
    return false;
  out->wi = wi;
  out->f = f;
  out->pdf = s.pdf;
  out->pdf_rev = s.pdf_rev;
  out->is_delta = s.is_delta;
  return true;
}

/* A continuation probability from the largest reflectance-like value q. */
static float continuation_of(float q) { return (q > 0.f) ? fminf(q, 1.f) : 0.f; }

/* Russian roulette: the largest channel of the material's reflectance-like parameters at uv,
 * capped at 1. It bounds what one bounce can return (Fresnel and the plastic base never exceed
 * their multipliers), so surviving paths never gain throughput from the division, and it is 0
 * only for an exactly black material. */
float pc_bsdf_continuation(const pc_material *m, const pc_texture *texs, const pc_shading *sh) {
  vec2 uv = sh->uv;
  float q = 0.f;
  if (m->type == PC_MAT_BUMPMAP) return m->inner ? pc_bsdf_continuation(m->inner, texs, sh) : 0.f;
  switch (m->type) {
  case PC_MAT_DIFFUSE:
  case PC_MAT_ROUGHDIFFUSE: q = v3_maxc(pc_slot_eval(&m->reflectance, texs, uv)); break;
  case PC_MAT_CONDUCTOR:
  case PC_MAT_ROUGHCONDUCTOR: q = v3_maxc(pc_slot_eval(&m->specular, texs, uv)); break;
  case PC_MAT_PLASTIC:
  case PC_MAT_ROUGHPLASTIC:
    q = fmaxf(v3_maxc(pc_slot_eval(&m->specular, texs, uv)),
              v3_maxc(pc_slot_eval(&m->reflectance, texs, uv)));
    break;
  case PC_MAT_DIELECTRIC:
  case PC_MAT_ROUGHDIELECTRIC:
  case PC_MAT_THINDIELECTRIC:
    q = fmaxf(v3_maxc(pc_slot_eval(&m->specular, texs, uv)),
              v3_maxc(pc_slot_eval(&m->transmittance, texs, uv)));
    break;
  case PC_MAT_WARD: /* the two lobes add */
    q = v3_maxc(v3_add(pc_slot_eval(&m->specular, texs, uv), pc_slot_eval(&m->reflectance, texs, uv)));
    break;
  case PC_MAT_PHONG:
    q = m->lobe_scale * v3_maxc(v3_add(pc_slot_eval(&m->specular, texs, uv), pc_slot_eval(&m->reflectance, texs, uv)));
    break;
  case PC_MAT_COATING:
  case PC_MAT_ROUGHCOATING: /* Fresnel splits between the layer's reflection and what it covers */
    q = fmaxf(v3_maxc(pc_slot_eval(&m->specular, texs, uv)), m->inner ? pc_bsdf_continuation(m->inner, texs, sh) : 0.f);
    break;
  case PC_MAT_DIFFTRANS: q = v3_maxc(pc_slot_eval(&m->transmittance, texs, uv)); break;
  case PC_MAT_MASK: { /* a q_inner + (1 - a), per channel */
    vec3 a = pc_slot_eval(&m->weight, texs, uv);
    float qi = m->inner ? pc_bsdf_continuation(m->inner, texs, sh) : 0.f;
    q = v3_maxc(v3_add(v3_scale(a, qi), v3_sub(v3s(1.f), a)));
    break;
  }
  case PC_MAT_BLEND: {
    vec3 t = pc_slot_eval(&m->weight, texs, uv);
    float b = fminf(fmaxf((t.x + t.y + t.z) / 3.f, 0.f), 1.f);
    q = (1.f - b) * (m->mix[0] ? pc_bsdf_continuation(m->mix[0], texs, sh) : 0.f) +
        b * (m->mix[1] ? pc_bsdf_continuation(m->mix[1], texs, sh) : 0.f);
    break;
  }
  case PC_MAT_MIXTURE:
    for (int k = 0; k < m->nmix; k++) q += m->mix_w[k] * (m->mix[k] ? pc_bsdf_continuation(m->mix[k], texs, sh) : 0.f);
    break;
  case PC_MAT_BUMPMAP: break;
  }
  return continuation_of(q);
}

bool pc_bsdf_out_is_delta(const pc_bsdf_out *o, const pc_material *m) {
  return o->m ? o->delta : pc_bsdf_is_delta(m); /* a bumpmap's is its wrapped material's */
}

float pc_bsdf_out_continuation(const pc_bsdf_out *o, const pc_material *m, const pc_texture *texs,
                               const pc_shading *sh) {
  if (o->m != m || m->type != PC_MAT_DIFFUSE) return pc_bsdf_continuation(m, texs, sh);
  return continuation_of(v3_maxc(o->albedo));
}
