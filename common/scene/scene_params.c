/* scene_params.c: the generic parts of the Mitsuba scene loader: typed plugin parameters,
 * ids and references, <default> parameters with $name substitution, and file references
 * confined to the scene's folder. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "file_read.h"
#include "scene_xml_ctx.h"
#include "spectrum.h"
#include "xml_values.h"

#define SUBST_MAX (64 << 10)
#define MAX_PARAMS 4096
#define MAX_IDS (1 << 20)

static const char *const param_elems[] = {"integer", "float", "boolean", "string", "rgb", "srgb",
                                          "spectrum", "blackbody", "point", "vector", "transform", "animation", NULL};

static bool is_param_elem(const char *name) {
  for (const char *const *p = param_elems; *p; p++)
    if (strcmp(*p, name) == 0) return true;
  return false;
}

static pc_param *find_param(pc_param *params, int np, const char *name) {
  pc_param *any = NULL;
  for (int i = 0; i < np; i++) {
    if (strcmp(params[i].name, name) == 0) return &params[i];
    if (strcmp(params[i].name, "*") == 0) any = &params[i];
  }
  return any;
}

bool pc_sx_is_param(const pc_xml_node *ch, const pc_param *params, int np) {
  if (is_param_elem(ch->name)) return true;
  if (strcmp(ch->name, "texture") != 0 && strcmp(ch->name, "ref") != 0) return false;
  const char *name = pc_xml_attr(ch, "name");
  if (!name) return false;
  const pc_param *p = find_param((pc_param *)params, np, name);
  return p && p->kind == PC_P_SLOT;
}

int pc_sx_params_only(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *p, int np) {
  int rc = pc_sx_params(c, n, what, p, np);
  for (const pc_xml_node *ch = n->first; ch && !rc; ch = ch->next)
    if (!pc_sx_is_param(ch, p, np)) rc = pc_sx_unexpected(c, ch, what);
  return rc;
}

static const char *ignored_as_mitsuba(const char *what, const char *name);

int pc_sx_unexpected(pc_sx *c, const pc_xml_node *ch, const char *what) {
  static const char *const unmodelled[] = {"medium", "subsurface", "phase", "volume", "sensor", NULL};
  const char *type = pc_xml_attr(ch, "type");
  /* a texture where Mitsuba's plugin takes one and pcbpt a constant (a roughness map, a Phong
     exponent map) */
  const char *name = pc_xml_attr(ch, "name");
  if (strcmp(ch->name, "texture") == 0 && name && !ignored_as_mitsuba(what, name))
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: a texture for '%s' (Mitsuba's plugin reads one): not modelled by pcbpt, which takes a constant there",
                   c->file, ch->line, what, name);
  /* a phase function or a volume only exists to describe a medium */
  bool media = strcmp(ch->name, "medium") == 0 || strcmp(ch->name, "phase") == 0 || strcmp(ch->name, "volume") == 0;
  for (const char *const *u = unmodelled; type && *u; u++)
    if (strcmp(ch->name, *u) == 0)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s '%s': not modelled by pcbpt (%sin %s)", c->file, ch->line, ch->name,
                     type, media ? "participating media, " : "", what);
  if (type)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: unexpected <%s type=\"%s\">", c->file, ch->line, what, ch->name, type);
  return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: unexpected <%s>", c->file, ch->line, what, ch->name);
}

static int parse_int(pc_sx *c, const pc_xml_node *ch, const char *what, int *out) {
  const char *v = pc_xml_attr(ch, "value");
  if (!v) return pc_errf(c->e, PC_EPARSE, "%s:%d: %s: <integer> lacks a value", c->file, ch->line, what);
  char *end;
  errno = 0;
  long x = strtol(v, &end, 10);
  while (*end == ' ') end++;
  if (end == v || *end || errno == ERANGE || x < INT_MIN || x > INT_MAX)
    return pc_errf(c->e, PC_EPARSE, "%s:%d: %s: '%.40s' is not an integer", c->file, ch->line, what, v);
  *out = (int)x;
  return 0;
}

#define SPD_MAX_BYTES (1 << 20)

/* <spectrum filename=...>: a spectral file as Mitsuba's InterpolatedSpectrum reads it (lines of
 * "wavelength value", blank and '#' lines skipped, the first other line that does not start
 * with two numbers ends it), zero-extended and integrated to RGB as a wavelength:value list is. */
static int spectrum_file(pc_sx *c, const pc_xml_node *ch, const char *what, vec3 *out) {
  static const char *const allowed[] = {"name", "filename", NULL};
  int rc = pc_xml_check_attrs(c->file, ch, allowed, c->e);
  if (rc) return rc; /* with value or intent too, as Mitsuba refuses them */
  const char *fname = pc_xml_attr(ch, "filename");
  char *path = NULL, *data = NULL;
  size_t len = 0;
  if ((rc = pc_sx_resolve(c, ch, what, fname, &path))) return rc;
  rc = pc_file_read(path, SPD_MAX_BYTES, &data, &len, c->e);
  free(path);
  if (rc) return rc;
  double lambda[PC_SPECTRUM_MAX_SAMPLES], value[PC_SPECTRUM_MAX_SAMPLES];
  int n = 0;
  for (char *line = data, *next; line && line < data + len; line = next) {
    next = memchr(line, '\n', (size_t)(data + len - line));
    if (next) *next++ = 0;
    line += strspn(line, " \t\r");
    if (!*line || *line == '#') continue;
    char *end_l, *end_v;
    double l = strtod(line, &end_l), v = strtod(end_l, &end_v);
    if (end_l == line || end_v == end_l) break;
    if (n == PC_SPECTRUM_MAX_SAMPLES || !isfinite(l) || !isfinite(v)) {
      rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: spectrum file '%s': %s", c->file, ch->line, what, fname,
                   n == PC_SPECTRUM_MAX_SAMPLES ? "more than 1024 entries" : "a value that is not a finite number");
      break;
    }
    lambda[n] = l;
    value[n++] = v;
  }
  free(data);
  if (rc) return rc;
  double rgb[3];
  if (n < 2 || pc_spectrum_sampled_rgb(lambda, value, n, rgb) != 0)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: spectrum file '%s': needs at least 2 entries at increasing wavelengths", c->file,
                   ch->line, what, fname);
  *out = v3((float)rgb[0], (float)rgb[1], (float)rgb[2]);
  return 0;
}

/* A colour parameter: <rgb>, <srgb>, <spectrum> (values or a file), <blackbody>. */
static int read_color(pc_sx *c, const pc_xml_node *ch, const char *what, bool signed_ok, vec3 *out) {
  if (strcmp(ch->name, "spectrum") == 0 && pc_xml_attr(ch, "filename")) return spectrum_file(c, ch, what, out);
  return signed_ok ? pc_xv_color_signed(c->file, ch, out, c->e) : pc_xv_color(c->file, ch, out, c->e);
}

static int parse_slot(pc_sx *c, const pc_xml_node *ch, const char *what, pc_tex_slot *slot) {
  if (strcmp(ch->name, "texture") == 0) {
    int idx, rc = pc_sx_texture(c, ch, &idx);
    if (rc) return rc;
    slot->tex = idx;
    return 0;
  }
  if (strcmp(ch->name, "ref") == 0) {
    static const char *const allowed[] = {"name", "id", NULL};
    int rc = pc_xml_check_attrs(c->file, ch, allowed, c->e);
    if (rc) return rc;
    const char *id = pc_xml_attr(ch, "id");
    if (!id) return pc_errf(c->e, PC_EPARSE, "%s:%d: %s: <ref> lacks an id", c->file, ch->line, what);
    const pc_sx_id *r = pc_sx_id_find(c, id);
    if (!r) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: reference to unknown id '%s'", c->file, ch->line, what, id);
    if (r->kind != PC_ID_TEXTURE)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: id '%s' is not a texture", c->file, ch->line, what, id);
    slot->tex = r->index;
    return 0;
  }
  slot->tex = -1;
  return read_color(c, ch, what, false, &slot->value);
}

/* An <animation> of <transform time=...> keyframes: a static one is the plain transform Mitsuba
 * makes of it (through its decomposition); a moving one is refused where the plugin takes no
 * PC_P_MOTION. */
static int read_animation(pc_sx *c, const pc_xml_node *ch, const char *what, pc_param *p) {
  pc_sx_xf *mx = p->kind == PC_P_MOTION ? p->out : NULL;
  mat4 *xf = mx ? &mx->xf : p->out;
  static const char *const n[] = {"name", NULL}, *const nt[] = {"time", NULL};
  int rc = pc_xml_check_attrs(c->file, ch, n, c->e);
  pc_anim a = {0};
  for (const pc_xml_node *k = ch->first; k && !rc; k = k->next) {
    double time;
    mat4 m;
    if (strcmp(k->name, "transform") != 0)
      rc = pc_errf(c->e, PC_EPARSE, "%s:%d: %s: <animation> holds <transform time=...> elements, not <%s>", c->file, k->line,
                   what, k->name);
    else if (!pc_xml_attr(k, "time"))
      rc = pc_errf(c->e, PC_EPARSE, "%s:%d: %s: a keyframe <transform> lacks its time", c->file, k->line, what);
    else if (!(rc = pc_xml_check_attrs(c->file, k, nt, c->e)) && !(rc = pc_xv_number(c->file, k, "time", &time, c->e)) &&
             !(rc = pc_xv_transform(c->file, k, &m, c->e)) && (rc = pc_anim_append(&a, time, &m, c->e)))
      rc = pc_sx_wrap(c, k, what, rc);
  }
  if (!rc && (rc = pc_anim_finish(&a, c->e))) rc = pc_sx_wrap(c, ch, what, rc);
  if (!rc && pc_anim_is_static(&a)) {
    *xf = pc_anim_eval(&a, 0.0);
    if (mx) pc_anim_free(&mx->anim);
  } else if (!rc && mx) {
    pc_anim_free(&mx->anim);
    mx->anim = a;
    *xf = mat4_identity(); /* an earlier <transform> of the same name is replaced */
    return 0;
  } else if (!rc) {
    rc = pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: a moving '%s' (motion blur): not modelled by pcbpt", c->file, ch->line, what,
                 p->name);
  }
  pc_anim_free(&a);
  return rc;
}

static int read_one(pc_sx *c, const pc_xml_node *ch, const char *what, pc_param *p) {
  static const char *const nv[] = {"name", "value", NULL};
  static const char *const nxyz[] = {"name", "x", "y", "z", NULL};
  const char *el = ch->name;
  int rc = 0;
  bool ok = false;
  double d;
  if (strcmp(el, "transform") != 0 && strcmp(el, "texture") != 0 && strcmp(el, "animation") != 0 && ch->first)
    return pc_errf(c->e, PC_EPARSE, "%s:%d: %s: <%s> must be empty", c->file, ch->line, what, el);
  switch (p->kind) {
  case PC_P_INT:
    if ((ok = strcmp(el, "integer") == 0) && !(rc = pc_xml_check_attrs(c->file, ch, nv, c->e)))
      rc = parse_int(c, ch, what, p->out);
    break;
  case PC_P_FLOAT:
  case PC_P_IOR:
    if ((ok = strcmp(el, "float") == 0 || strcmp(el, "integer") == 0) &&
        !(rc = pc_xml_check_attrs(c->file, ch, nv, c->e)) && !(rc = pc_xv_number(c->file, ch, "value", &d, c->e))) {
      if (!(fabs(d) <= 3.4e38)) rc = pc_errf(c->e, PC_ENUMERIC, "%s:%d: %s: '%s' out of range", c->file, ch->line, what, p->name);
      *(float *)p->out = (float)d;
    } else if (!ok && p->kind == PC_P_IOR && (ok = strcmp(el, "string") == 0) &&
               !(rc = pc_xml_check_attrs(c->file, ch, nv, c->e))) {
      const char *v = pc_xml_attr(ch, "value");
      if (!v || !pc_xv_ior_name(v, p->out))
        rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: unknown index of refraction '%s' for '%s'", c->file, ch->line, what,
                     v ? v : "", p->name);
    }
    break;
  case PC_P_BOOL:
    if ((ok = strcmp(el, "boolean") == 0) && !(rc = pc_xml_check_attrs(c->file, ch, nv, c->e))) {
      const char *v = pc_xml_attr(ch, "value");
      if (v && strcmp(v, "true") == 0) *(bool *)p->out = true;
      else if (v && strcmp(v, "false") == 0) *(bool *)p->out = false;
      else rc = pc_errf(c->e, PC_EPARSE, "%s:%d: %s: boolean '%s' must be true or false", c->file, ch->line, what, p->name);
    }
    break;
  case PC_P_STRING:
    if ((ok = strcmp(el, "string") == 0) && !(rc = pc_xml_check_attrs(c->file, ch, nv, c->e))) {
      const char *v = pc_xml_attr(ch, "value");
      if (!v) rc = pc_errf(c->e, PC_EPARSE, "%s:%d: %s: <string> lacks a value", c->file, ch->line, what);
      *(const char **)p->out = v;
    }
    break;
  case PC_P_COLOR:
    if ((ok = strcmp(el, "rgb") == 0 || strcmp(el, "srgb") == 0 || strcmp(el, "spectrum") == 0 ||
              strcmp(el, "blackbody") == 0))
      rc = read_color(c, ch, what, false, p->out);
    break;
  case PC_P_COLOR_SIGNED:
    if ((ok = strcmp(el, "rgb") == 0 || strcmp(el, "srgb") == 0 || strcmp(el, "spectrum") == 0 ||
              strcmp(el, "blackbody") == 0))
      rc = read_color(c, ch, what, true, p->out);
    break;
  case PC_P_SLOT:
    if ((ok = strcmp(el, "rgb") == 0 || strcmp(el, "srgb") == 0 || strcmp(el, "spectrum") == 0 ||
              strcmp(el, "blackbody") == 0 || strcmp(el, "texture") == 0 || strcmp(el, "ref") == 0))
      rc = parse_slot(c, ch, what, p->out);
    break;
  case PC_P_POINT:
  case PC_P_VECTOR:
    if ((ok = strcmp(el, p->kind == PC_P_POINT ? "point" : "vector") == 0) && !(rc = pc_xml_check_attrs(c->file, ch, nxyz, c->e))) {
      static const char *const xyz[3] = {"x", "y", "z"};
      double v[3] = {0, 0, 0};
      for (int i = 0; i < 3 && !rc; i++)
        if (pc_xml_attr(ch, xyz[i])) rc = pc_xv_number(c->file, ch, xyz[i], &v[i], c->e);
      *(vec3 *)p->out = v3((float)v[0], (float)v[1], (float)v[2]);
    }
    break;
  case PC_P_IGNORED:
    ok = true;
    break;
  case PC_P_TRANSFORM:
  case PC_P_MOTION:
    if ((ok = strcmp(el, "transform") == 0)) {
      static const char *const n[] = {"name", NULL};
      pc_sx_xf *mx = p->kind == PC_P_MOTION ? p->out : NULL;
      if (!(rc = pc_xml_check_attrs(c->file, ch, n, c->e))) rc = pc_xv_transform(c->file, ch, mx ? &mx->xf : p->out, c->e);
      if (mx) pc_anim_free(&mx->anim); /* the last value given wins */
    } else if ((ok = strcmp(el, "animation") == 0)) {
      rc = read_animation(c, ch, what, p);
    }
    break;
  }
  if (!ok)
    return pc_errf(c->e, PC_EPARSE, "%s:%d: %s: parameter '%s' cannot be given as <%s>", c->file, ch->line, what, p->name, el);
  return rc;
}

/* Mitsuba 0.6 warns about a parameter its plugin does not read and goes on, so such a
 * parameter cannot change the image; one it reads but pcbpt does not model stays an error. For
 * "what" (e.g. "bsdf 'conductor'"), the reason a parameter pcbpt does not take is ignored, or
 * NULL if Mitsuba's plugin reads it (the lists below are the props.get* calls of Mitsuba 0.6's
 * plugins and their base classes). */
static const char *ignored_as_mitsuba(const char *what, const char *name) {
  static const struct { const char *what, *params; } mitsuba[] = {
      {"bsdf 'diffuse'", " reflectance diffuseReflectance "},
      {"bsdf 'conductor'", " material eta k extEta specularReflectance "},
      {"bsdf 'roughconductor'", " distribution alpha alphaU alphaV material eta k extEta specularReflectance sampleVisible "},
      {"bsdf 'plastic'", " intIOR extIOR specularReflectance diffuseReflectance nonlinear "},
      {"bsdf 'roughplastic'", " distribution alpha intIOR extIOR specularReflectance diffuseReflectance nonlinear sampleVisible "},
      {"bsdf 'dielectric'", " intIOR extIOR specularReflectance specularTransmittance "},
      {"bsdf 'roughdielectric'", " distribution alpha alphaU alphaV intIOR extIOR specularReflectance specularTransmittance sampleVisible "},
      {"bsdf 'thindielectric'", " intIOR extIOR specularReflectance specularTransmittance "},
      {"bsdf 'ward'", " variant alpha alphaU alphaV specularReflectance diffuseReflectance "},
      {"bsdf 'twosided'", " "},
      {"bsdf 'null'", " "},
      {"bsdf 'phong'", " exponent specularReflectance diffuseReflectance ensureEnergyConservation "},
      {"bsdf 'roughdiffuse'", " reflectance diffuseReflectance alpha useFastApprox ensureEnergyConservation "},
      {"bsdf 'bumpmap'", " "},
      {"bsdf 'normalmap'", " "},
      {"bsdf 'coating'", " intIOR extIOR thickness sigmaA specularReflectance "},
      {"bsdf 'roughcoating'", " distribution alpha alphaU alphaV intIOR extIOR thickness sigmaA specularReflectance sampleVisible "},
      {"texture 'scale'", " scale value "},
      {"texture 'bitmap'", " filename wrapMode wrapModeU wrapModeV gamma filterType maxAnisotropy cache uoffset voffset uscale vscale channel "},
      {"texture 'checkerboard'", " color0 color1 uoffset voffset uscale vscale "},
      {"emitter 'area'", " radiance samplingWeight "},
      {"emitter 'point'", " toWorld position intensity samplingWeight "},
      {"emitter 'spot'", " toWorld intensity cutoffAngle beamWidth texture samplingWeight "},
      {"emitter 'directional'", " toWorld direction irradiance samplingWeight "},
      {"emitter 'constant'", " radiance samplingWeight "},
      {"emitter 'envmap'", " filename scale toWorld gamma cache samplingWeight "},
      {"shape 'obj'", " filename faceNormals maxSmoothAngle flipNormals flipTexCoords toWorld collapse shapeIndex loadMaterials "},
      {"shape 'ply'", " filename faceNormals maxSmoothAngle flipNormals toWorld srgb "},
      {"shape 'serialized'", " filename shapeIndex faceNormals maxSmoothAngle flipNormals toWorld "},
      {"shape 'rectangle'", " toWorld flipNormals "},
      {"shape 'cube'", " toWorld flipNormals "},
      {"shape 'disk'", " toWorld flipNormals "},
      {"shape 'sphere'", " center radius toWorld flipNormals "},
      {"shape 'cylinder'", " p0 p1 radius toWorld flipNormals "},
      {"shape 'instance'", " toWorld "},
      {"sensor 'perspective'", " toWorld focalLength fov fovAxis shutterOpen shutterClose nearClip farClip "},
      {"sensor 'thinlens'", " toWorld focalLength fov fovAxis shutterOpen shutterClose nearClip farClip focusDistance apertureRadius "},
  };
  /* read by Mitsuba, but only to steer its sampling */
  if (strcmp(name, "sampleVisible") == 0 || strcmp(name, "maxAnisotropy") == 0 || strcmp(name, "cache") == 0)
    return "it only steers Mitsuba's sampling or caching";
  char key[80];
  if (snprintf(key, sizeof key, " %s ", name) >= (int)sizeof key) return NULL;
  for (size_t i = 0; i < sizeof mitsuba / sizeof mitsuba[0]; i++)
    if (strcmp(mitsuba[i].what, what) == 0)
      return strstr(mitsuba[i].params, key) ? NULL : "Mitsuba's plugin does not read it either";
  /* every plugin pcbpt accepts is listed above; this is for the rest, e.g. a wrapper's */
  return "neither pcbpt nor, as far as pcbpt knows, Mitsuba's plugin reads it";
}

int pc_sx_params(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *params, int np) {
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next) {
    if (!pc_sx_is_param(ch, params, np)) continue;
    const char *name = pc_xml_attr(ch, "name");
    if (!name) return pc_errf(c->e, PC_EPARSE, "%s:%d: %s: <%s> lacks a name", c->file, ch->line, what, ch->name);
    pc_param *p = find_param(params, np, name);
    const char *unused = p ? NULL : ignored_as_mitsuba(what, name);
    if (unused) {
      int rc = pc_sx_warn(c, ch, "%s: parameter '%s' ignored (%s)", what, name, unused);
      if (rc) return rc;
      continue;
    }
    if (!p)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: parameter '%s' (read by Mitsuba's plugin): not modelled by pcbpt", c->file, ch->line,
                     what, name);
    int rc;
    if (p->kind == PC_P_IGNORED) {
      if ((rc = pc_sx_warn(c, ch, "%s: parameter '%s' ignored (%s)", what, name, (const char *)p->out))) return rc;
      p->set = true;
      p->line = ch->line;
      continue;
    }
    /* Mitsuba's Properties warn and keep the last value */
    if (p->set && (rc = pc_sx_warn(c, ch, "%s: parameter '%s' given more than once; the last value counts, as in Mitsuba", what, name)))
      return rc;
    rc = read_one(c, ch, what, p);
    if (rc) return rc;
    p->set = true;
    p->line = ch->line;
  }
  return 0;
}

static unsigned hash_str(const char *s) {
  unsigned h = 2166136261u;
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 16777619u;
  return h;
}

static int id_rehash(pc_sx *c, int size) {
  int *t = malloc((size_t)size * sizeof *t);
  if (!t) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  for (int i = 0; i < size; i++) t[i] = -1;
  for (int i = 0; i < c->nids; i++) {
    unsigned h = hash_str(c->ids[i].id) & (unsigned)(size - 1);
    while (t[h] >= 0) h = (h + 1) & (unsigned)(size - 1);
    t[h] = i;
  }
  free(c->id_table);
  c->id_table = t;
  c->id_table_size = size;
  return 0;
}

const pc_sx_id *pc_sx_id_find(const pc_sx *c, const char *id) {
  if (!c->id_table) return NULL;
  unsigned h = hash_str(id) & (unsigned)(c->id_table_size - 1);
  while (c->id_table[h] >= 0) {
    if (strcmp(c->ids[c->id_table[h]].id, id) == 0) return &c->ids[c->id_table[h]];
    h = (h + 1) & (unsigned)(c->id_table_size - 1);
  }
  return NULL;
}

int pc_sx_id_add(pc_sx *c, const char *id, pc_id_kind kind, int index, int line) {
  if (!*id) return pc_errf(c->e, PC_EPARSE, "%s:%d: empty id", c->file, line);
  const pc_sx_id *old = pc_sx_id_find(c, id);
  if (old) return pc_errf(c->e, PC_EINVAL, "%s:%d: duplicate id '%s' (first on line %d)", c->file, line, id, old->line);
  if (c->nids >= MAX_IDS) return pc_errf(c->e, PC_ELIMIT, "%s:%d: more than %d ids", c->file, line, MAX_IDS);
  if (c->nids == c->cap_ids) {
    int cap = c->cap_ids ? 2 * c->cap_ids : 64;
    pc_sx_id *q = realloc(c->ids, (size_t)cap * sizeof *q);
    if (!q) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
    c->ids = q;
    c->cap_ids = cap;
  }
  char *dup = strdup(id);
  if (!dup) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  c->ids[c->nids++] = (pc_sx_id){dup, kind, index, line};
  if (2 * c->nids > c->id_table_size) return id_rehash(c, c->id_table_size ? 2 * c->id_table_size : 128);
  unsigned h = hash_str(id) & (unsigned)(c->id_table_size - 1);
  while (c->id_table[h] >= 0) h = (h + 1) & (unsigned)(c->id_table_size - 1);
  c->id_table[h] = c->nids - 1;
  return 0;
}

/* Mitsuba replaces $name by the parameter's value; at each '$' the longest defined name
 * wins, and a '$' that matches no parameter is an error. */
static int substitute(pc_sx *c, const pc_xml_node *n, char **value) {
  const char *v = *value;
  if (!strchr(v, '$')) return 0;
  size_t cap = 256, len = 0;
  char *out = malloc(cap);
  if (!out) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  for (const char *p = v; *p;) {
    const char *piece = p;
    size_t plen = 1;
    if (*p == '$') {
      int best = -1;
      size_t blen = 0;
      for (int i = 0; i < c->nparams; i++) {
        size_t l = strlen(c->pnames[i]);
        if (l > blen && strncmp(p + 1, c->pnames[i], l) == 0) best = i, blen = l;
      }
      if (best < 0) {
        free(out);
        return pc_errf(c->e, PC_EINVAL, "%s:%d: <%s> refers to an undefined parameter in '%.60s'", c->file, n->line, n->name, v);
      }
      if (best < c->ndefines) c->define_used[best] = true;
      piece = c->pvalues[best];
      plen = strlen(piece);
      p += 1 + blen;
    } else {
      p++;
    }
    if (len + plen + 1 > SUBST_MAX) {
      free(out);
      return pc_errf(c->e, PC_ELIMIT, "%s:%d: <%s>: attribute longer than %d bytes after substitution", c->file, n->line,
                     n->name, SUBST_MAX);
    }
    while (len + plen + 1 > cap) cap *= 2;
    char *q = realloc(out, cap);
    if (!q) {
      free(out);
      return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
    }
    out = q;
    memcpy(out + len, piece, plen);
    len += plen;
  }
  out[len] = 0;
  free(*value);
  *value = out;
  return 0;
}

static int add_param(pc_sx *c, const pc_xml_node *n, const char *name, const char *value) {
  for (int i = 0; i < c->nparams; i++)
    if (strcmp(c->pnames[i], name) == 0) return 0; /* the first definition (or -D) wins, as in Mitsuba */
  if (c->nparams >= MAX_PARAMS)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: too many <default> parameters", c->file, n ? n->line : 0);
  if (c->nparams == c->cap_params) {
    int cap = c->cap_params ? 2 * c->cap_params : 16;
    char **a = realloc(c->pnames, (size_t)cap * sizeof *a);
    if (!a) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
    c->pnames = a;
    char **b = realloc(c->pvalues, (size_t)cap * sizeof *b);
    if (!b) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
    c->pvalues = b;
    c->cap_params = cap;
  }
  c->pnames[c->nparams] = strdup(name);
  c->pvalues[c->nparams] = strdup(value);
  c->nparams++;
  if (!c->pnames[c->nparams - 1] || !c->pvalues[c->nparams - 1])
    return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  return 0;
}

static bool defined(const pc_sx *c, const char *name) {
  for (int i = 0; i < c->nparams; i++)
    if (strcmp(c->pnames[i], name) == 0) return true;
  return false;
}

/* A <default> whose value names its own, still undefined, parameter would expand to itself. */
static int default_self_reference(pc_sx *c, const pc_xml_node *n) {
  const char *name = pc_xml_attr(n, "name"), *value = pc_xml_attr(n, "value");
  if (!name || !value || !*name || defined(c, name)) return 0;
  size_t nl = strlen(name);
  for (const char *p = strchr(value, '$'); p; p = strchr(p + 1, '$'))
    if (strncmp(p + 1, name, nl) == 0)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: <default name=\"%s\">: '$%s' expands to itself (give it with -D %s=...)",
                     c->file, n->line, name, name, name);
  return 0;
}

static int add_default(pc_sx *c, const pc_xml_node *n) {
  static const char *const allowed[] = {"name", "value", NULL};
  int rc = pc_xml_check_attrs(c->file, n, allowed, c->e);
  if (rc) return rc;
  const char *name = pc_xml_attr(n, "name"), *value = pc_xml_attr(n, "value");
  if (!name || !value || !*name)
    return pc_errf(c->e, PC_EPARSE, "%s:%d: <default> needs a name and a value", c->file, n->line);
  if (n->first) return pc_errf(c->e, PC_EPARSE, "%s:%d: <default> must be empty", c->file, n->line);
  for (const char *p = name; *p; p++)
    if (!(*p == '_' || (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9')))
      return pc_errf(c->e, PC_EPARSE, "%s:%d: <default> name '%s' must be letters, digits and _", c->file, n->line, name);
  return add_param(c, n, name, value);
}

static int subst_attrs(pc_sx *c, pc_xml_node *n) {
  for (int i = 0; i < n->nattrs; i++) {
    int rc = substitute(c, n, &n->attrs[2 * i + 1]);
    if (rc) return rc;
  }
  return 0;
}

static int subst_list(pc_sx *c, pc_xml_node **link, const pc_xml_node *stop, int depth, pc_xml_node ***end);

static int subst_rec(pc_sx *c, pc_xml_node *n, int depth) {
  c->file = n->file ? n->file : c->main_file;
  int rc = 0;
  if (strcmp(n->name, "default") == 0 && (rc = default_self_reference(c, n))) return rc;
  if ((rc = subst_attrs(c, n))) return rc;
  if (strcmp(n->name, "default") == 0) {
    if (depth != 1) return pc_errf(c->e, PC_EPARSE, "%s:%d: <default> must be a child of <scene>", c->file, n->line);
    if ((rc = add_default(c, n))) return rc;
  }
  pc_xml_node **end;
  return subst_list(c, &n->first, NULL, depth + 1, &end);
}

/* Substitutes the siblings from *link up to stop, splicing included files in as it meets them
 * (so their <default>s and $names take effect in document order, as in Mitsuba). */
static int subst_list(pc_sx *c, pc_xml_node **link, const pc_xml_node *stop, int depth, pc_xml_node ***end) {
  int rc = 0;
  while (*link != stop) {
    pc_xml_node *ch = *link;
    if (strcmp(ch->name, "include") != 0) {
      if ((rc = subst_rec(c, ch, depth))) return rc;
      link = &ch->next;
      continue;
    }
    c->file = ch->file ? ch->file : c->main_file;
    if (depth != 1) return pc_errf(c->e, PC_EPARSE, "%s:%d: <include> must be a child of <scene>", c->file, ch->line);
    pc_xml_node *inc;
    if ((rc = subst_attrs(c, ch)) || (rc = pc_sx_include_open(c, ch, &inc))) return rc;
    pc_xml_node *rest = ch->next, *kids = inc->first;
    inc->first = NULL;
    pc_xml_free(inc);
    ch->next = NULL;
    pc_xml_free(ch);
    *link = kids ? kids : rest;
    if (kids) {
      pc_xml_node *last = kids;
      while (last->next) last = last->next;
      last->next = rest;
    }
    pc_xml_node **after;
    rc = subst_list(c, link, rest, depth, &after);
    pc_sx_include_close(c);
    if (rc) return rc;
    link = after;
  }
  *end = link;
  return 0;
}

/* A -D value no $name of the scene (or of its included files) substitutes changes nothing: a
 * warning (a misspelt name is otherwise silent), and the scene keeps only the values it used, so
 * that what an image says it was rendered with (pcbpt.defines) does not differ between two
 * renders of the same scene for a value neither used. */
static int note_defines_used(pc_sx *c, const pc_xml_node *root) {
  const pc_scene_defines *d = c->opts->defines;
  for (int i = 0; d && i < d->n; i++) {
    const char *name, *value;
    pc_scene_defines_get(d, i, &name, &value);
    int rc = 0;
    if (!c->define_used[i])
      rc = pc_sx_warn(c, root, "-D %.60s=%.60s: the scene names no $%.60s, so the value changes nothing", name, value, name);
    else {
      char nv[PC_SCENE_DEFINES_BYTES + 2];
      snprintf(nv, sizeof nv, "%s=%s", name, value);
      rc = pc_scene_defines_add(&c->s->defines_used, nv, c->e);
    }
    if (rc) return rc;
  }
  return 0;
}

int pc_sx_substitute(pc_sx *c, pc_xml_node *root) {
  const pc_scene_defines *d = c->opts->defines;
  for (int i = 0; d && i < d->n; i++) {
    const char *name, *value;
    pc_scene_defines_get(d, i, &name, &value);
    int rc = add_param(c, NULL, name, value);
    if (rc) return rc;
  }
  /* -D names are distinct (pc_scene_defines_add), so they are the first d->n parameters */
  c->ndefines = d ? d->n : 0;
  int rc = subst_rec(c, root, 0);
  if (rc) return rc;
  c->file = c->main_file;
  return note_defines_used(c, root);
}

int pc_sx_name_below(pc_sx *c, const pc_xml_node *n, const char *base, const char *rel, char out[PATH_MAX]) {
  size_t k = 0;
  const char *slash = strrchr(base, '/');
  if (slash) {
    memcpy(out, base, (size_t)(slash - base));
    k = (size_t)(slash - base);
  }
  for (const char *s = rel; *s;) {
    const char *end = strchr(s, '/');
    size_t len = end ? (size_t)(end - s) : strlen(s);
    if (len == 2 && s[0] == '.' && s[1] == '.') {
      if (k == 0) return pc_errf(c->e, PC_EINVAL, "%s:%d: '%s' lies outside the scene folder", c->file, n->line, rel);
      while (k > 0 && out[k - 1] != '/') k--;
      if (k > 0) k--;
    } else if (len > 0 && !(len == 1 && s[0] == '.')) {
      if (k + len + 2 > PATH_MAX) return pc_errf(c->e, PC_ELIMIT, "%s:%d: path '%s' too long", c->file, n->line, rel);
      if (k) out[k++] = '/';
      memcpy(out + k, s, len);
      k += len;
    }
    s += len + (end ? 1 : 0);
  }
  out[k] = 0;
  if (k == 0) return pc_errf(c->e, PC_EINVAL, "%s:%d: '%s' names no file", c->file, n->line, rel);
  return 0;
}

int pc_sx_resolve(pc_sx *c, const pc_xml_node *n, const char *what, const char *rel, char **out) {
  *out = NULL;
  if (!*rel) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: empty filename", c->file, n->line, what);
  if (rel[0] == '/')
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: absolute path '%s' (paths must be relative to the scene folder)", c->file,
                   n->line, what, rel);
  /* Relative to the main scene file's folder, as Mitsuba's file resolver has it (also inside
   * included files); confined to the root folder. */
  const char *scene = c->incl_stack[0], *slash = strrchr(scene, '/');
  size_t dl = strlen(c->dir);
  char joined[PATH_MAX], real[PATH_MAX];
  if ((size_t)snprintf(joined, sizeof joined, "%.*s/%s", (int)(slash - scene), scene, rel) >= sizeof joined)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: %s: path too long", c->file, n->line, what);
  if (!realpath(joined, real))
    return pc_errf(c->e, PC_EIO, "%s:%d: %s: cannot find '%s': %s", c->file, n->line, what, rel, strerror(errno));
  bool inside = strcmp(c->dir, "/") == 0 || (strncmp(real, c->dir, dl) == 0 && real[dl] == '/');
  if (!inside)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: '%s' lies outside the scene folder", c->file, n->line, what, rel);
  char name[PATH_MAX];
  int rc = pc_sx_name_below(c, n, c->incl_names[0], rel, name);
  if (!rc) rc = pc_sx_note_file(c, real, name);
  if (rc) return rc;
  *out = strdup(real);
  if (!*out) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  return 0;
}

int pc_sx_grow(pc_sx *c, void **arr, int *cap, int need, size_t elem) {
  if (need <= *cap) return 0;
  int nc = *cap ? 2 * *cap : 16;
  while (nc < need) nc *= 2;
  void *q = realloc(*arr, (size_t)nc * elem);
  if (!q) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  *arr = q;
  *cap = nc;
  return 0;
}

int pc_sx_add_material(pc_sx *c, const pc_xml_node *n, const pc_material *m, int *index) {
  if (c->s->nmaterials >= PC_SCENE_MAX_MATERIALS)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: more than %d BSDFs", c->file, n->line, PC_SCENE_MAX_MATERIALS);
  int rc = pc_sx_grow(c, (void **)&c->s->materials, &c->cap_materials, c->s->nmaterials + 1, sizeof *m);
  if (rc) return rc;
  *index = c->s->nmaterials;
  c->s->materials[c->s->nmaterials++] = *m;
  return 0;
}

int pc_sx_add_texture(pc_sx *c, const pc_xml_node *n, const pc_texture *t, int *index) {
  if (c->s->ntextures >= PC_SCENE_MAX_TEXTURES)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: more than %d textures", c->file, n->line, PC_SCENE_MAX_TEXTURES);
  int rc = pc_sx_grow(c, (void **)&c->s->textures, &c->cap_textures, c->s->ntextures + 1, sizeof *t);
  if (rc) return rc;
  *index = c->s->ntextures;
  c->s->textures[c->s->ntextures++] = *t;
  return 0;
}

int pc_sx_wrap(pc_sx *c, const pc_xml_node *n, const char *what, int rc) {
  if (!c->e) return rc;
  char inner[sizeof c->e->msg];
  memcpy(inner, c->e->msg, sizeof inner);
  return pc_errf(c->e, rc, "%s:%d: %s: %s", c->file, n->line, what, inner);
}
