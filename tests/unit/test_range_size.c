/* test_range_size.c: the coordinator's range sizing (coordinator/range_size.c): probes for
 * unmeasured workers, the range_seconds cap, the floor, and, simulated on workers of known
 * speed, that an iteration-bounded job's ranges shrink at the end so the workers finish
 * within about PC_RANGE_MIN_SECONDS of each other with every iteration handed out once. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "range_size.h"

static void single_requests(void **st) {
  (void)st;
  pc_range_size_in in = {.rate = 0, .range_seconds = 3, .bounded = true, .unassigned = 500};
  assert_int_equal(pc_range_size(&in), 1); /* probe */
  in.rate = 20;
  in.bounded = false;
  assert_int_equal(pc_range_size(&in), 60); /* time-bounded: range_seconds of work */
  in.bounded = true;
  in.others_rate = 20;
  assert_int_equal(pc_range_size(&in), 60); /* plenty left: the cap */
  in.unassigned = 100;
  in.outstanding = 30;
  assert_int_equal(pc_range_size(&in), 32); /* half of 130 * 20/40 */
  in.unassigned = 12;
  in.outstanding = 4;
  assert_int_equal(pc_range_size(&in), 8); /* the whole share (16/2): under the floor of half a second */
  in.unassigned = 30;
  assert_int_equal(pc_range_size(&in), 10); /* the floor: half a second, less than the share (17) */
  in.unassigned = 3;
  assert_int_equal(pc_range_size(&in), 3); /* never more than is left */
  in.range_seconds = 0.1;
  in.unassigned = 100;
  assert_int_equal(pc_range_size(&in), 2); /* the cap wins over the floor */
  in.range_seconds = 3;
  in.others_rate = 0;
  in.outstanding = 0;
  in.unassigned = 40;
  assert_int_equal(pc_range_size(&in), 20); /* one worker so far: half kept back for any other */
  /* a worker whose uploads take 0.4 s to compress: ranges (and the floor) of 8 s, so the
   * upload costs it 5%; capped at PC_WIRE_UPLOAD_MAX_INTERVAL; no effect on a probe */
  in.bounded = false;
  in.upload_seconds = 0.4;
  assert_int_equal(pc_range_size(&in), 160);
  in.upload_seconds = 100;
  assert_int_equal(pc_range_size(&in), 600);
  in.bounded = true;
  in.unassigned = 1000;
  in.others_rate = 20;
  in.outstanding = 0;
  in.upload_seconds = 0.4;
  assert_int_equal(pc_range_size(&in), 160); /* 8 s of work, under half the share (250) */
  in.unassigned = 200;
  assert_int_equal(pc_range_size(&in), 100); /* the whole share (100) is under the 8 s floor (160) */
  in.unassigned = 400;
  assert_int_equal(pc_range_size(&in), 160); /* the floor (160) over half the share (100) */
  in.rate = 0;
  assert_int_equal(pc_range_size(&in), 1);
  in.rate = 20;
  in.upload_seconds = 0;
  in.unassigned = 40;
  in.others_rate = 0;
  in.alone = true;
  assert_int_equal(pc_range_size(&in), 40); /* nobody else will come: all that is left */
  in.unassigned = 100;
  assert_int_equal(pc_range_size(&in), 60); /* still the cap */
  in.rate = 0;
  assert_int_equal(pc_range_size(&in), 100); /* alone and unmeasured: no probe, the whole job */
  in.bounded = false;
  assert_int_equal(pc_range_size(&in), 1); /* but a time-bounded job is probed */
  in.bounded = true;
  in.rate = 20;
  /* a job of a study group bound at 100 iterations takes turns with the others of its group:
     ranges of at most 100 / PC_RANGE_INTERLEAVE, rounded up; not below 1, never past what is
     left, and a probe stays a probe */
  in.interleaved = 100;
  assert_int_equal(pc_range_size(&in), (100 + PC_RANGE_INTERLEAVE - 1) / PC_RANGE_INTERLEAVE);
  in.unassigned = 3;
  assert_int_equal(pc_range_size(&in), 3);
  in.interleaved = 2;
  assert_int_equal(pc_range_size(&in), 1);
  in.rate = 0;
  assert_int_equal(pc_range_size(&in), 1);
  /* only a bounded job: a time-bounded one is sized by time */
  in.rate = 20;
  in.bounded = false;
  in.interleaved = 100;
  assert_int_equal(pc_range_size(&in), 60);
}

#define NW 3
typedef struct sim {
  double rate[NW];     /* true speed */
  double reported[NW]; /* what the scheduler believes */
  double busy_until[NW], start[NW];
  uint64_t first[NW], count[NW];
} sim;

/* Runs a job of `total` iterations on nw workers; returns the spread of their finishing
 * times and checks that the ranges tile [0, total) and the last ones are short. */
static double simulate(sim *s, int nw, uint64_t total, double range_seconds) {
  uint64_t next = 0, largest = 0, last = 0;
  double t = 0, finish[NW] = {0};
  for (int i = 0; i < nw; i++) s->busy_until[i] = s->count[i] = 0;
  for (;;) {
    int w = 0; /* the worker that asks next: the first to become idle */
    for (int i = 1; i < nw; i++)
      if (s->busy_until[i] < s->busy_until[w]) w = i;
    t = s->busy_until[w];
    if (s->count[w]) finish[w] = t;
    if (next >= total) {
      s->busy_until[w] = INFINITY;
      bool all = true;
      for (int i = 0; i < nw; i++) all = all && isinf(s->busy_until[i]);
      if (all) break;
      continue;
    }
    pc_range_size_in in = {.rate = s->reported[w], .range_seconds = range_seconds, .bounded = true,
                           .unassigned = total - next};
    for (int i = 0; i < nw; i++) {
      if (i == w || isinf(s->busy_until[i])) continue;
      in.others_rate += s->reported[i];
      double done = (t - s->start[i]) * s->rate[i];
      if (done < (double)s->count[i]) in.outstanding += (double)s->count[i] - done;
    }
    uint64_t n = pc_range_size(&in);
    assert_true(n >= 1 && n <= total - next);
    s->first[w] = next;
    s->count[w] = n;
    s->start[w] = t;
    s->busy_until[w] = t + (double)n / s->rate[w];
    next += n;
    if (n > largest) largest = n;
    last = n;
  }
  assert_int_equal(next, total);
  assert_true(last < largest);
  double lo = INFINITY, hi = 0;
  for (int i = 0; i < nw; i++) {
    lo = fmin(lo, finish[i]);
    hi = fmax(hi, finish[i]);
  }
  return hi - lo;
}

static void tail_balance(void **st) {
  (void)st;
  /* two equal workers, as in the scaling benchmark */
  sim a = {.rate = {20, 20}, .reported = {20, 20}};
  assert_true(simulate(&a, 2, 512, 3) <= PC_RANGE_MIN_SECONDS + 1e-9);
  /* unequal speeds, three workers */
  sim b = {.rate = {30, 10, 20}, .reported = {30, 10, 20}};
  assert_true(simulate(&b, 3, 1000, 3) <= PC_RANGE_MIN_SECONDS + 1e-9);
  /* one worker 25% slower than it reports: the half kept back evens it out */
  sim c = {.rate = {15, 20}, .reported = {20, 20}};
  assert_true(simulate(&c, 2, 512, 3) <= 2 * PC_RANGE_MIN_SECONDS);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(single_requests), cmocka_unit_test(tail_balance)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
