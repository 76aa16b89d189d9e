/* thread_pool.c: see thread_pool.h. */
#include "thread_pool.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

struct pc_pool {
  int n;
  pthread_t *threads;
  pthread_mutex_t mu;
  pthread_cond_t cv_start, cv_done;
  uint64_t generation;
  int running; /* workers still inside the current loop */
  bool quit;
  pc_pool_fn fn;
  void *arg;
  int nitems;
  atomic_int next;
};

typedef struct worker_arg {
  pc_pool *p;
  int index;
} worker_arg;

static void drain(pc_pool *p, int thread) {
  for (;;) {
    int i = atomic_fetch_add_explicit(&p->next, 1, memory_order_relaxed);
    if (i >= p->nitems) break;
    p->fn(p->arg, thread, i);
  }
}

static void *worker_main(void *v) {
  worker_arg wa = *(worker_arg *)v;
  free(v); /* named as the thread that made the pool: a renderer's, or a coordinator's loop */
  pc_pool *p = wa.p;
  uint64_t seen = 0;
  pthread_mutex_lock(&p->mu);
  for (;;) {
    while (!p->quit && p->generation == seen) pthread_cond_wait(&p->cv_start, &p->mu);
    if (p->quit) break;
    seen = p->generation;
    pthread_mutex_unlock(&p->mu);
    drain(p, wa.index);
    pthread_mutex_lock(&p->mu);
    if (--p->running == 0) pthread_cond_signal(&p->cv_done);
  }
  pthread_mutex_unlock(&p->mu);
  return NULL;
}

int pc_pool_create(int nthreads, pc_pool **out, pc_err *e) {
  if (nthreads < 1 || nthreads > 1024) return pc_errf(e, PC_EINVAL, "thread count %d out of range 1..1024", nthreads);
  pc_pool *p = calloc(1, sizeof *p);
  if (!p) return pc_errf(e, PC_ENOMEM, "out of memory for the thread pool");
  p->n = nthreads;
  if (pthread_mutex_init(&p->mu, NULL) != 0) { free(p); return pc_errf(e, PC_EIO, "pthread_mutex_init failed"); }
  if (pthread_cond_init(&p->cv_start, NULL) != 0 || pthread_cond_init(&p->cv_done, NULL) != 0) {
    pthread_mutex_destroy(&p->mu);
    free(p);
    return pc_errf(e, PC_EIO, "pthread_cond_init failed");
  }
  p->threads = calloc((size_t)nthreads, sizeof(pthread_t));
  if (!p->threads) { pc_pool_destroy(p); return pc_errf(e, PC_ENOMEM, "out of memory for the thread pool"); }
  for (int i = 1; i < nthreads; i++) {
    worker_arg *wa = malloc(sizeof *wa);
    if (!wa) { p->n = i; pc_pool_destroy(p); return pc_errf(e, PC_ENOMEM, "out of memory for the thread pool"); }
    wa->p = p;
    wa->index = i;
    int rc = pthread_create(&p->threads[i], NULL, worker_main, wa);
    if (rc != 0) {
      free(wa);
      p->n = i;
      pc_pool_destroy(p);
      return pc_errf(e, PC_EIO, "cannot start render thread %d: %s", i, strerror(rc));
    }
  }
  *out = p;
  return PC_OK;
}

void pc_pool_destroy(pc_pool *p) {
  if (!p) return;
  pthread_mutex_lock(&p->mu);
  p->quit = true;
  pthread_cond_broadcast(&p->cv_start);
  pthread_mutex_unlock(&p->mu);
  for (int i = 1; i < p->n; i++)
    if (p->threads) pthread_join(p->threads[i], NULL);
  pthread_cond_destroy(&p->cv_start);
  pthread_cond_destroy(&p->cv_done);
  pthread_mutex_destroy(&p->mu);
  free(p->threads);
  free(p);
}

int pc_pool_size(const pc_pool *p) { return p->n; }

void pc_pool_run(pc_pool *p, int nitems, pc_pool_fn fn, void *arg) {
  if (nitems <= 0) return;
  pthread_mutex_lock(&p->mu);
  p->fn = fn;
  p->arg = arg;
  p->nitems = nitems;
  atomic_store(&p->next, 0);
  p->running = p->n - 1;
  p->generation++;
  pthread_cond_broadcast(&p->cv_start);
  pthread_mutex_unlock(&p->mu);
  drain(p, 0);
  pthread_mutex_lock(&p->mu);
  while (p->running > 0) pthread_cond_wait(&p->cv_done, &p->mu);
  pthread_mutex_unlock(&p->mu);
}

void pc_pool_run_once(int threads, int nitems, pc_pool_fn fn, void *arg) {
  if (nitems <= 0) return;
  if (threads <= 0) threads = pc_cpu_count();
  if (threads > nitems) threads = nitems;
  pc_pool *p = NULL;
  if (threads > 1 && pc_pool_create(threads, &p, NULL) == PC_OK) {
    pc_pool_run(p, nitems, fn, arg);
    pc_pool_destroy(p);
    return;
  }
  for (int i = 0; i < nitems; i++) fn(arg, 0, i); /* one thread, or no more to be had */
}

static double clock_seconds(clockid_t id) {
  struct timespec ts;
  if (clock_gettime(id, &ts) != 0) return -1.0;
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double pc_pool_cpu_seconds(const pc_pool *p) {
  double sum = clock_seconds(CLOCK_THREAD_CPUTIME_ID);
  for (int i = 1; i < p->n && sum >= 0; i++) {
    clockid_t id;
    double s = pthread_getcpuclockid(p->threads[i], &id) == 0 ? clock_seconds(id) : -1.0;
    sum = s < 0 ? -1.0 : sum + s;
  }
  return sum;
}

void pc_thread_set_name(const char *name) {
  char cut[16];
  snprintf(cut, sizeof cut, "%s", name);
  /* for the calling thread glibc sets the name with prctl, which only refuses a name longer
   * than the kernel's 15 characters (cut above); a refusal would leave the inherited name,
   * which only tools read */
  (void)pthread_setname_np(pthread_self(), cut);
}

int pc_cpu_count(void) {
  long n = sysconf(_SC_NPROCESSORS_ONLN);
  return n >= 1 ? (int)(n > 1024 ? 1024 : n) : 1;
}
