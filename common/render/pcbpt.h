/* pcbpt.h: the per-iteration state CBDPT and PCBPT share (DESIGN.md §4.4-4.5): the connectable
 * vertices of the iteration's first M light paths in one flat array, and for PCBPT the
 * importance records built from the cache eye paths. Prepared once per iteration, before the
 * eye pass; read-only while the pixels connect to it. */
#ifndef PC_PCBPT_H
#define PC_PCBPT_H

#include "integrator.h"
#include "irec.h"
#include "thread_pool.h"

/* Hard limit on the importance records' memory (PMF + CMF of every record). The paper's
 * scenes needed <= 50 MB at 820x512 and 200 MB at 1080p; 1 GiB leaves room for larger M. */
#define PC_PCBPT_RECORD_BYTES ((size_t)1 << 30)

/* A thread's vertices of the paths it traced in the current phase. */
typedef struct pc_pcbpt_tbuf {
  pc_path_vertex *v;
  int n, cap;
  bool oom;
} pc_pcbpt_tbuf;

/* Where path j's kept vertices are: tbuf[thread].v[offset .. offset+count). */
typedef struct pc_pcbpt_slot {
  int thread, offset, count;
} pc_pcbpt_slot;

typedef struct pc_pcbpt {
  int m;                  /* stored light paths */
  int nthreads;
  pc_pcbpt_tbuf *tbuf;    /* one per pool thread */
  pc_pcbpt_slot *slots;   /* one per path of the phase */
  int cap_slots;
  int ncache;             /* cache eye paths of the iteration, and their pixel rotation */
  float cache_rx, cache_ry;
  int nv, cap_v;          /* connectable light vertices: s >= 2, non-delta, non-zero throughput */
  pc_path_vertex *lv;
  int nr, cap_r;          /* cache eye vertices (t >= 2, non-delta), one record each */
  pc_path_vertex *cv;
  pc_irec_site *sites;
  pc_irec_store *store;   /* PCBPT only */
  pc_tctx *tctx;          /* the renderer's per-thread contexts, indexed by pool thread */
} pc_pcbpt;

int pc_pcbpt_create(const pc_render_settings *set, int nthreads, pc_pcbpt **out, pc_err *e);
void pc_pcbpt_destroy(pc_pcbpt *p);

/* Whether PCBPT's connections read the cached records: not with --pmf exact, nor with a
 * uniform mix of 1, where p_conn is the uniform PMF whatever the records say, unless the
 * resampling's target reads their seen share (visibility records or uncertain). */
bool pc_pcbpt_reads_records(const pc_render_settings *set);

/* Prepares iteration tctx[0].iteration: stores the light vertices of light paths 0..M-1 and,
 * for PCBPT whose connections read the records, traces the cache eye paths and builds their
 * records on pool (otherwise an empty store of the light vertices, whose lookups give the
 * uniform PMF or the exact one). */
int pc_pcbpt_prepare(pc_pcbpt *p, pc_tctx *tctx, pc_pool *pool, pc_err *e);

/* Where eye vertex v is, as the importance records see it. */
pc_irec_site pc_pcbpt_site(const pc_scene *scene, const pc_path_vertex *v);

/* Unnormalized connection importance of stored light vertex v for the eye vertex behind z:
 * luminance(light throughput * f_conn) times the connection's MIS weight, shadow ray included
 * (a pc_irec_importance_fn; user is the pc_pcbpt). The eye vertex must have throughput beta = 1:
 * its eye sub-path's own throughput is common to every light vertex (it cancels in the PMF,
 * Popov et al. eq. 12) and is left out so its colour does not skew the luminance; the caller
 * sets it once per site rather than this copying the vertex for every light vertex. */
float pc_pcbpt_importance(void *user, int thread, const pc_irec_site *z, int v);

#endif
