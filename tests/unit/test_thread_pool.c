/* test_thread_pool.c: a parallel loop runs every item once, on the pool's threads and the
 * caller; the pool's threads take the name of the thread that made the pool (a renderer's
 * pc-render, a coordinator's pc-coord: what the benchmarks split CPU time by, and what `top -H`
 * shows) and the caller keeps its own; pc_thread_set_name cuts a name to
 * the kernel's 15 characters instead of failing. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

#include "thread_pool.h"

#define ITEMS 4000
#define THREADS 3

typedef struct loop_state {
  atomic_int runs[ITEMS];
  atomic_int by_thread[THREADS];
  atomic_int arrived;
  char names[THREADS][16];
} loop_state;

static void record(void *arg, int thread, int item) {
  loop_state *s = arg;
  atomic_fetch_add(&s->runs[item], 1);
  if (atomic_fetch_add(&s->by_thread[thread], 1) == 0) {
    /* a thread's first item: note its name, then wait until every thread holds one, so that
     * each takes part (the others are still free to claim the remaining items meanwhile) */
    assert_int_equal(pthread_getname_np(pthread_self(), s->names[thread], sizeof s->names[thread]), 0);
    atomic_fetch_add(&s->arrived, 1);
    while (atomic_load(&s->arrived) < THREADS) usleep(1000);
  }
}

static void test_every_item_once_on_named_threads(void **state) {
  (void)state;
  char now[16];
  assert_int_equal(pthread_setname_np(pthread_self(), "test-caller"), 0); /* before the pool */
  pc_pool *p = NULL;
  pc_err e = {0};
  assert_int_equal(pc_pool_create(THREADS, &p, &e), PC_OK);
  assert_int_equal(pc_pool_size(p), THREADS);
  static loop_state s;
  memset(&s, 0, sizeof s);
  pc_pool_run(p, ITEMS, record, &s);
  for (int i = 0; i < ITEMS; i++) assert_int_equal(atomic_load(&s.runs[i]), 1);
  assert_string_equal(s.names[0], "test-caller"); /* thread 0 is the caller, not renamed */
  for (int t = 1; t < THREADS; t++) {
    assert_true(atomic_load(&s.by_thread[t]) > 0);
    assert_string_equal(s.names[t], "test-caller");
  }
  assert_int_equal(pthread_getname_np(pthread_self(), now, sizeof now), 0);
  assert_string_equal(now, "test-caller");
  assert_true(pc_pool_cpu_seconds(p) >= 0.0);
  pc_pool_destroy(p);
}

/* A pool made for one loop runs every item once on THREADS threads, each taking part (record
 * waits for all of them), and never more threads than items: with one item, thread 0 alone. */
static void test_run_once(void **state) {
  (void)state;
  static loop_state s;
  memset(&s, 0, sizeof s);
  pc_pool_run_once(THREADS, ITEMS, record, &s);
  for (int i = 0; i < ITEMS; i++) assert_int_equal(atomic_load(&s.runs[i]), 1);
  for (int t = 0; t < THREADS; t++) assert_true(atomic_load(&s.by_thread[t]) > 0);
  memset(&s, 0, sizeof s);
  atomic_store(&s.arrived, THREADS - 1); /* one thread to wait for */
  pc_pool_run_once(0, 1, record, &s);
  assert_int_equal(atomic_load(&s.runs[0]), 1);
  assert_int_equal(atomic_load(&s.by_thread[0]), 1);
}

static void *name_long(void *arg) {
  char *got = arg;
  pc_thread_set_name("pc-a-name-longer-than-fifteen");
  if (pthread_getname_np(pthread_self(), got, 16) != 0) got[0] = '\0';
  return NULL;
}

static void test_long_name_is_cut(void **state) {
  (void)state;
  char got[16] = {0};
  pthread_t t;
  assert_int_equal(pthread_create(&t, NULL, name_long, got), 0);
  assert_int_equal(pthread_join(t, NULL), 0);
  assert_string_equal(got, "pc-a-name-longe");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_every_item_once_on_named_threads),
      cmocka_unit_test(test_run_once),
      cmocka_unit_test(test_long_name_is_cut),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
