/* scene_instance_xml.c: Mitsuba's instancing, `shapegroup` and `instance`. pcbpt flattens it:
 * a group's shapes are loaded once and kept aside in object space, and each instance appends
 * copies of them through its toWorld (what Mitsuba renders, at the cost of memory; the
 * triangles copied are bounded). Like Mitsuba, a group holds plain shapes only: no emitter,
 * no nested group or instance. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "scene_xml_ctx.h"
#include "shape_cylinder.h"

/* Triangles all instances together may copy (about 3 GB of positions, normals and indices). */
#define PC_SX_MAX_INSTANCED_TRIS (64ull << 20)

void pc_sx_groups_free(pc_sx *c) {
  for (int i = 0; i < c->ngroup_shapes; i++) pc_mesh_free(&c->group_shapes[i].mesh);
  free(c->group_shapes);
  free(c->group_first);
  c->group_shapes = NULL;
  c->group_first = NULL;
  c->ngroup_shapes = c->ngroups = 0;
}

int pc_sx_shapegroup(pc_sx *c, const pc_xml_node *n) {
  const char *id = pc_xml_attr(n, "id");
  if (!id) return pc_errf(c->e, PC_EINVAL, "%s:%d: shape 'shapegroup': needs an id", c->file, n->line);
  int rc = pc_sx_grow(c, (void **)&c->group_first, &c->cap_group_first, c->ngroups + 2, sizeof *c->group_first);
  if (rc) return rc;
  c->group_first[c->ngroups] = c->ngroup_shapes;
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next) {
    const char *type = pc_xml_attr(ch, "type");
    if (strcmp(ch->name, "shape") != 0) return pc_sx_unexpected(c, ch, "shape 'shapegroup'");
    if (type && (strcasecmp(type, "shapegroup") == 0 || strcmp(type, "instance") == 0))
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: shape 'shapegroup': a nested '%s': not modelled by pcbpt", c->file,
                     ch->line, type);
    int first = c->s->nshapes, motions = c->s->nmotions;
    if ((rc = pc_sx_shape(c, ch))) return rc;
    if (c->s->nmotions != motions)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: shape 'shapegroup': a moving shape in a group: Mitsuba refuses it too (nested instancing)",
                     c->file, ch->line);
    /* move what the child appended out of the scene into the group */
    for (int i = first; i < c->s->nshapes; i++) {
      pc_shape *sh = &c->s->shapes[i];
      if (sh->light >= 0)
        return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: shape 'shapegroup': an emitter in a group: not modelled by pcbpt",
                       c->file, ch->line);
      if ((rc = pc_sx_grow(c, (void **)&c->group_shapes, &c->cap_group_shapes, c->ngroup_shapes + 1,
                           sizeof *c->group_shapes)))
        return rc;
      c->group_shapes[c->ngroup_shapes++] = *sh;
      memset(&sh->mesh, 0, sizeof sh->mesh);
    }
    c->s->nshapes = first;
  }
  c->group_first[++c->ngroups] = c->ngroup_shapes;
  return pc_sx_id_add(c, id, PC_ID_SHAPEGROUP, c->ngroups - 1, n->line);
}

/* One group shape through xf into the scene. */
static int place(pc_sx *c, const pc_xml_node *n, const pc_shape *src, const mat4 *xf) {
  pc_shape sh = *src;
  if (sh.kind == PC_SHAPE_SPHERE) {
    double s;
    if (!pc_sx_is_similarity(xf, &s))
      return pc_errf(c->e, PC_EUNSUPPORTED,
                     "%s:%d: shape 'instance': toWorld may only translate, rotate and scale uniformly (it holds a sphere)",
                     c->file, n->line);
    sh.center = mat4_point(xf, sh.center);
    sh.radius = (float)(s * sh.radius);
    if (!(sh.radius > 0.f) || !isfinite(sh.radius) || !v3_is_finite(sh.center))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: shape 'instance': the sphere's radius becomes %g", c->file, n->line, sh.radius);
    return pc_sx_add_shape(c, n, &sh);
  }
  if (sh.kind == PC_SHAPE_CYLINDER) {
    const char *why = pc_cylinder_transform(&sh, xf);
    if (why) return pc_errf(c->e, PC_EINVAL, "%s:%d: shape 'instance': %s (it holds a cylinder)", c->file, n->line, why);
    return pc_sx_add_shape(c, n, &sh);
  }
  c->instanced_tris += src->mesh.ntris;
  if (c->instanced_tris > PC_SX_MAX_INSTANCED_TRIS)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: shape 'instance': instances copy more than %llu triangles", c->file, n->line,
                   PC_SX_MAX_INSTANCED_TRIS);
  if (pc_mesh_copy(&src->mesh, &sh.mesh)) return pc_errf(c->e, PC_ENOMEM, "%s:%d: out of memory", c->file, n->line);
  pc_mesh_transform(&sh.mesh, xf);
  /* a mirroring toWorld turns the winding over, as pc_mesh_transform does for any mesh */
  char where[PC_SX_WHAT_MAX + 64];
  snprintf(where, sizeof where, "%s:%d: shape 'instance'", c->file, n->line);
  int rc = pc_mesh_validate(&sh.mesh, where, c->e);
  if (!rc) rc = pc_sx_add_shape(c, n, &sh);
  if (rc) pc_mesh_free(&sh.mesh);
  return rc;
}

static int instance(pc_sx *c, const pc_xml_node *n, pc_sx_xf *to_world) {
  const char *what = "shape 'instance'";
  const pc_anim *anim = &to_world->anim;
  pc_param p[] = {{"toWorld", PC_P_MOTION, to_world, 0, 0}};
  int rc = pc_sx_params(c, n, what, p, 1), group = -1;
  if (rc) return rc;
  mat4 xf = to_world->xf;
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next) {
    if (pc_sx_is_param(ch, p, 1)) continue;
    if (strcmp(ch->name, "ref") != 0) return pc_sx_unexpected(c, ch, what);
    static const char *const allowed[] = {"id", "name", NULL};
    if ((rc = pc_xml_check_attrs(c->file, ch, allowed, c->e))) return rc;
    const char *id = pc_xml_attr(ch, "id");
    const pc_sx_id *r = id ? pc_sx_id_find(c, id) : NULL;
    if (!r || r->kind != PC_ID_SHAPEGROUP)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: '%s' is not a shapegroup declared before", c->file, ch->line, what,
                     id ? id : "");
    if (group >= 0) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: more than one shapegroup", c->file, ch->line, what);
    group = r->index;
  }
  if (group < 0) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: refers to no shapegroup", c->file, n->line, what);
  /* a moving instance keeps each shape in the group's space, moved per iteration */
  for (int i = c->group_first[group]; i < c->group_first[group + 1] && !rc; i++)
    if (!(rc = place(c, n, &c->group_shapes[i], &xf)) && anim->n) rc = pc_sx_add_motion(c, n, what, anim);
  if (rc) return rc;
  const char *id = pc_xml_attr(n, "id");
  return id ? pc_sx_id_add(c, id, PC_ID_OTHER, c->s->nshapes - 1, n->line) : 0;
}

int pc_sx_instance(pc_sx *c, const pc_xml_node *n) {
  pc_sx_xf to_world = {.xf = mat4_identity()};
  int rc = instance(c, n, &to_world);
  pc_anim_free(&to_world.anim);
  return rc;
}
