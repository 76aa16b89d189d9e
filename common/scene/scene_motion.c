/* scene_motion.c: motion blur. Each iteration renders the whole scene at one time drawn
 * uniformly in the shutter, so every strategy of the iteration (and PCBPT's stored light paths
 * and records) sees one consistent scene, and the average over iterations integrates over the
 * shutter as Mitsuba does per sample: each iteration stays an unbiased estimate of the blurred
 * image. A renderer owns a view whose animated shapes and sensor it moves to its iteration's
 * time; static shapes are shared (an Embree geometry may belong to several scenes). */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"
#include "scene.h"
#include "scene_embree.h"
#include "shape_cylinder.h"

bool pc_scene_moves(const pc_scene *s) {
  return (s->nmotions > 0 || s->camera_anim.n > 0) && s->shutter_close > s->shutter_open;
}

float pc_scene_time(const pc_scene *s, uint64_t seed, uint64_t iteration) {
  if (!pc_scene_moves(s)) return s->shutter_open;
  pc_rng r = pc_rng_make(seed, iteration, PC_STREAM_TIME, 0);
  return s->shutter_open + (s->shutter_close - s->shutter_open) * pc_rng_f(&r);
}

static void place_shape(pc_shape *dst, const pc_motion *mo, double time) {
  mat4 m = pc_anim_eval(&mo->anim, time);
  const pc_shape *o = &mo->object;
  if (o->kind == PC_SHAPE_SPHERE) {
    /* the loader refused a motion that does not scale uniformly */
    dst->center = mat4_point(&m, o->center);
    dst->radius = o->radius * v3_len(mat4_vector(&m, v3(1, 0, 0)));
    return;
  }
  if (o->kind == PC_SHAPE_CYLINDER) {
    /* the same check: a uniform scale keeps it circular, so this cannot fail */
    pc_shape moved = *o;
    if (!pc_cylinder_transform(&moved, &m)) {
      dst->center = moved.center, dst->cyl_axes = moved.cyl_axes;
      dst->radius = moved.radius, dst->length = moved.length;
    }
    return;
  }
  pc_mesh *w = &dst->mesh;
  memcpy(w->p, o->mesh.p, sizeof(vec3) * o->mesh.nverts);
  if (o->mesh.n) memcpy(w->n, o->mesh.n, sizeof(vec3) * o->mesh.nverts);
  memcpy(w->idx, o->mesh.idx, sizeof(uint32_t) * 3 * (size_t)o->mesh.ntris);
  pc_mesh_transform(w, &m);
}

int pc_scene_place(pc_scene *s, float time, pc_err *e) {
  for (int i = 0; i < s->nmotions; i++) {
    const pc_motion *mo = &s->motions[i];
    if (mo->shape < 0 || mo->shape >= s->nshapes || s->shapes[mo->shape].kind != mo->object.kind)
      return pc_errf(e, PC_EINVAL, "%s: animation %d moves no shape of its kind", s->path, i);
    place_shape(&s->shapes[mo->shape], mo, time);
  }
  if (s->camera_anim.n) {
    s->camera.to_world = pc_anim_eval(&s->camera_anim, time);
    pc_camera_prepare(&s->camera);
  }
  return PC_OK;
}

void pc_scene_motion_bounds(const pc_scene *s, vec3 *lo, vec3 *hi) {
  /* Between keyframes the translation moves on a segment and the stretch stays within its
   * largest keyframe value, so every point lies within max|scale| * |x| of a box holding the
   * keyframes' translations. */
  for (int i = 0; i < s->nmotions; i++) {
    const pc_motion *mo = &s->motions[i];
    float r = 0.f;
    if (mo->object.kind == PC_SHAPE_SPHERE) {
      r = v3_len(mo->object.center) + mo->object.radius;
    } else if (mo->object.kind == PC_SHAPE_CYLINDER) {
      r = v3_len(mo->object.center) + mo->object.length + mo->object.radius;
    } else {
      for (uint32_t v = 0; v < mo->object.mesh.nverts; v++) r = fmaxf(r, v3_len(mo->object.mesh.p[v]));
    }
    r *= (float)pc_anim_max_scale(&mo->anim) * 1.0001f;
    for (int k = 0; k < mo->anim.n; k++) {
      const double *t = mo->anim.k[k].t;
      *lo = v3_min(*lo, v3((float)t[0] - r, (float)t[1] - r, (float)t[2] - r));
      *hi = v3_max(*hi, v3((float)t[0] + r, (float)t[1] + r, (float)t[2] + r));
    }
  }
}

int pc_scene_view_create(const pc_scene *s, pc_scene **out, pc_err *e) {
  pc_scene *v = calloc(1, sizeof *v);
  pc_shape *shapes = malloc(sizeof *shapes * (size_t)s->nshapes);
  if (!v || !shapes) {
    free(v);
    free(shapes);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory for a moving view", s->path);
  }
  *v = *s;
  memcpy(shapes, s->shapes, sizeof *shapes * (size_t)s->nshapes);
  v->shapes = shapes;
  v->rtc_scene = NULL;
  int rc = PC_OK;
  /* the animated meshes are the view's own; everything else stays the scene's */
  for (int i = 0; i < s->nmotions; i++) shapes[s->motions[i].shape].mesh = (pc_mesh){0};
  for (int i = 0; i < s->nmotions && rc == PC_OK; i++) {
    int k = s->motions[i].shape;
    if (s->shapes[k].kind == PC_SHAPE_MESH && pc_mesh_copy(&s->shapes[k].mesh, &shapes[k].mesh) != 0)
      rc = pc_errf(e, PC_ENOMEM, "%s: out of memory for a moving view", s->path);
  }
  if (rc == PC_OK && s->nmotions == 0) {
    /* only the sensor moves: the scene's geometry serves as it is */
    rtcRetainScene(s->rtc_scene);
    v->rtc_scene = s->rtc_scene;
  } else if (rc == PC_OK) {
    /* every shape starts as the scene's geometry; pc_scene_view_set_time replaces the moving
     * ones, so only they are rebuilt per iteration */
    RTCScene scn = rtcNewScene(s->rtc_device);
    v->rtc_scene = scn;
    if (!scn) rc = pc_errf(e, PC_EEMBREE, "%s: cannot create an Embree scene for a moving view", s->path);
    if (scn) {
      rtcSetSceneFlags(scn, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC);
      rtcSetSceneBuildQuality(scn, RTC_BUILD_QUALITY_LOW);
    }
    for (int i = 0; rc == PC_OK && i < s->nshapes; i++) {
      RTCGeometry g = rtcGetGeometry(s->rtc_scene, (unsigned)i);
      if (!g) rc = pc_errf(e, PC_EEMBREE, "%s: shape %d has no Embree geometry", s->path, i);
      else rtcAttachGeometryByID(scn, g, (unsigned)i);
    }
    if (rc == PC_OK) rc = pc_scene_commit(v, scn, e);
  }
  if (rc != PC_OK) {
    pc_scene_view_destroy(v);
    return rc;
  }
  *out = v;
  return PC_OK;
}

int pc_scene_view_set_time(pc_scene *v, float time, pc_err *e) {
  int rc = pc_scene_place(v, time, e);
  if (rc != PC_OK || v->nmotions == 0) return rc;
  for (int i = 0; i < v->nmotions && rc == PC_OK; i++) {
    unsigned id = (unsigned)v->motions[i].shape;
    rtcDetachGeometry(v->rtc_scene, id);
    rc = pc_scene_attach_shape(v, v->rtc_scene, (int)id, e);
  }
  return rc == PC_OK ? pc_scene_commit(v, v->rtc_scene, e) : rc;
}

void pc_scene_view_destroy(pc_scene *v) {
  if (!v) return;
  if (v->rtc_scene) rtcReleaseScene(v->rtc_scene);
  for (int i = 0; v->shapes && i < v->nmotions; i++) pc_mesh_free(&v->shapes[v->motions[i].shape].mesh);
  free(v->shapes);
  free(v);
}
