/* pilot.c: the pilot of `--method auto` (pilot.h, docs/auto.md): the candidate grid, the
 * choice by efficiency and its one-line report. */
#include "pilot.h"

#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static double clock_s(clockid_t id) {
  struct timespec ts;
  if (clock_gettime(id, &ts) != 0) return 0;
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double now_s(void) { return clock_s(CLOCK_MONOTONIC); }

/* Stage 1's candidates (BDPT, PT, K = 1 and K = 2) share 5 slices. An iteration-bound job gives
 * each PC_PILOT_FRACTION / 3 of its spp, as before PT was a candidate: PT's iterations cost a
 * third to a half of BDPT's. */
#define PILOT_SLICES 5
#define PILOT_STAGE1 3
/* The estimate needs 2 iterations (1 degree of freedom per pixel, averaged over the image). */
#define PILOT_MIN_ITERATIONS 2
/* The second batch's seed: the pilot's seed is the job's xor one constant, this is it xor
 * another, so it equals neither the job's nor the first batch's. */
#define SECOND_BATCH_SALT UINT64_C(0x6a09e667f3bcc909)

void pc_pilot_budget(double seconds, uint64_t spp, double *slice_seconds, uint64_t *min_iterations) {
  *min_iterations = PILOT_MIN_ITERATIONS;
  *slice_seconds = 0;
  if (seconds > 0) *slice_seconds = seconds * PC_PILOT_FRACTION / PILOT_SLICES;
  else if (spp > 0) {
    uint64_t n = (uint64_t)((double)spp * PC_PILOT_FRACTION / PILOT_STAGE1);
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

/* What stage 5's step divides the base's light-tracing paths by (step <= 2). */
static uint64_t light_divisor(int step) {
  uint64_t div = 1;
  for (int j = 0; j < step; j++) div *= PC_PILOT_LIGHT_DIVISOR;
  return div;
}

/* "pcbpt K=2", "pcbpt K=1 mis 4 N_L/4" */
static void pcbpt_label(pc_pilot_candidate *c) {
  int n = snprintf(c->label, sizeof c->label, "pcbpt K=%d", c->set.pcbpt_k);
  if (c->mis_raised && n > 0 && (size_t)n < sizeof c->label)
    n += snprintf(c->label + n, sizeof c->label - (size_t)n, " mis %g", (double)c->set.mis_count);
  if (c->light_step && n > 0 && (size_t)n < sizeof c->label)
    snprintf(c->label + n, sizeof c->label - (size_t)n, " N_L/%llu", (unsigned long long)light_divisor(c->light_step));
}

/* count > 0: a PCBPT candidate whose inner strategies carry that count in the MIS weights
 * instead of the base settings' (stage 4). `counts`: rendered whatever the data says (stages 1
 * and 4), so its iterations may count in the image. */
static void add_candidate(pc_pilot *p, const pc_render_settings *base, pc_method m, int k, float count, bool counts) {
  pc_pilot_candidate *c = &p->c[p->n++];
  memset(c, 0, sizeof *c);
  c->counts = counts;
  c->set = *base;
  c->set.method = m;
  c->set.seed = pc_pilot_seed(base->seed);
  c->relmse = c->own_relmse = -1;
  if (m == PC_METHOD_PCBPT) {
    c->set.pcbpt_k = k;
    c->mis_raised = count > 0;
    if (c->mis_raised) {
      c->set.mis_mode = PC_MIS_COUNT;
      c->set.mis_count = count;
    }
    pcbpt_label(c);
  } else {
    snprintf(c->label, sizeof c->label, "%s", pc_method_name(m));
  }
}

/* Stage 5: candidate `from` (PCBPT) again with the base's light-tracing paths divided by
 * PC_PILOT_LIGHT_DIVISOR once more. False when there are too few to divide. */
static bool add_fewer_lights(pc_pilot *p, const pc_render_settings *base, int from) {
  const pc_pilot_candidate *f = &p->c[from];
  uint64_t all = base->light_paths ? base->light_paths : (uint64_t)base->width * (uint64_t)base->height;
  uint64_t left = all / light_divisor(f->light_step + 1);
  if (left < 1) return false;
  pc_pilot_candidate *c = &p->c[p->n];
  add_candidate(p, base, PC_METHOD_PCBPT, f->set.pcbpt_k, f->mis_raised ? f->set.mis_count : 0.f, false);
  c->light_step = f->light_step + 1;
  c->set.light_paths = left;
  pcbpt_label(c);
  return true;
}

void pc_pilot_free(pc_pilot *p) {
  for (int i = 0; i < p->n; i++) {
    free(p->c[i].mean);
    free(p->c[i].var);
    p->c[i].mean = p->c[i].var = NULL;
    p->c[i].npix = 0;
  }
}

int pc_pilot_keep_image(pc_pilot_candidate *c, int w, int h, const float *mean, const float *var, pc_err *e) {
  free(c->mean);
  free(c->var);
  c->mean = c->var = NULL;
  c->npix = c->nx = 0;
  if (!var || w < 1 || h < 1) return PC_OK; /* it cannot tell its variance: no image */
  int step = 1;
  while ((size_t)((w + step - 1) / step) * (size_t)((h + step - 1) / step) > PC_PILOT_MAX_PIXELS) step++;
  int nx = (w + step - 1) / step, ny = (h + step - 1) / step;
  size_t n = (size_t)nx * (size_t)ny * 3;
  c->mean = malloc(n * sizeof *c->mean);
  c->var = malloc(n * sizeof *c->var);
  if (!c->mean || !c->var) {
    free(c->mean);
    free(c->var);
    c->mean = c->var = NULL;
    return pc_errf(e, PC_ENOMEM, "auto pilot: out of memory for a %dx%d image", nx, ny);
  }
  size_t k = 0;
  for (int y = 0; y < h; y += step)
    for (int x = 0; x < w; x += step)
      for (int ch = 0; ch < 3; ch++, k++) {
        size_t j = ((size_t)y * (size_t)w + (size_t)x) * 3 + (size_t)ch;
        c->mean[k] = mean[j];
        c->var[k] = var[j];
      }
  c->npix = nx * ny;
  c->nx = nx;
  return PC_OK;
}

/* The neighbourhood a value's denominator comes from: the (2 R + 1)^2 square around its pixel,
 * without the pixel itself. */
#define RING_RADIUS 2

/* relMSE of every candidate with an image, each value's variance v_c divided by the same
 * denominator for all: the square of the pooled mean m of all candidates' images (weighted by
 * iterations) around the value's pixel, not at it, less that ring mean's own variance (E[r^2] =
 * exact^2 + v_r, as in pc_film_relmse_estimate), plus PC_RELMSE_EPS; averaged over the kept
 * values. The same denominator keeps the ranking free of the noise of each candidate's own mean,
 * and taking it from the neighbours keeps it free of the pixel's own noise: where a candidate met
 * a rare large contribution, its variance there is large, and a pooled mean at the pixel would
 * hold the same contribution and divide it away. Candidates share their paths, so that pooled
 * mean carries each one's noise (and stage 4's twin, the same paths weighted otherwise, twice):
 * on ajar-door (tests/bench/bench_pilot: 60 pilots of 14 iterations at 128x128 against all 840
 * iterations of each) it rated BDPT 4.4x worse than K = 1 per iteration where the long render
 * says 1.9x, and K = 2 1.4x worse than K = 1 where it is 0.80x; from the ring, 1.78x and 0.79x. */
static void pooled_relmse(pc_pilot *p) {
  int npix = 0, nx = 0;
  double n_all = 0;
  for (int i = 0; i < p->n; i++) {
    pc_pilot_candidate *c = &p->c[i];
    c->relmse = c->own_relmse;
    if (!c->npix || c->iterations < 2) continue;
    if (npix && (c->npix != npix || c->nx != nx)) return; /* not the same image: own estimates only */
    npix = c->npix;
    nx = c->nx;
    n_all += (double)c->iterations;
  }
  if (!npix || nx < 1) return;
  size_t nv = (size_t)npix * 3;
  double *m = malloc(nv * sizeof *m), *vm = malloc(nv * sizeof *vm);
  if (!m || !vm) { /* own estimates only */
    free(m);
    free(vm);
    return;
  }
  for (size_t k = 0; k < nv; k++) {
    m[k] = vm[k] = 0;
    for (int i = 0; i < p->n; i++) {
      const pc_pilot_candidate *c = &p->c[i];
      if (!c->npix || c->iterations < 2) continue;
      double w = (double)c->iterations / n_all;
      m[k] += w * c->mean[k];
      vm[k] += w * w * c->var[k];
    }
  }
  /* A candidate that does not share the others' paths (PT): its disagreement with the mean of
   * the others, beyond what both images' variances explain, is error its own spread cannot show
   * (light it has not found yet: a caustic a few iterations of PT miss leaves an image darker
   * there and quieter too). The others' variance is taken as if they were fully correlated
   * (they share their paths), (sum_i w_i sqrt(v_i))^2, its upper bound: an honest candidate's
   * excess is then <= 0 in expectation, and it is added only where it is above 3 standard
   * errors of its own mean over the values (adding its positive part alone put an honest PT
   * 1.8% behind: test_auto's test_pt_disagreement). */
  int lone = -1;
  for (int i = 0; i < p->n; i++)
    if (p->c[i].npix && p->c[i].iterations >= 2 && p->c[i].set.method == PC_METHOD_PT) lone = i;
  double n_others = lone >= 0 ? n_all - (double)p->c[lone].iterations : 0, excess = 0, excess2 = 0;
  if (!(n_others > 0)) lone = -1;
  double sum[PC_PILOT_MAX] = {0};
  int ny = npix / nx;
  for (int y = 0; y < ny; y++)
    for (int x = 0; x < nx; x++)
      for (int ch = 0; ch < 3; ch++) {
        size_t k = ((size_t)y * (size_t)nx + (size_t)x) * 3 + (size_t)ch;
        double r = 0, vr = 0;
        int n = 0;
        for (int yy = y - RING_RADIUS; yy <= y + RING_RADIUS; yy++)
          for (int xx = x - RING_RADIUS; xx <= x + RING_RADIUS; xx++) {
            if (yy < 0 || yy >= ny || xx < 0 || xx >= nx || (xx == x && yy == y)) continue;
            size_t q = ((size_t)yy * (size_t)nx + (size_t)xx) * 3 + (size_t)ch;
            r += m[q];
            vr += vm[q];
            n++;
          }
        if (n) r /= n, vr /= (double)n * n;
        else r = m[k], vr = vm[k]; /* a single pixel: it is its own neighbourhood */
        double den = fmax(r * r - vr, 0.0) + PC_RELMSE_EPS;
        for (int i = 0; i < p->n; i++)
          if (p->c[i].npix && p->c[i].iterations >= 2) sum[i] += p->c[i].var[k] / den;
        if (lone >= 0) {
          double mo = 0, so = 0;
          for (int i = 0; i < p->n; i++) {
            const pc_pilot_candidate *c = &p->c[i];
            if (i == lone || !c->npix || c->iterations < 2) continue;
            double w = (double)c->iterations / n_others;
            mo += w * c->mean[k];
            so += w * sqrt(fmax(c->var[k], 0.f));
          }
          double d = p->c[lone].mean[k] - mo, x = (d * d - p->c[lone].var[k] - so * so) / den;
          excess += x;
          excess2 += x * x;
        }
      }
  free(m);
  free(vm);
  for (int i = 0; i < p->n; i++)
    if (p->c[i].npix && p->c[i].iterations >= 2) p->c[i].relmse = sum[i] / (double)nv;
  if (lone >= 0) {
    double mx = excess / (double)nv, se = sqrt(fmax(excess2 / (double)nv - mx * mx, 0) / (double)nv);
    if (mx > 3 * se) p->c[lone].relmse += mx;
  }
}

/* The candidate of method m and (for PCBPT) K = k, with the base MIS count or the raised one,
 * and stage 5's light step (0: the base's light-tracing paths), or -1. */
static int find_step(const pc_pilot *p, pc_method m, int k, bool raised, int step) {
  for (int i = 0; i < p->n; i++)
    if (p->c[i].set.method == m &&
        (m != PC_METHOD_PCBPT ||
         (p->c[i].set.pcbpt_k == k && p->c[i].mis_raised == raised && p->c[i].light_step == step)))
      return i;
  return -1;
}

static int find(const pc_pilot *p, pc_method m, int k, bool raised) { return find_step(p, m, k, raised, 0); }

/* The cost the candidates are compared by: CPU seconds of the render threads when every
 * candidate has them, else wall seconds. The pilot's short ranges run beside the farm's other
 * work (on an embedded farm, the coordinator merging and writing the candidates' images on the
 * same cores): a render thread that loses its core stalls the others at the next barrier, and
 * PCBPT, with more phases per iteration, stalls more. On cornell-box 128x128 that put K = 1 at
 * 1.3-1.6x BDPT's wall time per iteration in the pilot against 1.15-1.2x in a render of its own;
 * in CPU seconds the pilot saw 1.07-1.38 (docs/auto.md). */
static bool cpu_known(const pc_pilot *p) {
  for (int i = 0; i < p->n; i++)
    if (p->c[i].iterations && !(p->c[i].cpu_seconds > 0)) return false;
  return true;
}

static double pilot_cost(const pc_pilot_candidate *c, bool cpu) { return cpu ? c->cpu_seconds : c->seconds; }

/* A raised-count candidate does the work of its base candidate (same K, same iterations: the
 * count only weights): their cost is one quantity measured twice, and the mean of the two is the
 * better estimate of it (in the pilot of a 128x128 render on a loaded machine the two differed
 * by up to 35%, which would have decided the choice instead of their errors). */
static double candidate_cost(const pc_pilot *p, int i, bool cpu) {
  const pc_pilot_candidate *c = &p->c[i];
  if (c->set.method != PC_METHOD_PCBPT || c->light_step) return pilot_cost(c, cpu);
  int twin = find(p, PC_METHOD_PCBPT, c->set.pcbpt_k, !c->mis_raised);
  if (twin < 0 || p->c[twin].iterations != c->iterations) return pilot_cost(c, cpu);
  return 0.5 * (pilot_cost(c, cpu) + pilot_cost(&p->c[twin], cpu));
}

/* The PCBPT candidate chosen by the efficiencies so far (pc_pilot_choose's rule), or -1. */
static int pcbpt_choice(const pc_pilot *p) {
  /* K = 1 unless doubling K is clearly better, step by step (pc_pilot_run) */
  int pc = -1;
  for (int k = 1; k <= 8; k *= 2) {
    int i = find(p, PC_METHOD_PCBPT, k, false);
    if (i < 0) break;
    if (pc < 0) {
      if (p->c[i].efficiency > 0) pc = i;
      continue;
    }
    if (!(p->c[i].efficiency > PC_PILOT_K_MARGIN * p->c[pc].efficiency)) break;
    pc = i;
  }
  /* then the same K with the raised MIS count, if it was tried and is clearly better */
  int raised = pc >= 0 ? find(p, PC_METHOD_PCBPT, p->c[pc].set.pcbpt_k, true) : -1;
  if (raised >= 0 && p->c[raised].efficiency > PC_PILOT_COUNT_MARGIN * p->c[pc].efficiency) pc = raised;
  /* then fewer light-tracing paths, step by step, while each step is clearly better */
  for (int step = 1; pc >= 0; step++) {
    int f = find_step(p, PC_METHOD_PCBPT, p->c[pc].set.pcbpt_k, p->c[pc].mis_raised, step);
    if (f < 0 || !(p->c[f].efficiency > PC_PILOT_LIGHT_MARGIN * p->c[pc].efficiency)) break;
    pc = f;
  }
  return pc;
}

void pc_pilot_choose(pc_pilot *p) {
  pooled_relmse(p);
  bool cpu = cpu_known(p);
  for (int i = 0; i < p->n; i++) {
    pc_pilot_candidate *c = &p->c[i];
    double cost = candidate_cost(p, i, cpu);
    c->efficiency = c->relmse > 0 && cost > 0 ? 1.0 / (c->relmse * cost) : 0;
    /* an image without noise (all black, or exact) is infinitely efficient */
    if (c->relmse == 0 && c->iterations >= 2) c->efficiency = INFINITY;
  }
  int pc = pcbpt_choice(p);
  int bdpt = find(p, PC_METHOD_BDPT, 0, false);
  p->best = pc;
  if (bdpt >= 0 && p->c[bdpt].efficiency > 0 &&
      (pc < 0 || p->c[pc].efficiency < PC_PILOT_BDPT_MARGIN * p->c[bdpt].efficiency))
    p->best = bdpt;
  /* then PT against the winner, by a margin of its own: where it fails (light only through
   * glass) its few iterations are quieter than its long run, and disagree with the others */
  int pt = find(p, PC_METHOD_PT, 0, false);
  if (pt >= 0 && p->c[pt].efficiency > 0 &&
      (p->best < 0 || p->c[pt].efficiency > PC_PILOT_PT_MARGIN * p->c[p->best].efficiency))
    p->best = pt;
  if (p->best < 0) p->best = bdpt >= 0 ? bdpt : 0; /* nothing could tell: BDPT, the safe default */
}

/* A batch's figures and image taken into c: the first batch's as they are; a later batch (other
 * seeds, so none repeats the first's) folded in: the pooled mean of the two images, weighted by
 * iterations, and the variance of that mean. */
static void take_batch(pc_pilot_candidate *c, pc_pilot_candidate *b) {
  if (!c->iterations) {
    free(c->mean);
    free(c->var);
    c->iterations = b->iterations;
    c->seconds = b->seconds;
    c->cpu_seconds = b->cpu_seconds;
    c->own_relmse = b->own_relmse;
    c->npix = b->npix;
    c->nx = b->nx;
    c->mean = b->mean;
    c->var = b->var;
    b->mean = b->var = NULL;
    return;
  }
  double na = (double)c->iterations, nb = (double)b->iterations, n = na + nb;
  if (c->npix && c->npix == b->npix) {
    for (size_t k = 0; k < (size_t)c->npix * 3; k++) {
      c->mean[k] = (float)((na * c->mean[k] + nb * b->mean[k]) / n);
      c->var[k] = (float)((na * na * c->var[k] + nb * nb * b->var[k]) / (n * n));
    }
  }
  /* the own estimates (each against its own batch's mean) combine only roughly, as if both had
   * the same denominator; they are the fallback where no image could be kept */
  if (c->own_relmse >= 0 && b->own_relmse >= 0) c->own_relmse = (na * na * c->own_relmse + nb * nb * b->own_relmse) / (n * n);
  else c->own_relmse = -1;
  c->iterations += b->iterations;
  c->seconds += b->seconds;
  c->cpu_seconds = c->cpu_seconds > 0 && b->cpu_seconds > 0 ? c->cpu_seconds + b->cpu_seconds : -1.0;
}

/* Renders one batch of candidates from..p->n-1 (iterations with seed ^ salt), takes it into
 * them and chooses again. */
static int render_batch(pc_pilot *p, int from, uint64_t iterations, uint64_t salt, pc_pilot_render_fn render,
                        void *user, pc_err *e) {
  int n = p->n - from;
  pc_pilot_candidate out[PC_PILOT_MAX];
  memset(out, 0, sizeof out);
  int rc = render(user, &p->c[from], n, iterations, salt, out, e);
  for (int i = 0; i < n; i++) {
    if (!rc) take_batch(&p->c[from + i], &out[i]);
    free(out[i].mean);
    free(out[i].var);
  }
  if (!rc) pc_pilot_choose(p);
  return rc;
}

/* The second batch: as many iterations as the rest of the 5 slices buys at the first batch's
 * cost of the three together (0 if fewer than 2: a batch needs 2 for its variance). */
static uint64_t second_batch(const pc_pilot *p, double slice) {
  double spent = 0, per_it = 0;
  for (int i = 0; i < p->n; i++) {
    if (!p->c[i].iterations) return 0;
    spent += p->c[i].seconds;
    per_it += p->c[i].seconds / (double)p->c[i].iterations;
  }
  double left = PILOT_SLICES * slice - spent;
  return per_it > 0 && left >= 2 * per_it ? (uint64_t)(left / per_it) : 0;
}

int pc_pilot_run(pc_pilot *p, const pc_render_settings *base, bool with_pt, bool with_fewer_lights, double slice,
                 uint64_t min_it, pc_pilot_render_fn render, void *user, pc_err *e) {
  memset(p, 0, sizeof *p);
  double t0 = now_s();
  /* stage 1: BDPT, PT, K = 1 and K = 2, whatever the data says, so the iterations of BDPT and
   * PCBPT may count in the image; all of them on the same iterations, where the bidirectional
   * ones share their eye and light paths (PCBPT's connections draw from a stream of their own),
   * so the noise of the strategies they share cancels in the comparison: with a batch each of
   * its own, slit-room's K = 1 met a light path through the slit that K = 2's batch did not, and
   * K = 2 looked 170x better */
  add_candidate(p, base, PC_METHOD_BDPT, 0, 0.f, true);
  /* PT is rendered whatever the data says too, but does not count: where it fails (caustics),
   * the rare paths that find the light are fireflies its few pilot iterations would put into
   * the chosen method's image. PT renders its own paths, not the bidirectional ones. Not at all
   * where it cannot sample every path (with_pt false): no margin can make up for missing light. */
  if (with_pt) add_candidate(p, base, PC_METHOD_PT, 0, 0.f, false);
  add_candidate(p, base, PC_METHOD_PCBPT, 1, 0.f, true);
  add_candidate(p, base, PC_METHOD_PCBPT, 2, 0.f, true);
  uint64_t second = 0;
  int rc = render_batch(p, 0, min_it, 0, render, user, e);
  if (!rc && slice > 0 && (second = second_batch(p, slice)) != 0)
    rc = render_batch(p, 0, second, SECOND_BATCH_SALT, render, user, e);
  /* stages 2 and 3: K doubles while the last doubling paid by PC_PILOT_K_MARGIN, on the same
   * iterations; efficiency over K has one peak (more connections cost linearly and gain less
   * each). The uniform mix is not tried: a less defensive mix has heavier tails, which a few
   * iterations miss (docs/auto.md) */
  for (int k = 4; !rc && k <= 8; k *= 2) {
    if (p->c[p->n - 1].efficiency <= PC_PILOT_K_MARGIN * p->c[p->n - 2].efficiency) break;
    add_candidate(p, base, PC_METHOD_PCBPT, k, 0.f, false);
    rc = render_batch(p, p->n - 1, min_it, 0, render, user, e);
    if (!rc && second) rc = render_batch(p, p->n - 1, second, SECOND_BATCH_SALT, render, user, e);
  }
  /* stage 4: K = 1 with the inner strategies' MIS count raised to PC_PILOT_RAISED_COUNT
   * (docs/pmf-ceiling.md: it pays on diffuse scenes, where K = 1 is the best K, and costs on
   * glossy ones), on the same iterations: the same paths and connections, weighted otherwise, at
   * the same cost. Always K = 1, whichever K the doublings reached, so that it too is rendered
   * whatever the data says and its iterations count in the image: when it tried the chosen K its
   * time was lost to the image wherever BDPT won, a fifth of the pilot (on env-objects at 60 s,
   * 0.36 of 1.62 worker-seconds). Only where stage 1 left room in the time budget
   * for its second batch: a refinement of a few per cent is not worth a pilot past its share
   * (glossy-floor at 60 s: 2 iterations of each candidate already take 4% of the budget) */
  float count = fminf(PC_PILOT_RAISED_COUNT, (float)base->pcbpt_m);
  bool room = slice <= 0 || second > 0;
  int k1 = find(p, PC_METHOD_PCBPT, 1, false);
  if (!rc && room && k1 >= 0 && count > pc_render_settings_inner_count(&p->c[k1].set) && p->n < PC_PILOT_MAX) {
    add_candidate(p, base, PC_METHOD_PCBPT, 1, count, true);
    rc = render_batch(p, p->n - 1, min_it, 0, render, user, e);
    if (!rc && second) rc = render_batch(p, p->n - 1, second, SECOND_BATCH_SALT, render, user, e);
  }
  /* stage 5: the PCBPT configuration chosen so far with a PC_PILOT_LIGHT_DIVISOR-th of the
   * light-tracing paths, then with the square of it if that paid, on the same iterations (the
   * first N_L light paths are the same ones, so these share their paths with the others too).
   * Not counted: whether it is rendered depends on the data. Not where the scene has caustics
   * (pilot.h). Also where stage 1 left no room:
   * unlike stage 4's few per cent, this is worth 1.2-2x where it pays (docs/auto.md) */
  for (int step = 1; !rc && with_fewer_lights && step <= 2 && p->n < PC_PILOT_MAX; step++) {
    int from = pcbpt_choice(p);
    if (from < 0 || p->c[from].light_step != step - 1) break; /* the last step did not pay */
    if (!add_fewer_lights(p, base, from)) break;
    rc = render_batch(p, p->n - 1, min_it, 0, render, user, e);
    if (!rc && second) rc = render_batch(p, p->n - 1, second, SECOND_BATCH_SALT, render, user, e);
  }
  if (rc) return rc;
  p->seconds = now_s() - t0;
  return PC_OK;
}

double pc_pilot_counted_share(const pc_pilot *p) {
  int n = 0;
  for (int i = 0; i < p->n; i++) n += p->c[i].counts && p->c[i].iterations > 0;
  return n ? 1.0 / n : 0.0;
}

void pc_pilot_report(const pc_pilot *p, char *buf, size_t size) {
  bool cpu = cpu_known(p);
  size_t n = (size_t)snprintf(buf, size, "chose %s (pilot %.2f s), cost in %s", p->c[p->best].label, p->seconds,
                              cpu ? "CPU ms/it" : "wall ms/it");
  for (int i = 0; i < p->n && n < size; i++) {
    const pc_pilot_candidate *c = &p->c[i];
    double ms = c->iterations ? 1e3 * pilot_cost(c, cpu) / (double)c->iterations : 0;
    double wall = c->iterations ? 1e3 * c->seconds / (double)c->iterations : 0;
    n += (size_t)snprintf(buf + n, size - n, "; %s eff %.4g relMSE %.4g cost %.1f wall %.1f it %llu", c->label,
                          c->efficiency, c->relmse, ms, wall, (unsigned long long)c->iterations);
  }
}
