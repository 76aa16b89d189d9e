/* integrator_pcbpt.c: CBDPT and PCBPT pixels (DESIGN.md §4.4; Popov et al. 2015, Alg. 1).
 * Strategies s=0, s=1 and t=1 are BDPT's, drawn from the same streams, so those layers equal
 * BDPT's for the same seed. The inner strategies (s>=2, t>=2) connect each non-delta eye vertex
 * to the M stored light paths: CBDPT to every stored vertex, adding w f / (p M); PCBPT to K
 * vertices drawn from p_conn, adding (1/K) sum w f / (p M p_conn). The weights use the
 * method's counts (render.c): inner strategies count --mis (2 by default; 1 for the
 * upper-bound weights of eqs. 16-17, M for standard ones). Connection draws use the pixel's
 * PC_STREAM_CONNECT stream. With --pcbpt-rate R < 1 an eye vertex connects to the stored paths
 * only with probability R, and what it adds counts 1/R: unbiased for any R > 0, and the MIS
 * weights, which do not involve how often the inner strategies are tried, stay as they are.
 * PCBPT applies --pcbpt-unseen-rate the same way in an iteration none of whose records sees a
 * light vertex: a fact of the iteration, known before any of its pixels draws. */
#include <float.h>

#include "bidir.h"
#include "pcbpt.h"

static void add_inner(pc_tctx *c, int x, int y, const pc_path_vertex *lv, const pc_path_vertex *ev, float scale) {
  pc_connection k;
  if (lv->depth + ev->depth - 1 > c->max_segments) return;
  if (pc_connect(c, &c->counts, lv, ev, c->weighted, &k))
    pc_tctx_add(c, PC_LAYER_INNER, lv->depth, ev->depth, x, y, v3_scale(k.f, k.weight * scale));
}

/* A resampling candidate's unoccluded connection, and its visibility when the target traced
 * it (so the selected candidate does not trace it again). */
typedef struct candidates {
  pc_tctx *c;
  const pc_path_vertex *ev;
  const pc_irec_lookup *L;
  int v[PC_IREC_MAX_CANDIDATES];
  signed char visible[PC_IREC_MAX_CANDIDATES]; /* 1 visible, 0 occluded, -1 not traced */
  pc_connection k[PC_IREC_MAX_CANDIDATES];
} candidates;

/* Whether the target traces this candidate's shadow ray (--pcbpt-candidate-visibility):
 * always, or unless every interpolated record sees the light vertex (seen: the share of the
 * records that do, read only when the mode needs it). Tracing only where the records disagree
 * (0 < seen < 1) gained little on ajar-door (inner relMSE 0.180 against 0.185 without tracing
 * and 0.154 tracing all, N = 4): what the records get wrong is mostly the light vertices none
 * of them sees, drawn from the uniform part of p_conn. */
static bool traces_candidate(pc_candidate_visibility mode, const pc_irec_lookup *L, int v, double *seen) {
  if (mode == PC_CANDVIS_TRACED) return true;
  *seen = pc_irec_interp_seen(L, v);
  return mode == PC_CANDVIS_UNCERTAIN && *seen < 1.0;
}

/* Target of the resampling: the luminance of the weighted contribution without visibility,
 * times the candidate's visibility: its own shadow ray's where it is traced (the target is
 * then the contribution's luminance itself), elsewhere the share of the interpolated records
 * that see the light vertex (their PMF is > 0 there), floored at RESAMPLE_UNSEEN. Either way
 * > 0 wherever the contribution is non-zero, so the resampled estimate stays unbiased.
 * Measured on ajar-door at 128x128 (inner relMSE after 64 iterations, K = 1, 4 candidates;
 * plain cache 0.237, exact PMF 0.131): the unoccluded contribution alone 0.231 (geometry is
 * not what the cache blurs; visibility is), times an unseen floor of 0.01 / 0.05 / 0.1 / 0.2:
 * 0.239 / 0.188 / 0.181 / 0.185 (too low a floor starves light vertices the records miss, as
 * a uniform mix that is too small does); with every candidate traced, 0.153. */
#define RESAMPLE_UNSEEN 0.1
static float candidate_target(void *user, int slot, int v) {
  candidates *cs = user;
  pc_tctx *c = cs->c;
  const pc_path_vertex *lv = &c->pcbpt->lv[v];
  cs->v[slot] = v;
  cs->visible[slot] = -1;
  if (lv->depth + cs->ev->depth - 1 > c->max_segments) return 0.f;
  pc_connection *k = &cs->k[slot];
  if (!pc_connect_unoccluded(c, &c->counts, lv, cs->ev, c->weighted, k)) return 0.f;
  float h = v3_luminance(k->f) * k->weight;
  double seen = 0.0;
  if (traces_candidate(c->set->candidate_visibility, cs->L, v, &seen)) {
    cs->visible[slot] = pc_connect_visible(c, lv, cs->ev);
    if (!cs->visible[slot]) return 0.f;
  } else {
    /* The records know visibility, blurred; the candidate's own h knows geometry, sharply. */
    h *= (float)(RESAMPLE_UNSEEN + (1.0 - RESAMPLE_UNSEEN) * seen);
  }
  return h > 0.f ? h : FLT_MIN; /* non-zero contribution whose luminance underflowed */
}

/* K connections resampled from `candidates` draws of p_conn by the target above
 * (pc_irec_resample): the shadow rays go to the connections that matter most at this eye
 * vertex, which the records only know up to their interpolation blur. The MIS weights are the
 * strategies' (they do not involve p_conn), so only this estimate of the sum over the stored
 * vertices changes; it stays unbiased for any p_conn > 0. */
static void resample_stored(pc_tctx *c, int x, int y, pc_rng *crng, const pc_path_vertex *ev, const pc_irec_lookup *L,
                            double xi, double m_eff, int ncand) {
  const pc_render_settings *set = c->set;
  candidates cs; /* not zeroed: 2 KB per eye vertex; candidate_target fills each slot it is given */
  cs.c = c;
  cs.ev = ev;
  cs.L = L;
  int slot[PC_IREC_MAX_CANDIDATES];
  double factor[PC_IREC_MAX_CANDIDATES];
  int n = pc_irec_resample(L, ncand, set->pcbpt_k, xi, crng, candidate_target, &cs, slot, factor);
  for (int k = 0; k < n; k++) {
    const pc_connection *con = &cs.k[slot[k]];
    const pc_path_vertex *lv = &c->pcbpt->lv[cs.v[slot[k]]];
    int visible = cs.visible[slot[k]];
    if (visible == 0 || (visible < 0 && !pc_connect_visible(c, lv, ev))) continue;
    float scale = (float)(factor[k] / ((double)n * m_eff));
    pc_tctx_add(c, PC_LAYER_INNER, lv->depth, ev->depth, x, y, v3_scale(con->f, con->weight * scale));
  }
}

static void connect_stored(pc_tctx *c, int x, int y, pc_rng *crng, const pc_path_vertex *ev) {
  const pc_pcbpt *p = c->pcbpt;
  const pc_render_settings *set = c->set;
  if (p->nv == 0) return; /* no connectable vertex: the sum over the stored paths is 0 */
  /* Decided before the lookup, which on a large scene costs about what the connection does.
   * The draw is taken only when R < 1, so R = 1 renders what it did before the setting. */
  double rate = set->pcbpt_rate;
  if (rate < 1.0 && !((double)pc_rng_f(crng) < rate)) return;
  double m_eff = (double)p->m * rate; /* what the sum over the stored paths is divided by */
  if (set->method == PC_METHOD_CBDPT) {
    float inv_m = 1.f / (float)m_eff;
    for (int v = 0; v < p->nv; v++) add_inner(c, x, y, &p->lv[v], ev, inv_m);
    return;
  }
  /* No record sees a light vertex (slit-room while no stored path got through the slit): the
   * stored paths are unlikely to reach this vertex either. Drawn only when the rate is < 1. */
  double unseen = set->pcbpt_unseen_rate;
  if (unseen < 1.0 && pc_irec_none_seen(p->store)) {
    if (!((double)pc_rng_f(crng) < unseen)) return;
    m_eff *= unseen;
  }
  pc_irec_lookup L;
  int ncand = set->pcbpt_candidates;
  if (set->pmf_mode == PC_PMF_EXACT) {
    pc_path_vertex unit = *ev; /* pc_pcbpt_importance wants throughput 1 */
    unit.beta = v3s(1.f);
    pc_irec_site z = pc_pcbpt_site(c->scene, &unit);
    if (pc_irec_lookup_exact(p->store, c->thread, &z, pc_pcbpt_importance, c->pcbpt, set->uniform_mix, &L, NULL) != PC_OK)
      return;
  } else {
    pc_irec_site z = pc_pcbpt_site(c->scene, ev);
    pc_irec_lookup_cached(p->store, c->thread, &z, set->knn, set->uniform_mix, &L);
    /* Dark vertices only where records shape p_conn (at uniform-mix 1 the user asked for none)
     * and see something somewhere (in an iteration where none does, more candidates drawn
     * uniformly would find as little as one), and where K connections can be resampled. */
    if (set->pcbpt_dark_seen > 0.f && set->uniform_mix < 1.f && set->pcbpt_k <= PC_IREC_MAX_CANDIDATES &&
        !pc_irec_none_seen(p->store) &&
        pc_irec_lookup_dark(&L, set->pcbpt_dark_seen, set->pcbpt_dark_mix)) {
      /* per connection, so that K connections still come from K times as many candidates */
      long dark = (long)set->pcbpt_dark_candidates * set->pcbpt_k;
      if (dark > PC_IREC_MAX_CANDIDATES) dark = PC_IREC_MAX_CANDIDATES;
      if (dark > ncand) ncand = (int)dark;
    }
  }
  /* The draws' component choices are stratified: each draw alone follows p_conn (so every
   * term of the sum is unbiased), and together they take the uniform PMF in proportion u. */
  double xi = (double)pc_rng_f(crng);
  if (ncand > 1) {
    resample_stored(c, x, y, crng, ev, &L, xi, m_eff, ncand);
    return;
  }
  for (int k = 0; k < set->pcbpt_k; k++) {
    int v;
    double pconn;
    if (!pc_irec_sample_mix(&L, ((double)k + xi) / set->pcbpt_k, crng, &v, &pconn))
      return; /* u = 0 and no PMF here: reported as no sample */
    add_inner(c, x, y, &p->lv[v], ev, (float)(1.0 / ((double)set->pcbpt_k * m_eff * pconn)));
  }
}

void pc_pcbpt_pixel(pc_tctx *c, int x, int y) {
  const pc_render_settings *set = c->set;
  const pc_mis_counts *n = &c->counts;
  uint64_t j = (uint64_t)y * (uint64_t)set->width + (uint64_t)x;
  bool timed = pc_timed(j);
  double t0 = pc_stamp(timed);
  int nl = j < c->n_light ? pc_light_subpath(c, n, j, c->light_path) : 0;
  double t1 = pc_stamp(timed);
  if (nl > 0) pc_lt_splat(c, c->light_path, nl, j);
  double t2 = pc_stamp(timed);
  pc_rng rng = pc_rng_make(set->seed, c->iteration, PC_STREAM_EYE, j);
  pc_rng crng = pc_rng_make(set->seed, c->iteration, PC_STREAM_CONNECT, j);
  pc_pixel_target h = {x, y};
  int ne = pc_eye_subpath(c, n, &rng, x, y, c->max_segments + 1, c->eye_path, pc_emitter_hit, &h);
  double t3 = pc_stamp(timed);
  /* The lookups' memo entries start loading now, so their misses overlap this pixel's NEE rays
   * (ajar-door with 3 candidates: 1-1.5% of an iteration in three alternated pairs) */
  if (c->pcbpt->store && set->pmf_mode != PC_PMF_EXACT)
    for (int t = 2; t <= ne && t <= c->max_segments; t++)
      pc_irec_prefetch(c->pcbpt->store, c->thread, c->eye_path[t - 1].p);
  for (int t = 2; t <= ne && t <= c->max_segments; t++) {
    const pc_path_vertex *ev = &c->eye_path[t - 1];
    if (ev->delta) continue;
    pc_connect_nee(c, n, &rng, ev, x, y);
    connect_stored(c, x, y, &crng, ev);
  }
  if (timed) {
    c->t_paths += PC_TIMED_EVERY * ((t1 - t0) + (t3 - t2));
    c->t_lt += PC_TIMED_EVERY * (t2 - t1);
    c->t_connect += PC_TIMED_EVERY * (pc_seconds() - t3);
  }
}
