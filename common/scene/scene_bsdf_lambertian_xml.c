/* scene_bsdf_lambertian_xml.c: the <bsdf> plugins built on a Lambertian base that
 * scene_materials_xml.c hands on: `phong` and `roughdiffuse`, with Mitsuba 0.6's defaults and
 * its ensureEnergyConservation; any other plugin is refused in one line. */
#include <stdio.h>
#include <string.h>

#include "scene_xml_ctx.h"

static vec3 slot_maximum(const pc_sx *c, const pc_tex_slot *s) {
  return s->tex < 0 ? s->value : pc_texture_maximum(&c->s->textures[s->tex]);
}

/* Mitsuba scales parameters whose componentwise maximum exceeds 1 by 0.99 / maximum (and warns),
 * unless ensureEnergyConservation is false. */
static int energy_scale(pc_sx *c, const pc_xml_node *n, bool ensure, vec3 max, const char *names, float *scale) {
  float top = v3_maxc(max);
  *scale = 1.f;
  if (!ensure || !(top > 1.f)) return 0;
  *scale = 0.99f / top;
  return pc_sx_warn(c, n, "%s: maximum %g above 1, scaled by %g as Mitsuba does (ensureEnergyConservation)", names, top,
                    *scale);
}

static int phong(pc_sx *c, const pc_xml_node *n, const char *what, pc_material *m) {
  bool ensure = true;
  m->type = PC_MAT_PHONG;
  m->specular = (pc_tex_slot){.tex = -1, .value = v3s(0.2f)};
  m->exponent = 30.f;
  pc_param p[] = {{"specularReflectance", PC_P_SLOT, &m->specular, 0, 0},
                  {"diffuseReflectance", PC_P_SLOT, &m->reflectance, 0, 0},
                  {"exponent", PC_P_FLOAT, &m->exponent, 0, 0},
                  {"ensureEnergyConservation", PC_P_BOOL, &ensure, 0, 0}};
  int rc = pc_sx_params_only(c, n, what, p, 4);
  if (rc) return rc;
  if (!(m->exponent >= 0.f && m->exponent <= 1e6f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: exponent must lie in [0, 1e6]", c->file, p[2].line, what);
  vec3 sum = v3_add(slot_maximum(c, &m->specular), slot_maximum(c, &m->reflectance));
  return energy_scale(c, n, ensure, sum, "specularReflectance + diffuseReflectance", &m->lobe_scale);
}

static int roughdiffuse(pc_sx *c, const pc_xml_node *n, const char *what, pc_material *m) {
  bool ensure = true;
  pc_tex_slot diffuse = m->reflectance;
  m->type = PC_MAT_ROUGHDIFFUSE;
  m->alpha = 0.2f;
  pc_param p[] = {{"reflectance", PC_P_SLOT, &m->reflectance, 0, 0},
                  {"diffuseReflectance", PC_P_SLOT, &diffuse, 0, 0},
                  {"alpha", PC_P_FLOAT, &m->alpha, 0, 0},
                  {"useFastApprox", PC_P_BOOL, &m->fast_approx, 0, 0},
                  {"ensureEnergyConservation", PC_P_BOOL, &ensure, 0, 0}};
  int rc = pc_sx_params_only(c, n, what, p, 5);
  if (rc) return rc;
  if (p[0].set && p[1].set)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give reflectance or diffuseReflectance, not both", c->file, n->line, what);
  if (p[1].set) m->reflectance = diffuse; /* Mitsuba takes either name */
  if (!(m->alpha >= 0.f && m->alpha <= 10.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: alpha must lie in [0, 10]", c->file, p[2].line, what);
  /* A scaled texture would need a scale on the slot: refused rather than rendered brighter. */
  float s;
  if ((rc = energy_scale(c, n, ensure, slot_maximum(c, &m->reflectance), "reflectance", &s))) return rc;
  if (s != 1.f && m->reflectance.tex >= 0)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: a reflectance texture above 1: not modelled by pcbpt", c->file,
                   n->line, what);
  m->reflectance.value = v3_scale(m->reflectance.value, s);
  return 0;
}

int pc_sx_bsdf_more(pc_sx *c, const pc_xml_node *n, const char *type, const char *what, pc_material *m) {
  m->lobe_scale = 1.f;
  if (strcmp(type, "phong") == 0) return phong(c, n, what, m);
  if (strcmp(type, "roughdiffuse") == 0) return roughdiffuse(c, n, what, m);
  /* Mitsuba's scattering-layer BSDFs integrate a participating medium inside the surface */
  if (strcmp(type, "hk") == 0 || strcmp(type, "dipolebrdf") == 0 || strcmp(type, "sssbrdf") == 0)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: bsdf '%s': not modelled by pcbpt (participating media in a layer)",
                   c->file, n->line, type);
  return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: bsdf '%s': not modelled by pcbpt", c->file, n->line, type);
}
