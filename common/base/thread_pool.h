/* thread_pool.h: a fixed set of threads that run one parallel loop at a time; the caller
 * takes part as thread 0. Items are claimed dynamically (an atomic counter), so threads of
 * different speed stay busy. */
#ifndef PC_THREAD_POOL_H
#define PC_THREAD_POOL_H

#include "error.h"

typedef struct pc_pool pc_pool;
typedef void (*pc_pool_fn)(void *arg, int thread, int item);

/* nthreads >= 1 (including the caller). The threads take the calling thread's name. */
int pc_pool_create(int nthreads, pc_pool **out, pc_err *e);
void pc_pool_destroy(pc_pool *p);
int pc_pool_size(const pc_pool *p);
/* Runs fn(arg, thread, item) for item in [0, nitems) and returns when all are done. */
void pc_pool_run(pc_pool *p, int nitems, pc_pool_fn fn, void *arg);
/* pc_pool_run on a pool made for the call, of up to `threads` threads (0: one per core; never
 * more than nitems), destroyed after; where no other thread can be had, on the caller's alone
 * (as thread 0). */
void pc_pool_run_once(int threads, int nitems, pc_pool_fn fn, void *arg);
/* CPU seconds the pool's threads (the caller as thread 0 when it is the calling thread) have
 * run so far, from the kernel's per-thread clocks: unlike wall time, it does not grow while
 * another process or thread holds the cores. < 0 when a clock cannot be read. */
double pc_pool_cpu_seconds(const pc_pool *p);
/* Number of online CPUs (at least 1). */
int pc_cpu_count(void);
/* Names the calling thread (at most 15 characters; longer names are cut) for `top -H`, perf
 * and debuggers, and so for the benchmarks' CPU split by role. Threads it then starts inherit
 * the name. Best effort: a name the kernel refuses leaves the thread as it was. Never call it
 * on a process's main thread, whose name is the one `ps` shows. */
void pc_thread_set_name(const char *name);

#endif
