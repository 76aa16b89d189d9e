/* pilot.c: the pilot of `--method auto` (pilot.h, docs/auto.md): the candidate grid, the
 * choice by efficiency, its one-line report, and the in-process renderer of candidates. */
#include "pilot.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static double clock_s(clockid_t id) {
  struct timespec ts;
  if (clock_gettime(id, &ts) != 0) return 0;
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double now_s(void) { return clock_s(CLOCK_MONOTONIC); }

/* Stage 1 has at most 5 candidates and stage 2 at most 1: the budget is split over 6. */
#define PILOT_SLICES 6
/* The estimate needs 2 iterations (1 degree of freedom per pixel, averaged over the image). */
#define PILOT_MIN_ITERATIONS 2

void pc_pilot_budget(double seconds, uint64_t spp, double *slice_seconds, uint64_t *min_iterations) {
  *min_iterations = PILOT_MIN_ITERATIONS;
  *slice_seconds = 0;
  if (seconds > 0) *slice_seconds = seconds * PC_PILOT_FRACTION / PILOT_SLICES;
  else if (spp > 0) {
    uint64_t n = (uint64_t)((double)spp * PC_PILOT_FRACTION / PILOT_SLICES);
    if (n > *min_iterations) *min_iterations = n;
  } else {
    *min_iterations = 8; /* --halt-noise alone: no budget to take a share of */
  }
}

double pc_pilot_remaining(double seconds, double pilot_seconds) {
  double rest = seconds - pilot_seconds;
  return rest > 0.1 * seconds ? rest : 0.1 * seconds;
}

uint64_t pc_pilot_seed(uint64_t job_seed) { return job_seed ^ UINT64_C(0x9e3779b97f4a7c15); }

static void add_candidate(pc_pilot *p, const pc_render_settings *base, pc_method m, int k, float mix) {
  pc_pilot_candidate *c = &p->c[p->n++];
  memset(c, 0, sizeof *c);
  c->set = *base;
  c->set.method = m;
  c->set.seed = pc_pilot_seed(base->seed);
  c->relmse = -1;
  if (m == PC_METHOD_PCBPT) {
    c->set.pcbpt_k = k;
    c->set.uniform_mix = mix;
    if (mix != base->uniform_mix) snprintf(c->label, sizeof c->label, "pcbpt K=%d mix=%.2g", k, (double)mix);
    else snprintf(c->label, sizeof c->label, "pcbpt K=%d", k);
  } else {
    snprintf(c->label, sizeof c->label, "%s", pc_method_name(m));
  }
}

void pc_pilot_choose(pc_pilot *p) {
  p->best = -1;
  for (int i = 0; i < p->n; i++) {
    pc_pilot_candidate *c = &p->c[i];
    c->efficiency = c->relmse > 0 && c->seconds > 0 ? 1.0 / (c->relmse * c->seconds) : 0;
    /* an image without noise (all black, or exact) is infinitely efficient */
    if (c->relmse == 0 && c->iterations >= 2) c->efficiency = INFINITY;
  }
  int bdpt = -1;
  for (int i = 0; i < p->n; i++) {
    if (p->c[i].set.method == PC_METHOD_BDPT && bdpt < 0) bdpt = i;
    if (p->c[i].efficiency > 0 && (p->best < 0 || p->c[i].efficiency > p->c[p->best].efficiency)) p->best = i;
  }
  if (bdpt >= 0 && p->best >= 0 && p->best != bdpt && p->c[bdpt].efficiency > 0 &&
      p->c[p->best].efficiency < PC_PILOT_BDPT_MARGIN * p->c[bdpt].efficiency)
    p->best = bdpt;
  if (p->best < 0) p->best = bdpt >= 0 ? bdpt : 0; /* nothing could tell: BDPT, the safe default */
}

static int render_from(pc_pilot *p, int from, double slice, uint64_t min_it, pc_pilot_render_fn render, void *user,
                       pc_err *e) {
  for (int i = from; i < p->n; i++) {
    int rc = render(user, &p->c[i].set, slice, min_it, &p->c[i], e);
    if (rc) return rc;
  }
  return PC_OK;
}

int pc_pilot_run(pc_pilot *p, const pc_render_settings *base, double slice, uint64_t min_it, pc_pilot_render_fn render,
                 void *user, pc_err *e) {
  memset(p, 0, sizeof *p);
  double t0 = now_s();
  add_candidate(p, base, PC_METHOD_BDPT, 0, 0);
  add_candidate(p, base, PC_METHOD_PCBPT, 1, base->uniform_mix);
  add_candidate(p, base, PC_METHOD_PCBPT, 2, base->uniform_mix);
  int rc = render_from(p, 0, slice, min_it, render, user, e);
  if (rc) return rc;
  pc_pilot_choose(p);
  /* K = 4 and 8 only while doubling K still paid: efficiency over K has one peak (more
   * connections cost linearly and gain less each), so past a drop there is nothing to find */
  for (int k = 4; k <= 8 && p->c[p->n - 1].efficiency >= p->c[p->n - 2].efficiency; k *= 2) {
    add_candidate(p, base, PC_METHOD_PCBPT, k, base->uniform_mix);
    if ((rc = render_from(p, p->n - 1, slice, min_it, render, user, e)) != 0) return rc;
    pc_pilot_choose(p);
  }
  if (p->c[p->best].set.method == PC_METHOD_PCBPT) {
    int n = p->n;
    add_candidate(p, base, PC_METHOD_PCBPT, p->c[p->best].set.pcbpt_k, base->uniform_mix >= 0.35f ? 0.2f : 0.5f);
    if ((rc = render_from(p, n, slice, min_it, render, user, e)) != 0) return rc;
    pc_pilot_choose(p);
  }
  p->seconds = now_s() - t0;
  return PC_OK;
}

void pc_pilot_report(const pc_pilot *p, char *buf, size_t size) {
  size_t n = (size_t)snprintf(buf, size, "chose %s (pilot %.2f s)", p->c[p->best].label, p->seconds);
  for (int i = 0; i < p->n && n < size; i++) {
    const pc_pilot_candidate *c = &p->c[i];
    double ms = c->iterations ? 1e3 * c->seconds / (double)c->iterations : 0;
    n += (size_t)snprintf(buf + n, size - n, "; %s eff %.4g relMSE %.4g cost ms/it %.1f it %llu", c->label, c->efficiency,
                          c->relmse, ms, (unsigned long long)c->iterations);
  }
}

int pc_pilot_local_render(void *user, const pc_render_settings *set, double seconds, uint64_t min_iterations,
                          pc_pilot_candidate *c, pc_err *e) {
  const pc_pilot_local *l = user;
  pc_film film;
  int rc = pc_film_init(&film, set->width, set->height, 0, e);
  if (rc) return rc;
  pc_renderer *r = NULL;
  pc_render_settings s = *set;
  s.strategy_layers = 0;
  rc = pc_renderer_create(l->scene, &s, l->threads, &r, e);
  pc_render_stats st = {0};
  double spent = 0, cpu = 0, cpu_first = 0;
  uint64_t it = 0;
  /* one iteration at a time, so a slow candidate overruns its slice by one iteration at most.
   * The cost is the process's CPU time, not wall time: on a shared machine the wall time of a
   * few iterations mostly measures the other processes (the renderer's phases all run on its
   * pool, so on an idle machine CPU time / threads is the wall time) */
  while (!rc && (it < min_iterations || spent < seconds)) {
    double t0 = now_s(), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    rc = pc_render_iterations(r, it, 1, &film, &st, NULL, NULL, NULL, e);
    spent += now_s() - t0;
    cpu += clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
    if (it == 0) cpu_first = cpu;
    it++;
  }
  /* the first iteration also warms caches and allocators: the cost per iteration comes from
   * the others when there are any */
  if (it >= 2 && cpu > cpu_first) cpu = (cpu - cpu_first) * (double)it / (double)(it - 1);
  if (!rc) {
    c->iterations = it;
    c->seconds = cpu > 0 ? cpu : spent;
    if (!pc_film_relmse_estimate(&film, &c->relmse)) c->relmse = -1;
  }
  pc_renderer_destroy(r);
  pc_film_free(&film);
  return rc;
}
