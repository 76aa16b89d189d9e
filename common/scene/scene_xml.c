/* scene_xml.c: pc_scene_load, the Mitsuba 0.6 XML scene reader (the subset of DESIGN.md §5):
 * the scene element, integrator, perspective sensor with hdrfilm, shapes (meshes in world
 * space, exact spheres and cylinders) with their BSDFs and area emitters, point emitters and the environment
 * (constant, envmap). Anything else
 * is refused with "file:line: what". BSDFs and textures are in scene_materials_xml.c. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "scene_xml_ctx.h"
#include "shape_cylinder.h"
#include "xml_values.h"

#define DISK_SEGMENTS 256

/* id_ok: the element can be referred to; elsewhere an id is accepted with a warning. */
static int object_type(pc_sx *c, const pc_xml_node *n, bool id_ok, const char **type) {
  static const char *const with_id[] = {"type", "id", "name", NULL}; /* Mitsuba's schema allows a name on any object */
  int rc = pc_xml_check_attrs(c->file, n, with_id, c->e);
  if (rc) return rc;
  if (!id_ok && pc_xml_attr(n, "id") && (rc = pc_sx_warn(c, n, "<%s>: id ignored (nothing refers to it)", n->name)))
    return rc;
  *type = pc_xml_attr(n, "type");
  if (!*type) return pc_errf(c->e, PC_EPARSE, "%s:%d: <%s> lacks a type", c->file, n->line, n->name);
  return 0;
}

/* Refuses every child that is not a parameter of `p`. */
static int only_params(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *p, int np) {
  int rc = pc_sx_params(c, n, what, p, np);
  for (const pc_xml_node *ch = n->first; ch && !rc; ch = ch->next)
    if (!pc_sx_is_param(ch, p, np)) rc = pc_sx_unexpected(c, ch, what);
  return rc;
}

/* The first <medium> anywhere in the tree, or NULL. */
static const pc_xml_node *find_medium(const pc_xml_node *n) {
  for (; n; n = n->next) {
    if (strcmp(n->name, "medium") == 0) return n;
    const pc_xml_node *m = find_medium(n->first); /* recursion bounded by PC_XML_MAX_DEPTH */
    if (m) return m;
  }
  return NULL;
}

static int integrator(pc_sx *c, const pc_xml_node *root, const pc_xml_node *n);

/* Mitsuba's adaptive and irrcache integrators wrap one sampling integrator, whose image they
 * compute (adaptively sampled, or with cached indirect light): the image is the nested one's. */
static int wrapper_integrator(pc_sx *c, const pc_xml_node *root, const pc_xml_node *n, const char *what) {
  const pc_xml_node *nested = NULL;
  pc_param p[] = {{"*", PC_P_IGNORED, "it steers the wrapper's own sampling or caching, not the image", 0, 0}};
  int rc = pc_sx_params(c, n, what, p, 1);
  if (rc) return rc;
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next) {
    if (pc_sx_is_param(ch, p, 1)) continue;
    if (strcmp(ch->name, "integrator") != 0) return pc_sx_unexpected(c, ch, what);
    if (nested) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: more than one nested <integrator>", c->file, ch->line, what);
    nested = ch;
  }
  if (!nested) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: needs a nested <integrator> (as in Mitsuba)", c->file, n->line, what);
  if ((rc = pc_sx_warn(c, n, "%s: rendering what its nested integrator renders (without the wrapper's own sampling)", what)))
    return rc;
  return integrator(c, root, nested);
}

static int integrator(pc_sx *c, const pc_xml_node *root, const pc_xml_node *n) {
  const char *type;
  int rc = object_type(c, n, false, &type);
  if (rc) return rc;
  char what[PC_SX_WHAT_MAX];
  snprintf(what, sizeof what, "integrator '%.60s'", type);
  if (strcmp(type, "adaptive") == 0 || strcmp(type, "irrcache") == 0) return wrapper_integrator(c, root, n, what);
  /* these compute something else than the light arriving at the camera */
  static const struct { const char *type, *why; } other_images[] = {
      {"ao", "ambient occlusion"},
      {"field", "geometric fields (positions, normals, depth, ...)"},
      {"multichannel", "several images as channels of one file"},
      {"motion", "motion vectors"},
  };
  for (size_t i = 0; i < sizeof other_images / sizeof other_images[0]; i++)
    if (strcmp(type, other_images[i].type) == 0)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: it renders %s, not light: not modelled by pcbpt", c->file, n->line,
                     what, other_images[i].why);
  bool direct = strcmp(type, "direct") == 0;
  if (strcmp(type, "path") == 0) c->s->method = PC_METHOD_PT;
  else if (strcmp(type, "bdpt") == 0) c->s->method = PC_METHOD_BDPT;
  else if (strcmp(type, "pcbpt") == 0) c->s->method = PC_METHOD_PCBPT;
  else {
    /* Another integrator computes the same image (up to noise) unless the scene holds what only
     * it models: participating media, which pcbpt does not. */
    const pc_xml_node *m = find_medium(root->first);
    if (m)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: the scene has participating media (<medium> on line %d): not modelled by pcbpt",
                     c->file, n->line, what, m->line);
    if (direct) {
      /* emitters seen, and light one bounce away: the paths of at most two segments */
      rc = pc_sx_warn(c, n, "%s: direct illumination only: rendered as maxDepth 2 with the default method (%s, or --method)",
                      what, pc_method_name(c->s->method));
    } else {
      rc = pc_sx_warn(c, n, "%s: not a pcbpt method; rendering with the default (%s, or --method)", what,
                      pc_method_name(c->s->method));
    }
    if (rc) return rc;
  }
  /* Mitsuba's defaults: vpl 5, every other integrator -1 (infinite) */
  int depth = strcmp(type, "vpl") == 0 ? 5 : -1;
  bool hide = false, light_image = true;
  /* maxDepth is honoured; rrDepth is ignored since pcbpt's Russian roulette is local by design;
   * the two switches that leave light out of the image are refused when set; every other
   * parameter only steers that integrator's own sampling. */
  pc_param p[] = {{"maxDepth", PC_P_INT, &depth, 0, 0},
                  {"rrDepth", PC_P_IGNORED, "pcbpt's Russian roulette depends on local vertex data only", 0, 0},
                  {"hideEmitters", PC_P_BOOL, &hide, 0, 0}, {"lightImage", PC_P_BOOL, &light_image, 0, 0},
                  {"*", PC_P_IGNORED, "it steers that integrator's own sampling, not the image", 0, 0}};
  if (direct) p[0] = (pc_param){"maxDepth", PC_P_IGNORED, "Mitsuba's direct integrator does not read it", 0, 0};
  if ((rc = pc_sx_params(c, n, what, p, 5))) return rc;
  if (hide || !light_image)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: '%s' (leaving light out of the image): not modelled by pcbpt", c->file,
                   hide ? p[2].line : p[3].line, what, hide ? "hideEmitters" : "lightImage");
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next)
    if (!pc_sx_is_param(ch, p, 5) && (rc = pc_sx_warn(c, ch, "%s: nested <%s> ignored", what, ch->name))) return rc;
  if (depth == 0 || depth < -1)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: maxDepth must be -1 (infinite) or at least 1", c->file, p[0].line, what);
  c->s->max_depth = direct ? 2 : depth;
  return 0;
}

/* Mitsuba's box, tent and gaussian filters are each pixel's measurement (rfilter.h); its
 * filters with negative lobes are not, and their pixels are boxes with a warning. */
static int rfilter(pc_sx *c, const pc_xml_node *n, pc_rfilter *out) {
  const char *ft;
  int rc = object_type(c, n, false, &ft);
  if (rc) return rc;
  char what[PC_SX_WHAT_MAX];
  snprintf(what, sizeof what, "rfilter '%.60s'", ft);
  pc_rfilter_type type;
  float param = 0.5f; /* the box's radius, the gaussian's stddev */
  pc_param p[] = {{"radius", PC_P_FLOAT, &param, 0, 0}, {"stddev", PC_P_FLOAT, &param, 0, 0},
                  {"*", PC_P_IGNORED, "Mitsuba's filter does not read it", 0, 0}};
  if (strcmp(ft, "box") == 0) {
    type = PC_RFILTER_BOX;
    p[1] = (pc_param){"stddev", PC_P_IGNORED, "Mitsuba's box does not read it", 0, 0};
  } else if (strcmp(ft, "tent") == 0) {
    type = PC_RFILTER_TENT;
    p[0] = (pc_param){"radius", PC_P_IGNORED, "Mitsuba's tent has radius 1 whatever it says", 0, 0};
    p[1] = (pc_param){"stddev", PC_P_IGNORED, "Mitsuba's tent does not read it", 0, 0};
  } else if (strcmp(ft, "gaussian") == 0) {
    type = PC_RFILTER_GAUSSIAN;
    p[0] = (pc_param){"radius", PC_P_IGNORED, "Mitsuba's gaussian has radius 4 stddev", 0, 0};
  } else {
    if ((rc = pc_sx_warn(c, n, "%s: a filter with negative lobes is not modelled: each pixel is a box", what))) return rc;
    p[0] = (pc_param){"*", PC_P_IGNORED, "the filter is not modelled", 0, 0};
    return only_params(c, n, what, p, 1);
  }
  if ((rc = only_params(c, n, what, p, 3))) return rc;
  if (!pc_rfilter_make(out, type, param))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: radius %g out of range (0, %g] pixels", c->file, n->line, what,
                   type == PC_RFILTER_GAUSSIAN ? 4.0 * param : (double)param, (double)PC_RFILTER_MAX_RADIUS);
  return 0;
}

static int film(pc_sx *c, const pc_xml_node *n) {
  const char *type;
  int rc = object_type(c, n, false, &type);
  if (rc) return rc;
  char what[PC_SX_WHAT_MAX];
  snprintf(what, sizeof what, "film '%.60s'", type);
  bool ldr = strcmp(type, "ldrfilm") == 0;
  if (strcmp(type, "hdrfilm") != 0 && strcmp(type, "tiledhdrfilm") != 0 && !ldr)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: unsupported film plugin '%s' (hdrfilm, tiledhdrfilm, ldrfilm)", c->file,
                   n->line, type);
  if (ldr && (rc = pc_sx_warn(c, n, "%s: pcbpt writes a linear EXR (plus a PNG preview); only the size is used", what)))
    return rc;
  int w = 768, h = 576, crop = 0;
  bool hq_edges = false;
  pc_param p[] = {{"width", PC_P_INT, &w, 0, 0}, {"height", PC_P_INT, &h, 0, 0},
                  {"cropOffsetX", PC_P_INT, &crop, 0, 0}, {"cropOffsetY", PC_P_INT, &crop, 0, 0},
                  {"cropWidth", PC_P_INT, &crop, 0, 0}, {"cropHeight", PC_P_INT, &crop, 0, 0},
                  {"highQualityEdges", PC_P_BOOL, &hq_edges, 0, 0},
                  {"*", PC_P_IGNORED, "it sets the output file, not the image", 0, 0}};
  if ((rc = pc_sx_params(c, n, what, p, 8))) return rc;
  for (int i = 2; i < 6; i++)
    if (p[i].set)
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: '%s' (a crop window) is not supported", c->file, p[i].line, what,
                     p[i].name);
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next) {
    if (pc_sx_is_param(ch, p, 8)) continue;
    if (strcmp(ch->name, "rfilter") != 0) return pc_sx_unexpected(c, ch, what);
    if ((rc = rfilter(c, ch, &c->s->camera.filter))) return rc;
  }
  /* Mitsuba then also samples beyond the film for the pixels at its edge; pcbpt weighs the
   * film alone there, as Mitsuba does by default. */
  if (hq_edges && !pc_rfilter_is_pixel(&c->s->camera.filter) &&
      (rc = pc_sx_warn(c, n, "%s: highQualityEdges: the pixels at the film's edge weigh what the film sees only", what)))
    return rc;
  if (w < 1 || w > PC_SCENE_MAX_FILM_DIM || h < 1 || h > PC_SCENE_MAX_FILM_DIM)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: width and height must lie in 1..%d", c->file, n->line, what,
                   PC_SCENE_MAX_FILM_DIM);
  c->s->camera.width = w;
  c->s->camera.height = h;
  return 0;
}

/* Whether the 3x3 part's columns (rows: by_rows) are orthonormal to within tol. */
static bool orthonormal(const mat4 *m, bool by_rows, double tol) {
  for (int i = 0; i < 3; i++)
    for (int j = i; j < 3; j++) {
      double d = 0;
      for (int k = 0; k < 3; k++) d += by_rows ? m->m[i][k] * m->m[j][k] : m->m[k][i] * m->m[k][j];
      if (fabs(d - (i == j)) > tol) return false;
    }
  return true;
}

/* Rotations and mirror flips only. */
static bool is_rigid(const mat4 *m) { return orthonormal(m, false, 1e-4); }

/* Mitsuba's Transform::hasScale, which its perspective sensors refuse: a row of the 3x3 part
 * off unit length, or two rows off orthogonal, by more than 1e-3. */
static bool mitsuba_has_scale(const mat4 *m) { return !orthonormal(m, true, 1e-3); }

/* What Mitsuba's perspective sensor and hdrfilm assume where a scene says nothing (a sensor of
 * its own, or the one Mitsuba makes for a scene without). */
static void mitsuba_sensor_defaults(pc_camera *cam) {
  cam->width = 768, cam->height = 576;
  cam->near_clip = 1e-2f, cam->far_clip = 1e4f;
  cam->focus_distance = 0.f, cam->aperture_radius = 0.f;
}

/* pcbpt draws its own independent samples; the sampler's sampleCount is the default number of
 * iterations (one sample per pixel each), as it is Mitsuba's samples per pixel. */
static int sampler(pc_sx *c, const pc_xml_node *n) {
  const char *type;
  int rc = object_type(c, n, false, &type);
  if (rc) return rc;
  char what[PC_SX_WHAT_MAX];
  snprintf(what, sizeof what, "sampler '%.60s'", type);
  int count = 4; /* Mitsuba's default */
  pc_param p[] = {{"sampleCount", PC_P_INT, &count, 0, 0},
                  {"*", PC_P_IGNORED, "pcbpt draws independent samples", 0, 0}};
  if ((rc = only_params(c, n, what, p, 2))) return rc;
  if (count < 1) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: sampleCount must be at least 1", c->file, p[0].line, what);
  c->s->sample_count = count;
  return pc_sx_warn(c, n, "%s: pcbpt draws its own samples; sampleCount %d is the default iteration count", what, count);
}

static int sensor(pc_sx *c, const pc_xml_node *n) {
  const char *type;
  int rc = object_type(c, n, true, &type);
  if (rc) return rc;
  bool lens = strcmp(type, "thinlens") == 0;
  if (strcmp(type, "perspective") != 0 && !lens)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: sensor '%s': not modelled by pcbpt (perspective, thinlens)", c->file,
                   n->line, type);
  const char *what = lens ? "sensor 'thinlens'" : "sensor 'perspective'";
  pc_camera *cam = &c->s->camera;
  float fov = 0, aperture = 0.f;
  const char *axis = "x", *focal = "50mm"; /* Mitsuba's default: a 50 mm lens on 35 mm film */
  mat4 xf;
  pc_sx_xf cx = {.xf = mat4_identity()};
  /* pcbpt does not clip, which only differs for geometry closer than nearClip or beyond
   * farClip (which is also a thin lens's default focus distance, as in Mitsuba): the clip range
   * is kept for the probe that says where that is; focusDistance does nothing in a pinhole. */
  pc_scene *s = c->s;
  mitsuba_sensor_defaults(cam);
  pc_param p[] = {{"fov", PC_P_FLOAT, &fov, 0, 0}, {"fovAxis", PC_P_STRING, &axis, 0, 0},
                  {"toWorld", PC_P_MOTION, &cx, 0, 0},
                  {"nearClip", PC_P_FLOAT, &cam->near_clip, 0, 0},
                  {"farClip", PC_P_FLOAT, &cam->far_clip, 0, 0},
                  {"focusDistance", PC_P_IGNORED, "a pinhole camera has no focus", 0, 0},
                  {"shutterOpen", PC_P_FLOAT, &s->shutter_open, 0, 0},
                  {"shutterClose", PC_P_FLOAT, &s->shutter_close, 0, 0},
                  {"apertureRadius", PC_P_FLOAT, &aperture, 0, 0},
                  {"focalLength", PC_P_STRING, &focal, 0, 0}};
  if (lens) {
    p[5] = (pc_param){"focusDistance", PC_P_FLOAT, &cam->focus_distance, 0, 0};
  } else {
    p[8] = p[9]; /* a pinhole has no aperture */
  }
  const int np = lens ? 10 : 9;
  rc = pc_sx_params(c, n, what, p, np);
  pc_anim_free(&s->camera_anim);
  s->camera_anim = cx.anim;
  xf = cx.xf;
  if (rc) return rc;
  bool have_film = false;
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next) {
    if (pc_sx_is_param(ch, p, np)) continue;
    if (strcmp(ch->name, "film") == 0) {
      if (have_film) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: more than one film", c->file, ch->line, what);
      have_film = true;
      if ((rc = film(c, ch))) return rc;
    } else if (strcmp(ch->name, "sampler") == 0) {
      if ((rc = sampler(c, ch))) return rc;
    } else {
      return pc_sx_unexpected(c, ch, what);
    }
  }
  const pc_param *focal_p = &p[np - 1];
  if (p[0].set && focal_p->set)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give fov or focalLength, not both (as Mitsuba)", c->file, focal_p->line, what);
  if (!p[0].set) {
    /* Mitsuba's focal length, "<x>mm" (or a bare number), of a 35 mm film: its diagonal field */
    char *end = NULL;
    errno = 0;
    double mm = strtod(focal, &end);
    if (end == focal || !(strcmp(end, "mm") == 0 || *end == 0) || errno || !(mm > 0) || !isfinite(mm))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: focalLength '%.40s' must be a positive length in mm, e.g. \"35mm\"",
                     c->file, focal_p->set ? focal_p->line : n->line, what, focal);
    fov = (float)(2.0 * atan(sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * mm)) * 180.0 / M_PI);
    axis = "diagonal";
  }
  if (!(fov > 0.f && fov < 180.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: fov must lie in (0, 180) degrees", c->file, p[0].line, what);
  static const struct { const char *name; char c; } axes[] = {
      {"x", 'x'}, {"y", 'y'}, {"diagonal", 'd'}, {"smaller", 's'}, {"larger", 'l'}};
  cam->fov_axis = 0;
  for (size_t i = 0; i < sizeof axes / sizeof axes[0]; i++)
    if (strcmp(axis, axes[i].name) == 0) cam->fov_axis = axes[i].c;
  if (!cam->fov_axis)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: unknown fovAxis '%s' (x, y, diagonal, smaller, larger)", c->file, p[1].line,
                   what, axis);
  if (!(cam->near_clip > 0.f && cam->far_clip > cam->near_clip && isfinite(cam->far_clip)))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: the clip range must satisfy 0 < nearClip < farClip (finite)", c->file,
                   p[3].set ? p[3].line : p[4].set ? p[4].line : n->line, what);
  if (!(s->shutter_close >= s->shutter_open))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: shutterClose %g is before shutterOpen %g", c->file, n->line, what,
                   (double)s->shutter_close, (double)s->shutter_open);
  /* a moving sensor stays rigid between rigid keyframes of one stretch */
  bool rigid = is_rigid(&xf) && pc_anim_same_scale(&s->camera_anim);
  for (int k = 0; rigid && k < s->camera_anim.n; k++) {
    mat4 m = pc_anim_eval(&s->camera_anim, s->camera_anim.k[k].time);
    rigid = is_rigid(&m);
  }
  /* Mitsuba tests the transform at time 0 with a tolerance ten times this one's */
  mat4 at0 = s->camera_anim.n ? pc_anim_eval(&s->camera_anim, 0.f) : xf;
  if (!rigid && mitsuba_has_scale(&at0))
    return pc_errf(c->e, PC_EUNSUPPORTED,
                   "%s:%d: %s: a toWorld that scales or shears (not rigid): Mitsuba 0.6 refuses it too (\"scale factors in"
                   " the camera-to-world transformation are not allowed\")",
                   c->file, p[2].line, what);
  /* what Mitsuba accepts (a matrix printed with few digits) a still sensor uses with its axes
     as they are, not squared up (camera.c); a moving one must be rigid */
  if (!rigid && s->camera_anim.n)
    return pc_errf(c->e, PC_EUNSUPPORTED,
                   "%s:%d: %s: a moving toWorld that scales or shears (not rigid to 1e-4): not modelled by pcbpt"
                   " (Mitsuba accepts a camera matrix rigid to 1e-3)",
                   c->file, p[2].line, what);
  if (lens) {
    if (!p[5].set) cam->focus_distance = cam->far_clip;
    if (!p[8].set)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'apertureRadius' is required", c->file, n->line, what);
    if (!(aperture >= 0.f) || !isfinite(aperture))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: apertureRadius must be finite and not negative", c->file, p[8].line, what);
    if (!(cam->focus_distance > 0.f) || !isfinite(cam->focus_distance))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: focusDistance must be positive and finite", c->file,
                     p[5].set ? p[5].line : p[4].line, what);
    /* Mitsuba makes a zero aperture an epsilon one, i.e. a pinhole */
    if (aperture == 0.f && (rc = pc_sx_warn(c, n, "%s: a zero apertureRadius renders as a pinhole, as in Mitsuba", what)))
      return rc;
    cam->aperture_radius = aperture;
  }
  cam->fov_deg = fov;
  cam->to_world = xf;
  return 0;
}

int pc_sx_add_shape(pc_sx *c, const pc_xml_node *n, pc_shape *sh) {
  if (c->s->nshapes >= PC_SCENE_MAX_SHAPES)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: more than %d shapes", c->file, n->line, PC_SCENE_MAX_SHAPES);
  int rc = pc_sx_grow(c, (void **)&c->s->shapes, &c->cap_shapes, c->s->nshapes + 1, sizeof *sh);
  if (rc) return rc;
  sh->xml_line = n->line;
  sh->xml_file = 0;
  for (int k = 0; n->file && k < c->nnames && !sh->xml_file; k++)
    if (c->names[k] == n->file) sh->xml_file = k + 1;
  c->s->shapes[c->s->nshapes++] = *sh;
  return 0;
}

static int add_light(pc_sx *c, const pc_xml_node *n, const pc_light *l, int *index) {
  if (c->s->nlights >= PC_SCENE_MAX_LIGHTS)
    return pc_errf(c->e, PC_ELIMIT, "%s:%d: more than %d emitters", c->file, n->line, PC_SCENE_MAX_LIGHTS);
  int rc = pc_sx_grow(c, (void **)&c->s->lights, &c->cap_lights, c->s->nlights + 1, sizeof *l);
  if (rc) return rc;
  *index = c->s->nlights;
  c->s->lights[c->s->nlights++] = *l;
  return 0;
}

static int positive_color(pc_sx *c, const pc_param *p, vec3 v, const char *what) {
  if (v3_maxc(v) > 0.f) return 0;
  return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: '%s' must be positive in some channel", c->file, p->line, what, p->name);
}

/* Mitsuba's samplingWeight scales how often the emitter is chosen; pcbpt multiplies it into its
 * power-proportional choice, whose pdf every method uses alike. */
static int sampling_weight(pc_sx *c, const pc_param *p, float w, const char *what) {
  if (!p->set || (w > 0.f && w <= 1e6f)) return 0;
  return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: samplingWeight must lie in (0, 1e6]", c->file, p->line, what);
}

static int area_emitter(pc_sx *c, const pc_xml_node *n, vec3 *radiance, float *weight) {
  const char *type;
  int rc = object_type(c, n, true, &type);
  if (rc) return rc;
  if (strcmp(type, "area") != 0)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: emitter '%s' cannot be attached to a shape (only area)", c->file, n->line, type);
  *radiance = v3s(1.f); /* Mitsuba's D65 default, white in RGB mode */
  pc_param p[] = {{"radiance", PC_P_COLOR, radiance, 0, 0}, {"samplingWeight", PC_P_FLOAT, weight, 0, 0}};
  if ((rc = only_params(c, n, "emitter 'area'", p, 2)) || (rc = sampling_weight(c, &p[1], *weight, "emitter 'area'"))) return rc;
  return p[0].set ? positive_color(c, &p[0], *radiance, "emitter 'area'") : 0;
}

/* A similarity transform (rotation, translation, uniform scale, possibly mirrored): sets s. */
bool pc_sx_is_similarity(const mat4 *m, double *s) {
  double s2 = 0;
  for (int k = 0; k < 3; k++) s2 += m->m[k][0] * m->m[k][0];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double d = 0;
      for (int k = 0; k < 3; k++) d += m->m[k][i] * m->m[k][j];
      if (fabs(d - (i == j ? s2 : 0)) > 1e-4 * s2) return false;
    }
  *s = sqrt(s2);
  return *s > 0;
}

static int load_mesh(pc_sx *c, const pc_xml_node *n, const char *type, const char *what, const char *filename,
                     int shape_index, bool *file_face_normals, pc_mesh *m) {
  int rc;
  if (strcmp(type, "rectangle") == 0) rc = pc_mesh_rectangle(m);
  else if (strcmp(type, "cube") == 0) rc = pc_mesh_cube(m);
  else if (strcmp(type, "disk") == 0) rc = pc_mesh_disk(m, DISK_SEGMENTS);
  else {
    if (!filename) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'filename' is required", c->file, n->line, what);
    char *path;
    if ((rc = pc_sx_resolve(c, n, what, filename, &path))) return rc;
    if (type[0] == 's') rc = pc_mesh_load_serialized(path, shape_index, m, file_face_normals, c->e);
    else rc = pc_mesh_load_ply(path, m, c->e);
    free(path);
    return rc ? pc_sx_wrap(c, n, what, rc) : 0;
  }
  return rc ? pc_errf(c->e, rc, "%s:%d: %s: out of memory", c->file, n->line, what) : 0;
}

/* maxSmoothAngle: normals rebuilt as Mitsuba does (a file's own face-normal flag gives way, as
 * the serialized plugin's faceNormals parameter overrides it); Mitsuba refuses it together with
 * faceNormals. */
static int smooth_angle_normals(pc_sx *c, const pc_param *p, const char *what, bool face_normals, float angle, pc_mesh *m) {
  if (face_normals)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'maxSmoothAngle' and 'faceNormals' cannot be given together (as in Mitsuba)",
                   c->file, p->line, what);
  if (!(fabsf(angle) <= 360.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'maxSmoothAngle' must lie in [-360, 360] degrees", c->file, p->line, what);
  int rc = pc_mesh_rebuild_topology(m, angle);
  if (!rc) return 0;
  return pc_errf(c->e, rc, "%s:%d: %s: maxSmoothAngle: %s", c->file, p->line, what,
                 rc == PC_ENOMEM ? "out of memory" : rc == PC_ELIMIT ? "the split mesh has too many vertices" : "invalid mesh data");
}

/* What a mesh shape's parameters ask of each of its meshes. */
typedef struct mesh_opts {
  bool obj, file, face_normals, file_face_normals, flip_normals, flip_tex;
  const pc_param *smooth; /* maxSmoothAngle when given */
  float smooth_angle;
  mat4 xf;
  const pc_anim *anim;    /* a moving toWorld (xf is then the identity), or NULL */
} mesh_opts;

/* A loaded mesh made into a shape's mesh as Mitsuba's TriMesh does: texture coordinates flipped,
 * toWorld applied, normals rebuilt, computed or dropped, flipNormals, then validated. */
static int finish_mesh(pc_sx *c, const pc_xml_node *n, const char *what, const mesh_opts *o, pc_mesh *m) {
  int rc;
  if (o->obj && o->flip_tex && m->uv)
    for (uint32_t i = 0; i < m->nverts; i++) m->uv[i].y = 1.f - m->uv[i].y;
  pc_mesh_transform(m, &o->xf);
  if (o->smooth) {
    if ((rc = smooth_angle_normals(c, o->smooth, what, o->face_normals, o->smooth_angle, m))) return rc;
  } else if (o->face_normals || o->file_face_normals) {
    free(m->n);
    m->n = NULL;
  } else if (o->file && !m->n && pc_mesh_compute_normals(m)) {
    return pc_errf(c->e, PC_ENOMEM, "%s:%d: %s: out of memory", c->file, n->line, what);
  }
  if (o->flip_normals) pc_mesh_flip(m);
  char where[PC_SX_WHAT_MAX + 64];
  snprintf(where, sizeof where, "%s:%d: %s", c->file, n->line, what);
  return pc_mesh_validate(m, where, c->e);
}

/* Appends a shape (taking its mesh) and the area light it carries, if any. */
static int add_shape_with_light(pc_sx *c, const pc_xml_node *n, pc_shape *sh, bool emits, vec3 radiance, float weight) {
  /* Mitsuba loads such a mesh and never hits it (a published staircase has one); as an
     emitter it would have no area to emit from */
  int rc = 0;
  const char *type = pc_xml_attr(n, "type") ? pc_xml_attr(n, "type") : "?";
  if (sh->kind == PC_SHAPE_MESH && !pc_mesh_has_area(&sh->mesh))
    rc = emits ? pc_errf(c->e, PC_EINVAL, "%s:%d: shape '%s': an emitter whose every triangle is degenerate (zero area)",
                         c->file, n->line, type)
               : pc_sx_warn(c, n, "shape '%s': every triangle is degenerate (zero area), so nothing of it is ever hit", type);
  if (!rc) rc = pc_sx_add_shape(c, n, sh);
  if (rc) {
    pc_mesh_free(&sh->mesh);
    return rc;
  }
  if (!emits) return 0;
  pc_light l;
  memset(&l, 0, sizeof l);
  l.type = PC_LIGHT_AREA;
  l.radiance = radiance;
  l.sampling_weight = weight;
  l.shape = c->s->nshapes - 1;
  return add_light(c, n, &l, &c->s->shapes[c->s->nshapes - 1].light);
}

int pc_sx_add_motion(pc_sx *c, const pc_xml_node *n, const char *what, const pc_anim *anim) {
  pc_scene *s = c->s;
  pc_shape_kind kind = s->shapes[s->nshapes - 1].kind;
  for (int k = 0; kind != PC_SHAPE_MESH && k < anim->n; k++) {
    const double *sc = anim->k[k].s;
    if (fabs(sc[0] - sc[1]) > 1e-5 * fabs(sc[0]) || fabs(sc[0] - sc[2]) > 1e-5 * fabs(sc[0]))
      return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: a moving toWorld that does not scale uniformly (a %s must keep its shape)",
                     c->file, n->line, what, kind == PC_SHAPE_SPHERE ? "sphere" : "cylinder");
  }
  int rc = pc_sx_grow(c, (void **)&s->motions, &c->cap_motions, s->nmotions + 1, sizeof *s->motions);
  if (rc) return rc;
  pc_motion *mo = &s->motions[s->nmotions];
  memset(mo, 0, sizeof *mo);
  mo->shape = s->nshapes - 1;
  mo->object = s->shapes[mo->shape];
  mo->object.mesh = (pc_mesh){0};
  mo->anim.k = malloc(sizeof *anim->k * (size_t)anim->n);
  if (!mo->anim.k || (mo->object.kind == PC_SHAPE_MESH && pc_mesh_copy(&s->shapes[mo->shape].mesh, &mo->object.mesh))) {
    free(mo->anim.k);
    return pc_errf(c->e, PC_ENOMEM, "%s:%d: out of memory for an animation", c->file, n->line);
  }
  memcpy(mo->anim.k, anim->k, sizeof *anim->k * (size_t)anim->n);
  mo->anim.n = mo->anim.cap = anim->n;
  s->nmotions++;
  return 0;
}

/* A BSDF child of a shape: the material and the name it was given (NULL: none). */
typedef struct shape_bsdf {
  const char *name;
  int material, line;
} shape_bsdf;

/* The meshes of an OBJ file, each with its material (scene_obj_xml.c has the rules). */
static int obj_shapes(pc_sx *c, const pc_xml_node *n, const char *what, const char *filename, bool collapse, int shape_index,
                      bool load_materials, const mesh_opts *o, const shape_bsdf *bsdfs, int nb, bool emits, vec3 radiance,
                      float weight) {
  char *path;
  int rc = pc_sx_resolve(c, n, what, filename, &path);
  if (rc) return rc;
  pc_obj obj;
  rc = pc_obj_load(path, collapse, shape_index, &obj, c->e);
  free(path);
  if (rc) return pc_sx_wrap(c, n, what, rc);
  pc_sx_mtl *lib = NULL;
  if (emits && obj.n > 1)
    rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: an emitter on an OBJ file of %d meshes (groups or materials); Mitsuba refuses it too",
                 c->file, n->line, what, obj.n);
  if (!rc && obj.n == 0)
    rc = pc_sx_warn(c, n, "%s: shapeIndex %d selects no mesh of '%s' (as in Mitsuba): the shape is empty", what, shape_index, filename);
  if (!rc && load_materials && obj.mtllib) rc = pc_sx_mtl_load(c, n, filename, obj.mtllib, obj.mtllib_line, &lib);
  for (int j = 0; j < nb && !rc; j++) {
    bool used = !bsdfs[j].name;
    for (int i = 0; i < obj.n && !used; i++) used = strcmp(obj.meshes[i].material, bsdfs[j].name) == 0;
    if (!used)
      rc = pc_sx_warn(c, n, "%s: the BSDF named '%s' (line %d) names no material of '%s', as Mitsuba warns too", what, bsdfs[j].name,
                      bsdfs[j].line, filename);
  }
  for (int i = 0; i < obj.n && !rc; i++) {
    pc_shape sh;
    memset(&sh, 0, sizeof sh);
    sh.kind = PC_SHAPE_MESH;
    sh.light = -1;
    sh.material = -1;
    const char *mtl = obj.meshes[i].material;
    for (int j = 0; j < nb; j++)
      if (!bsdfs[j].name || strcmp(bsdfs[j].name, mtl) == 0) sh.material = bsdfs[j].material;
    if (sh.material < 0 && *mtl) rc = pc_sx_mtl_material(c, lib, mtl, &sh.material);
    if (!rc && sh.material < 0) rc = pc_sx_default_material(c, n, &sh.material);
    sh.mesh = obj.meshes[i].mesh;
    obj.meshes[i].mesh = (pc_mesh){0};
    if (!rc && (rc = finish_mesh(c, n, what, o, &sh.mesh))) pc_mesh_free(&sh.mesh);
    if (!rc && !(rc = add_shape_with_light(c, n, &sh, emits, radiance, weight)) && o->anim) rc = pc_sx_add_motion(c, n, what, o->anim);
    else if (rc) pc_mesh_free(&sh.mesh);
  }
  pc_sx_mtl_free(lib);
  pc_obj_free(&obj);
  return rc;
}

static int shape(pc_sx *c, const pc_xml_node *n, pc_sx_xf *to_world) {
  const pc_anim *anim = &to_world->anim;
  const char *type;
  int rc = object_type(c, n, true, &type);
  if (rc) return rc;
  /* Mitsuba lowercases plugin names: scenes write shapeGroup */
  if (strcasecmp(type, "shapegroup") == 0) return pc_sx_shapegroup(c, n);
  if (strcmp(type, "instance") == 0) return pc_sx_instance(c, n);
  bool is_file = strcmp(type, "obj") == 0 || strcmp(type, "ply") == 0 || strcmp(type, "serialized") == 0;
  bool is_obj = strcmp(type, "obj") == 0;
  bool is_sphere = strcmp(type, "sphere") == 0, is_cylinder = strcmp(type, "cylinder") == 0;
  if (!is_file && !is_sphere && !is_cylinder && strcmp(type, "rectangle") != 0 && strcmp(type, "cube") != 0 && strcmp(type, "disk") != 0)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: shape '%s': not modelled by pcbpt", c->file, n->line, type);
  char what[PC_SX_WHAT_MAX];
  snprintf(what, sizeof what, "shape '%s'", type);
  const char *filename = NULL;
  mesh_opts o = {.obj = is_obj, .file = is_file, .flip_tex = true, .xf = mat4_identity()};
  bool collapse = false, load_materials = true;
  int shape_index = is_obj ? -1 : 0;
  vec3 center = v3s(0), p0 = v3s(0), p1 = v3(0, 0, 1);
  float radius = 1.f;
  pc_param p[10] = {{"toWorld", PC_P_MOTION, to_world, 0, 0}, {"flipNormals", PC_P_BOOL, &o.flip_normals, 0, 0}};
  int np = 2;
  if (is_file) {
    p[np++] = (pc_param){"filename", PC_P_STRING, &filename, 0, 0};
    p[np++] = (pc_param){"faceNormals", PC_P_BOOL, &o.face_normals, 0, 0};
    if (is_obj) {
      p[np++] = (pc_param){"flipTexCoords", PC_P_BOOL, &o.flip_tex, 0, 0};
      p[np++] = (pc_param){"collapse", PC_P_BOOL, &collapse, 0, 0};
      p[np++] = (pc_param){"loadMaterials", PC_P_BOOL, &load_materials, 0, 0};
    }
    if (type[0] == 's' || is_obj) p[np++] = (pc_param){"shapeIndex", PC_P_INT, &shape_index, 0, 0};
    p[np++] = (pc_param){"maxSmoothAngle", PC_P_FLOAT, &o.smooth_angle, 0, 0};
  } else if (is_sphere) {
    p[np++] = (pc_param){"center", PC_P_POINT, &center, 0, 0};
    p[np++] = (pc_param){"radius", PC_P_FLOAT, &radius, 0, 0};
  } else if (is_cylinder) {
    p[np++] = (pc_param){"p0", PC_P_POINT, &p0, 0, 0};
    p[np++] = (pc_param){"p1", PC_P_POINT, &p1, 0, 0};
    p[np++] = (pc_param){"radius", PC_P_FLOAT, &radius, 0, 0};
  }
  if ((rc = pc_sx_params(c, n, what, p, np))) return rc;
  if (is_file && p[np - 1].set) o.smooth = &p[np - 1];
  o.xf = to_world->xf;
  if (anim->n) o.anim = anim;
  int nchildren = 0;
  for (const pc_xml_node *ch = n->first; ch; ch = ch->next) nchildren++;
  shape_bsdf *bsdfs = calloc((size_t)(nchildren ? nchildren : 1), sizeof *bsdfs);
  if (!bsdfs) return pc_errf(c->e, PC_ENOMEM, "%s: out of memory", c->file);
  int nb = 0;
  bool emits = false;
  vec3 radiance = v3s(0);
  float weight = 1.f;
  for (const pc_xml_node *ch = n->first; ch && !rc; ch = ch->next) {
    if (pc_sx_is_param(ch, p, np)) continue;
    if (strcmp(ch->name, "bsdf") == 0 || strcmp(ch->name, "ref") == 0) {
      /* an OBJ's BSDFs may be named after its materials; other shapes have one */
      if (nb > 0 && !is_obj) {
        rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: more than one BSDF", c->file, ch->line, what);
        break;
      }
      shape_bsdf *b = &bsdfs[nb];
      b->name = is_obj ? pc_xml_attr(ch, "name") : NULL;
      b->line = ch->line;
      if (ch->name[0] == 'b') {
        if (!(rc = pc_sx_bsdf(c, ch, &b->material))) nb++;
        continue;
      }
      static const char *const allowed[] = {"id", "name", NULL};
      if ((rc = pc_xml_check_attrs(c->file, ch, allowed, c->e))) break;
      const char *id = pc_xml_attr(ch, "id");
      const pc_sx_id *r = id ? pc_sx_id_find(c, id) : NULL;
      if (!r) rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: reference to unknown id '%s'", c->file, ch->line, what, id ? id : "");
      else if (r->kind != PC_ID_BSDF) rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: id '%s' is not a BSDF", c->file, ch->line, what, id);
      else b->material = r->index, nb++;
    } else if (strcmp(ch->name, "emitter") == 0) {
      if (emits) rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: more than one emitter", c->file, ch->line, what);
      else if (!(rc = area_emitter(c, ch, &radiance, &weight))) emits = true;
    } else {
      rc = pc_sx_unexpected(c, ch, what);
    }
  }
  if (!rc && emits && anim->n)
    rc = pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: an emitter on a moving shape: Mitsuba refuses it too (an instanced emitter)",
                 c->file, n->line, what);
  if (!rc && is_obj) {
    if (!filename) rc = pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'filename' is required", c->file, n->line, what);
    else rc = obj_shapes(c, n, what, filename, collapse, shape_index, load_materials, &o, bsdfs, nb, emits, radiance, weight);
    free(bsdfs);
    if (rc) return rc;
    const char *id = pc_xml_attr(n, "id");
    return id ? pc_sx_id_add(c, id, PC_ID_OTHER, c->s->nshapes - 1, n->line) : 0;
  }
  int material = nb > 0 ? bsdfs[0].material : -1;
  free(bsdfs);
  if (rc) return rc;
  if (material < 0 && (rc = pc_sx_default_material(c, n, &material))) return rc;

  pc_shape sh;
  memset(&sh, 0, sizeof sh);
  sh.material = material;
  sh.light = -1;
  if (is_sphere) {
    double s;
    if (!pc_sx_is_similarity(&o.xf, &s))
      return pc_errf(c->e, PC_EUNSUPPORTED,
                     "%s:%d: %s: toWorld may only translate, rotate and scale uniformly (a sphere must stay a sphere)",
                     c->file, n->line, what);
    sh.kind = PC_SHAPE_SPHERE;
    sh.center = mat4_point(&o.xf, center);
    sh.radius = (float)(s * radius);
    sh.flip_normals = o.flip_normals;
    if (!(radius > 0.f) || !(sh.radius > 0.f) || !isfinite(sh.radius) || !v3_is_finite(sh.center))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: radius must be positive and finite", c->file, n->line, what);
  } else if (is_cylinder) {
    const char *why = pc_cylinder_place(&sh, p0, p1, radius, &o.xf);
    if (why) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: %s", c->file, n->line, what, why);
    sh.flip_normals = o.flip_normals;
  } else {
    sh.kind = PC_SHAPE_MESH;
    if ((rc = load_mesh(c, n, type, what, filename, shape_index, &o.file_face_normals, &sh.mesh))) return rc;
    if ((rc = finish_mesh(c, n, what, &o, &sh.mesh))) {
      pc_mesh_free(&sh.mesh);
      return rc;
    }
  }
  if ((rc = add_shape_with_light(c, n, &sh, emits, radiance, weight))) return rc;
  if (anim->n && (rc = pc_sx_add_motion(c, n, what, anim))) return rc;
  const char *id = pc_xml_attr(n, "id");
  return id ? pc_sx_id_add(c, id, PC_ID_OTHER, c->s->nshapes - 1, n->line) : 0;
}

int pc_sx_shape(pc_sx *c, const pc_xml_node *n) {
  pc_sx_xf to_world = {.xf = mat4_identity()};
  int rc = shape(c, n, &to_world);
  pc_anim_free(&to_world.anim);
  return rc;
}

/* Mitsuba's `constant` and `envmap` (light.h, light_env.c). */
static int env_emitter(pc_sx *c, const pc_xml_node *n, const char *type, pc_light *l) {
  char what[PC_SX_WHAT_MAX];
  snprintf(what, sizeof what, "emitter '%s'", type);
  l->type = PC_LIGHT_ENV;
  l->shape = -1;
  l->radiance = v3s(1.f); /* Mitsuba's D65 default, white in RGB */
  l->env_scale = 1.f;
  int rc;
  if (c->have_env)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: only one environment emitter per scene (as in Mitsuba)", c->file, n->line, what);
  if (type[0] == 'c') {
    pc_param p[] = {{"radiance", PC_P_COLOR, &l->radiance, 0, 0}, {"samplingWeight", PC_P_FLOAT, &l->sampling_weight, 0, 0}};
    if ((rc = only_params(c, n, what, p, 2)) || (rc = positive_color(c, &p[0], l->radiance, what)) ||
        (rc = sampling_weight(c, &p[1], l->sampling_weight, what)))
      return rc;
    l->env_frame = (frame){v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)};
    c->have_env = true;
    return 0;
  }
  const char *filename = NULL;
  float gamma = 0.f;
  bool cache = false;
  mat4 xf = mat4_identity();
  /* `cache` only decides whether Mitsuba writes a MIP-map file next to the image. */
  pc_param p[] = {{"filename", PC_P_STRING, &filename, 0, 0}, {"scale", PC_P_FLOAT, &l->env_scale, 0, 0},
                  {"toWorld", PC_P_TRANSFORM, &xf, 0, 0}, {"gamma", PC_P_FLOAT, &gamma, 0, 0},
                  {"cache", PC_P_BOOL, &cache, 0, 0}, {"samplingWeight", PC_P_FLOAT, &l->sampling_weight, 0, 0}};
  if ((rc = only_params(c, n, what, p, 6)) || (rc = sampling_weight(c, &p[5], l->sampling_weight, what))) return rc;
  if (!filename) return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'filename' is required", c->file, n->line, what);
  if (!(l->env_scale > 0.f) || !isfinite(l->env_scale))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: 'scale' must be positive and finite", c->file, p[1].line, what);
  /* Mitsuba's gamma override: -1 sRGB, 1 linear; 0 (unset) detects it (8-bit files are sRGB). */
  if (p[3].set && gamma != -1.f && gamma != 1.f)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: gamma %g not modelled by pcbpt (-1 for sRGB or 1 for linear)", c->file,
                   p[3].line, what, (double)gamma);
  if (!is_rigid(&xf))
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: toWorld must be a rotation (it scales or shears)", c->file, p[2].line, what);
  l->env_frame = (frame){v3_norm(mat4_vector(&xf, v3(1, 0, 0))), v3_norm(mat4_vector(&xf, v3(0, 1, 0))),
                         v3_norm(mat4_vector(&xf, v3(0, 0, 1)))};
  char *path;
  if ((rc = pc_sx_resolve(c, n, what, filename, &path))) return rc;
  rc = pc_image_read(path, gamma != 1.f, &l->env_img, c->e);
  free(path);
  if (rc) return pc_sx_wrap(c, n, what, rc);
  c->have_env = true;
  return 0;
}

/* Mitsuba's `spot`: at the origin of its toWorld frame, shining along the frame's +z. */
static int spot_emitter(pc_sx *c, const pc_xml_node *n, pc_light *l) {
  static const char what[] = "emitter 'spot'";
  mat4 xf = mat4_identity();
  float cutoff = 20.f, beam = 0.f;
  pc_tex_slot tex = {.tex = -1};
  l->type = PC_LIGHT_SPOT;
  l->intensity = v3s(1.f);
  l->shape = -1;
  pc_param p[] = {{"toWorld", PC_P_TRANSFORM, &xf, 0, 0},       {"intensity", PC_P_COLOR, &l->intensity, 0, 0},
                  {"cutoffAngle", PC_P_FLOAT, &cutoff, 0, 0},   {"beamWidth", PC_P_FLOAT, &beam, 0, 0},
                  {"texture", PC_P_SLOT, &tex, 0, 0},           {"samplingWeight", PC_P_FLOAT, &l->sampling_weight, 0, 0}};
  int rc;
  if ((rc = only_params(c, n, what, p, 6)) || (rc = sampling_weight(c, &p[5], l->sampling_weight, what)) ||
      (rc = positive_color(c, &p[1], l->intensity, what)))
    return rc;
  if (!(cutoff > 0.f && cutoff <= 180.f))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: cutoffAngle must lie in (0, 180] degrees", c->file, p[2].line ? p[2].line : n->line,
                   what);
  if (!p[3].set) beam = cutoff * 0.75f; /* Mitsuba's default */
  if (!(beam >= 0.f && beam <= cutoff))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: beamWidth must lie in [0, cutoffAngle]", c->file, p[3].line ? p[3].line : n->line,
                   what);
  if (!is_rigid(&xf))
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: %s: a toWorld that scales or shears (not rigid): not modelled by pcbpt", c->file,
                   p[0].line, what);
  l->position = mat4_point(&xf, v3s(0));
  if (!v3_is_finite(l->position))
    return pc_errf(c->e, PC_ENUMERIC, "%s:%d: %s: position is not finite", c->file, p[0].line, what);
  l->spot_frame = (frame){v3_norm(mat4_vector(&xf, v3(1, 0, 0))), v3_norm(mat4_vector(&xf, v3(0, 1, 0))),
                          v3_norm(mat4_vector(&xf, v3(0, 0, 1)))};
  pc_spot_set_angles(l, cutoff, beam);
  /* Mitsuba projects only a non-constant texture; a plain colour has no effect there either. */
  if (tex.tex >= 0 && (c->s->textures[tex.tex].type != PC_TEX_CONST || c->s->textures[tex.tex].scaled)) {
    if (!(l->spot_tex = calloc(1, sizeof *l->spot_tex)) || !pc_texture_copy(&c->s->textures[tex.tex], l->spot_tex)) {
      free(l->spot_tex);
      l->spot_tex = NULL;
      return pc_errf(c->e, PC_ENOMEM, "%s:%d: %s: out of memory for its texture", c->file, p[4].line, what);
    }
  } else if (p[4].set && (rc = pc_sx_warn(c, n, "%s: a constant 'texture' is ignored (as by Mitsuba)", what))) {
    return rc;
  }
  return 0;
}

/* Mitsuba's `directional`: a distant light sending `irradiance` along the unit `direction`, or
 * along the +z axis of its toWorld (which, as in Mitsuba, may neither scale nor shear); one of
 * the two, not both. */
static int directional_emitter(pc_sx *c, const pc_xml_node *n, pc_light *l) {
  static const char what[] = "emitter 'directional'";
  mat4 xf = mat4_identity();
  vec3 dir = v3(0, 0, 1);
  l->type = PC_LIGHT_DIRECTIONAL;
  l->irradiance = v3s(1.f);
  l->shape = -1;
  pc_param p[] = {{"toWorld", PC_P_TRANSFORM, &xf, 0, 0},
                  {"direction", PC_P_VECTOR, &dir, 0, 0},
                  {"irradiance", PC_P_COLOR, &l->irradiance, 0, 0},
                  {"samplingWeight", PC_P_FLOAT, &l->sampling_weight, 0, 0}};
  int rc;
  if ((rc = only_params(c, n, what, p, 4)) || (rc = sampling_weight(c, &p[3], l->sampling_weight, what)) ||
      (rc = positive_color(c, &p[2], l->irradiance, what)))
    return rc;
  if (p[0].set && p[1].set)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: give direction or toWorld, not both (as Mitsuba)", c->file, n->line, what);
  if (p[0].set) {
    if (mitsuba_has_scale(&xf))
      return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: a toWorld that scales or shears: Mitsuba 0.6 refuses it too", c->file,
                     p[0].line, what);
    dir = mat4_vector(&xf, v3(0, 0, 1));
  }
  float len = v3_len(dir);
  if (!(len > 1e-12f) || !isfinite(len))
    return pc_errf(c->e, PC_EINVAL, "%s:%d: %s: the direction must be a finite, non-zero vector", c->file,
                   p[1].set ? p[1].line : p[0].line ? p[0].line : n->line, what);
  l->direction = v3_scale(dir, 1.f / len);
  return 0;
}

static int emitter(pc_sx *c, const pc_xml_node *n) {
  const char *type;
  int rc = object_type(c, n, true, &type);
  if (rc) return rc;
  if (strcmp(type, "area") == 0)
    return pc_errf(c->e, PC_EINVAL, "%s:%d: emitter 'area' must be nested in a <shape>", c->file, n->line);
  pc_light l;
  memset(&l, 0, sizeof l);
  l.sampling_weight = 1.f;
  if (strcmp(type, "constant") == 0 || strcmp(type, "envmap") == 0) {
    if ((rc = env_emitter(c, n, type, &l))) {
      pc_light_free(&l);
      return rc;
    }
  } else if (strcmp(type, "spot") == 0) {
    if ((rc = spot_emitter(c, n, &l))) {
      pc_light_free(&l);
      return rc;
    }
  } else if (strcmp(type, "directional") == 0) {
    if ((rc = directional_emitter(c, n, &l))) return rc;
  } else if (strcmp(type, "point") == 0) {
    l.type = PC_LIGHT_POINT;
    l.intensity = v3s(1.f);
    l.shape = -1;
    mat4 xf = mat4_identity();
    pc_param p[] = {{"position", PC_P_POINT, &l.position, 0, 0}, {"toWorld", PC_P_TRANSFORM, &xf, 0, 0},
                    {"intensity", PC_P_COLOR, &l.intensity, 0, 0}, {"samplingWeight", PC_P_FLOAT, &l.sampling_weight, 0, 0}};
    if ((rc = only_params(c, n, "emitter 'point'", p, 4)) || (rc = sampling_weight(c, &p[3], l.sampling_weight, "emitter 'point'")))
      return rc;
    if (p[0].set && p[1].set)
      return pc_errf(c->e, PC_EINVAL, "%s:%d: emitter 'point': give position or toWorld, not both", c->file, n->line);
    if (p[1].set) l.position = mat4_point(&xf, v3s(0));
    if (!v3_is_finite(l.position))
      return pc_errf(c->e, PC_ENUMERIC, "%s:%d: emitter 'point': position is not finite", c->file, n->line);
    if ((rc = positive_color(c, &p[2], l.intensity, "emitter 'point'"))) return rc;
  } else {
    /* Mitsuba's sky and sun are an environment map it computes from published model tables */
    bool sky = strcmp(type, "sunsky") == 0 || strcmp(type, "sky") == 0 || strcmp(type, "sun") == 0;
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: emitter '%s': not modelled by pcbpt%s", c->file, n->line, type,
                   sky ? " (an 'envmap' of the same sky, e.g. one Mitsuba rendered with a spherical sensor, stands in for it)" : "");
  }
  int idx;
  if ((rc = add_light(c, n, &l, &idx))) {
    pc_light_free(&l);
    return rc;
  }
  const char *id = pc_xml_attr(n, "id");
  return id ? pc_sx_id_add(c, id, PC_ID_OTHER, idx, n->line) : 0;
}

/* Mitsuba's <alias id="a" as="b"/>: b names the object a names. */
static int alias(pc_sx *c, const pc_xml_node *n) {
  static const char *const attrs[] = {"id", "as", NULL};
  int rc = pc_xml_check_attrs(c->file, n, attrs, c->e);
  if (rc) return rc;
  const char *id = pc_xml_attr(n, "id"), *as = pc_xml_attr(n, "as");
  if (!id || !as) return pc_errf(c->e, PC_EPARSE, "%s:%d: <alias> needs both 'id' and 'as'", c->file, n->line);
  const pc_sx_id *old = pc_sx_id_find(c, id);
  if (!old) return pc_errf(c->e, PC_EINVAL, "%s:%d: <alias>: no object has the id '%s' (yet)", c->file, n->line, id);
  pc_id_kind kind = old->kind; /* pc_sx_id_add may move the table */
  int index = old->index;
  return pc_sx_id_add(c, as, kind, index, n->line);
}

/* Mitsuba's Scene::configure without a sensor: a perspective camera, fov 45 along x, default
 * film, unrotated (looking along +z), centred on the shapes' bounds in x and y and far enough
 * in front of their nearest z for the x-y extent to fill the fov; at the origin if there are no
 * shapes. */
static int default_sensor(pc_sx *c, const pc_xml_node *root) {
  int rc = pc_sx_warn(c, root, "the scene has no <sensor>: Mitsuba's default perspective camera (fov 45, looking along +z at the shapes)");
  if (rc) return rc;
  vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
  for (int i = 0; i < c->s->nshapes; i++) pc_shape_grow_bounds(&c->s->shapes[i], &lo, &hi);
  pc_camera *cam = &c->s->camera;
  mitsuba_sensor_defaults(cam);
  cam->fov_deg = 45.f;
  cam->fov_axis = 'x';
  cam->to_world = mat4_identity();
  if (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z) {
    vec3 ext = v3_sub(hi, lo);
    float dist = fmaxf(ext.x, ext.y) / (2.f * tanf(45.f * 0.5f * (float)M_PI / 180.f));
    cam->to_world.m[0][3] = 0.5f * (lo.x + hi.x);
    cam->to_world.m[1][3] = 0.5f * (lo.y + hi.y);
    cam->to_world.m[2][3] = lo.z - dist;
  }
  return 0;
}

static int scene_root(pc_sx *c, const pc_xml_node *root) {
  static const char *const allowed[] = {"version", NULL};
  if (strcmp(root->name, "scene") != 0)
    return pc_errf(c->e, PC_EPARSE, "%s:%d: the root element must be <scene>, not <%s>", c->file, root->line, root->name);
  int rc = pc_xml_check_attrs(c->file, root, allowed, c->e);
  if (rc) return rc;
  const char *v = pc_xml_attr(root, "version");
  if (!v) return pc_errf(c->e, PC_EPARSE, "%s:%d: <scene> lacks a version", c->file, root->line);
  int major, minor, patch, end = 0;
  if (sscanf(v, "%d.%d.%d%n", &major, &minor, &patch, &end) != 3 || v[end] || major != 0 || minor < 4 || minor > 6)
    return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: scene version '%s' unsupported (0.4.0 to 0.6.x)", c->file, root->line, v);
  bool have_integrator = false, have_sensor = false;
  static const char *const param_elems[] = {"integer", "float", "boolean", "string", "rgb", "srgb", "spectrum",
                                            "blackbody", "point", "vector", "transform", NULL};
  for (const pc_xml_node *ch = root->first; ch; ch = ch->next) {
    const char *el = ch->name;
    int idx;
    c->file = ch->file ? ch->file : c->main_file; /* an included file's element */
    if (strcmp(el, "default") == 0) continue; /* applied by pc_sx_substitute */
    bool is_param = false;
    for (const char *const *pe = param_elems; *pe; pe++) is_param |= strcmp(el, *pe) == 0;
    if (is_param) {
      /* Mitsuba keeps scene-level parameters for plugins that ask; none of pcbpt's does. */
      const char *name = pc_xml_attr(ch, "name");
      rc = pc_sx_warn(c, ch, "scene: parameter '%.60s' ignored (no plugin reads scene-level parameters)", name ? name : "");
    } else if (strcmp(el, "integrator") == 0) {
      if (have_integrator) return pc_errf(c->e, PC_EINVAL, "%s:%d: more than one <integrator>", c->file, ch->line);
      have_integrator = true;
      rc = integrator(c, root, ch);
    } else if (strcmp(el, "sensor") == 0) {
      if (have_sensor) return pc_errf(c->e, PC_EUNSUPPORTED, "%s:%d: more than one <sensor>", c->file, ch->line);
      have_sensor = true;
      rc = sensor(c, ch);
    } else if (strcmp(el, "shape") == 0) {
      rc = pc_sx_shape(c, ch);
    } else if (strcmp(el, "bsdf") == 0) {
      rc = pc_sx_bsdf(c, ch, &idx);
    } else if (strcmp(el, "texture") == 0) {
      if (!pc_xml_attr(ch, "id"))
        return pc_errf(c->e, PC_EINVAL, "%s:%d: a <texture> at scene level needs an id", c->file, ch->line);
      if (pc_xml_attr(ch, "name"))
        return pc_errf(c->e, PC_EPARSE, "%s:%d: a <texture> at scene level takes no name", c->file, ch->line);
      rc = pc_sx_texture(c, ch, &idx);
    } else if (strcmp(el, "emitter") == 0) {
      rc = emitter(c, ch);
    } else if (strcmp(el, "alias") == 0) {
      rc = alias(c, ch);
    } else {
      return pc_sx_unexpected(c, ch, "scene");
    }
    if (rc) return rc;
  }
  c->file = c->main_file;
  return have_sensor ? 0 : default_sensor(c, root);
}

int pc_scene_load_with(const char *path, const pc_scene_load_opts *opts, pc_scene *out, pc_err *e) {
  static const pc_scene_load_opts none = {0};
  memset(out, 0, sizeof *out);
  out->method = PC_METHOD_PT;
  out->max_depth = -1;
  pc_sx c = {.file = path, .main_file = path, .s = out, .e = e, .default_material = -1, .opts = opts ? opts : &none};
  pc_xml_node *root = NULL;
  char real[PATH_MAX], rootreal[PATH_MAX];
  int rc = 0;
  out->path = strdup(path);
  if (!out->path) rc = pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  else if (!realpath(path, real)) rc = pc_errf(e, PC_EIO, "%s: cannot open: %s", path, strerror(errno));
  if (!rc && c.opts->root) {
    if (!realpath(c.opts->root, rootreal)) rc = pc_errf(e, PC_EIO, "%s: cannot open: %s", c.opts->root, strerror(errno));
    size_t rl = strlen(rootreal);
    if (!rc && !(strcmp(rootreal, "/") == 0 || (strncmp(real, rootreal, rl) == 0 && real[rl] == '/')))
      rc = pc_errf(e, PC_EINVAL, "%s: the scene lies outside its root folder %s", path, c.opts->root);
  } else if (!rc) {
    memcpy(rootreal, real, sizeof real);
    char *slash = strrchr(rootreal, '/');
    if (slash == rootreal) slash[1] = 0;
    else *slash = 0;
  }
  if (!rc && (!(c.dir = strdup(rootreal)) || !(out->root = strdup(rootreal)) || !(c.incl_stack[0] = strdup(real))))
    rc = pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
  if (!rc) {
    /* below the root (checked above); the root itself is a folder */
    size_t rl = strlen(rootreal);
    const char *name = strcmp(rootreal, "/") == 0 ? real + 1 : real + rl + 1;
    if (!(c.incl_names[0] = strdup(name))) rc = pc_errf(e, PC_ENOMEM, "%s: out of memory", path);
    else c.incl_depth = 1;
  }
  if (!rc) rc = pc_sx_note_file(&c, real, c.incl_names[0]);
  if (!rc) rc = pc_xml_parse(path, path, &root, e);
  if (!rc) rc = pc_sx_substitute(&c, root);
  if (!rc) rc = scene_root(&c, root);
  pc_xml_free(root);
  pc_sx_groups_free(&c);
  free(c.dir);
  if (c.incl_depth == 0) free((char *)c.incl_stack[0]); /* its name could not be allocated */
  while (c.incl_depth > 0) {
    free(c.incl_names[c.incl_depth - 1]);
    free((char *)c.incl_stack[--c.incl_depth]);
  }
  /* the shapes name their included files in messages (pc_shape.xml_file) */
  out->xml_includes = c.names;
  out->nxml_includes = c.nnames;
  for (int i = 0; i < c.nwarned; i++) free(c.warned[i]);
  free(c.warned);
  for (int i = 0; i < c.nids; i++) free(c.ids[i].id);
  free(c.ids);
  free(c.id_table);
  for (int i = 0; i < c.nparams; i++) {
    free(c.pnames[i]);
    free(c.pvalues[i]);
  }
  free(c.pnames);
  free(c.pvalues);
  if (rc) pc_scene_free(out);
  return rc;
}

int pc_scene_load(const char *path, pc_scene *out, pc_err *e) { return pc_scene_load_with(path, NULL, out, e); }
