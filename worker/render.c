/* render.c: the worker's render thread: loads and builds the job's scene once per job (kept
 * for the next job of the same scene bundle, -D values and film size: a study's interleaved
 * jobs differ in method and seed only, and switch often), then renders the assigned range in
 * batches of about half a second into the pending film, and compresses that into an upload
 * when the loop asks (between batches, on this thread, so the film is never shared). Over
 * one scene it keeps the renderers and films of the last few jobs (a study's methods and
 * auto's pilot candidates alternate range by range): a fresh renderer's first iteration pays
 * for allocating and first touching its buffers, and PCBPT's stores grow back over a few
 * iterations, which would be charged to every range of every method and weigh most in the
 * pilot's short ranges.
 * Cancel is polled by the renderer between work items, so it takes effect well within a
 * second. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render_flags.h"
#include "wire_film.h"
#include "scene.h"
#include "thread_pool.h"
#include "wire_log.h"
#include "worker.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* One job's renderer and films over the loaded scene. */
typedef struct job_rend {
  uint64_t job;
  pc_renderer *rend;
  pc_film pending;  /* iterations not yet taken for upload */
  bool pending_dirty;
  size_t film_bytes; /* its films and the renderer's per-thread ones */
  size_t bytes;     /* about what it holds: film_bytes and the most its PCBPT records held */
  uint64_t used;    /* when it last rendered (a counter) */
} job_rend;

/* Renderers kept besides the current one: at most this many, holding at most this much. A
 * study's group of six methods alternates range by range; with 4 kept, least recently used
 * went first, so each range of each method found its renderer dropped and made a new one. */
#define KEEP_RENDERERS 8
#define KEEP_BYTES ((size_t)256 << 20)

typedef struct job_ctx {
  bool loaded;
  pc_scene scene;
  job_rend kept[KEEP_RENDERERS + 1];
  int nkept;
  job_rend *cur;    /* the job being rendered, one of kept */
  uint64_t clock;
  /* what the built scene depends on */
  char path[1200], root[1200];
  int width, height;
  pc_scene_defines defines;
} job_ctx;

/* The render pool's size (threads 0: one per core), which also compresses the uploads. */
static int pool_threads(const pc_wrender *w) { return w->threads > 0 ? w->threads : pc_cpu_count(); }

/* Kept renderer k (withdrawn from the loop's progress reads first when it is the current). */
static void drop_rend(job_ctx *c, pc_wrender *w, int k) {
  job_rend *r = &c->kept[k];
  if (c->cur == r) {
    uv_mutex_lock(&w->mu);
    w->rend = NULL;
    uv_mutex_unlock(&w->mu);
    c->cur = NULL;
  }
  pc_renderer_destroy(r->rend);
  pc_film_free(&r->pending);
  job_rend *cur = c->cur;
  c->kept[k] = c->kept[--c->nkept];
  if (cur == &c->kept[c->nkept]) c->cur = &c->kept[k]; /* it moved */
}

static void ctx_free(job_ctx *c, pc_wrender *w) {
  if (!c->loaded) return;
  while (c->nkept > 0) drop_rend(c, w, c->nkept - 1);
  pc_scene_free(&c->scene);
  c->loaded = false;
}

static bool same_scene(const job_ctx *c, const pc_render_settings *set, const char *path, const char *root) {
  return c->loaded && strcmp(c->path, path) == 0 && strcmp(c->root, root) == 0 && c->width == set->width &&
         c->height == set->height && c->defines.n == set->defines.n && c->defines.used == set->defines.used &&
         memcmp(c->defines.buf, set->defines.buf, (size_t)set->defines.used) == 0;
}

/* Makes job's renderer and films (for its settings: method, seed, depth, layers ...) the
 * current ones: a kept one, or new ones, after dropping the least recently used past the
 * bounds. The scene must be built. On failure the whole context is freed. */
static int ctx_films(job_ctx *c, pc_wrender *w, uint64_t job, const pc_render_settings *set, pc_err *e) {
  job_rend *r = NULL;
  for (int k = 0; k < c->nkept && !r; k++)
    if (c->kept[k].job == job) r = &c->kept[k];
  if (!r) {
    /* the job's pending film, and the renderer's scratch and light-splat films */
    size_t bytes = pc_film_bytes(set->width, set->height, set->strategy_layers) + pc_renderer_film_bytes(set, w->threads);
    if (w->max_film && bytes > w->max_film) {
      int nthreads = w->threads ? w->threads : pc_cpu_count();
      ctx_free(c, w);
      return pc_errf(e, PC_ELIMIT,
                     "the films of a %dx%d render on %d thread%s take %zu MB, more than this worker's %zu MB "
                     "(its memory, or --max-film-mb)",
                     set->width, set->height, nthreads, nthreads == 1 ? "" : "s", pc_big_mb(bytes), pc_big_mb(w->max_film));
    }
    for (;;) { /* room for one more: drop the least recently used while over a bound */
      size_t held = bytes;
      int lru = -1;
      for (int k = 0; k < c->nkept; k++) {
        held += c->kept[k].bytes;
        if (lru < 0 || c->kept[k].used < c->kept[lru].used) lru = k;
      }
      if (lru < 0 || (c->nkept <= KEEP_RENDERERS && held - bytes <= KEEP_BYTES)) break;
      drop_rend(c, w, lru);
    }
    r = &c->kept[c->nkept];
    memset(r, 0, sizeof *r);
    int rc = pc_renderer_create(&c->scene, set, w->threads, &r->rend, e);
    if (!rc) rc = pc_film_alloc_stored(&r->pending, set->width, set->height, set->strategy_layers, PC_FILM_NORMS_ALL, e);
    if (rc) { /* the pending film frees itself on failure; r->rend is NULL unless it was made */
      pc_renderer_destroy(r->rend);
      ctx_free(c, w);
      return rc;
    }
    pc_renderer_zero_film(r->rend, &r->pending);
    r->job = job;
    r->film_bytes = r->bytes = bytes;
    c->nkept++;
  }
  r->used = ++c->clock;
  c->cur = r;
  c->loaded = true;
  uv_mutex_lock(&w->mu);
  w->rend = r->rend;
  uv_mutex_unlock(&w->mu);
  return 0;
}

static int ctx_load(job_ctx *c, pc_wrender *w, uint64_t job, const pc_render_settings *set, const char *path,
                    const char *root, pc_err *e) {
  if (same_scene(c, set, path, root)) return ctx_films(c, w, job, set, e);
  ctx_free(c, w);
  memset(&c->scene, 0, sizeof c->scene);
  snprintf(c->path, sizeof c->path, "%s", path);
  snprintf(c->root, sizeof c->root, "%s", root);
  c->width = set->width;
  c->height = set->height;
  c->defines = set->defines;
  /* The client checked the scene and showed its warnings; the worker loads the same files with
   * the same -D values and needs no warnings. */
  pc_scene_load_opts o = {.root = root, .defines = &set->defines};
  int rc = pc_scene_load_with(path, &o, &c->scene, e);
  if (!rc) {
    /* the job's settings are complete: apply them over the scene's own values */
    pc_render_request req;
    pc_render_request_default(&req);
    req.set = *set;
    req.method_set = req.depth_set = req.width_set = req.height_set = true;
    pc_render_request_apply_scene(&req, &c->scene);
    rc = pc_scene_build(&c->scene, e);
  }
  if (rc) {
    pc_scene_free(&c->scene);
    return rc;
  }
  c->loaded = true;
  return ctx_films(c, w, job, set, e);
}

/* The loop asked for an upload: compresses what is pending (outside the lock: a 4K film takes
 * seconds) and hands it over, unless the range changed meanwhile (then it is dropped). */
static void take_pending(pc_wrender *w, job_ctx *c) {
  uv_mutex_lock(&w->mu);
  uint64_t range = w->range_id, first = w->pend_first, count = w->pend_count;
  pc_render_stats st = w->pend_stats;
  size_t zcap, zn = 0;
  uint8_t *z = pc_big_spare_take(&w->spare, &zcap);
  uv_mutex_unlock(&w->mu);
  pc_err e = {0};
  double t0 = now_s();
  job_rend *r = c->loaded ? c->cur : NULL;
  int rc = 0;
  if (count && r) {
    /* zstd's threads start inside the call and inherit the name: the upload's CPU time is
     * told apart from the render's */
    pc_thread_set_name("pc-upload");
    rc = pc_wire_film_zip_reuse(&r->pending, pool_threads(w), &z, &zcap, &zn, &e);
    pc_thread_set_name("pc-render");
  }
  double dt = now_s() - t0;
  if (rc) pc_wire_log("upload: %s", e.msg);
  bool zipped = count && r && !rc;
  uv_mutex_lock(&w->mu);
  w->take = false;
  if (zipped) w->zip_seconds = dt;
  if (zipped && w->range_id == range && w->pend_count == count) {
    w->zip = z;
    w->zip_len = zn;
    w->zip_cap = zcap;
    w->zip_raw = pc_wire_film_size(&r->pending);
    w->zip_range = range;
    w->zip_first = first;
    w->zip_count = count;
    w->zip_stats = st;
    w->zip_ready = true;
    w->pend_first = first + count;
    w->pend_count = 0;
    memset(&w->pend_stats, 0, sizeof w->pend_stats);
    z = NULL;
  }
  pc_big_spare_keep(&w->spare, z, zcap);
  uv_mutex_unlock(&w->mu);
  if (zipped) {
    pc_film_clear(&r->pending);
    r->pending_dirty = false;
  }
  uv_async_send(w->notify);
}

static void thread_main(void *arg) {
  pc_wrender *w = arg;
  pc_thread_set_name("pc-render");
  job_ctx ctx = {0};
  uint64_t loaded_job = 0;
  for (;;) {
    uv_mutex_lock(&w->mu);
    while (!w->quit && !(w->have_range && !w->range_done) && !w->take) uv_cond_wait(&w->cv, &w->mu);
    if (w->quit) { uv_mutex_unlock(&w->mu); break; }
    if (w->take) {
      uv_mutex_unlock(&w->mu);
      take_pending(w, &ctx);
      continue;
    }
    uint64_t job = w->job_id, first = w->first, count = w->count;
    pc_render_settings set = w->set;
    char path[sizeof w->scene_path], root[sizeof w->scene_root];
    memcpy(path, w->scene_path, sizeof path);
    memcpy(root, w->scene_root, sizeof root);
    uv_mutex_unlock(&w->mu);

    pc_err e = {0};
    int rc = 0;
    if (!ctx.loaded || loaded_job != job) {
      rc = ctx_load(&ctx, w, job, &set, path, root, &e);
      loaded_job = rc ? 0 : job;
    }
    job_rend *r = rc ? NULL : ctx.cur;
    if (r && r->pending_dirty) { /* a dropped range's batches */
      pc_film_clear(&r->pending);
      r->pending_dirty = false;
    }
    uint64_t done = 0;
    while (!rc && done < count && !atomic_load(&w->cancel)) {
      uv_mutex_lock(&w->mu);
      double rate = w->rate;
      uv_mutex_unlock(&w->mu);
      uint64_t batch = rate > 0 ? (uint64_t)(rate * 0.5) : 1;
      if (batch < 1) batch = 1;
      if (batch > count - done) batch = count - done;
      pc_render_stats st = {0};
      double t0 = now_s();
      /* straight into the pending film: the renderer adds whole iterations only, and st
       * counts them, even when cancelled part-way */
      rc = pc_render_iterations(r->rend, first + done, batch, &r->pending, &st, &w->cancel, NULL, NULL, &e);
      double dt = now_s() - t0;
      uint64_t got = st.iterations;
      r->pending_dirty |= got > 0;
      if (r->film_bytes + st.pmf_bytes > r->bytes) r->bytes = r->film_bytes + st.pmf_bytes;
      if (rc == PC_ECANCELED) rc = 0;
      if (rc) break; /* the range goes back; its pending iterations are cleared with the next */
      uv_mutex_lock(&w->mu);
      if (got) {
        if (w->pend_count == 0) w->pend_first = first + done;
        w->pend_count += got;
        pc_render_stats_add(&w->pend_stats, &st);
        w->rendered += got;
        if (dt > 0) w->rate = w->rate > 0 ? 0.5 * w->rate + 0.5 * (double)got / dt : (double)got / dt;
      }
      bool take = w->take;
      uv_mutex_unlock(&w->mu);
      done += got;
      if (take) take_pending(w, &ctx);
      else uv_async_send(w->notify);
      if (got < batch) break; /* cancelled part-way */
    }
    uv_mutex_lock(&w->mu);
    if (rc) {
      w->failed = true;
      snprintf(w->error, sizeof w->error, "%s", e.msg);
    }
    w->range_done = true;
    uv_mutex_unlock(&w->mu);
    uv_async_send(w->notify);
  }
  ctx_free(&ctx, w);
}

int pc_wrender_start(pc_wrender *w, int threads, size_t max_film, uv_async_t *notify, pc_err *e) {
  memset(w, 0, sizeof *w);
  w->threads = threads;
  w->max_film = max_film ? max_film : pc_big_memory_limit();
  w->notify = notify;
  atomic_init(&w->cancel, false);
  if (uv_mutex_init(&w->mu) != 0 || uv_cond_init(&w->cv) != 0) return pc_errf(e, PC_EIO, "worker: mutex init failed");
  if (uv_thread_create(&w->thread, thread_main, w) != 0) return pc_errf(e, PC_EIO, "worker: cannot start the render thread");
  return 0;
}

void pc_wrender_stop(pc_wrender *w) {
  uv_mutex_lock(&w->mu);
  w->quit = true;
  atomic_store(&w->cancel, true);
  uv_cond_signal(&w->cv);
  uv_mutex_unlock(&w->mu);
  uv_thread_join(&w->thread);
  free(w->zip);
  pc_big_spare_free(&w->spare);
  uv_cond_destroy(&w->cv);
  uv_mutex_destroy(&w->mu);
}

void pc_wrender_assign(pc_wrender *w, uint64_t job, uint64_t range, uint64_t first, uint64_t count,
                       const pc_render_settings *s, const char *scene_path, const char *scene_root) {
  uv_mutex_lock(&w->mu);
  if (w->job_id != job) w->rate = 0;
  w->job_id = job;
  w->range_id = range;
  w->first = first;
  w->count = count;
  w->set = *s;
  snprintf(w->scene_path, sizeof w->scene_path, "%s", scene_path);
  snprintf(w->scene_root, sizeof w->scene_root, "%s", scene_root);
  w->rendered = w->pend_count = 0;
  memset(&w->pend_stats, 0, sizeof w->pend_stats);
  w->pend_first = first;
  w->failed = false;
  w->range_done = false;
  w->have_range = true;
  atomic_store(&w->cancel, false);
  uv_cond_signal(&w->cv);
  uv_mutex_unlock(&w->mu);
}

void pc_wrender_take(pc_wrender *w) {
  uv_mutex_lock(&w->mu);
  if (!w->take && !w->zip_ready) {
    w->take = true;
    uv_cond_signal(&w->cv);
  }
  uv_mutex_unlock(&w->mu);
}
