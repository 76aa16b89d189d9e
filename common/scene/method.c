/* method.c: names of the rendering methods, for the CLI, the integrator element and headers,
 * which scenes a method cannot render in full, and which ones have caustics. */
#include <string.h>

#include "scene.h"

const char *pc_method_name(pc_method m) {
  switch (m) {
  case PC_METHOD_PT: return "pt";
  case PC_METHOD_LT: return "lt";
  case PC_METHOD_BDPT: return "bdpt";
  case PC_METHOD_CBDPT: return "cbdpt";
  case PC_METHOD_PCBPT: return "pcbpt";
  case PC_METHOD_AUTO: return "auto";
  }
  return "unknown";
}

int pc_method_parse(const char *name, pc_method *out) {
  static const struct { const char *name; pc_method m; } tab[] = {
      {"pt", PC_METHOD_PT},       {"path", PC_METHOD_PT},     {"lt", PC_METHOD_LT},
      {"bdpt", PC_METHOD_BDPT},   {"cbdpt", PC_METHOD_CBDPT}, {"pcbpt", PC_METHOD_PCBPT},
      {"auto", PC_METHOD_AUTO},
  };
  if (!name) return PC_EINVAL;
  for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
    if (strcmp(name, tab[i].name) == 0) {
      *out = tab[i].m;
      return 0;
    }
  return PC_EINVAL;
}

/* Whether any shape's material answers yes to a material predicate of bsdf.h. */
static bool any_shape(const pc_scene *s, bool (*has)(const pc_material *, int, int)) {
  for (int i = 0; i < s->nshapes; i++)
    if (has(s->materials, s->nmaterials, s->shapes[i].material)) return true;
  return false;
}

bool pc_scene_pt_complete(const pc_scene *s) {
  bool delta_light = false;
  for (int i = 0; i < s->nlights && !delta_light; i++) delta_light = pc_light_is_delta(&s->lights[i]);
  return !delta_light || !any_shape(s, pc_material_has_delta);
}

bool pc_scene_lt_complete(const pc_scene *s) { return !any_shape(s, pc_material_has_delta); }

bool pc_scene_has_caustics(const pc_scene *s) { return any_shape(s, pc_material_casts_caustics); }
