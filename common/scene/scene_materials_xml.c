/* scene_materials_xml.c: <bsdf> and <texture> elements of a Mitsuba 0.6 scene, turned into
 * pc_material and pc_texture plain data (Mitsuba's defaults; anything pcbpt does not model is
 * refused). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_xml_ctx.h"

static pc_tex_slot konst(float v) { return (pc_tex_slot){.tex = -1, .value = v3s(v)}; }


static int what_of(const pc_xml_node *n, const char *type, char *buf) {
  snprintf(buf, PC_SX_WHAT_MAX, "%s '%.60s'", n->name, type);
  return 0;
}

static int check_object(pc_sx *c, const pc_xml_node *n, const char **type) {
  static const char *const allowed[] = {"type", "id", "name", NULL};
  int rc = pc_xml_check_attrs(c->file, n, allowed, c->e);
  if (rc) return rc;
  *type = pc_xml_attr(n, "type");
  if (!*type) return pc_errf(c->e, PC_EPARSE, "%s:%d: <%s> lacks a type", c->file, n->line, n->name);
  return 0;
}

/* Only constant slots can be checked at load; textures are the user's responsibility. */
static int check_max1(pc_sx *c, const pc_param *p, const pc_tex_slot *s, const char *what) {
  if (p->set && s->tex < 0 && v3_maxc(s->value) > 1.f)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: '%s' above 1 would create energy", c->file, p->line, what, p->name);
  return 0;
}

/* alpha, or alphaU and alphaV, into m->alpha (and m->alpha_v when they differ: anisotropic
 * roughness, which Mitsuba's roughconductor and roughdielectric have; the others refuse it). */
static int check_roughness(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *alpha, pc_param *au, pc_param *av,
                           float a, float u, float v, pc_material *m) {
  if (au->set != av->set)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give both alphaU and alphaV or neither", c->file, n->line, what);
  if (au->set) {
    if (alpha->set) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give alpha or alphaU/alphaV, not both", c->file, n->line, what);
    bool aniso_ok = m->type == PC_MAT_ROUGHCONDUCTOR || m->type == PC_MAT_ROUGHDIELECTRIC;
    if (u != v && !aniso_ok)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: anisotropic roughness (alphaU != alphaV) unsupported", c->file, n->line, what);
    if (u != v && !(v > 0.f && v <= 1.f))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: roughness alphaV must lie in (0, 1]", c->file, n->line, what);
    a = u;
    m->alpha_v = u != v ? v : 0.f;
  }
  if (!(a > 0.f && a <= 1.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: roughness alpha must lie in (0, 1]", c->file, n->line, what);
  m->alpha = a;
  return 0;
}

static int check_alpha(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *alpha, pc_param *au, pc_param *av,
                       float a, float u, float v, const char *dist, pc_material *m) {
  /* Mitsuba's default when no distribution is given is beckmann. */
  if (pc_sx_distribution(dist, &m->distribution) != 0)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: distribution '%s' unknown (beckmann, ggx, phong or as)", c->file, n->line,
                   what, dist);
  return check_roughness(c, n, what, alpha, au, av, a, u, v, m);
}

static int check_ior(pc_sx *c, const pc_xml_node *n, const char *what, const char *name, float v) {
  if (!(v > 0.f) || !isfinite(v))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: '%s' must be positive", c->file, n->line, what, name);
  return 0;
}

/* Parses a non-twosided BSDF (or a twosided wrapper) into *m. */
static int bsdf_value(pc_sx *c, const pc_xml_node *n, const char *type, pc_material *m) {
  char what[PC_SX_WHAT_MAX];
  what_of(n, type, what);
  memset(m, 0, sizeof *m);
  m->reflectance = konst(0.5f);
  m->specular = konst(1.f);
  m->transmittance = konst(1.f);
  int rc;
  if (strcmp(type, "diffuse") == 0) {
    pc_tex_slot other = m->reflectance;
    pc_param p[] = {{"reflectance", PC_P_SLOT, &m->reflectance, 0, 0}, {"diffuseReflectance", PC_P_SLOT, &other, 0, 0}};
    m->type = PC_MAT_DIFFUSE;
    if ((rc = pc_sx_params_only(c, n, what, p, 2))) return rc;
    if (p[0].set && p[1].set)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give reflectance or diffuseReflectance, not both", c->file, n->line, what);
    if (p[1].set) m->reflectance = other; /* Mitsuba takes either name */
    if ((rc = check_max1(c, &p[p[1].set ? 1 : 0], &m->reflectance, what))) return rc;
  } else if (strcmp(type, "conductor") == 0 || strcmp(type, "roughconductor") == 0) {
    bool rough = type[0] == 'r';
    const char *material = "Cu", *dist = "beckmann";
    float alpha = 0.1f, au = 0, av = 0, ext = 1.f;
    vec3 eta = v3s(0), k = v3s(0);
    pc_param p[] = {{"material", PC_P_STRING, &material, 0, 0}, {"eta", PC_P_COLOR_SIGNED, &eta, 0, 0},
                    {"k", PC_P_COLOR_SIGNED, &k, 0, 0}, {"extEta", PC_P_IOR, &ext, 0, 0},
                    {"specularReflectance", PC_P_SLOT, &m->specular, 0, 0},
                    {"distribution", PC_P_STRING, &dist, 0, 0}, {"alpha", PC_P_FLOAT, &alpha, 0, 0},
                    {"alphaU", PC_P_FLOAT, &au, 0, 0}, {"alphaV", PC_P_FLOAT, &av, 0, 0}};
    m->type = rough ? PC_MAT_ROUGHCONDUCTOR : PC_MAT_CONDUCTOR;
    if ((rc = pc_sx_params_only(c, n, what, p, rough ? 9 : 5))) return rc;
    if (rough && (rc = check_alpha(c, n, what, &p[6], &p[7], &p[8], alpha, au, av, dist, m))) return rc;
    if (p[1].set != p[2].set) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give both eta and k or neither", c->file, n->line, what);
    if (p[1].set && p[0].set)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give a material name or eta and k, not both", c->file, n->line, what);
    if (!p[1].set && !pc_conductor_ior(material, &eta, &k))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: unknown conductor material '%s'", c->file, n->line, what, material);
    if ((rc = check_ior(c, n, what, "extEta", ext))) return rc;
    /* Mitsuba's exact conductor Fresnel sees eta and k only as eta^2, k^2 and (eta k)^2, so a
     * negative value (exported scenes have them) reflects as its magnitude does */
    m->eta = v3_scale(v3(fabsf(eta.x), fabsf(eta.y), fabsf(eta.z)), 1.f / ext);
    m->k = v3_scale(v3(fabsf(k.x), fabsf(k.y), fabsf(k.z)), 1.f / ext);
  } else if (strcmp(type, "plastic") == 0 || strcmp(type, "roughplastic") == 0) {
    bool rough = type[0] == 'r';
    const char *dist = "beckmann";
    float au = 0, av = 0;
    m->type = rough ? PC_MAT_ROUGHPLASTIC : PC_MAT_PLASTIC;
    m->int_ior = 1.49f;
    m->ext_ior = 1.000277f;
    m->alpha = 0.1f;
    pc_param p[] = {{"intIOR", PC_P_IOR, &m->int_ior, 0, 0}, {"extIOR", PC_P_IOR, &m->ext_ior, 0, 0},
                    {"specularReflectance", PC_P_SLOT, &m->specular, 0, 0},
                    {"diffuseReflectance", PC_P_SLOT, &m->reflectance, 0, 0},
                    {"nonlinear", PC_P_BOOL, &m->nonlinear, 0, 0}, {"distribution", PC_P_STRING, &dist, 0, 0},
                    {"alpha", PC_P_FLOAT, &m->alpha, 0, 0}, {"alphaU", PC_P_FLOAT, &au, 0, 0},
                    {"alphaV", PC_P_FLOAT, &av, 0, 0}};
    if ((rc = pc_sx_params_only(c, n, what, p, rough ? 9 : 5)) || (rc = check_max1(c, &p[3], &m->reflectance, what)) ||
        (rc = check_ior(c, n, what, "intIOR", m->int_ior)) || (rc = check_ior(c, n, what, "extIOR", m->ext_ior)))
      return rc;
    if (rough && (rc = check_alpha(c, n, what, &p[6], &p[7], &p[8], m->alpha, au, av, dist, m))) return rc;
  } else if (strcmp(type, "dielectric") == 0 || strcmp(type, "roughdielectric") == 0 ||
             strcmp(type, "thindielectric") == 0) {
    bool rough = type[0] == 'r';
    m->type = rough ? PC_MAT_ROUGHDIELECTRIC : (type[0] == 't' ? PC_MAT_THINDIELECTRIC : PC_MAT_DIELECTRIC);
    m->int_ior = 1.5046f;
    m->ext_ior = 1.000277f;
    m->alpha = 0.1f;
    const char *dist = "beckmann";
    float au = 0, av = 0;
    pc_param p[] = {{"intIOR", PC_P_IOR, &m->int_ior, 0, 0}, {"extIOR", PC_P_IOR, &m->ext_ior, 0, 0},
                    {"specularReflectance", PC_P_SLOT, &m->specular, 0, 0},
                    {"specularTransmittance", PC_P_SLOT, &m->transmittance, 0, 0},
                    {"distribution", PC_P_STRING, &dist, 0, 0}, {"alpha", PC_P_FLOAT, &m->alpha, 0, 0},
                    {"alphaU", PC_P_FLOAT, &au, 0, 0}, {"alphaV", PC_P_FLOAT, &av, 0, 0}};
    if ((rc = pc_sx_params_only(c, n, what, p, rough ? 8 : 4)) || (rc = check_ior(c, n, what, "intIOR", m->int_ior)) ||
        (rc = check_ior(c, n, what, "extIOR", m->ext_ior)))
      return rc;
    if (rough && (rc = check_alpha(c, n, what, &p[5], &p[6], &p[7], m->alpha, au, av, dist, m))) return rc;
    if (m->int_ior == m->ext_ior)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: intIOR equals extIOR (an invisible interface)", c->file, n->line, what);
  } else if (strcmp(type, "ward") == 0) {
    const char *variant = "balanced";
    float au = 0, av = 0;
    m->type = PC_MAT_WARD;
    m->reflectance = konst(0.5f);
    m->specular = konst(0.2f);
    m->alpha = 0.1f;
    pc_param p[] = {{"variant", PC_P_STRING, &variant, 0, 0}, {"specularReflectance", PC_P_SLOT, &m->specular, 0, 0},
                    {"diffuseReflectance", PC_P_SLOT, &m->reflectance, 0, 0}, {"alpha", PC_P_FLOAT, &m->alpha, 0, 0},
                    {"alphaU", PC_P_FLOAT, &au, 0, 0}, {"alphaV", PC_P_FLOAT, &av, 0, 0}};
    if ((rc = pc_sx_params_only(c, n, what, p, 6)) || (rc = check_roughness(c, n, what, &p[3], &p[4], &p[5], m->alpha, au, av, m)))
      return rc;
    if (strcmp(variant, "balanced") == 0) m->ward = PC_WARD_BALANCED;
    else if (strcmp(variant, "ward") == 0) m->ward = PC_WARD_ORIGINAL;
    else if (strcmp(variant, "ward-duer") == 0) m->ward = PC_WARD_DUER;
    else
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: variant '%s' unknown (ward, ward-duer or balanced)", c->file, p[0].line,
                     what, variant);
    /* The lobes add: Mitsuba would scale both down to keep their sum at most 1. */
    if (m->specular.tex < 0 && m->reflectance.tex < 0 && v3_maxc(v3_add(m->specular.value, m->reflectance.value)) > 1.f)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: specularReflectance + diffuseReflectance above 1 would create energy",
                     c->file, n->line, what);
  } else if (strcmp(type, "difftrans") == 0) {
    pc_param p[] = {{"transmittance", PC_P_SLOT, &m->transmittance, 0, 0}};
    m->type = PC_MAT_DIFFTRANS;
    m->transmittance = konst(0.5f);
    if ((rc = pc_sx_params_only(c, n, what, p, 1)) || (rc = check_max1(c, &p[0], &m->transmittance, what))) return rc;
  } else if (strcmp(type, "null") == 0) {
    /* Mitsuba's null: every ray passes straight through, which a mask of opacity 0 is exactly
     * (its wrapped BSDF, the default, never counts) */
    if ((rc = pc_sx_params_only(c, n, what, NULL, 0))) return rc;
    m->type = PC_MAT_MASK;
    m->weight = konst(0.f);
    return pc_sx_default_material(c, n, &m->nested);
  } else if (strcmp(type, "mask") == 0 || strcmp(type, "blendbsdf") == 0 || strcmp(type, "mixturebsdf") == 0) {
    return pc_sx_bsdf_mix(c, n, type, what, m);
  } else if (strcmp(type, "bumpmap") == 0 || strcmp(type, "normalmap") == 0 || strcmp(type, "coating") == 0 ||
             strcmp(type, "roughcoating") == 0) {
    return pc_sx_bsdf_wrapper(c, n, type, what, m);
  } else if (strcmp(type, "twosided") == 0) {
    if ((rc = pc_sx_params(c, n, what, NULL, 0))) return rc;
    const pc_xml_node *inner = NULL;
    for (const pc_xml_node *ch = n->first; ch; ch = ch->next) {
      if (strcmp(ch->name, "bsdf") != 0 && strcmp(ch->name, "ref") != 0) return pc_sx_unexpected(c, ch, what);
      if (inner) return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: wraps more than one BSDF", c->file, ch->line, what);
      inner = ch;
    }
    if (!inner) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: wraps no BSDF", c->file, n->line, what);
    if (strcmp(inner->name, "ref") == 0) {
      static const char *const allowed[] = {"id", "name", NULL};
      if ((rc = pc_xml_check_attrs(c->file, inner, allowed, c->e))) return rc;
      const char *id = pc_xml_attr(inner, "id");
      const pc_sx_id *r = id ? pc_sx_id_find(c, id) : NULL;
      if (!r) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: reference to unknown id '%s'", c->file, inner->line, what, id ? id : "");
      if (r->kind != PC_ID_BSDF) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: id '%s' is not a BSDF", c->file, inner->line, what, id);
      *m = c->s->materials[r->index];
    } else {
      const char *itype;
      if ((rc = check_object(c, inner, &itype))) return rc;
      if (strcmp(itype, "twosided") == 0)
        return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: wraps another twosided BSDF", c->file, inner->line, what);
      if ((rc = bsdf_value(c, inner, itype, m))) return rc;
      const char *id = pc_xml_attr(inner, "id");
      if (id) {
        int idx;
        if ((rc = pc_sx_add_material(c, inner, m, &idx)) || (rc = pc_sx_id_add(c, id, PC_ID_BSDF, idx, inner->line))) return rc;
      }
    }
    if (m->twosided) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: wraps another twosided BSDF", c->file, inner->line, what);
    if (m->type == PC_MAT_DIELECTRIC || m->type == PC_MAT_ROUGHDIELECTRIC || m->type == PC_MAT_THINDIELECTRIC)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: cannot wrap a dielectric (it is two-sided already)", c->file, inner->line, what);
    if (pc_sx_transmits(c, m)) /* as Mitsuba: only materials without transmission (a mask's null component included) */
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: cannot wrap a material that transmits light", c->file, inner->line, what);
    m->twosided = true;
    return 0;
  } else {
    return pc_sx_bsdf_more(c, n, type, what, m);
  }
  return 0;
}

int pc_sx_bsdf(pc_sx *c, const pc_xml_node *n, int *index) {
  const char *type;
  pc_material m;
  int rc;
  if ((rc = check_object(c, n, &type))) return rc;
  /* a name is allowed (Mitsuba's schema has it on every object) and means nothing here */
  if ((rc = bsdf_value(c, n, type, &m)) || (rc = pc_sx_add_material(c, n, &m, index))) return rc;
  const char *id = pc_xml_attr(n, "id");
  return id ? pc_sx_id_add(c, id, PC_ID_BSDF, *index, n->line) : 0;
}

int pc_sx_default_material(pc_sx *c, const pc_xml_node *n, int *index) {
  if (c->default_material < 0) {
    pc_material m;
    memset(&m, 0, sizeof m);
    m.type = PC_MAT_DIFFUSE;
    m.reflectance = konst(0.5f);
    m.specular = konst(1.f);
    m.transmittance = konst(1.f);
    int rc = pc_sx_add_material(c, n, &m, &c->default_material);
    if (rc) return rc;
  }
  *index = c->default_material;
  return 0;
}

/* Mitsuba's Texture2D: uscale and vscale default to uvscale. p: the common parameters as read. */
static void uv_defaults(const pc_param *p, float uvscale, pc_texture *t) {
  if (!p[0].set) t->uscale = uvscale;
  if (!p[1].set) t->vscale = uvscale;
}

int pc_sx_texture(pc_sx *c, const pc_xml_node *n, int *index) {
  const char *type;
  char what[PC_SX_WHAT_MAX];
  int rc;
  if ((rc = check_object(c, n, &type))) return rc;
  what_of(n, type, what);
  pc_texture t;
  memset(&t, 0, sizeof t);
  t.uscale = t.vscale = 1.f;
  float uvscale = 1.f;
  pc_param common[] = {{"uscale", PC_P_FLOAT, &t.uscale, 0, 0}, {"vscale", PC_P_FLOAT, &t.vscale, 0, 0},
                       {"uoffset", PC_P_FLOAT, &t.uoffset, 0, 0}, {"voffset", PC_P_FLOAT, &t.voffset, 0, 0},
                       {"uvscale", PC_P_FLOAT, &uvscale, 0, 0}};
  if (strcmp(type, "bitmap") == 0) {
    const char *filename = NULL, *filter = "ewa", *wrap = "repeat", *wrapu = "repeat", *wrapv = "repeat";
    float gamma = 0; /* Mitsuba: 0 the file's own (sRGB for 8-bit), -1 sRGB, else v^gamma */
    pc_param p[] = {{"gamma", PC_P_FLOAT, &gamma, 0, 0},
                    {"filename", PC_P_STRING, &filename, 0, 0}, {"filterType", PC_P_STRING, &filter, 0, 0},
                    {"wrapMode", PC_P_STRING, &wrap, 0, 0}, {"wrapModeU", PC_P_STRING, &wrapu, 0, 0},
                    {"wrapModeV", PC_P_STRING, &wrapv, 0, 0}, common[0], common[1], common[2], common[3], common[4]};
    if ((rc = pc_sx_params_only(c, n, what, p, 11))) return rc;
    uv_defaults(&p[6], uvscale, &t);
    if (!(gamma == 0 || gamma == -1 || (gamma > 0 && gamma <= 10)))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: gamma must be -1 (sRGB) or in (0, 10]", c->file, p[0].line, what);
    if (!filename) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'filename' is required", c->file, n->line, what);
    /* pcbpt filters bilinearly whatever Mitsuba's filter; the difference is only blur. */
    if (strcmp(filter, "ewa") != 0 && strcmp(filter, "trilinear") != 0 && strcmp(filter, "nearest") != 0)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: unknown filterType '%s'", c->file, n->line, what, filter);
    if (strcmp(wrap, "repeat") != 0 || strcmp(wrapu, "repeat") != 0 || strcmp(wrapv, "repeat") != 0)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: only wrapMode 'repeat' is supported", c->file, n->line, what);
    char *path;
    if ((rc = pc_sx_resolve(c, n, what, filename, &path))) return rc;
    t.type = PC_TEX_BITMAP;
    t.nearest = strcmp(filter, "nearest") == 0;
    /* 8-bit images are sRGB-encoded as Mitsuba assumes; the reader ignores the flag for EXR. */
    /* 8-bit files stay in their bytes: a quarter of the memory, the same values */
    rc = pc_image_read_bytes(path, gamma <= 0, &t.img, c->e);
    free(path);
    if (rc) return pc_sx_wrap(c, n, what, rc);
    if (gamma > 0) { /* the file's values are v^(1/gamma)-encoded, whatever its format */
      float *v = t.img.rgb8 ? t.img.lut8 : t.img.rgb;
      size_t nv = t.img.rgb8 ? 256 : 3 * (size_t)t.img.w * (size_t)t.img.h;
      for (size_t i = 0; i < nv; i++) v[i] = powf(fmaxf(v[i], 0.f), gamma);
    }
  } else if (strcmp(type, "checkerboard") == 0) {
    t.type = PC_TEX_CHECKER;
    t.color0 = v3s(0.4f);
    t.color1 = v3s(0.2f);
    pc_param p[] = {{"color0", PC_P_COLOR, &t.color0, 0, 0}, {"color1", PC_P_COLOR, &t.color1, 0, 0},
                    common[0], common[1], common[2], common[3], common[4]};
    if ((rc = pc_sx_params_only(c, n, what, p, 7))) return rc;
    uv_defaults(&p[2], uvscale, &t);
  } else if (strcmp(type, "scale") == 0) {
    if ((rc = pc_sx_scale_texture(c, n, what, &t))) return rc;
  } else {
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: texture '%s': not modelled by pcbpt", c->file, n->line, type);
  }
  if ((!isfinite(t.uscale) || !isfinite(t.vscale) || t.uscale == 0.f || t.vscale == 0.f))
    rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: uscale and vscale must be nonzero", c->file, n->line, what);
  if (!rc) rc = pc_sx_add_texture(c, n, &t, index);
  if (rc) {
    pc_image_free(&t.img);
    return rc;
  }
  const char *id = pc_xml_attr(n, "id");
  return id ? pc_sx_id_add(c, id, PC_ID_TEXTURE, *index, n->line) : 0;
}
