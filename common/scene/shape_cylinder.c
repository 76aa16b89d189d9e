/* shape_cylinder.c: Mitsuba 0.6's `cylinder` (see shape_cylinder.h): placement, the quadric's
 * intersection as an Embree user geometry, hit records and area sampling. */
#include "shape_cylinder.h"

#include <embree3/rtcore.h>
#include <math.h>

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* The linear part of xf applied to v, in double. */
static void xf_vector(const mat4 *xf, vec3 v, double out[3]) {
  for (int r = 0; r < 3; r++) out[r] = xf->m[r][0] * v.x + xf->m[r][1] * v.y + xf->m[r][2] * v.z;
}

const char *pc_cylinder_transform(pc_shape *sh, const mat4 *xf) {
  double wx[3], wy[3], wz[3];
  xf_vector(xf, v3_scale(sh->cyl_axes.s, sh->radius), wx);
  xf_vector(xf, v3_scale(sh->cyl_axes.t, sh->radius), wy);
  xf_vector(xf, v3_scale(sh->cyl_axes.n, sh->length), wz);
  double rx = dot3(wx, wx), ry = dot3(wy, wy), lz = dot3(wz, wz);
  if (!(rx > 0) || !(lz > 0) || !isfinite(rx) || !isfinite(ry) || !isfinite(lz))
    return "toWorld makes the cylinder degenerate or infinite";
  /* the same tolerance as a sphere's similarity test */
  if (fabs(rx - ry) > 1e-4 * rx || fabs(dot3(wx, wy)) > 1e-4 * rx || fabs(dot3(wx, wz)) > 1e-4 * sqrt(rx * lz) ||
      fabs(dot3(wy, wz)) > 1e-4 * sqrt(rx * lz))
    return "toWorld must keep the cylinder circular (Mitsuba does not permit non-uniform scales across its axis)";
  double r = sqrt(rx), l = sqrt(lz);
  sh->center = mat4_point(xf, sh->center);
  sh->cyl_axes.s = v3((float)(wx[0] / r), (float)(wx[1] / r), (float)(wx[2] / r));
  sh->cyl_axes.t = v3((float)(wy[0] / r), (float)(wy[1] / r), (float)(wy[2] / r));
  sh->cyl_axes.n = v3((float)(wz[0] / l), (float)(wz[1] / l), (float)(wz[2] / l));
  sh->radius = (float)r;
  sh->length = (float)l;
  if (!(sh->radius > 0.f) || !(sh->length > 0.f) || !isfinite(sh->radius) || !isfinite(sh->length) || !v3_is_finite(sh->center))
    return "toWorld makes the cylinder degenerate or infinite";
  return NULL;
}

const char *pc_cylinder_place(pc_shape *sh, vec3 p0, vec3 p1, float radius, const mat4 *xf) {
  vec3 d = v3_sub(p1, p0);
  float len = v3_len(d);
  if (!(radius > 0.f) || !isfinite(radius)) return "radius must be positive and finite";
  if (!(len > 0.f) || !isfinite(len) || !v3_is_finite(p0)) return "p0 and p1 must be distinct finite points";
  sh->kind = PC_SHAPE_CYLINDER;
  sh->center = p0;
  sh->cyl_axes = frame_mitsuba(v3_scale(d, 1.f / len)); /* u = 0 where Mitsuba's is: textures wrap as there */
  sh->radius = radius;
  sh->length = len;
  return pc_cylinder_transform(sh, xf);
}

void pc_cylinder_bounds(const pc_shape *sh, vec3 *lo, vec3 *hi) {
  vec3 x = sh->cyl_axes.s, y = sh->cyl_axes.t;
  vec3 r = v3(sh->radius * sqrtf(x.x * x.x + y.x * y.x), sh->radius * sqrtf(x.y * x.y + y.y * y.y),
              sh->radius * sqrtf(x.z * x.z + y.z * y.z));
  vec3 a = sh->center, b = v3_madd(sh->center, sh->cyl_axes.n, sh->length);
  *lo = v3_sub(v3_min(a, b), r);
  *hi = v3_add(v3_max(a, b), r);
}

float pc_cylinder_area(const pc_shape *sh) { return 2.f * PC_PI * sh->radius * sh->length; }

float pc_cylinder_eps(const pc_shape *sh, vec3 p) {
  return PC_OFFSET_RELATIVE * pc_maxf(v3_maxabs(p), v3_maxabs(sh->center) + sh->length + sh->radius);
}

/* +1 where cross(dpdu, dpdv) points out of the tube, -1 where flipNormals or a mirroring toWorld
 * (axes of the other handedness) turn it in. */
static float normal_sign(const pc_shape *sh) {
  bool mirrored = v3_dot(v3_cross(sh->cyl_axes.s, sh->cyl_axes.t), sh->cyl_axes.n) < 0.f;
  return mirrored != sh->flip_normals ? -1.f : 1.f;
}

void pc_cylinder_hit(const pc_shape *sh, vec3 p, pc_hit *hit) {
  const frame *a = &sh->cyl_axes;
  vec3 l = v3_sub(p, sh->center);
  float lx = v3_dot(l, a->s), ly = v3_dot(l, a->t), lz = v3_dot(l, a->n);
  float rho = sqrtf(lx * lx + ly * ly);
  float cx = rho > 0.f ? lx / rho : 1.f, cy = rho > 0.f ? ly / rho : 0.f;
  vec3 out = v3_add(v3_scale(a->s, cx), v3_scale(a->t, cy));
  /* re-project onto the surface: the ray's parametric point drifts with distance */
  hit->p = v3_madd(v3_madd(sh->center, a->n, lz), out, sh->radius);
  float phi = atan2f(cy, cx);
  if (phi < 0.f) phi += 2.f * PC_PI;
  hit->uv = (vec2){phi * (0.5f * PC_INV_PI), lz / sh->length};
  hit->dpdu = v3_scale(v3_add(v3_scale(a->s, -cy), v3_scale(a->t, cx)), 2.f * PC_PI * sh->radius);
  hit->dpdv = v3_scale(a->n, sh->length);
  hit->ng = hit->ns = v3_scale(out, normal_sign(sh));
  hit->eps = pc_cylinder_eps(sh, hit->p);
}

void pc_cylinder_sample(const pc_shape *sh, float u1, float u2, vec3 *p, vec3 *n) {
  const frame *a = &sh->cyl_axes;
  float phi = 2.f * PC_PI * u2;
  vec3 out = v3_add(v3_scale(a->s, cosf(phi)), v3_scale(a->t, sinf(phi)));
  *p = v3_madd(v3_madd(sh->center, a->n, u1 * sh->length), out, sh->radius);
  *n = v3_scale(out, normal_sign(sh));
}

/* The nearest t in [tnear, tfar] where o + t d meets the tube between its ends, in double as
 * Mitsuba solves it; false if none. Both roots are tried: a ray from inside meets the far one. */
static bool intersect(const pc_shape *sh, const float o[3], const float d[3], float tnear, float tfar, float *t_out) {
  const frame *a = &sh->cyl_axes;
  double rel[3] = {(double)o[0] - sh->center.x, (double)o[1] - sh->center.y, (double)o[2] - sh->center.z};
  double ax[3][3] = {{a->s.x, a->s.y, a->s.z}, {a->t.x, a->t.y, a->t.z}, {a->n.x, a->n.y, a->n.z}};
  double dd[3] = {d[0], d[1], d[2]};
  double ox = dot3(rel, ax[0]), oy = dot3(rel, ax[1]), oz = dot3(rel, ax[2]);
  double dx = dot3(dd, ax[0]), dy = dot3(dd, ax[1]), dz = dot3(dd, ax[2]);
  double A = dx * dx + dy * dy, B = 2 * (dx * ox + dy * oy), C = ox * ox + oy * oy - (double)sh->radius * sh->radius;
  if (!(A > 0)) return false; /* along the axis: never meets the tube's wall */
  double disc = B * B - 4 * A * C;
  if (!(disc >= 0)) return false;
  double q = B < 0 ? -0.5 * (B - sqrt(disc)) : -0.5 * (B + sqrt(disc));
  double t0 = q / A, t1 = q != 0 ? C / q : t0;
  if (t0 > t1) {
    double tmp = t0;
    t0 = t1, t1 = tmp;
  }
  double ts[2] = {t0, t1};
  for (int k = 0; k < 2; k++) {
    double t = ts[k], z = oz + dz * t;
    if (t >= tnear && t <= tfar && z >= 0 && z <= sh->length) {
      *t_out = (float)t;
      return *t_out >= tnear && *t_out <= tfar;
    }
  }
  return false;
}

/* Embree's ray and hit arrays of N lanes (rtcore_ray.h's accessors are C++ only): field k of
 * lane i. */
#define LANE_F(base, N, k, i) (((float *)(base))[(k) * (N) + (i)])
#define LANE_U(base, N, k, i) (((unsigned *)(base))[(k) * (N) + (i)])
enum { RAY_ORG = 0, RAY_TNEAR = 3, RAY_DIR = 4, RAY_TFAR = 8, HIT_NG = 0, HIT_V = 4, HIT_PRIM = 5, HIT_GEOM = 6, HIT_INST = 7 };

static bool lane_intersect(const pc_shape *sh, void *ray, unsigned N, unsigned i, float *t) {
  float o[3], d[3];
  for (int k = 0; k < 3; k++) {
    o[k] = LANE_F(ray, N, RAY_ORG + k, i);
    d[k] = LANE_F(ray, N, RAY_DIR + k, i);
  }
  return intersect(sh, o, d, LANE_F(ray, N, RAY_TNEAR, i), LANE_F(ray, N, RAY_TFAR, i), t);
}

static void on_intersect(const struct RTCIntersectFunctionNArguments *args) {
  const pc_shape *sh = args->geometryUserPtr;
  unsigned N = args->N;
  void *ray = args->rayhit, *hit = (float *)args->rayhit + 12 * N;
  for (unsigned i = 0; i < N; i++) {
    float t;
    if (args->valid[i] != -1 || !lane_intersect(sh, ray, N, i, &t)) continue;
    /* pc_cylinder_hit builds the hit record from t alone; nothing reads Embree's Ng, u, v */
    LANE_F(ray, N, RAY_TFAR, i) = t;
    for (int k = HIT_NG; k <= HIT_V; k++) LANE_F(hit, N, k, i) = 0.f;
    LANE_U(hit, N, HIT_PRIM, i) = args->primID;
    LANE_U(hit, N, HIT_GEOM, i) = args->geomID;
    for (unsigned l2 = 0; l2 < RTC_MAX_INSTANCE_LEVEL_COUNT; l2++) LANE_U(hit, N, HIT_INST + l2, i) = args->context->instID[l2];
  }
}

static void on_occluded(const struct RTCOccludedFunctionNArguments *args) {
  const pc_shape *sh = args->geometryUserPtr;
  for (unsigned i = 0; i < args->N; i++) {
    float t;
    if (args->valid[i] == -1 && lane_intersect(sh, args->ray, args->N, i, &t))
      LANE_F(args->ray, args->N, RAY_TFAR, i) = -INFINITY;
  }
}

static void on_bounds(const struct RTCBoundsFunctionArguments *args) {
  const pc_shape *sh = args->geometryUserPtr;
  vec3 lo, hi;
  pc_cylinder_bounds(sh, &lo, &hi);
  /* a hit computed in double may lie an ulp outside bounds rounded to float */
  float pad = PC_OFFSET_RELATIVE * pc_maxf(v3_maxabs(lo), v3_maxabs(hi));
  struct RTCBounds *b = args->bounds_o;
  b->lower_x = lo.x - pad, b->lower_y = lo.y - pad, b->lower_z = lo.z - pad;
  b->upper_x = hi.x + pad, b->upper_y = hi.y + pad, b->upper_z = hi.z + pad;
}

void *pc_cylinder_geometry(void *device, const pc_shape *sh) {
  RTCGeometry g = rtcNewGeometry((RTCDevice)device, RTC_GEOMETRY_TYPE_USER);
  if (!g) return NULL;
  rtcSetGeometryUserPrimitiveCount(g, 1);
  rtcSetGeometryUserData(g, (void *)sh);
  rtcSetGeometryBoundsFunction(g, on_bounds, NULL);
  rtcSetGeometryIntersectFunction(g, on_intersect);
  rtcSetGeometryOccludedFunction(g, on_occluded);
  return g;
}
