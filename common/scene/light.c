/* light.c: sampling and evaluation of area, point and spot emitters, and the power-proportional
 * choice among them (see light.h). */
#include "light.h"

#include <stdlib.h>

#include "scene.h"
#include "shape_cylinder.h"

int pc_cdf_find(const float *cdf, int n, float u) {
  int lo = 0, hi = n - 1;
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (cdf[mid + 1] > u) hi = mid;
    else lo = mid + 1;
  }
  while (lo > 0 && cdf[lo + 1] == cdf[lo]) lo--;
  return lo;
}

int pc_light_choose(const pc_scene *s, float u, float *pdf) {
  int n = s->nlights;
  float total = s->light_cdf[n];
  int i = pc_cdf_find(s->light_cdf, n, u * total);
  *pdf = (s->light_cdf[i + 1] - s->light_cdf[i]) / total;
  return i;
}

float pc_light_choose_pdf(const pc_scene *s, int light) {
  return (s->light_cdf[light + 1] - s->light_cdf[light]) / s->light_cdf[s->nlights];
}

void pc_light_sample_point(const pc_scene *s, const pc_light *l, float u0, float u1, float u2,
                           pc_light_point *out) {
  if (pc_light_is_delta_pos(l)) {
    out->p = l->position;
    out->n = v3s(0.f);
    out->pdf_area = 1.f;
    out->eps = pc_point_eps(out->p);
    return;
  }
  const pc_shape *sh = &s->shapes[l->shape];
  out->pdf_area = 1.f / l->area;
  if (sh->kind == PC_SHAPE_SPHERE) {
    float z = 1.f - 2.f * u1;
    float r = sqrtf(fmaxf(0.f, 1.f - z * z));
    float phi = 2.f * PC_PI * u2;
    vec3 d = v3(r * cosf(phi), r * sinf(phi), z);
    out->p = v3_madd(sh->center, d, sh->radius);
    out->n = sh->flip_normals ? v3_neg(d) : d;
    out->eps = pc_sphere_eps(sh->center, sh->radius, out->p);
    return;
  }
  if (sh->kind == PC_SHAPE_CYLINDER) {
    pc_cylinder_sample(sh, u1, u2, &out->p, &out->n);
    out->eps = pc_cylinder_eps(sh, out->p);
    return;
  }
  float target = u0 * l->tri_cdf[l->ntris];
  int t = pc_cdf_find(l->tri_cdf, (int)l->ntris, target);
  const pc_mesh *m = &sh->mesh;
  const uint32_t *ix = m->idx + 3 * (size_t)t;
  vec3 p0 = m->p[ix[0]], p1 = m->p[ix[1]], p2 = m->p[ix[2]];
  float su = sqrtf(u1);
  float b0 = 1.f - su, b1 = u2 * su;
  out->p = v3_add(v3_add(v3_scale(p0, b0), v3_scale(p1, b1)), v3_scale(p2, 1.f - b0 - b1));
  out->n = l->tri_n[t];
  out->eps = sh->tri ? pc_triangle_eps_vmax(out->p, sh->tri[t].vmax) : pc_triangle_eps(out->p, p0, p1, p2);
}

vec3 pc_light_profile(const pc_light *l, vec3 w) {
  return l->type == PC_LIGHT_SPOT ? pc_spot_falloff(l, w) : v3s(1.f);
}

vec3 pc_light_le(const pc_light *l, vec3 n, vec3 w) {
  if (pc_light_is_delta_pos(l)) return v3_mul(l->intensity, pc_light_profile(l, w));
  return v3_dot(n, w) > 0.f ? l->radiance : v3s(0.f);
}

vec3 pc_light_sample_dir(const pc_light *l, vec3 n, float u0, float u1, float *pdf_dir) {
  if (l->type == PC_LIGHT_SPOT) return pc_spot_sample_dir(l, u0, u1, pdf_dir);
  if (l->type == PC_LIGHT_POINT) {
    float z = 1.f - 2.f * u0;
    float r = sqrtf(fmaxf(0.f, 1.f - z * z));
    float phi = 2.f * PC_PI * u1;
    *pdf_dir = 0.25f * PC_INV_PI;
    return v3(r * cosf(phi), r * sinf(phi), z);
  }
  float r = sqrtf(u0), phi = 2.f * PC_PI * u1;
  float x = r * cosf(phi), y = r * sinf(phi), z = sqrtf(fmaxf(0.f, 1.f - u0));
  frame f = frame_from_normal(n);
  *pdf_dir = z * PC_INV_PI;
  return frame_to_world(&f, v3(x, y, z));
}

float pc_light_pdf_dir(const pc_light *l, vec3 n, vec3 w) {
  if (l->type == PC_LIGHT_POINT) return 0.25f * PC_INV_PI;
  if (l->type == PC_LIGHT_SPOT) return pc_spot_pdf_dir(l, w);
  float c = v3_dot(n, w);
  return c > 0.f ? c * PC_INV_PI : 0.f;
}

void pc_light_free(pc_light *l) {
  pc_env_free(l);
  if (l->spot_tex) pc_texture_free(l->spot_tex);
  free(l->spot_tex);
  l->spot_tex = NULL;
}
