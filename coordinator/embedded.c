/* embedded.c: the one-machine farm of `pcbpt-coord render` (see embedded.h). The coordinator
 * loop and the worker loop each run on their own thread; the caller talks to the coordinator
 * as an ordinary client. The store is volatile (no fsync): its directory is thrown away. */
#include "embedded.h"

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "auth.h"
#include "big_alloc.h"
#include "film.h"
#include "render.h"
#include "serve.h"
#include "thread_pool.h"
#include "wire_log.h"
#include "wire_upload.h"

static void coord_main(void *arg) {
  pc_embedded *f = arg;
  pc_thread_set_name("pc-coord");
  uv_run(&f->loop, UV_RUN_DEFAULT);
}

static void worker_main(void *arg) {
  pc_err e;
  pc_thread_set_name("pc-worker");
  if (pc_worker_run(arg, &e) != 0) pc_wire_log("worker: %s", e.msg); /* (one token for both: cannot happen) */
}

static void walk_close(uv_handle_t *h, void *arg) {
  (void)arg;
  if (!uv_is_closing(h)) uv_close(h, NULL);
}

static int write_token(const char *path, pc_err *e) {
  uint8_t raw[32];
  char hex[2 * sizeof raw + 2];
  randombytes_buf(raw, sizeof raw);
  sodium_bin2hex(hex, sizeof hex, raw, sizeof raw);
  sodium_memzero(raw, sizeof raw);
  size_t n = strlen(hex);
  int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  int rc = 0;
  if (fd < 0 || write(fd, hex, n) != (ssize_t)n) rc = pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  if (fd >= 0 && close(fd) != 0 && !rc) rc = pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  sodium_memzero(hex, sizeof hex);
  return rc;
}

static int rm_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st;
  (void)flag;
  (void)ftw;
  return remove(path) == 0 || errno == ENOENT ? 0 : -1;
}

/* The farm's log lines go to dir/farm.log so the terminal shows only the render's output. */
static int redirect_log(pc_embedded *f, pc_err *e) {
  char path[300];
  snprintf(path, sizeof path, "%s/farm.log", f->dir);
  int fd = open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0600);
  if (fd < 0) return pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  fflush(stderr);
  f->term_fd = dup(STDERR_FILENO);
  if (f->term_fd < 0 || dup2(fd, STDERR_FILENO) < 0) {
    int rc = pc_errf(e, PC_EIO, "redirecting the farm log: %s", strerror(errno));
    close(fd);
    if (f->term_fd >= 0) close(f->term_fd);
    f->term_fd = -1;
    return rc;
  }
  close(fd);
  return 0;
}

int pc_embedded_start(pc_embedded *f, pc_err *e) {
  memset(f, 0, sizeof *f);
  f->term_fd = -1;
  const char *tmp = getenv("TMPDIR");
  snprintf(f->dir, sizeof f->dir, "%s/pcbpt-render-XXXXXX", tmp && *tmp ? tmp : "/tmp");
  if (!mkdtemp(f->dir)) {
    int rc = pc_errf(e, PC_EIO, "%s: cannot create a temporary directory: %s", f->dir, strerror(errno));
    f->dir[0] = 0;
    return rc;
  }
  snprintf(f->token, sizeof f->token, "%s/token", f->dir);
  uint8_t *key = f->key;
  char data[300];
  snprintf(data, sizeof data, "%s/data", f->dir);
  int rc = pc_auth_init(e);
  if (!rc) rc = write_token(f->token, e);
  if (!rc) rc = pc_auth_load_token(f->token, key, e);
  if (!rc) rc = redirect_log(f, e);
  if (rc) goto fail;
  int r = uv_loop_init(&f->loop);
  if (r) { rc = pc_errf(e, PC_EIO, "embedded farm: loop: %s", uv_strerror(r)); goto fail; }
  f->loop_ready = true;
  /* a short tick so the end of a short render is noticed at once; no EXR until the end; long
   * ranges of the one worker, each ending in an upload (a --seconds budget or --halt-noise
   * stops a range early, and uploads within one are spaced by their cost: upload_share) */
  f->coord.tick_ms = 20;
  f->coord.range_seconds = PC_WIRE_UPLOAD_MAX_INTERVAL;
  f->coord.one_worker = true;
  f->coord.exr_interval = 1e9;
  f->coord.volatile_store = true;
  if ((rc = pc_coord_start(&f->coord, &f->loop, "127.0.0.1", 0, data, key, e)) != 0) goto fail;
  if ((r = uv_thread_create(&f->coord_thread, coord_main, f)) != 0) {
    rc = pc_errf(e, PC_EIO, "embedded farm: coordinator thread: %s", uv_strerror(r));
    goto fail;
  }
  f->coord_running = true;
  snprintf(f->hostport, sizeof f->hostport, "127.0.0.1:%d", f->coord.bound_port);
  return 0;
fail:
  pc_embedded_stop(f);
  return rc;
}

int pc_embedded_start_worker(pc_embedded *f, int threads, double upload_share, pc_err *e) {
  char cache[300];
  snprintf(cache, sizeof cache, "%s/cache", f->dir);
  pc_worker_opts o = {.host = "127.0.0.1", .port = f->coord.bound_port, .key = f->key, .threads = threads,
                      .name = "local", .cache_dir = cache, .upload_share = upload_share};
  int rc = pc_worker_create(&o, &f->worker, e);
  if (rc) return rc;
  int r = uv_thread_create(&f->worker_thread, worker_main, f->worker);
  if (r) return pc_errf(e, PC_EIO, "embedded farm: worker thread: %s", uv_strerror(r));
  f->worker_running = true;
  return 0;
}

int pc_embedded_check_memory(const pc_render_settings *set, int threads, int jobs, pc_err *e) {
  size_t limit = pc_big_memory_limit(), job = pc_film_bytes(set->width, set->height, set->strategy_layers);
  size_t need = (size_t)jobs * job + job + pc_renderer_film_bytes(set, threads);
  if (!limit || need <= limit) return PC_OK;
  int nthreads = threads ? threads : pc_cpu_count();
  char what[64];
  if (jobs == 1) snprintf(what, sizeof what, "a %dx%d render", set->width, set->height);
  else snprintf(what, sizeof what, "%d jobs of %dx%d", jobs, set->width, set->height);
  return pc_errf(e, PC_ELIMIT,
                 "%s on %d thread%s take%s %zu MB of films (the coordinator's and the worker's), more than this "
                 "machine's %zu MB of memory",
                 what, nthreads, nthreads == 1 ? "" : "s", jobs == 1 ? "s" : " at least", pc_big_mb(need),
                 pc_big_mb(limit));
}

void pc_embedded_stop(pc_embedded *f) {
  if (f->worker_running) {
    pc_worker_stop(f->worker);
    uv_thread_join(&f->worker_thread);
    f->worker_running = false;
  }
  pc_worker_destroy(f->worker);
  f->worker = NULL;
  if (f->coord_running) {
    pc_coord_stop(&f->coord);
    uv_thread_join(&f->coord_thread);
    f->coord_running = false;
  }
  if (f->loop_ready) {
    /* after a failed start nothing ran the loop: close what was opened */
    uv_walk(&f->loop, walk_close, NULL);
    uv_run(&f->loop, UV_RUN_DEFAULT);
    pc_coord_free(&f->coord);
    if (uv_loop_close(&f->loop) != 0) fprintf(stderr, "embedded farm: the coordinator loop still has open handles\n");
    f->loop_ready = false;
  }
  if (f->term_fd >= 0) {
    fflush(stderr);
    if (dup2(f->term_fd, STDERR_FILENO) < 0) perror("embedded farm: restoring stderr");
    close(f->term_fd);
    f->term_fd = -1;
  }
  sodium_memzero(f->key, sizeof f->key);
  if (f->dir[0] && nftw(f->dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS) != 0)
    fprintf(stderr, "pcbpt-coord render: warning: could not remove %s\n", f->dir);
  f->dir[0] = 0;
}
