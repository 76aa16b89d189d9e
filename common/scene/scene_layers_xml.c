/* scene_layers_xml.c: the Mitsuba 0.6 BSDFs that wrap or combine others (`bumpmap`, `coating`,
 * `roughcoating`, `mask`, `blendbsdf`, `mixturebsdf`) and the `scale` texture that bump maps are usually given through. Each
 * wrapper's material keeps the index of the one it wraps (read first, so always a lower index);
 * pc_scene_build links them. */
#include <stdlib.h>
#include <string.h>

#include "scene_xml_ctx.h"

/* The index of a <bsdf> or <texture> child, read in place (registering its id) or found by
 * <ref id=...>. */
static int child_object(pc_sx *c, const pc_xml_node *ch, const char *what, pc_id_kind kind, int *index) {
  if (strcmp(ch->name, "ref") != 0)
    return kind == PC_ID_BSDF ? pc_sx_bsdf(c, ch, index) : pc_sx_texture(c, ch, index);
  static const char *const allowed[] = {"id", "name", NULL};
  int rc = pc_xml_check_attrs(c->file, ch, allowed, c->e);
  if (rc) return rc;
  const char *id = pc_xml_attr(ch, "id");
  const pc_sx_id *r = id ? pc_sx_id_find(c, id) : NULL;
  if (!r) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: reference to unknown id '%s'", c->file, ch->line, what, id ? id : "");
  if (r->kind != kind)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: id '%s' is not a %s", c->file, ch->line, what, id,
                   kind == PC_ID_BSDF ? "BSDF" : "texture");
  *index = r->index;
  return 0;
}

/* What a <ref> child names: a BSDF or a texture (by its id), for wrappers that take either. */
static pc_id_kind ref_kind(pc_sx *c, const pc_xml_node *ch) {
  const char *id = pc_xml_attr(ch, "id");
  const pc_sx_id *r = id ? pc_sx_id_find(c, id) : NULL;
  return r ? r->kind : PC_ID_OTHER;
}

static bool bitmap_without_gamma(const pc_xml_node *tex) {
  const char *type = pc_xml_attr(tex, "type");
  if (!type || strcmp(type, "bitmap") != 0) return false;
  for (const pc_xml_node *g = tex->first; g; g = g->next) {
    const char *name = pc_xml_attr(g, "name");
    if (name && strcmp(name, "gamma") == 0) return false;
  }
  return true;
}

/* Reads the wrapped BSDF (exactly one) and, for bumpmap, the displacement texture (exactly
 * one) among the children that are not parameters. */
static int wrapped(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *p, int np, pc_material *m, bool bump) {
  int nb = 0, nt = 0, rc = 0;
  for (const pc_xml_node *ch = n->first; ch && !rc; ch = ch->next) {
    if (pc_sx_is_param(ch, p, np)) continue;
    bool ref = strcmp(ch->name, "ref") == 0;
    bool is_bsdf = strcmp(ch->name, "bsdf") == 0 || (ref && ref_kind(c, ch) == PC_ID_BSDF);
    bool is_tex = bump && (strcmp(ch->name, "texture") == 0 || (ref && ref_kind(c, ch) == PC_ID_TEXTURE));
    /* Mitsuba refuses a bitmap bump map without an explicit gamma (8-bit files would be read as
     * sRGB, rarely what a height field means). */
    if (is_tex && !ref && nt == 0 && bitmap_without_gamma(ch))
      rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: a bitmap %s map needs an explicit 'gamma' (usually 1.0), as Mitsuba requires",
                   c->file, ch->line, what, m->normal_map ? "normal" : "bump");
    else if (is_bsdf && nb++ == 0) rc = child_object(c, ch, what, PC_ID_BSDF, &m->nested);
    else if (is_tex && nt++ == 0) rc = child_object(c, ch, what, PC_ID_TEXTURE, &m->bump_tex);
    else if (is_bsdf || is_tex)
      rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: more than one nested %s", c->file, ch->line, what, is_bsdf ? "BSDF" : "texture");
    else rc = pc_sx_unexpected(c, ch, what);
  }
  if (rc) return rc;
  if (nb == 0) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: wraps no BSDF", c->file, n->line, what);
  if (bump && nt == 0)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: needs a %s texture", c->file, n->line, what,
                   m->normal_map ? "normal" : "displacement");
  /* The bump map's frame is made once per hit for the material a shape has, so a bump map can
   * only be the outermost wrapper. */
  const pc_material *in = &c->s->materials[m->nested];
  if (in->type == PC_MAT_BUMPMAP)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: a bumpmap inside another BSDF: not modelled by pcbpt", c->file, n->line, what);
  return 0;
}

static int positive(pc_sx *c, const pc_xml_node *n, const char *what, const char *name, float v) {
  if (!(v > 0.f) || !isfinite(v)) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: '%s' must be positive", c->file, n->line, what, name);
  return 0;
}

int pc_sx_distribution(const char *name, pc_mf_type *out) {
  if (strcmp(name, "beckmann") == 0) *out = PC_MF_BECKMANN;
  else if (strcmp(name, "ggx") == 0) *out = PC_MF_GGX;
  else if (strcmp(name, "phong") == 0 || strcmp(name, "as") == 0) *out = PC_MF_PHONG;
  else return -1;
  return 0;
}

int pc_sx_bsdf_wrapper(pc_sx *c, const pc_xml_node *n, const char *type, const char *what, pc_material *m) {
  m->nested = m->bump_tex = -1;
  if (strcmp(type, "bumpmap") == 0 || strcmp(type, "normalmap") == 0) {
    m->type = PC_MAT_BUMPMAP;
    m->normal_map = type[0] == 'n';
    int rc = pc_sx_params(c, n, what, NULL, 0);
    return rc ? rc : wrapped(c, n, what, NULL, 0, m, true);
  }
  bool rough = strcmp(type, "roughcoating") == 0;
  m->type = rough ? PC_MAT_ROUGHCOATING : PC_MAT_COATING;
  m->int_ior = 1.5046f; /* Mitsuba's defaults: bk7 in air */
  m->ext_ior = 1.000277f;
  m->thickness = 1.f;
  m->sigma_a = (pc_tex_slot){.tex = -1, .value = v3s(0.f)};
  m->alpha = 0.1f;
  m->distribution = PC_MF_BECKMANN;
  const char *dist = "beckmann";
  float au = 0, av = 0;
  pc_param p[] = {{"intIOR", PC_P_IOR, &m->int_ior, 0, 0}, {"extIOR", PC_P_IOR, &m->ext_ior, 0, 0},
                  {"thickness", PC_P_FLOAT, &m->thickness, 0, 0}, {"sigmaA", PC_P_SLOT, &m->sigma_a, 0, 0},
                  {"specularReflectance", PC_P_SLOT, &m->specular, 0, 0},
                  {"distribution", PC_P_STRING, &dist, 0, 0}, {"alpha", PC_P_FLOAT, &m->alpha, 0, 0},
                  {"alphaU", PC_P_FLOAT, &au, 0, 0}, {"alphaV", PC_P_FLOAT, &av, 0, 0}};
  int np = rough ? 9 : 5, rc;
  if ((rc = pc_sx_params(c, n, what, p, np)) || (rc = wrapped(c, n, what, p, np, m, false)) ||
      (rc = positive(c, n, what, "intIOR", m->int_ior)) || (rc = positive(c, n, what, "extIOR", m->ext_ior)))
    return rc;
  if (m->int_ior == m->ext_ior)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: intIOR equals extIOR (Mitsuba requires them to differ)", c->file, n->line, what);
  if (!(m->thickness >= 0.f) || !isfinite(m->thickness))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'thickness' must be at least 0", c->file, n->line, what);
  if (m->sigma_a.tex < 0 && !(v3_minc(m->sigma_a.value) >= 0.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'sigmaA' must not be negative", c->file, n->line, what);
  if (m->specular.tex < 0 && v3_maxc(m->specular.value) > 1.f)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'specularReflectance' above 1 would create energy", c->file, n->line, what);
  if (!rough) return 0;
  if (pc_sx_distribution(dist, &m->distribution) != 0)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: distribution '%s' unknown (beckmann, ggx, phong or as)", c->file, n->line,
                   what, dist);
  if (p[7].set != p[8].set || (p[7].set && p[6].set))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give alpha, or both alphaU and alphaV", c->file, n->line, what);
  if (p[7].set && au != av)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: anisotropic roughness (alphaU != alphaV) unsupported, as in Mitsuba",
                   c->file, n->line, what);
  if (p[7].set) m->alpha = au;
  if (!(m->alpha > 0.f && m->alpha <= 1.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: roughness alpha must lie in (0, 1]", c->file, n->line, what);
  return 0;
}

int pc_sx_scale_texture(pc_sx *c, const pc_xml_node *n, const char *what, pc_texture *t) {
  vec3 scale = v3s(1.f), value = v3s(0.f);
  float fscale = 1.f;
  /* Mitsuba's scale is a float or a spectrum. */
  bool as_float = false;
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next)
    as_float |= strcmp(ch->name, "float") == 0 && pc_xml_attr(ch, "name") && strcmp(pc_xml_attr(ch, "name"), "scale") == 0;
  pc_param p[] = {{"scale", as_float ? PC_P_FLOAT : PC_P_COLOR, as_float ? (void *)&fscale : (void *)&scale, 0, 0},
                  {"value", PC_P_COLOR, &value, 0, 0}};
  int rc = pc_sx_params(c, n, what, p, 2), idx = -1, nt = 0;
  bool inline_child = false;
  for (const pc_xml_node *ch = n->first; ch && !rc; ch = ch->next) {
    if (pc_sx_is_param(ch, p, 2)) continue;
    if ((strcmp(ch->name, "texture") == 0 || strcmp(ch->name, "ref") == 0) && nt++ == 0) {
      rc = child_object(c, ch, what, PC_ID_TEXTURE, &idx);
      inline_child = strcmp(ch->name, "texture") == 0 && !pc_xml_attr(ch, "id");
    } else {
      rc = pc_sx_unexpected(c, ch, what);
    }
  }
  if (rc) return rc;
  if (as_float) scale = v3s(fscale);
  if (!(v3_minc(scale) > 0.f) || !v3_is_finite(scale))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'scale' must be positive", c->file, n->line, what);
  if ((idx >= 0) == p[1].set)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give one nested texture or a 'value'", c->file, n->line, what);
  if (idx < 0) {
    memset(t, 0, sizeof *t);
    t->type = PC_TEX_CONST;
    t->value = value;
    t->uscale = t->vscale = 1.f;
  } else if (inline_child && idx == c->s->ntextures - 1) {
    *t = c->s->textures[--c->s->ntextures]; /* nothing else can name it: take it over */
  } else if (!pc_texture_copy(&c->s->textures[idx], t)) {
    return pc_errf(c->e, PC_ENOMEM, "%s:%d: %s: out of memory", c->file, n->line, what);
  }
  /* Folded into the copy: a scale of a scale multiplies. */
  t->scale = t->scaled ? v3_mul(t->scale, scale) : scale;
  t->scaled = true;
  return 0;
}

/* ---- mask, blendbsdf, mixturebsdf ---- */

bool pc_sx_transmits(const pc_sx *c, const pc_material *m) {
  switch (m->type) {
  case PC_MAT_DIELECTRIC:
  case PC_MAT_ROUGHDIELECTRIC:
  case PC_MAT_THINDIELECTRIC:
  case PC_MAT_DIFFTRANS:
  case PC_MAT_MASK: return true;
  case PC_MAT_BUMPMAP:
  case PC_MAT_COATING:
  case PC_MAT_ROUGHCOATING: return pc_sx_transmits(c, &c->s->materials[m->nested]);
  case PC_MAT_BLEND:
  case PC_MAT_MIXTURE:
    for (int k = 0; k < m->nmix; k++)
      if (pc_sx_transmits(c, &c->s->materials[m->mix_nested[k]])) return true;
    return false;
  default: return false;
  }
}

/* The nested BSDFs (bsdf or ref children that are not parameters), at most `max`, into idx. */
static int components(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *p, int np, int *idx, int max, int *count) {
  int nb = 0, rc = 0;
  for (const pc_xml_node *ch = n->first; ch && !rc; ch = ch->next) {
    if (pc_sx_is_param(ch, p, np)) continue;
    bool ref = strcmp(ch->name, "ref") == 0;
    if (!(strcmp(ch->name, "bsdf") == 0 || (ref && ref_kind(c, ch) == PC_ID_BSDF))) {
      rc = pc_sx_unexpected(c, ch, what);
    } else if (nb >= max) {
      rc = pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: more than %d nested BSDFs", c->file, ch->line, what, max);
    } else if (!(rc = child_object(c, ch, what, PC_ID_BSDF, &idx[nb])) && c->s->materials[idx[nb]].type == PC_MAT_BUMPMAP) {
      rc = pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: a bumpmap inside another BSDF: not modelled by pcbpt", c->file, ch->line, what);
    }
    nb++;
  }
  *count = nb;
  return rc;
}

/* A weight or opacity given as a <float> (Mitsuba's blendbsdf reads a float) or a colour or texture. */
static bool given_as_float(const pc_xml_node *n, const char *name) {
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next)
    if (strcmp(ch->name, "float") == 0 && pc_xml_attr(ch, "name") && strcmp(pc_xml_attr(ch, "name"), name) == 0) return true;
  return false;
}

/* Mitsuba's `weights` string: numbers separated by spaces, commas or semicolons. */
static int parse_weights(pc_sx *c, const pc_xml_node *n, const char *what, const char *s, float *w, int max, int *count) {
  int k = 0;
  while (*s) {
    if (strchr(" ,;\t\n\r", *s)) {
      s++;
      continue;
    }
    char *end;
    double v = strtod(s, &end);
    if (end == s || (*end && !strchr(" ,;\t\n\r", *end)))
      return pc_errf(c->e, PC_EPARSE, "%s:%d: %s: could not parse the BSDF weights", c->file, n->line, what);
    if (!(v >= 0.0) || !isfinite(v))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: invalid BSDF weight %g", c->file, n->line, what, v);
    if (k >= max) return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: more than %d weights", c->file, n->line, what, max);
    w[k++] = (float)v;
    s = end;
  }
  *count = k;
  return 0;
}

int pc_sx_bsdf_mix(pc_sx *c, const pc_xml_node *n, const char *type, const char *what, pc_material *m) {
  m->nested = m->bump_tex = -1;
  int rc, nb = 0;
  if (strcmp(type, "mixturebsdf") == 0) {
    const char *weights = NULL;
    bool ensure = true;
    pc_param p[] = {{"weights", PC_P_STRING, &weights, 0, 0}, {"ensureEnergyConservation", PC_P_BOOL, &ensure, 0, 0}};
    m->type = PC_MAT_MIXTURE;
    int nw = 0;
    if ((rc = pc_sx_params(c, n, what, p, 2)) || (rc = components(c, n, what, p, 2, m->mix_nested, PC_MIX_MAX, &nb)))
      return rc;
    if (!weights) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'weights' is required", c->file, n->line, what);
    if ((rc = parse_weights(c, n, what, weights, m->mix_w, PC_MIX_MAX, &nw))) return rc;
    if (nw != nb)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: %d nested BSDFs but %d weights", c->file, n->line, what, nb, nw);
    float total = 0.f;
    for (int k = 0; k < nw; k++) total += m->mix_w[k];
    if (!(total > 0.f) || !isfinite(total))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: the weights must sum to more than zero", c->file, n->line, what);
    for (int k = 0; k < nw; k++) {
      m->mix_p[k] = m->mix_w[k] / total;
      if (ensure && total > 1.f) m->mix_w[k] /= total;
    }
    m->nmix = nb;
    return 0;
  }
  bool mask = strcmp(type, "mask") == 0;
  m->type = mask ? PC_MAT_MASK : PC_MAT_BLEND;
  const char *name = mask ? "opacity" : "weight";
  float fw = 0.5f;
  m->weight = (pc_tex_slot){.tex = -1, .value = v3s(0.5f)}; /* both default to 0.5 */
  bool as_float = given_as_float(n, name);
  pc_param p[] = {{name, as_float ? PC_P_FLOAT : PC_P_SLOT, as_float ? (void *)&fw : (void *)&m->weight, 0, 0}};
  int idx[2];
  if ((rc = pc_sx_params(c, n, what, p, 1)) || (rc = components(c, n, what, p, 1, idx, mask ? 1 : 2, &nb))) return rc;
  if (nb != (mask ? 1 : 2))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: needs %s nested BSDF%s", c->file, n->line, what, mask ? "one" : "two",
                   mask ? "" : "s");
  if (as_float) m->weight.value = v3s(fw);
  if (m->weight.tex < 0 && !(v3_minc(m->weight.value) >= 0.f && v3_maxc(m->weight.value) <= 1.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: '%s' must lie in [0, 1]", c->file, n->line, what, name);
  if (mask) {
    m->nested = idx[0];
  } else {
    m->nmix = 2;
    m->mix_nested[0] = idx[0];
    m->mix_nested[1] = idx[1];
  }
  return 0;
}
