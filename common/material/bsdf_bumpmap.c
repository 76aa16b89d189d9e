/* bsdf_bumpmap.c: the shading frame of a surface point, and Mitsuba 0.6's `bumpmap`, which
 * perturbs it. The frame is Mitsuba's computeShadingFrame: normal ns, first tangent along dp/du
 * projected into the tangent plane (anisotropic models read it). A bumpmap material replaces
 * it, once per hit, by the frame its displacement texture h defines, as Mitsuba's
 * BumpMap::getFrame does (ignoring the normal's own derivative, so a constant offset of h
 * changes nothing):
 *   dpdu' = dpdu + ns (dh/du - ns.dpdu),  dpdv' = dpdv + ns (dh/dv - ns.dpdv)
 *   n' = normalize(dpdu' x dpdv') turned to the geometric normal's side,
 *   s' = dpdu' projected into the plane of n'
 * with dh/du, dh/dv the luminance of the texture's gradient (texture_gradient.c). The wrapped
 * material is then evaluated in that frame by bsdf.c, so integrators' cosines and the adjoint
 * correction of importance transport use the bumped normal too (what makes light tracing the
 * adjoint of path tracing; Mitsuba's own particle tracer corrects with the unbumped normal).
 * Mitsuba's `normalmap` is the same wrapper with the frame read, not derived: the texture's
 * colour c gives the normal 2c - 1 in the unbumped shading frame (NormalMap::getFrame):
 *   n' = normalize(frame(2c - 1)) turned to the geometric normal's side, s' = dpdu projected. */
#include "bsdf.h"

/* Written in place, component by component: returned by value, the 36-byte frame went through
 * a stack temporary whose narrow stores the copy's wide loads could not forward from. */
void pc_shading_frame(frame *f, vec3 n, vec3 dpdu) {
  vec3 s = v3_sub(dpdu, v3_scale(n, v3_dot(n, dpdu)));
  float len = v3_len(s);
  if (!(len > 1e-12f * v3_len(dpdu)) || !isfinite(len)) {
    *f = frame_from_normal(n);
    return;
  }
  f->n = n;
  f->s = v3_scale(s, 1.f / len);
  f->t = v3_cross(n, f->s);
}

/* The bumped frame, or the unbumped one where the texture's slopes give no valid frame. */
static frame bumped_frame(const pc_texture *tex, vec3 ng, frame f, vec3 dpdu, vec3 dpdv, vec2 uv) {
  vec3 grad[2];
  pc_texture_gradient(tex, uv, grad);
  float du = v3_luminance(grad[0]), dv = v3_luminance(grad[1]);
  vec3 n = f.n;
  vec3 pu = v3_add(dpdu, v3_scale(n, du - v3_dot(n, dpdu)));
  vec3 pv = v3_add(dpdv, v3_scale(n, dv - v3_dot(n, dpdv)));
  vec3 c = v3_cross(pu, pv);
  float len = v3_len(c);
  if (!(len > 0.f) || !isfinite(len)) return f;
  vec3 nb = v3_scale(c, 1.f / len);
  if (v3_dot(nb, ng) < 0.f) nb = v3_neg(nb);
  frame r;
  pc_shading_frame(&r, nb, pu);
  return v3_is_finite(r.s) && v3_is_finite(r.t) ? r : f;
}

/* The frame of a normal map, or the unperturbed one where its texel gives no direction. */
static frame normal_mapped_frame(const pc_texture *tex, vec3 ng, frame f, vec3 dpdu, vec2 uv) {
  vec3 c = pc_texture_eval(tex, uv);
  vec3 local = v3(2.f * c.x - 1.f, 2.f * c.y - 1.f, 2.f * c.z - 1.f);
  vec3 n = v3_add(v3_add(v3_scale(f.s, local.x), v3_scale(f.t, local.y)), v3_scale(f.n, local.z));
  float len = v3_len(n);
  if (!(len > 0.f) || !isfinite(len)) return f;
  n = v3_scale(n, 1.f / len);
  if (v3_dot(n, ng) < 0.f) n = v3_neg(n);
  frame r;
  pc_shading_frame(&r, n, dpdu);
  return v3_is_finite(r.s) && v3_is_finite(r.t) ? r : f;
}

/* Mitsuba's twosided around a bumpmap, queried from behind, turns the directions over the
 * unbumped tangent plane and evaluates the bumped material in front. The same, with the
 * directions kept: the bumped frame mirrored through that plane to the back (made right-handed
 * again, which no model can tell), and the unbumped normal flipped to the back too. */
static vec3 mirror(vec3 v, vec3 nb) { return v3_sub(v, v3_scale(nb, 2.f * v3_dot(v, nb))); }

static void to_back(pc_shading *sh) {
  vec3 nb = sh->nb;
  frame f = sh->sh;
  sh->sh.n = mirror(f.n, nb);
  sh->sh.s = mirror(f.s, nb);
  sh->sh.t = v3_cross(sh->sh.n, sh->sh.s);
  sh->nb = v3_neg(nb);
}

/* The rest of pc_shading_make once sh->sh holds the unbumped frame. */
static void finish_shading(pc_shading *sh, const pc_material *m, const pc_texture *texs, vec3 ng, vec3 ns, vec3 dpdu,
                           vec3 dpdv, vec2 uv, vec3 wo) {
  sh->ng = ng;
  sh->uv = uv;
  sh->nb = ns;
  if (m && m->type == PC_MAT_BUMPMAP && m->bump_tex >= 0 && texs) {
    const pc_texture *tex = &texs[m->bump_tex];
    sh->sh = m->normal_map ? normal_mapped_frame(tex, ng, sh->sh, dpdu, uv) : bumped_frame(tex, ng, sh->sh, dpdu, dpdv, uv);
    if (m->twosided && v3_dot(wo, ns) < 0.f) to_back(sh);
  }
}

void pc_shading_make(pc_shading *sh, const pc_material *m, const pc_texture *texs, vec3 ng, vec3 ns, vec3 dpdu,
                     vec3 dpdv, vec2 uv, vec3 wo) {
  pc_shading_frame(&sh->sh, ns, dpdu);
  finish_shading(sh, m, texs, ng, ns, dpdu, dpdv, uv, wo);
}

void pc_shading_make_framed(pc_shading *sh, const pc_material *m, const pc_texture *texs, vec3 ng, const frame *f,
                            vec3 dpdu, vec3 dpdv, vec2 uv, vec3 wo) {
  sh->sh = *f;
  finish_shading(sh, m, texs, ng, f->n, dpdu, dpdv, uv, wo);
}
