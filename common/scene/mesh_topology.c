/* mesh_topology.c: Mitsuba's maxSmoothAngle (TriMesh::rebuildTopology). The mesh's normals are
 * discarded; corners that share a position and texture coordinate are one vertex, which is
 * split into as many vertices as there are greedy clusters of its faces' normals (a face joins
 * the cluster of the first unclustered face, in face order, whose normal is within the angle);
 * smooth normals are then computed over the new topology, so shading is smooth across edges
 * flatter than the angle and creased elsewhere. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"

/* Below this a face normal is taken as degenerate (Mitsuba's RCPOVERFLOW_FLT). */
#define DEGENERATE_LEN 2.93873587705571876e-39f

typedef struct corner {
  vec3 p;
  vec2 uv;
  uint32_t tri;
  uint8_t k, clustered;
} corner;

/* Mitsuba's vertex_key_order on (position, uv), then face order: std::multimap keeps equal
 * keys in insertion order, which is the order the greedy clustering sees them in. */
static int cmp_corner(const void *pa, const void *pb) {
  const corner *a = pa, *b = pb;
  const float ka[5] = {a->p.x, a->p.y, a->p.z, a->uv.x, a->uv.y}, kb[5] = {b->p.x, b->p.y, b->p.z, b->uv.x, b->uv.y};
  for (int i = 0; i < 5; i++)
    if (ka[i] != kb[i]) return ka[i] < kb[i] ? -1 : 1;
  if (a->tri != b->tri) return a->tri < b->tri ? -1 : 1;
  return (a->k > b->k) - (a->k < b->k);
}

static bool same_key(const corner *a, const corner *b) {
  return a->p.x == b->p.x && a->p.y == b->p.y && a->p.z == b->p.z && a->uv.x == b->uv.x && a->uv.y == b->uv.y;
}

static bool v3_eq(vec3 a, vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

int pc_mesh_rebuild_topology(pc_mesh *m, float max_angle_deg) {
  if (!(fabsf(max_angle_deg) <= 360.f)) return PC_EINVAL;
  for (uint32_t i = 0; i < m->nverts; i++)
    if (!v3_is_finite(m->p[i]) || (m->uv && !(isfinite(m->uv[i].x) && isfinite(m->uv[i].y)))) return PC_ENUMERIC;
  for (uint32_t i = 0; i < 3 * m->ntris; i++)
    if (m->idx[i] >= m->nverts) return PC_EINVAL;
  const double thresh = cos(max_angle_deg * M_PI / 180.0);
  size_t nc = 3 * (size_t)m->ntris;
  corner *cs = malloc((nc ? nc : 1) * sizeof *cs);
  vec3 *fn = malloc((m->ntris ? m->ntris : 1) * sizeof *fn);
  uint32_t *nidx = malloc((nc ? nc : 1) * sizeof *nidx);
  /* every new vertex comes from a distinct corner, so there are at most nc of them */
  vec3 *np = malloc((nc ? nc : 1) * sizeof *np);
  vec2 *nuv = m->uv ? malloc((nc ? nc : 1) * sizeof *nuv) : NULL;
  if (!cs || !fn || !nidx || !np || (m->uv && !nuv)) {
    free(cs), free(fn), free(nidx), free(np), free(nuv);
    return PC_ENOMEM;
  }
  for (uint32_t t = 0; t < m->ntris; t++) {
    const uint32_t *ix = &m->idx[3 * t];
    vec3 n = v3_cross(v3_sub(m->p[ix[1]], m->p[ix[0]]), v3_sub(m->p[ix[2]], m->p[ix[0]]));
    float len = v3_len(n);
    fn[t] = len > DEGENERATE_LEN ? v3_scale(n, 1.f / len) : v3s(0.f);
    for (int k = 0; k < 3; k++)
      cs[3 * t + k] = (corner){m->p[ix[k]], m->uv ? m->uv[ix[k]] : (vec2){0, 0}, t, (uint8_t)k, 0};
  }
  qsort(cs, nc, sizeof *cs, cmp_corner);
  uint32_t nv = 0;
  for (size_t start = 0, end; start < nc; start = end) {
    for (end = start + 1; end < nc && same_key(&cs[start], &cs[end]); end++) {}
    for (size_t a = start; a < end; a++) {
      if (cs[a].clustered) continue;
      vec3 n1 = fn[cs[a].tri];
      uint32_t v = nv++;
      np[v] = cs[a].p;
      if (nuv) nuv[v] = cs[a].uv;
      for (size_t b = a; b < end; b++) {
        if (cs[b].clustered) continue;
        vec3 n2 = fn[cs[b].tri];
        if (!(v3_eq(n1, n2) || v3_dot(n1, n2) > thresh)) continue;
        /* as Mitsuba: every corner of that face at this position (uv aside) */
        const uint32_t *ix = &m->idx[3 * cs[b].tri];
        for (int k = 0; k < 3; k++)
          if (v3_eq(m->p[ix[k]], cs[a].p)) nidx[3 * cs[b].tri + k] = v;
        cs[b].clustered = 1;
      }
    }
  }
  free(cs);
  free(fn);
  if (nv > PC_MESH_MAX_VERTICES) {
    free(nidx), free(np), free(nuv);
    return PC_ELIMIT;
  }
  vec3 *p2 = realloc(np, (nv ? nv : 1) * sizeof *p2);
  if (p2) np = p2;
  if (nuv) {
    vec2 *uv2 = realloc(nuv, (nv ? nv : 1) * sizeof *uv2);
    if (uv2) nuv = uv2;
  }
  free(m->p), free(m->uv), free(m->idx), free(m->n);
  m->p = np, m->uv = nuv, m->idx = nidx, m->n = NULL, m->nverts = nv;
  return pc_mesh_compute_normals(m);
}
