/* mesh.c: the triangle mesh's operations that do not depend on a file format: freeing,
 * transforming to world space, flipping, Mitsuba's smooth normals, validation, and the
 * built-in rectangle, cube and disk shapes. */
#include "mesh.h"

#include "big_alloc.h"

#include <stdlib.h>
#include <string.h>

void pc_mesh_free(pc_mesh *m) {
  if (!m) return;
  free(m->p);
  free(m->n);
  free(m->uv);
  free(m->idx);
  memset(m, 0, sizeof *m);
}

int pc_mesh_copy(const pc_mesh *src, pc_mesh *dst) {
  memset(dst, 0, sizeof *dst);
  dst->nverts = src->nverts;
  dst->ntris = src->ntris;
  size_t nv = src->nverts, ni = 3 * (size_t)src->ntris;
  bool ok = (dst->p = pc_big_alloc(nv * sizeof *dst->p)) && (dst->idx = pc_big_alloc(ni * sizeof *dst->idx)) &&
            (!src->n || (dst->n = pc_big_alloc(nv * sizeof *dst->n))) && (!src->uv || (dst->uv = pc_big_alloc(nv * sizeof *dst->uv)));
  if (!ok) {
    pc_mesh_free(dst);
    return -1;
  }
  memcpy(dst->p, src->p, nv * sizeof *dst->p);
  memcpy(dst->idx, src->idx, ni * sizeof *dst->idx);
  if (src->n) memcpy(dst->n, src->n, nv * sizeof *dst->n);
  if (src->uv) memcpy(dst->uv, src->uv, nv * sizeof *dst->uv);
  return 0;
}

void pc_mesh_transform(pc_mesh *m, const mat4 *xf) {
  const double(*a)[4] = xf->m;
  /* Normals use the cofactor matrix (det * inverse transpose): no inverse needed and the
   * scale cancels in the renormalisation; the sign of det keeps them on the same side. */
  double c[3][3];
  for (int r = 0; r < 3; r++)
    for (int k = 0; k < 3; k++) {
      int r1 = (r + 1) % 3, r2 = (r + 2) % 3, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      c[r][k] = a[r1][k1] * a[r2][k2] - a[r1][k2] * a[r2][k1];
    }
  double det = a[0][0] * c[0][0] + a[0][1] * c[0][1] + a[0][2] * c[0][2];
  double sgn = det < 0 ? -1.0 : 1.0;
  for (uint32_t i = 0; i < m->nverts; i++) m->p[i] = mat4_point(xf, m->p[i]);
  if (m->n)
    for (uint32_t i = 0; i < m->nverts; i++) {
      vec3 n = m->n[i];
      vec3 r = v3((float)(sgn * (c[0][0] * n.x + c[0][1] * n.y + c[0][2] * n.z)),
                  (float)(sgn * (c[1][0] * n.x + c[1][1] * n.y + c[1][2] * n.z)),
                  (float)(sgn * (c[2][0] * n.x + c[2][1] * n.y + c[2][2] * n.z)));
      m->n[i] = v3_norm(r);
    }
  /* A mirroring transform turns counter-clockwise into clockwise; restore the winding so the
   * geometric front side follows the transformed normal, as Mitsuba's analytic shapes do. */
  if (det < 0)
    for (uint32_t t = 0; t < m->ntris; t++) {
      uint32_t tmp = m->idx[3 * t + 1];
      m->idx[3 * t + 1] = m->idx[3 * t + 2];
      m->idx[3 * t + 2] = tmp;
    }
}

void pc_mesh_flip(pc_mesh *m) {
  for (uint32_t t = 0; t < m->ntris; t++) {
    uint32_t tmp = m->idx[3 * t + 1];
    m->idx[3 * t + 1] = m->idx[3 * t + 2];
    m->idx[3 * t + 2] = tmp;
  }
  if (m->n)
    for (uint32_t i = 0; i < m->nverts; i++) m->n[i] = v3_neg(m->n[i]);
}

/* Angle between unit vectors, accurate for small and large angles (Mitsuba's unitAngle). */
static double unit_angle(vec3 u, vec3 v) {
  if (v3_dot(u, v) < 0) return PC_PI - 2.0 * asin(fmin(1.0, v3_len(v3_add(u, v)) / 2.0));
  return 2.0 * asin(fmin(1.0, v3_len(v3_sub(v, u)) / 2.0));
}

int pc_mesh_compute_normals(pc_mesh *m) {
  vec3 *n = calloc(m->nverts ? m->nverts : 1, sizeof *n);
  if (!n) return PC_ENOMEM;
  for (uint32_t t = 0; t < m->ntris; t++) {
    const uint32_t *ix = &m->idx[3 * t];
    vec3 fn = v3(0, 0, 0);
    for (int i = 0; i < 3; i++) {
      vec3 v0 = m->p[ix[i]], v1 = m->p[ix[(i + 1) % 3]], v2 = m->p[ix[(i + 2) % 3]];
      vec3 a = v3_sub(v1, v0), b = v3_sub(v2, v0);
      if (i == 0) {
        fn = v3_cross(a, b);
        float len = v3_len(fn);
        if (!(len > 0)) break;
        fn = v3_scale(fn, 1.f / len);
      }
      double ang = unit_angle(v3_norm(a), v3_norm(b));
      n[ix[i]] = v3_madd(n[ix[i]], fn, (float)ang);
    }
  }
  for (uint32_t i = 0; i < m->nverts; i++) {
    float len = v3_len(n[i]);
    /* Vertices only on degenerate triangles (never hit) get Mitsuba's arbitrary value. */
    n[i] = len > 0 && isfinite(len) ? v3_scale(n[i], 1.f / len) : v3(1, 0, 0);
  }
  free(m->n);
  m->n = n;
  return 0;
}

int pc_mesh_validate(const pc_mesh *m, const char *where, pc_err *e) {
  if (m->nverts == 0 || m->ntris == 0) return pc_errf(e, PC_EINVAL, "%s: mesh has no triangles", where);
  if (m->nverts > PC_MESH_MAX_VERTICES || m->ntris > PC_MESH_MAX_TRIANGLES)
    return pc_errf(e, PC_ELIMIT, "%s: mesh exceeds the size limits", where);
  for (uint32_t i = 0; i < 3 * m->ntris; i++)
    if (m->idx[i] >= m->nverts)
      return pc_errf(e, PC_EINVAL, "%s: triangle %u has an out-of-range vertex index", where, i / 3);
  for (uint32_t i = 0; i < m->nverts; i++) {
    if (!v3_is_finite(m->p[i]))
      return pc_errf(e, PC_ENUMERIC, "%s: vertex %u has a non-finite position", where, i);
    if (m->n && !(fabsf(v3_len(m->n[i]) - 1.f) < 1e-3f))
      return pc_errf(e, PC_ENUMERIC, "%s: vertex %u has an invalid normal", where, i);
    if (m->uv && !(isfinite(m->uv[i].x) && isfinite(m->uv[i].y)))
      return pc_errf(e, PC_ENUMERIC, "%s: vertex %u has non-finite texture coordinates", where, i);
  }
  return 0;
}

bool pc_mesh_has_area(const pc_mesh *m) {
  for (uint32_t t = 0; t < m->ntris; t++) {
    vec3 a = m->p[m->idx[3 * t]], b = m->p[m->idx[3 * t + 1]], c = m->p[m->idx[3 * t + 2]];
    if (v3_len2(v3_cross(v3_sub(b, a), v3_sub(c, a))) > 0) return true;
  }
  return false;
}

static int mesh_alloc(pc_mesh *m, uint32_t nverts, uint32_t ntris, bool uv) {
  memset(m, 0, sizeof *m);
  m->p = pc_big_alloc(nverts * sizeof *m->p);
  m->uv = uv ? pc_big_alloc(nverts * sizeof *m->uv) : NULL;
  m->idx = pc_big_alloc(3 * (size_t)ntris * sizeof *m->idx);
  if (!m->p || !m->idx || (uv && !m->uv)) {
    pc_mesh_free(m);
    return PC_ENOMEM;
  }
  m->nverts = nverts;
  m->ntris = ntris;
  return 0;
}

int pc_mesh_rectangle(pc_mesh *out) {
  int rc = mesh_alloc(out, 4, 2, true);
  if (rc) return rc;
  static const float xy[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int i = 0; i < 4; i++) {
    out->p[i] = v3(xy[i][0], xy[i][1], 0);
    /* Mitsuba's rectangle maps [-1,1]^2 to [0,1]^2. */
    out->uv[i] = (vec2){0.5f * (xy[i][0] + 1), 0.5f * (xy[i][1] + 1)};
  }
  static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
  memcpy(out->idx, idx, sizeof idx);
  return 0;
}

int pc_mesh_cube(pc_mesh *out) {
  int rc = mesh_alloc(out, 24, 12, true);
  if (rc) return rc;
  /* One quad per face with its own vertices, so each face has its own [0,1]^2 uv square. */
  static const float face[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  static const float corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int f = 0; f < 6; f++) {
    vec3 n = v3(face[f][0], face[f][1], face[f][2]);
    frame fr = frame_from_normal(n);
    /* (s, t, n) is right-handed, so corners counter-clockwise in (s, t) face outward. */
    for (int c = 0; c < 4; c++) {
      vec3 p = v3_add(n, v3_add(v3_scale(fr.s, corner[c][0]), v3_scale(fr.t, corner[c][1])));
      out->p[4 * f + c] = v3(roundf(p.x), roundf(p.y), roundf(p.z));
      out->uv[4 * f + c] = (vec2){0.5f * (corner[c][0] + 1), 0.5f * (corner[c][1] + 1)};
    }
    uint32_t b = 4 * (uint32_t)f;
    uint32_t q[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
    memcpy(&out->idx[6 * f], q, sizeof q);
  }
  return 0;
}

int pc_mesh_disk(pc_mesh *out, int segments) {
  if (segments < 3 || segments > (1 << 20)) return PC_EINVAL;
  uint32_t n = (uint32_t)segments;
  /* A centre vertex per segment and a duplicated seam vertex, so Mitsuba's polar uv
   * (u = r, v = phi / 2pi) interpolates without wrapping. */
  int rc = mesh_alloc(out, 2 * n + 1, n, true);
  if (rc) return rc;
  for (uint32_t i = 0; i <= n; i++) {
    double phi = 2.0 * 3.14159265358979323846 * i / n;
    out->p[n + i] = i == n ? v3(1, 0, 0) : v3((float)cos(phi), (float)sin(phi), 0);
    out->uv[n + i] = (vec2){1.f, (float)i / (float)n};
  }
  for (uint32_t i = 0; i < n; i++) {
    out->p[i] = v3(0, 0, 0);
    out->uv[i] = (vec2){0.f, ((float)i + 0.5f) / (float)n};
    out->idx[3 * i] = i;
    out->idx[3 * i + 1] = n + i;
    out->idx[3 * i + 2] = n + i + 1;
  }
  return 0;
}
