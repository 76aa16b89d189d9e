/* render.c: the worker's render thread: loads and builds the job's scene once per job, then
 * renders the assigned range in batches of about half a second into a scratch film and adds
 * each finished batch to the pending film the loop uploads. Cancel is polled by the renderer
 * between work items, so it takes effect well within a second. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "render_flags.h"
#include "scene.h"
#include "wire_log.h"
#include "worker.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct job_ctx {
  uint64_t job_id;
  bool loaded;
  pc_scene scene;
  pc_renderer *rend;
  pc_film work;
} job_ctx;

static void ctx_free(job_ctx *c) {
  if (!c->loaded) return;
  pc_renderer_destroy(c->rend);
  pc_film_free(&c->work);
  pc_scene_free(&c->scene);
  c->loaded = false;
}

static int ctx_load(job_ctx *c, const pc_wrender *w, const pc_render_settings *set, const char *path, const char *root,
                    pc_err *e) {
  ctx_free(c);
  memset(&c->scene, 0, sizeof c->scene);
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
  if (!rc) rc = pc_renderer_create(&c->scene, set, w->threads, &c->rend, e);
  if (!rc) {
    rc = pc_film_init(&c->work, set->width, set->height, set->strategy_layers, e);
    if (rc) pc_renderer_destroy(c->rend);
  }
  if (rc) { pc_scene_free(&c->scene); return rc; }
  c->loaded = true;
  return 0;
}

static void thread_main(void *arg) {
  pc_wrender *w = arg;
  job_ctx ctx = {0};
  uint64_t loaded_job = 0;
  for (;;) {
    uv_mutex_lock(&w->mu);
    while (!w->quit && !(w->have_range && !w->range_done)) uv_cond_wait(&w->cv, &w->mu);
    if (w->quit) { uv_mutex_unlock(&w->mu); break; }
    uint64_t job = w->job_id, first = w->first, count = w->count;
    pc_render_settings set = w->set;
    char path[sizeof w->scene_path], root[sizeof w->scene_root];
    memcpy(path, w->scene_path, sizeof path);
    memcpy(root, w->scene_root, sizeof root);
    uv_mutex_unlock(&w->mu);

    pc_err e = {0};
    int rc = 0;
    if (!ctx.loaded || loaded_job != job) {
      rc = ctx_load(&ctx, w, &set, path, root, &e);
      loaded_job = rc ? 0 : job;
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
      pc_film_clear(&ctx.work);
      double t0 = now_s();
      rc = pc_render_iterations(ctx.rend, first + done, batch, &ctx.work, &st, &w->cancel, NULL, NULL, &e);
      double dt = now_s() - t0;
      uint64_t got = ctx.work.layers[PC_LAYER_PT].count;
      if (rc == PC_ECANCELED) rc = 0;
      if (rc || got > batch) break;
      uv_mutex_lock(&w->mu);
      if (got) {
        if (w->pend_count == 0) w->pend_first = first + done;
        rc = pc_film_add(&w->pending, &ctx.work, &e);
        w->pend_count += got;
        pc_render_stats_add(&w->pend_stats, &st);
        w->rendered += got;
        if (dt > 0) w->rate = w->rate > 0 ? 0.5 * w->rate + 0.5 * (double)got / dt : (double)got / dt;
      }
      uv_mutex_unlock(&w->mu);
      done += got;
      uv_async_send(w->notify);
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
  ctx_free(&ctx);
}

int pc_wrender_start(pc_wrender *w, int threads, uv_async_t *notify, pc_err *e) {
  memset(w, 0, sizeof *w);
  w->threads = threads;
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
  if (w->pending_ready) pc_film_free(&w->pending);
  uv_cond_destroy(&w->cv);
  uv_mutex_destroy(&w->mu);
}

int pc_wrender_assign(pc_wrender *w, uint64_t job, uint64_t range, uint64_t first, uint64_t count,
                      const pc_render_settings *s, const char *scene_path, const char *scene_root, pc_err *e) {
  uv_mutex_lock(&w->mu);
  int rc = 0;
  if (w->pending_ready && (w->pending.w != s->width || w->pending.h != s->height)) {
    pc_film_free(&w->pending);
    w->pending_ready = false;
  }
  if (!w->pending_ready) {
    rc = pc_film_init(&w->pending, s->width, s->height, s->strategy_layers, e);
    w->pending_ready = rc == 0;
  } else {
    pc_film_clear(&w->pending);
  }
  if (!rc) {
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
  }
  uv_mutex_unlock(&w->mu);
  return rc;
}
