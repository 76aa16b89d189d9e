/* scene_build.c: turns a parsed scene into a renderable one: Embree geometry (one geometry per
 * shape, geomID == shape index; triangles, exact spheres), light sampling tables, derived
 * material data; the same checks and tables without Embree for a client (pc_scene_check); and
 * the ray queries (closest hit, visibility, origin offsets). */
#include <embree3/rtcore.h>
#include <malloc.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "big_alloc.h"
#include "scene.h"
#include "scene_embree.h"
#include "shape_cylinder.h"

typedef struct embree_error {
  int failed;
  char msg[256];
} embree_error;

static void on_embree_error(void *user, enum RTCError code, const char *str) {
  embree_error *ee = user;
  if (ee->failed) return;
  ee->failed = 1;
  snprintf(ee->msg, sizeof ee->msg, "Embree error %d: %s", (int)code, str ? str : "");
}

/* Whether Embree may read a mesh array in place instead of a copy: it loads a shared buffer's
 * last 12-byte element with 16 bytes, so 4 more must be readable. A scene's mesh arrays are
 * its own, from the malloc family (pc_mesh_free frees them), so their allocation can be asked:
 * those from pc_big_alloc have PC_BIG_ALLOC_SLACK, those grown by realloc may (under
 * AddressSanitizer the answer is the size asked for, so they are copied there). A
 * 5M-triangle mesh's copies were 120 MB, most of the faults left in its start. */
static bool shareable(const void *p, size_t bytes) {
  return p && malloc_usable_size((void *)p) >= bytes + 4 && (uintptr_t)p % 4 == 0;
}

/* Gives g its buffer of n 12-byte elements at data: shared when it can be, else a copy. */
static bool set_buffer(RTCGeometry g, enum RTCBufferType type, enum RTCFormat format, const void *data, size_t n) {
  if (shareable(data, 12 * n)) {
    rtcSetSharedGeometryBuffer(g, type, 0, format, data, 0, 12, n);
    return true;
  }
  void *b = rtcSetNewGeometryBuffer(g, type, 0, format, 12, n);
  if (b) memcpy(b, data, 12 * n);
  return b != NULL;
}

static int build_lights(pc_scene *s, pc_err *e) {
  if (s->nlights == 0) return pc_errf(e, PC_EINVAL, "%s: the scene has no emitter", s->path);
  s->env_light = -1;
  /* A little outside the bounding sphere, so the disk light paths start from misses nothing. */
  s->env_radius = 1.01f * s->scene_radius;
  s->light_cdf = malloc(sizeof(float) * (size_t)(s->nlights + 1));
  if (!s->light_cdf) return pc_errf(e, PC_ENOMEM, "%s: out of memory for lights", s->path);
  s->light_cdf[0] = 0.f;
  for (int i = 0; i < s->nlights; i++) {
    pc_light *l = &s->lights[i];
    if (l->type == PC_LIGHT_POINT) {
      l->power = 4.f * PC_PI * v3_luminance(l->intensity);
    } else if (l->type == PC_LIGHT_SPOT) {
      /* A texture enters the choice by its mean (the choice needs no exact flux). */
      vec3 t = l->spot_tex ? pc_texture_average(l->spot_tex) : v3s(1.f);
      l->power = (float)(pc_spot_solid_angle(l) * v3_luminance(v3_mul(l->intensity, t)));
    } else if (l->type == PC_LIGHT_DIRECTIONAL) {
      /* what crosses the disk its light paths start on (Mitsuba's, over its own bounding disk) */
      l->power = PC_PI * s->env_radius * s->env_radius * v3_luminance(l->irradiance);
    } else if (l->type == PC_LIGHT_ENV) {
      /* Mitsuba allows one environment emitter per scene; the loader refuses a second. */
      if (s->env_light >= 0) return pc_errf(e, PC_EINVAL, "%s: more than one environment emitter", s->path);
      s->env_light = i;
      char what[64];
      snprintf(what, sizeof what, "%s: environment emitter", s->path);
      int rc = pc_env_prepare(l, s->env_radius, what, e);
      if (rc != PC_OK) return rc;
    } else {
      if (l->shape < 0 || l->shape >= s->nshapes)
        return pc_errf(e, PC_EINVAL, "%s: area light %d has no shape", s->path, i);
      const pc_shape *sh = &s->shapes[l->shape];
      if (sh->kind == PC_SHAPE_SPHERE || sh->kind == PC_SHAPE_CYLINDER) {
        l->area = sh->kind == PC_SHAPE_SPHERE ? 4.f * PC_PI * sh->radius * sh->radius : pc_cylinder_area(sh);
        l->ntris = 0;
      } else {
        const pc_mesh *m = &sh->mesh;
        free(l->tri_cdf);
        free(l->tri_n);
        l->tri_cdf = malloc(sizeof(float) * ((size_t)m->ntris + 1));
        l->tri_n = malloc(sizeof(vec3) * (m->ntris ? (size_t)m->ntris : 1));
        if (!l->tri_cdf || !l->tri_n) return pc_errf(e, PC_ENOMEM, "%s: out of memory for light %d", s->path, i);
        double acc = 0.0;
        l->tri_cdf[0] = 0.f;
        for (uint32_t t = 0; t < m->ntris; t++) {
          const uint32_t *ix = m->idx + 3 * (size_t)t;
          vec3 c = v3_cross(v3_sub(m->p[ix[1]], m->p[ix[0]]), v3_sub(m->p[ix[2]], m->p[ix[0]]));
          acc += 0.5 * (double)v3_len(c);
          l->tri_cdf[t + 1] = (float)acc;
          l->tri_n[t] = v3_norm(c);
        }
        l->ntris = m->ntris;
        l->area = (float)acc;
      }
      if (!(l->area > 0.f) || !isfinite(l->area))
        return pc_errf(e, PC_EINVAL, "%s: area light on shape %d has zero area", s->path, l->shape);
      l->power = PC_PI * l->area * v3_luminance(l->radiance);
    }
    if (!(l->power >= 0.f) || !isfinite(l->power))
      return pc_errf(e, PC_EINVAL, "%s: emitter %d has a negative or non-finite power", s->path, i);
    s->light_cdf[i + 1] = s->light_cdf[i] + l->power * (l->sampling_weight > 0.f ? l->sampling_weight : 1.f);
  }
  if (!(s->light_cdf[s->nlights] > 0.f))
    return pc_errf(e, PC_EINVAL, "%s: every emitter has zero power", s->path);
  return PC_OK;
}

int pc_scene_attach_shape(const pc_scene *s, void *rtc_scene, int i, pc_err *e) {
  RTCDevice dev = s->rtc_device;
  const embree_error *ee = s->rtc_error;
  const pc_shape *sh = &s->shapes[i];
  RTCGeometry g;
  if (sh->kind == PC_SHAPE_SPHERE) {
    if (!rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_POINT_GEOMETRY_SUPPORTED))
      return pc_errf(e, PC_EEMBREE, "%s: this Embree build has no sphere geometry", s->path);
    g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    float *v = g ? rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 16, 1) : NULL;
    if (!v) goto fail;
    v[0] = sh->center.x; v[1] = sh->center.y; v[2] = sh->center.z; v[3] = sh->radius;
  } else if (sh->kind == PC_SHAPE_CYLINDER) {
    g = pc_cylinder_geometry(dev, sh);
    if (!g) goto fail;
  } else {
    const pc_mesh *m = &sh->mesh;
    g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) goto fail;
    if (!set_buffer(g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, m->p, m->nverts) ||
        !set_buffer(g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3, m->idx, m->ntris) || ee->failed)
      goto fail;
  }
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(rtc_scene, g, (unsigned)i);
  rtcReleaseGeometry(g);
  if (ee->failed) return pc_errf(e, PC_EEMBREE, "%s: shape %d: %s", s->path, i, ee->msg);
  return PC_OK;
fail:
  if (g) rtcReleaseGeometry(g);
  return pc_errf(e, PC_EEMBREE, "%s: shape %d: %s", s->path, i, ee->failed ? ee->msg : "cannot create geometry");
}

int pc_scene_commit(const pc_scene *s, void *rtc_scene, pc_err *e) {
  const embree_error *ee = s->rtc_error;
  rtcCommitScene(rtc_scene);
  return ee->failed ? pc_errf(e, PC_EEMBREE, "%s: %s", s->path, ee->msg) : PC_OK;
}

/* The bounding sphere of the box lo..hi of the still shapes, grown to hold the animated ones
 * at every time (light paths from the environment start outside it). */
static void set_bounding_sphere(pc_scene *s, vec3 lo, vec3 hi) {
  pc_scene_motion_bounds(s, &lo, &hi);
  s->scene_center = v3_scale(v3_add(lo, hi), 0.5f);
  s->scene_radius = 0.5f * v3_len(v3_sub(hi, lo));
}

/* A triangle's hit record, in parts: the texture coordinates at barycentrics (b0, b1, b2) (the
 * barycentrics themselves without any) ... */
static inline vec2 interpolated_uv(const pc_mesh *m, const uint32_t *ix, float b0, float b1, float b2) {
  if (!m->uv) return (vec2){b1, b2};
  vec2 t0 = m->uv[ix[0]], t1 = m->uv[ix[1]], t2 = m->uv[ix[2]];
  return (vec2){b0 * t0.x + b1 * t1.x + b2 * t2.x, b0 * t0.y + b1 * t1.y + b2 * t2.y};
}

/* ... the interpolated shading normal (ng where it vanishes), with *ng turned to its side:
 * Mitsuba's front side is the shading normal's side (one-sided BSDFs and emitters test the
 * shading frame) ... */
static inline vec3 interpolated_normal(const pc_mesh *m, const uint32_t *ix, float b0, float b1, float b2, vec3 *ng) {
  vec3 ns = v3_add(v3_add(v3_scale(m->n[ix[0]], b0), v3_scale(m->n[ix[1]], b1)), v3_scale(m->n[ix[2]], b2));
  float l = v3_len(ns);
  if (!(l > 0.f && isfinite(l))) return *ng;
  ns = v3_scale(ns, 1.f / l);
  if (v3_dot(ns, *ng) < 0.f) *ng = v3_neg(*ng);
  return ns;
}

/* ... and dp/du, dp/dv: Mitsuba's computeUVTangents, solving the edges for them; the edges
 * themselves without texture coordinates. Returns false where the texture coordinates are
 * degenerate: the tangents are then an arbitrary pair of the plane, frame_from_normal(ng),
 * which depends on the side ng was turned to. */
static inline bool uv_tangents(const pc_mesh *m, const uint32_t *ix, vec3 p0, vec3 p1, vec3 p2, vec3 ng, vec3 *dpdu,
                               vec3 *dpdv) {
  vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0);
  *dpdu = e1;
  *dpdv = e2;
  if (!m->uv) return true;
  vec2 t0 = m->uv[ix[0]], t1 = m->uv[ix[1]], t2 = m->uv[ix[2]];
  float du1 = t1.x - t0.x, dv1 = t1.y - t0.y, du2 = t2.x - t0.x, dv2 = t2.y - t0.y;
  float det = du1 * dv2 - dv1 * du2;
  if (det != 0.f && isfinite(det)) {
    float inv = 1.f / det;
    *dpdu = v3_scale(v3_sub(v3_scale(e1, dv2), v3_scale(e2, dv1)), inv);
    *dpdv = v3_scale(v3_sub(v3_scale(e2, du1), v3_scale(e1, du2)), inv);
    return true;
  }
  frame f = frame_from_normal(ng);
  *dpdu = f.s;
  *dpdv = f.t;
  return false;
}

/* Mesh shape sh's pc_tri_consts, the same values fill_hit would take at each hit. A mesh with
 * shading normals keeps no frame (its normal varies over the triangle): f.s.x = 1 there marks
 * degenerate texture coordinates, whose tangents the hit takes from the side ng turns to. */
static void fill_tri_consts(const pc_shape *sh, pc_tri_consts *tri) {
  const pc_mesh *m = &sh->mesh;
  for (uint32_t t = 0; t < m->ntris; t++) {
    const uint32_t *ix = m->idx + 3 * (size_t)t;
    vec3 p0 = m->p[ix[0]], p1 = m->p[ix[1]], p2 = m->p[ix[2]];
    pc_tri_consts *c = &tri[t];
    vec3 ng = v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
    bool solved = uv_tangents(m, ix, p0, p1, p2, ng, &c->dpdu, &c->dpdv);
    if (m->n) {
      c->f = (frame){v3(solved ? 0.f : 1.f, 0.f, 0.f), v3s(0.f), ng};
    } else {
      pc_shading_frame(&c->f, ng, c->dpdu);
    }
    c->vmax = pc_triangle_vmax(p0, p1, p2);
  }
}

/* The still meshes' pc_tri_consts, while their total stays within PC_TRI_CONSTS_MAX_BYTES
 * (the rest compute theirs at each hit, as the moving ones do). */
static int build_tri_consts(pc_scene *s, pc_err *e) {
  bool *moves = calloc((size_t)s->nshapes, sizeof *moves);
  if (!moves) return pc_errf(e, PC_ENOMEM, "%s: out of memory", s->path);
  for (int i = 0; i < s->nmotions; i++)
    if (s->motions[i].shape >= 0 && s->motions[i].shape < s->nshapes) moves[s->motions[i].shape] = true;
  size_t total = 0;
  int rc = PC_OK;
  for (int i = 0; i < s->nshapes && rc == PC_OK; i++) {
    pc_shape *sh = &s->shapes[i];
    free(sh->tri);
    sh->tri = NULL;
    if (sh->kind != PC_SHAPE_MESH || sh->mesh.ntris == 0 || moves[i]) continue;
    size_t bytes = (size_t)sh->mesh.ntris * sizeof *sh->tri;
    if (bytes > PC_TRI_CONSTS_MAX_BYTES - total) continue;
    sh->tri = pc_big_alloc(bytes);
    if (!sh->tri) rc = pc_errf(e, PC_ENOMEM, "%s: out of memory for shape %d's triangle data (%zu bytes)", s->path, i, bytes);
    else fill_tri_consts(sh, sh->tri);
    total += bytes;
  }
  free(moves);
  return rc;
}

static int build_embree(pc_scene *s, embree_error *ee, enum RTCBuildQuality quality, pc_err *e) {
  RTCDevice dev = rtcNewDevice("verbose=0");
  if (!dev) return pc_errf(e, PC_EEMBREE, "%s: cannot create an Embree device (error %d)", s->path, (int)rtcGetDeviceError(NULL));
  s->rtc_device = dev;
  rtcSetDeviceErrorFunction(dev, on_embree_error, ee);
  RTCScene scn = rtcNewScene(dev);
  if (!scn) return pc_errf(e, PC_EEMBREE, "%s: cannot create an Embree scene: %s", s->path, ee->msg);
  s->rtc_scene = scn;
  rtcSetSceneFlags(scn, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scn, quality);
  int rc = PC_OK;
  for (int i = 0; i < s->nshapes && rc == PC_OK; i++) rc = pc_scene_attach_shape(s, scn, i, e);
  if (rc == PC_OK) rc = pc_scene_commit(s, scn, e);
  if (rc != PC_OK) return rc;
  struct RTCBounds b;
  rtcGetSceneBounds(scn, &b);
  set_bounding_sphere(s, v3(b.lower_x, b.lower_y, b.lower_z), v3(b.upper_x, b.upper_y, b.upper_z));
  return PC_OK;
}

/* What pc_scene_build and pc_scene_check share: the scene's own checks, the sensor and the
 * shapes placed at shutter_open, and the materials' derived data. */
static int prepare(pc_scene *s, pc_err *e) {
  if (s->nshapes == 0) return pc_errf(e, PC_EINVAL, "%s: the scene has no shapes", s->path);
  if (s->camera.width < 1 || s->camera.height < 1)
    return pc_errf(e, PC_EINVAL, "%s: the scene has no sensor with a film", s->path);
  int rc = pc_scene_place(s, s->shutter_open, e);
  if (rc != PC_OK) return rc;
  pc_camera_prepare(&s->camera);
  if (!(s->camera.image_area > 0.f) || !isfinite(s->camera.image_area))
    return pc_errf(e, PC_EINVAL, "%s: camera field of view %.3g is out of range", s->path, s->camera.fov_deg);
  for (int i = 0; i < s->nmaterials; i++) {
    pc_material *m = &s->materials[i];
    /* Derived quantities (plastic's lobe choice) use a slot's constant; for a textured slot
     * that is the texture's average, as Mitsuba's getAverage(). */
    pc_tex_slot *slots[] = {&m->reflectance, &m->specular, &m->transmittance, &m->sigma_a};
    /* A wrapper's material comes before it (so wrapping cannot loop), and is prepared first. */
    bool wraps = m->type == PC_MAT_BUMPMAP || m->type == PC_MAT_COATING || m->type == PC_MAT_ROUGHCOATING ||
                 m->type == PC_MAT_MASK;
    bool mixes = m->type == PC_MAT_BLEND || m->type == PC_MAT_MIXTURE;
    if (mixes && !(m->nmix >= 1 && m->nmix <= PC_MIX_MAX))
      return pc_errf(e, PC_EINVAL, "%s: material %d mixes %d materials", s->path, i, m->nmix);
    for (int k = 0; k < (mixes ? m->nmix : 0); k++) {
      if (!(m->mix_nested[k] >= 0 && m->mix_nested[k] < i))
        return pc_errf(e, PC_EINVAL, "%s: material %d mixes material %d", s->path, i, m->mix_nested[k]);
      m->mix[k] = &s->materials[m->mix_nested[k]];
    }
    if ((m->type == PC_MAT_MASK || m->type == PC_MAT_BLEND) && m->weight.tex >= s->ntextures)
      return pc_errf(e, PC_EINVAL, "%s: material %d refers to texture %d of %d", s->path, i, m->weight.tex, s->ntextures);
    if (wraps && !(m->nested >= 0 && m->nested < i))
      return pc_errf(e, PC_EINVAL, "%s: material %d wraps material %d", s->path, i, m->nested);
    if (m->type == PC_MAT_BUMPMAP && !(m->bump_tex >= 0 && m->bump_tex < s->ntextures))
      return pc_errf(e, PC_EINVAL, "%s: material %d refers to texture %d of %d", s->path, i, m->bump_tex, s->ntextures);
    m->inner = wraps ? &s->materials[m->nested] : NULL;
    bool coating = m->type == PC_MAT_COATING || m->type == PC_MAT_ROUGHCOATING;
    for (int k = 0; k < (coating ? 4 : 3); k++) {
      if (slots[k]->tex >= s->ntextures)
        return pc_errf(e, PC_EINVAL, "%s: material %d refers to texture %d of %d", s->path, i, slots[k]->tex, s->ntextures);
      if (slots[k]->tex >= 0) slots[k]->value = pc_texture_average(&s->textures[slots[k]->tex]);
    }
    pc_material_prepare(m);
  }
  return PC_OK;
}

void pc_shape_grow_bounds(const pc_shape *sh, vec3 *lo, vec3 *hi) {
  if (sh->kind == PC_SHAPE_SPHERE) {
    *lo = v3_min(*lo, v3_sub(sh->center, v3s(sh->radius)));
    *hi = v3_max(*hi, v3_add(sh->center, v3s(sh->radius)));
  } else if (sh->kind == PC_SHAPE_CYLINDER) {
    vec3 a, b;
    pc_cylinder_bounds(sh, &a, &b);
    *lo = v3_min(*lo, a);
    *hi = v3_max(*hi, b);
  } else {
    for (uint32_t v = 0; v < sh->mesh.nverts; v++) {
      *lo = v3_min(*lo, sh->mesh.p[v]);
      *hi = v3_max(*hi, sh->mesh.p[v]);
    }
  }
}

/* The bounding sphere from the shapes' own data (pc_scene_check: no Embree scene to ask). */
static void bounds_from_shapes(pc_scene *s) {
  vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
  for (int i = 0; i < s->nshapes; i++) pc_shape_grow_bounds(&s->shapes[i], &lo, &hi);
  set_bounding_sphere(s, lo, hi);
}

int pc_scene_check(pc_scene *s, pc_err *e) {
  int rc = prepare(s, e);
  if (rc != PC_OK) return rc;
  bounds_from_shapes(s);
  return build_lights(s, e);
}

int pc_scene_build(pc_scene *s, pc_err *e) {
  int rc = prepare(s, e);
  if (rc != PC_OK) return rc;
  /* Embree calls the error function with this address for the device's lifetime; it lives in
   * the scene so it outlives every call. */
  embree_error *ee = calloc(1, sizeof *ee);
  if (!ee) return pc_errf(e, PC_ENOMEM, "%s: out of memory", s->path);
  s->rtc_error = ee;
  rc = build_embree(s, ee, RTC_BUILD_QUALITY_HIGH, e);
  if (rc == PC_OK) rc = build_tri_consts(s, e);
  /* After the geometry: the environment's light paths need the bounding sphere. */
  return rc != PC_OK ? rc : build_lights(s, e);
}

static void release_embree(pc_scene *s) {
  if (s->rtc_scene) rtcReleaseScene(s->rtc_scene);
  if (s->rtc_device) rtcReleaseDevice(s->rtc_device);
  free(s->rtc_error);
  s->rtc_scene = s->rtc_device = s->rtc_error = NULL;
}

int pc_scene_probe_backs(pc_scene *s, int grid, pc_scene_backs *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  if (s->rtc_scene) return pc_errf(e, PC_EINVAL, "%s: the scene is built already", s->path);
  if (grid < 1 || grid > 1024) return pc_errf(e, PC_EINVAL, "%s: a probe grid of %d rays a side", s->path, grid);
  if (s->nshapes < 1) return PC_OK;
  int *hits = calloc((size_t)s->nshapes, sizeof *hits);
  embree_error *ee = calloc(1, sizeof *ee);
  if (!hits || !ee) {
    free(hits);
    free(ee);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory", s->path);
  }
  s->rtc_error = ee;
  /* the quickest build Embree has: the probe traces a few thousand rays */
  int rc = build_embree(s, ee, RTC_BUILD_QUALITY_LOW, e);
  const pc_camera *cam = &s->camera;
  for (int gy = 0; gy < grid && rc == PC_OK; gy++)
    for (int gx = 0; gx < grid; gx++) {
      vec3 d = pc_camera_ray_dir(cam, (gx + 0.5f) * (float)cam->width / (float)grid, (gy + 0.5f) * (float)cam->height / (float)grid);
      pc_hit h;
      out->rays++;
      if (!pc_scene_intersect(s, cam->pos, d, INFINITY, &h)) continue;
      float depth = v3_dot(v3_sub(h.p, cam->pos), cam->dir);
      out->nearer += depth < cam->near_clip;
      out->farther += depth > cam->far_clip;
      int m = s->shapes[h.shape].material;
      if (v3_dot(d, h.ns) < 0.f || pc_material_shows_behind(s->materials, s->nmaterials, m)) continue;
      out->backs++;
      hits[h.shape]++;
    }
  release_embree(s);
  /* the most hit shapes, in order */
  for (int k = 0; k < PC_SCENE_BACKS_NAMED && rc == PC_OK; k++) {
    int best = -1;
    for (int i = 0; i < s->nshapes; i++)
      if (hits[i] > 0 && (best < 0 || hits[i] > hits[best])) best = i;
    if (best < 0) break;
    out->shape[k] = best;
    out->count[k] = hits[best];
    out->nshapes = k + 1;
    hits[best] = 0;
  }
  free(hits);
  return rc;
}

void pc_scene_free(pc_scene *s) {
  release_embree(s);
  for (int i = 0; i < s->nshapes; i++) {
    pc_mesh_free(&s->shapes[i].mesh);
    free(s->shapes[i].tri);
  }
  for (int i = 0; i < s->ntextures; i++) pc_texture_free(&s->textures[i]);
  for (int i = 0; i < s->nlights; i++) {
    free(s->lights[i].tri_cdf);
    free(s->lights[i].tri_n);
    pc_light_free(&s->lights[i]);
  }
  for (int i = 0; i < s->nmotions; i++) {
    pc_anim_free(&s->motions[i].anim);
    pc_mesh_free(&s->motions[i].object.mesh);
  }
  free(s->motions);
  pc_anim_free(&s->camera_anim);
  free(s->shapes);
  free(s->materials);
  free(s->textures);
  free(s->lights);
  free(s->light_cdf);
  free(s->path);
  for (int i = 0; i < s->nfiles; i++) {
    free(s->files[i]);
    free(s->file_names[i]);
  }
  free(s->files);
  free(s->file_names);
  free(s->root);
  for (int i = 0; i < s->nxml_includes; i++) free(s->xml_includes[i]);
  free(s->xml_includes);
  memset(s, 0, sizeof *s);
}

static inline void fill_hit(const pc_scene *s, const struct RTCRayHit *rh, vec3 o, vec3 d, pc_hit *hit) {
  int shape = (int)rh->hit.geomID;
  const pc_shape *sh = &s->shapes[shape];
  hit->t = rh->ray.tfar;
  hit->shape = shape;
  hit->prim = (int)rh->hit.primID;
  hit->p = v3_madd(o, d, rh->ray.tfar);
  if (sh->kind == PC_SHAPE_SPHERE) {
    vec3 n = v3_norm(v3_sub(hit->p, sh->center));
    /* Re-project onto the surface: the parametric hit point drifts with distance. */
    hit->p = v3_madd(sh->center, n, sh->radius);
    float phi = atan2f(n.y, n.x);
    if (phi < 0.f) phi += 2.f * PC_PI;
    float theta = acosf(fminf(1.f, fmaxf(-1.f, n.z)));
    hit->uv = (vec2){phi * (0.5f * PC_INV_PI), theta * PC_INV_PI};
    /* Mitsuba's sphere: p(u, v) = r (sin v pi cos u 2pi, sin v pi sin u 2pi, cos v pi). */
    vec3 l = v3_scale(n, sh->radius);
    hit->dpdu = v3(-l.y * 2.f * PC_PI, l.x * 2.f * PC_PI, 0.f);
    hit->dpdv = v3_scale(v3(l.z * cosf(phi), l.z * sinf(phi), -sh->radius * sinf(theta)), PC_PI);
    if (sh->flip_normals) n = v3_neg(n);
    hit->ng = hit->ns = n;
    hit->eps = pc_sphere_eps(sh->center, sh->radius, hit->p);
    return;
  }
  if (sh->kind == PC_SHAPE_CYLINDER) {
    pc_cylinder_hit(sh, hit->p, hit);
    return;
  }
  const pc_mesh *m = &sh->mesh;
  const uint32_t *ix = m->idx + 3 * (size_t)rh->hit.primID;
  float b1 = rh->hit.u, b2 = rh->hit.v, b0 = 1.f - b1 - b2;
  vec3 p0 = m->p[ix[0]], p1 = m->p[ix[1]], p2 = m->p[ix[2]];
  hit->p = v3_add(v3_add(v3_scale(p0, b0), v3_scale(p1, b1)), v3_scale(p2, b2));
  if (sh->tri) {
    const pc_tri_consts *tc = &sh->tri[rh->hit.primID];
    hit->eps = pc_triangle_eps_vmax(hit->p, tc->vmax);
    hit->uv = interpolated_uv(m, ix, b0, b1, b2);
    vec3 ng = tc->f.n;
    hit->dpdu = tc->dpdu;
    hit->dpdv = tc->dpdv;
    if (!m->n) {
      hit->ng = hit->ns = ng;
      return;
    }
    hit->ns = interpolated_normal(m, ix, b0, b1, b2, &ng);
    hit->ng = ng;
    if (tc->f.s.x != 0.f) {
      frame f = frame_from_normal(ng); /* degenerate texture coordinates: the tangents of this side */
      hit->dpdu = f.s;
      hit->dpdv = f.t;
    }
    return;
  }
  hit->eps = pc_triangle_eps(hit->p, p0, p1, p2);
  vec3 ng = v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
  hit->uv = interpolated_uv(m, ix, b0, b1, b2);
  hit->ns = m->n ? interpolated_normal(m, ix, b0, b1, b2, &ng) : ng;
  hit->ng = ng;
  uv_tangents(m, ix, p0, p1, p2, ng, &hit->dpdu, &hit->dpdv);
}

bool pc_scene_intersect(const pc_scene *s, vec3 o, vec3 d, float tmax, pc_hit *hit) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRayHit rh;
  rh.ray.org_x = o.x; rh.ray.org_y = o.y; rh.ray.org_z = o.z;
  rh.ray.dir_x = d.x; rh.ray.dir_y = d.y; rh.ray.dir_z = d.z;
  rh.ray.tnear = 0.f;
  rh.ray.tfar = tmax;
  rh.ray.time = 0.f;
  rh.ray.mask = 0xffffffffu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  if (s->ray_hook) s->ray_hook(s->ray_hook_user, false, o, d, tmax);
  rtcIntersect1((RTCScene)s->rtc_scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  fill_hit(s, &rh, o, d, hit);
  return true;
}

/* Whether nothing blocks the segment o + t d, t in [0, tfar). */
static bool unoccluded(const pc_scene *s, vec3 o, vec3 d, float tfar) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRay r;
  r.org_x = o.x; r.org_y = o.y; r.org_z = o.z;
  r.dir_x = d.x; r.dir_y = d.y; r.dir_z = d.z;
  r.tnear = 0.f;
  r.tfar = tfar;
  r.time = 0.f;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
  if (s->ray_hook) s->ray_hook(s->ray_hook_user, true, o, d, tfar);
  rtcOccluded1((RTCScene)s->rtc_scene, &ctx, &r);
  return r.tfar >= 0.f;
}

bool pc_scene_escapes(const pc_scene *s, vec3 p, vec3 ng, float eps, vec3 d) {
  return unoccluded(s, v3_is_zero(ng) ? p : pc_offset_by(p, ng, d, eps), d, INFINITY);
}

bool pc_scene_visible(const pc_scene *s, vec3 a, vec3 na, float ea, vec3 b, vec3 nb, float eb) {
  vec3 ab = v3_sub(b, a);
  vec3 o = v3_is_zero(na) ? a : pc_offset_by(a, na, ab, ea);
  vec3 t = v3_is_zero(nb) ? b : pc_offset_by(b, nb, v3_neg(ab), eb);
  /* Both ends are already off their surfaces; the segment stops 2^-20 of its length short of
   * t on top, so that with eb the margin is at least 8 ulps of the larger end's coordinates
   * (the far end of a long segment, or the near end of a short one). It stopped 1e-4 short,
   * which on a 10 m segment hid an occluder within a millimetre of the light. */
  return unoccluded(s, o, v3_sub(t, o), 1.f - 0x1p-20f);
}
