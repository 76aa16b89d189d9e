/* pcbpt.c: see pcbpt.h. The M light paths are the iteration's light paths 0..M-1 (the same
 * ones pixels 0..M-1 light-trace), traced here once more to keep them; cache eye paths use
 * their own stream (PC_STREAM_CACHE), so the image's eye paths are the same for every method. */
#include "pcbpt.h"

#include <stdlib.h>

#include "bidir.h"
#include "cache_pixels.h"

int pc_pcbpt_create(const pc_render_settings *set, int nthreads, pc_pcbpt **out, pc_err *e) {
  *out = NULL;
  pc_pcbpt *p = calloc(1, sizeof *p);
  if (!p) return pc_errf(e, PC_ENOMEM, "out of memory for PCBPT");
  p->m = set->pcbpt_m;
  if (set->method == PC_METHOD_PCBPT) {
    int rc = pc_irec_create(nthreads, PC_PCBPT_RECORD_BYTES, &p->store, e);
    if (rc != PC_OK) {
      free(p);
      return rc;
    }
  }
  *out = p;
  return PC_OK;
}

void pc_pcbpt_destroy(pc_pcbpt *p) {
  if (!p) return;
  free(p->lv);
  free(p->cv);
  free(p->sites);
  pc_irec_destroy(p->store);
  free(p);
}

/* Makes room for `more` vertices after n in *buf (capacity *cap). */
static int reserve_vertices(pc_path_vertex **buf, int *cap, int n, int more, pc_err *e) {
  if (n + more <= *cap) return PC_OK;
  int want = *cap ? *cap : 256;
  while (want < n + more) want *= 2;
  pc_path_vertex *b = realloc(*buf, (size_t)want * sizeof *b);
  if (!b) return pc_errf(e, PC_ENOMEM, "PCBPT: out of memory for %d path vertices", want);
  *buf = b;
  *cap = want;
  return PC_OK;
}

static int store_light_vertices(pc_pcbpt *p, pc_tctx *c, pc_err *e) {
  p->nv = 0;
  for (int j = 0; j < p->m; j++) {
    int nl = pc_light_subpath(c, &c->counts, (uint64_t)j, c->light_path);
    int rc = reserve_vertices(&p->lv, &p->cap_v, p->nv, nl, e);
    if (rc != PC_OK) return rc;
    for (int i = 1; i < nl; i++) { /* i = 0 is on the light: s = 1 belongs to NEE */
      const pc_path_vertex *v = &c->light_path[i];
      if (v->delta || v3_is_zero(v->beta)) continue;
      p->lv[p->nv++] = *v;
    }
  }
  return PC_OK;
}

static int trace_cache_paths(pc_pcbpt *p, pc_tctx *c, pc_err *e) {
  const pc_render_settings *set = c->set;
  int n = pc_cache_path_count(set->cache_fraction, set->width, set->height);
  pc_rng rot = pc_rng_make(set->seed, c->iteration, PC_STREAM_CACHE, (uint64_t)n);
  float rx = pc_rng_f(&rot), ry = pc_rng_f(&rot);
  p->nr = 0;
  for (int i = 0; i < n; i++) {
    int x, y;
    pc_cache_pixel(i, n, set->width, set->height, rx, ry, &x, &y);
    pc_rng rng = pc_rng_make(set->seed, c->iteration, PC_STREAM_CACHE, (uint64_t)i);
    int ne = pc_eye_subpath(c, &c->counts, &rng, x, y, c->max_segments + 1, c->eye_path, NULL, NULL);
    int rc = reserve_vertices(&p->cv, &p->cap_r, p->nr, ne, e);
    if (rc != PC_OK) return rc;
    for (int t = 2; t <= ne && t <= c->max_segments; t++)
      if (!c->eye_path[t - 1].delta) p->cv[p->nr++] = c->eye_path[t - 1];
  }
  pc_irec_site *s = realloc(p->sites, (size_t)(p->nr ? p->nr : 1) * sizeof *s);
  if (!s) return pc_errf(e, PC_ENOMEM, "PCBPT: out of memory for %d record sites", p->nr);
  p->sites = s;
  for (int r = 0; r < p->nr; r++) {
    const pc_path_vertex *v = &p->cv[r];
    s[r] = (pc_irec_site){v->p, v->sh.sh.n, v->wo, v};
  }
  return PC_OK;
}

float pc_pcbpt_importance(void *user, int thread, const pc_irec_site *z, int v) {
  const pc_pcbpt *p = user;
  pc_tctx *c = &p->tctx[thread];
  const pc_path_vertex *lv = &p->lv[v];
  pc_path_vertex ev = *(const pc_path_vertex *)z->vertex;
  if (lv->depth + ev.depth - 1 > c->max_segments) return 0.f;
  /* The eye sub-path's own throughput is common to every light vertex (it cancels in the PMF,
   * Popov et al. eq. 12) and is left out so its colour does not skew the luminance. */
  ev.beta = v3s(1.f);
  pc_connection k;
  if (!pc_connect(c, &c->counts, lv, &ev, false, &k)) return 0.f;
  float lum = v3_luminance(k.f);
  return lum > 0.f && isfinite(lum) ? lum : 0.f;
}

int pc_pcbpt_prepare(pc_pcbpt *p, pc_tctx *tctx, pc_pool *pool, pc_err *e) {
  p->tctx = tctx;
  /* Light and cache paths are few (M, and a fraction of W*H): traced on thread 0, so their
   * order in the arrays is fixed. The records' R*V connections are the cost, in parallel. */
  int rc = store_light_vertices(p, &tctx[0], e);
  if (rc != PC_OK || !p->store) return rc;
  if (tctx[0].set->pmf_mode == PC_PMF_EXACT) return pc_irec_build(p->store, NULL, 0, p->nv, pc_pcbpt_importance, p, pool, e);
  rc = trace_cache_paths(p, &tctx[0], e);
  if (rc != PC_OK) return rc;
  return pc_irec_build(p->store, p->sites, p->nr, p->nv, pc_pcbpt_importance, p, pool, e);
}
