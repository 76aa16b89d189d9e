/* test_auto.c: --method auto's pilot (common/render/pilot.h).
 * - choose: the most efficient candidate wins; BDPT keeps ties within PC_PILOT_BDPT_MARGIN; a
 *   pilot that could not tell falls back to BDPT; a noiseless candidate wins (deterministic).
 * - fewer lights: stage 5 tries the chosen PCBPT configuration with a quarter, then a sixteenth,
 *   of the light-tracing paths, each kept only past PC_PILOT_LIGHT_MARGIN, on the same
 *   iterations, never counted in the image.
 * - grid: K = 4 and 8 are tried only while doubling K paid by PC_PILOT_K_MARGIN, a smaller gain
 *   keeps the smaller K, the job's uniform mix is kept, every
 *   candidate renders with the pilot seed, never the job's (a scripted
 *   renderer of known efficiencies: deterministic).
 * - matched: every candidate renders the same iterations (the same batches, seeds and counts).
 * - pooled: candidates are measured against the pooled mean of their images, not each against
 *   its own few iterations' mean.
 * - pooled own noise: that mean is taken around each pixel, not at it, so a candidate whose rare
 *   large contributions are also in the pool (shared paths, stage 4's twin) is not favoured
 *   (equal heavy-tailed estimators, tolerances from their spread over 40 seeds).
 * - PT disagreement: PT, whose paths are its own, carries in its relMSE what its image disagrees
 *   with the others' beyond both variances (an honest PT measures as BDPT does over 40 seeds; one
 *   that missed a tenth of the image loses), and wins only past PC_PILOT_PT_MARGIN.
 * - picks the clear winner on a real scene: ajar-door, where PCBPT K=1's relMSE per iteration is
 *   about half BDPT's (48x48, 64 iterations, seeds 5-7, each image's own estimate: 0.427, 0.457,
 *   0.433 against 0.197, 0.220, 0.243) at a lower cost per iteration, so no timing noise of a
 *   shared machine can reverse it; the pilot's 4 iterations (seed 5) measure 2.6x.
 * - unbiased: on the white furnace (exact 2 everywhere) the mean over 64 seeds of auto's image
 *   (pilot, then the winner with the job's seed, and the counted candidates' films mixed in
 *   with the weight the coordinator gives them under --spp: coordinator/job_prior.c) is 2
 *   within 4 standard errors of the seeds' spread: the choice never leaks into the image. The
 *   pilot's costs are scripted so that its choice is decided by its images alone (BDPT, PT,
 *   PCBPT and PCBPT with stage 5's fewer light paths each win on some seeds, so the job and the
 *   counted candidates it is mixed with differ in their light paths too) and is the same on
 *   every machine: with measured costs and 8
 *   seeds, a loaded CI machine chose otherwise and the 8 seeds' spread came out at 0.4x its
 *   true size (per-seed sd 0.012 over 300 seeds, whose mean was 2.0002 +- 0.0007).
 * Candidates render in this process here (local_render), each keeping its film. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "pilot.h"
#include "rng.h"
#include "stat_util.h"

static void set_candidate(pc_pilot *p, pc_method m, int k, double relmse, double seconds) {
  pc_pilot_candidate *c = &p->c[p->n++];
  memset(c, 0, sizeof *c);
  pc_render_settings_default(&c->set);
  c->set.method = m;
  c->set.pcbpt_k = k;
  c->own_relmse = relmse;
  c->seconds = seconds;
  c->iterations = 4;
}

static void test_choose(void **state) {
  (void)state;
  pc_pilot p = {0};
  set_candidate(&p, PC_METHOD_BDPT, 1, 0.1, 1.0);   /* eff 10 */
  set_candidate(&p, PC_METHOD_PCBPT, 1, 0.05, 1.0); /* eff 20 */
  set_candidate(&p, PC_METHOD_PCBPT, 2, 0.04, 3.0); /* eff 8.3 */
  pc_pilot_choose(&p);
  assert_int_equal(p.best, 1);
  assert_true(fabs(p.c[1].efficiency - 20) < 1e-9);
  /* within the margin BDPT stays */
  p.c[1].own_relmse = 0.1 / (0.5 * (1 + PC_PILOT_BDPT_MARGIN)) * 1.0;
  pc_pilot_choose(&p);
  assert_int_equal(p.best, 0);
  /* nothing could tell (fewer than 2 iterations everywhere): BDPT */
  for (int i = 0; i < p.n; i++) p.c[i].own_relmse = -1;
  pc_pilot_choose(&p);
  assert_int_equal(p.best, 0);
  /* a noiseless candidate is infinitely efficient */
  p.c[2].own_relmse = 0;
  pc_pilot_choose(&p);
  assert_int_equal(p.best, 2);
  /* CPU seconds are the cost when every candidate has them: K = 1 lost wall time to other load
     (wall: eff 8 against BDPT's 10; CPU: 10 against 5) */
  double relmse[3] = {0.1, 0.05, 0.04}, wall[3] = {1.0, 2.5, 3.0}, cpu[3] = {2.0, 2.0, 6.0};
  for (int i = 0; i < p.n; i++) p.c[i].own_relmse = relmse[i], p.c[i].seconds = wall[i], p.c[i].cpu_seconds = cpu[i];
  pc_pilot_choose(&p);
  assert_int_equal(p.best, 1);
  assert_true(fabs(p.c[1].efficiency - 10) < 1e-9);
  /* one candidate without them: wall seconds for all */
  p.c[2].cpu_seconds = -1;
  pc_pilot_choose(&p);
  assert_int_equal(p.best, 0);
  assert_true(fabs(p.c[0].efficiency - 10) < 1e-9);
}

/* The raised MIS count does its twin's work: both are charged the mean of their two measured
 * costs, so the count is chosen by error alone. */
static void test_choose_raised(void **state) {
  (void)state;
  pc_pilot p = {0};
  set_candidate(&p, PC_METHOD_BDPT, 1, 1.0, 1.0);
  set_candidate(&p, PC_METHOD_PCBPT, 1, 0.5, 2.0);
  set_candidate(&p, PC_METHOD_PCBPT, 1, 0.47, 0.5); /* 6% better, but measured 4x cheaper */
  p.c[2].mis_raised = true;
  pc_pilot_choose(&p);
  assert_true(fabs(p.c[1].efficiency - 1 / (0.5 * 1.25)) < 1e-9);
  assert_true(fabs(p.c[2].efficiency - 1 / (0.47 * 1.25)) < 1e-9);
  assert_int_equal(p.best, 1); /* within PC_PILOT_COUNT_MARGIN */
  p.c[2].own_relmse = 0.5 / (1.01 * PC_PILOT_COUNT_MARGIN); /* just past the margin */
  pc_pilot_choose(&p);
  assert_int_equal(p.best, 2);
  /* a raised candidate of other iterations is charged its own cost */
  p.c[2].iterations = 6;
  pc_pilot_choose(&p);
  assert_true(fabs(p.c[2].efficiency - 1 / (p.c[2].own_relmse * 0.5)) < 1e-9);
}

/* Two candidates of equal variance whose few iterations landed on different means: measured
 * each against its own mean, the one that happened to land high looks 9x better; against the
 * pooled mean they are equal (and a third without an image keeps its own estimate). */
static void test_pooled(void **state) {
  (void)state;
  pc_pilot p = {0};
  set_candidate(&p, PC_METHOD_BDPT, 1, 0.5, 1.0);
  set_candidate(&p, PC_METHOD_PCBPT, 1, 0.5, 1.0);
  set_candidate(&p, PC_METHOD_PCBPT, 2, 0.3, 1.0);
  float mean_a[4 * 3], mean_b[4 * 3], var[4 * 3];
  for (int i = 0; i < 12; i++) mean_a[i] = 1, mean_b[i] = 3, var[i] = 0.01f;
  pc_err e = {0};
  assert_int_equal(pc_pilot_keep_image(&p.c[0], 2, 2, mean_a, var, &e), 0);
  assert_int_equal(pc_pilot_keep_image(&p.c[1], 2, 2, mean_b, var, &e), 0);
  pc_pilot_choose(&p);
  /* each pixel's denominator comes from its 3 neighbours: their pooled mean 2, less the
     variance of that ring mean (3 values of variance 0.25 * 0.01 * 2, over 3^2) */
  double expect = 0.01 / (4.0 - 3 * 0.25 * 0.01 * 2 / 9 + PC_RELMSE_EPS);
  assert_true(fabs(p.c[0].relmse - expect) < 1e-6 && fabs(p.c[1].relmse - expect) < 1e-6);
  assert_true(p.c[2].relmse == 0.3);
  assert_int_equal(p.best, 0); /* a tie: BDPT */
  /* without variance there is no image to pool */
  assert_int_equal(pc_pilot_keep_image(&p.c[1], 2, 2, mean_b, NULL, &e), 0);
  assert_int_equal(p.c[1].npix, 0);
  pc_pilot_free(&p);
}

/* The image of n iterations of a heavy-tailed estimator of the value 1 + q x everywhere: each
 * iteration 1, plus x with probability q (a rare large contribution), per pixel; its mean and
 * the variance of that mean, the same in the three channels. */
static void heavy_tailed_image(uint64_t seed, int w, int h, int n, double q, double x, float *mean, float *var) {
  pc_rng r = pc_rng_make(seed, 0, PC_STREAM_MISC, 0);
  for (int k = 0; k < w * h; k++) {
    double s = 0, s2 = 0;
    for (int i = 0; i < n; i++) {
      double b = 1.0 + (pc_rng_f(&r) < q ? x : 0.0);
      s += b;
      s2 += b * b;
    }
    double m = s / n, v = (s2 / n - m * m) / (n - 1);
    for (int ch = 0; ch < 3; ch++) mean[3 * k + ch] = (float)m, var[3 * k + ch] = (float)v;
  }
}

/* Candidates share their paths, so the pooled mean carries each one's noise: a candidate that met
 * a rare large contribution at a pixel also raised the pooled mean there, and a denominator taken
 * at the pixel divided its own variance away. Here BDPT and PCBPT K = 1 are estimators of equal
 * variance, K = 1 with its stage-4 twin (the same image), which puts its noise twice in the pool:
 * both must measure alike, near their true relMSE q (1 - q) x^2 / n / ((1 + q x)^2 + eps) = 0.873
 * (the ring's own noise in the denominator raises both by 8%: E[1 / d] > 1 / E[d]). Over the seed
 * pairs (2 s + 1, 2 s + 2), s = 1..40, at this size: each estimate 1.078x the true one, sd 0.030;
 * K = 1 over BDPT 1.006, sd 0.042. With the denominator at the pixel (before 2026-11-25) K = 1
 * measured 0.345x the true relMSE and BDPT 0.815x, so the pilot saw K = 1 2.4x better. The
 * tolerances are 4 sd. */
static void test_pooled_own_noise(void **state) {
  (void)state;
  enum { W = 64, H = 64, N = 14 };
  const double q = 0.02, x = 50, exact = q * (1 - q) * x * x / N / ((1 + q * x) * (1 + q * x) + PC_RELMSE_EPS);
  pc_pilot p = {0};
  set_candidate(&p, PC_METHOD_BDPT, 1, -1, 1.0);
  set_candidate(&p, PC_METHOD_PCBPT, 1, -1, 1.0);
  set_candidate(&p, PC_METHOD_PCBPT, 1, -1, 1.0);
  p.c[2].mis_raised = true;
  for (int i = 0; i < 3; i++) p.c[i].iterations = N;
  static float mean[2][W * H * 3], var[2][W * H * 3];
  heavy_tailed_image(3, W, H, N, q, x, mean[0], var[0]);
  heavy_tailed_image(4, W, H, N, q, x, mean[1], var[1]);
  pc_err e = {0};
  for (int i = 0; i < 3; i++) assert_int_equal(pc_pilot_keep_image(&p.c[i], W, H, mean[i > 0], var[i > 0], &e), 0);
  pc_pilot_choose(&p);
  printf("pooled own noise: exact %.4f, bdpt %.4f, pcbpt K=1 %.4f (twice in the pool)\n", exact, p.c[0].relmse,
         p.c[1].relmse);
  assert_true(fabs(p.c[0].relmse / exact - 1.078) < 4 * 0.030);
  assert_true(fabs(p.c[1].relmse / exact - 1.078) < 4 * 0.030);
  assert_true(fabs(p.c[1].relmse / p.c[0].relmse - 1) < 4 * 0.042);
  pc_pilot_free(&p);
}

/* PT renders paths of its own, so its few iterations can miss light the others found (a caustic):
 * its image is then darker there and quieter too. Its relMSE carries the excess of its
 * disagreement with the others' mean over both images' variances. Here BDPT and PCBPT K = 1 are
 * the same heavy-tailed image (shared paths) and PT an independent one of the same estimator:
 * an honest PT must measure as BDPT does: over seeds s = 1..40 (images 3 s, and 3 s + 1 for PT)
 * PT's relMSE over BDPT's has mean 1.0074 and sd 0.0308 (1.018 when the excess's positive part
 * was added whatever its noise), so the mean over the 40 must be within 4 sd / sqrt(40) of 1.
 * A PT that found nothing in the top tenth of the image (its mean and variance 0 there) must
 * measure far worse (seed 1: 0.214 against 0.026), and lose although its own variance would
 * otherwise make it about twice as efficient. */
static void test_pt_disagreement(void **state) {
  (void)state;
  enum { W = 64, H = 64, N = 14, SEEDS = 40, DARK_ROWS = 6 };
  const double q = 0.2, x = 2; /* relMSE of the mean 0.023, as a pilot's (docs/auto.md) */
  static float mean[2][W * H * 3], var[2][W * H * 3];
  const double sd_honest = 0.0308;
  double sum = 0, sum2 = 0;
  pc_err e = {0};
  for (int seed = 1; seed <= SEEDS; seed++) {
    pc_pilot p = {0};
    set_candidate(&p, PC_METHOD_BDPT, 1, -1, 1.0);
    set_candidate(&p, PC_METHOD_PT, 0, -1, 1.0);
    set_candidate(&p, PC_METHOD_PCBPT, 1, -1, 1.0);
    for (int i = 0; i < 3; i++) p.c[i].iterations = N;
    heavy_tailed_image(3 * (uint64_t)seed, W, H, N, q, x, mean[0], var[0]);
    heavy_tailed_image(3 * (uint64_t)seed + 1, W, H, N, q, x, mean[1], var[1]);
    for (int i = 0; i < 3; i++) assert_int_equal(pc_pilot_keep_image(&p.c[i], W, H, mean[i == 1], var[i == 1], &e), 0);
    pc_pilot_choose(&p);
    double r = p.c[1].relmse / p.c[0].relmse;
    sum += r;
    sum2 += r * r;
    if (seed == 1) {
      /* the dark top rows: PT's cost halved, so that without the excess it would win 2x */
      for (int k = 0; k < DARK_ROWS * W * 3; k++) p.c[1].mean[k] = p.c[1].var[k] = 0;
      p.c[1].seconds = 0.5;
      pc_pilot_choose(&p);
      printf("PT dark in the top %d rows: relMSE %.4f against BDPT's %.4f\n", DARK_ROWS, p.c[1].relmse, p.c[0].relmse);
      assert_true(p.c[1].relmse > 3 * p.c[0].relmse);
      assert_int_not_equal(p.c[p.best].set.method, PC_METHOD_PT);
    }
    pc_pilot_free(&p);
  }
  double m = sum / SEEDS, sd = sqrt(fmax(sum2 / SEEDS - m * m, 0) * SEEDS / (SEEDS - 1));
  printf("honest PT over BDPT: mean %.4f sd %.4f over %d seeds\n", m, sd, SEEDS);
  assert_true(fabs(m - 1) < 4 * sd_honest / sqrt(SEEDS));
}

/* Scripted efficiencies: relMSE per iteration by K, and by K with the raised MIS count (0: as
 * with the base count) (cost 1 s per candidate). */
typedef struct script {
  double bdpt, pt, k[9], raised[9]; /* pt 0: PT cannot tell its error */
  double fewer[3]; /* stage 5: [1] with a quarter, [2] a sixteenth of the light paths (0: as its base) */
  int calls, raised_calls;
  uint64_t job_seed;
  bool seed_leaked;
  bool no_pt; /* the scene has paths PT cannot sample: pc_pilot_run without PT */
  bool caustics; /* the scene has caustics: pc_pilot_run without stage 5 */
  /* the batches each candidate rendered (index 0 BDPT, else K; 9 the raised count, 10 PT, 11
   * and 12 stage 5's quarter and sixteenth of the light paths): iterations and salt */
  int nbatch[13];
  uint64_t batch_it[13][2], batch_salt[13][2];
} script;

static int scripted(void *user, const pc_pilot_candidate *c, int n, uint64_t iterations, uint64_t salt,
                    pc_pilot_candidate *out, pc_err *e) {
  (void)e;
  script *s = user;
  for (int i = 0; i < n; i++) {
    const pc_render_settings *set = &c[i].set;
    s->calls++;
    if ((set->seed ^ salt) == s->job_seed) s->seed_leaked = true;
    int step = c[i].light_step;
    int key = set->method == PC_METHOD_BDPT ? 0 : set->method == PC_METHOD_PT ? 10 : step ? 10 + step : c[i].mis_raised ? 9 : set->pcbpt_k;
    /* stage 5 divides the job's light paths (W*H) and keeps everything else of its base */
    assert_int_equal(set->light_paths, step ? (uint64_t)set->width * set->height / (step == 1 ? 4 : 16) : 0);
    assert_true(!step || !c[i].counts);
    int b = s->nbatch[key]++;
    if (b < 2) s->batch_it[key][b] = iterations, s->batch_salt[key][b] = salt;
    out[i].iterations = iterations;
    out[i].seconds = 0.5 * (double)iterations;
    out[i].own_relmse = set->method == PC_METHOD_BDPT ? s->bdpt : s->k[set->pcbpt_k];
    if (set->method == PC_METHOD_PT) out[i].own_relmse = s->pt > 0 ? s->pt : -1;
    if (c[i].mis_raised) {
      s->raised_calls++;
      assert_true(set->mis_mode == PC_MIS_COUNT && set->mis_count == PC_PILOT_RAISED_COUNT);
      if (s->raised[set->pcbpt_k] > 0) out[i].own_relmse = s->raised[set->pcbpt_k];
    }
    if (step && s->fewer[step] > 0) out[i].own_relmse = s->fewer[step];
  }
  return 0;
}

static void run_script(script *s, double slice, pc_pilot *p) {
  pc_render_settings base;
  pc_render_settings_default(&base);
  base.method = PC_METHOD_PCBPT;
  base.seed = s->job_seed = 77;
  pc_err e = {0};
  assert_int_equal(pc_pilot_run(p, &base, !s->no_pt, !s->caustics, slice, 2, scripted, s, &e), 0);
  assert_false(s->seed_leaked);
  char line[1024];
  pc_pilot_report(p, line, sizeof line);
  printf("%s\n", line);
}

static void test_grid(void **state) {
  (void)state;
  pc_pilot p;
  /* stage 1 is BDPT, PT, K = 1 and K = 2 (a slice too small for a second batch). K=2 worse than K=1:
   * no K=4 or 8 (however good they would have been); the job's uniform mix is kept; no stage 4
   * either (however good the raised count would have been): stage 1 took the whole budget */
  script a = {.bdpt = 1.0, .k = {[1] = 0.2, [2] = 0.3, [4] = 0.01, [8] = 0.01}, .raised = {[1] = 0.01}};
  run_script(&a, 0.1, &p);
  assert_int_equal(a.calls, 5); /* and stage 5's quarter of the light paths, no better */
  assert_int_equal(a.raised_calls, 0);
  assert_int_equal(p.c[p.best].set.pcbpt_k, 1);
  assert_false(p.c[p.best].mis_raised);
  assert_true(p.c[p.best].set.uniform_mix == 0.5f);
  pc_pilot_free(&p);
  /* the same with room for a second batch (two batches per candidate from here on): stage 4
   * tries K=1 with the raised count, which is no better, so the base count stays; stage 5 K=1
   * with a quarter of the light paths, no better either, so a sixteenth is not tried */
  script a2 = {.bdpt = 1.0, .k = {[1] = 0.2, [2] = 0.3, [4] = 0.01, [8] = 0.01}};
  run_script(&a2, 2.0, &p);
  assert_int_equal(a2.calls, 12);
  assert_int_equal(a2.nbatch[11], 2);
  assert_int_equal(a2.nbatch[12], 0);
  assert_int_equal(a2.raised_calls, 2);
  assert_int_equal(p.c[p.best].set.pcbpt_k, 1);
  assert_false(p.c[p.best].mis_raised);
  pc_pilot_free(&p);
  /* efficiency rises to K=4 (each doubling by more than the margin) and drops at 8: K=4. The
   * raised count is tried at K=1 whatever K the doublings reached (so that its iterations count
   * in the image: stages 1 and 4 count, K=4 and 8 do not), and K=1 with it is no match for K=4.
   * K=4 with it would win, which shows that it is never tried */
  script b = {.bdpt = 1.0, .k = {[1] = 0.8, [2] = 0.3, [4] = 0.1, [8] = 0.25}, .raised = {[1] = 0.5, [4] = 0.08}};
  run_script(&b, 2.0, &p);
  assert_int_equal(b.calls, 16);
  assert_int_equal(b.nbatch[9], 2);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_PCBPT);
  assert_int_equal(p.c[p.best].set.pcbpt_k, 4);
  assert_false(p.c[p.best].mis_raised);
  for (int i = 0; i < p.n; i++) {
    assert_true(!p.c[i].mis_raised || p.c[i].set.pcbpt_k == 1);
    assert_int_equal(p.c[i].counts, p.c[i].set.method == PC_METHOD_BDPT ||
                                        (p.c[i].set.method == PC_METHOD_PCBPT && p.c[i].set.pcbpt_k <= 2));
  }
  pc_pilot_free(&p);
  /* K=2 better than K=1 but within the margin: K=1, and K=4 is not tried; the raised count
   * better, but within its margin: not taken */
  script d = {.bdpt = 1.0, .k = {[1] = 0.4, [2] = 0.4 / (0.5 * (1 + PC_PILOT_K_MARGIN)), [4] = 0.01},
              .raised = {[1] = 0.4 / (0.5 * (1 + PC_PILOT_COUNT_MARGIN))}};
  run_script(&d, 2.0, &p);
  assert_int_equal(d.calls, 12);
  assert_int_equal(p.c[p.best].set.pcbpt_k, 1);
  assert_false(p.c[p.best].mis_raised);
  pc_pilot_free(&p);
  /* BDPT best, also against the raised count */
  script c = {.bdpt = 0.1, .k = {[1] = 0.4, [2] = 0.5, [4] = 0.6, [8] = 0.5}, .raised = {[1] = 0.2}};
  run_script(&c, 2.0, &p);
  assert_int_equal(c.calls, 12);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_BDPT);
  pc_pilot_free(&p);
  /* BDPT better than K=1 with the base count, but not than K=1 with the raised one */
  script f = {.bdpt = 0.2, .k = {[1] = 0.22, [2] = 0.5}, .raised = {[1] = 0.1}};
  run_script(&f, 2.0, &p);
  assert_int_equal(f.calls, 12);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_PCBPT);
  assert_true(p.c[p.best].mis_raised);
  pc_pilot_free(&p);
  /* PT more efficient than the winner, but within PC_PILOT_PT_MARGIN: the winner stays; past it, PT */
  script g = {.bdpt = 0.2, .pt = 0.2 / (0.5 * (1 + PC_PILOT_PT_MARGIN)), .k = {[1] = 0.4, [2] = 0.5}};
  run_script(&g, 2.0, &p);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_BDPT);
  pc_pilot_free(&p);
  script h = {.bdpt = 0.2, .pt = 0.2 / (1.01 * PC_PILOT_PT_MARGIN), .k = {[1] = 0.4, [2] = 0.5}};
  run_script(&h, 2.0, &p);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_PT);
  pc_pilot_free(&p);
  /* the same where the scene has paths PT cannot sample: PT is not rendered, BDPT wins */
  script h2 = {.bdpt = 0.2, .pt = 0.2 / (1.01 * PC_PILOT_PT_MARGIN), .k = {[1] = 0.4, [2] = 0.5}, .no_pt = true};
  run_script(&h2, 2.0, &p);
  assert_int_equal(h2.nbatch[10], 0);
  for (int j = 0; j < p.n; j++) assert_int_not_equal(p.c[j].set.method, PC_METHOD_PT);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_BDPT);
  pc_pilot_free(&p);
  /* ... also past a PCBPT winner, which PT must beat rather than BDPT */
  script i = {.bdpt = 0.4, .pt = 0.2, .k = {[1] = 0.1, [2] = 0.5}};
  run_script(&i, 2.0, &p);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_PCBPT);
  pc_pilot_free(&p);
}

/* Stage 5: the PCBPT configuration chosen so far, with a quarter of the light-tracing paths, then
 * a sixteenth, each taken only past PC_PILOT_LIGHT_MARGIN; it renders the same two batches as the
 * others and does not count in the image (the scripted renderer checks both, and that the light
 * paths are the job's W*H divided). */
static void test_fewer_lights(void **state) {
  (void)state;
  pc_pilot p;
  /* a quarter past the margin, a sixteenth within it: a quarter */
  script j = {.bdpt = 1.0, .k = {[1] = 0.2, [2] = 0.3}, .fewer = {[1] = 0.2 / (1.01 * PC_PILOT_LIGHT_MARGIN)}};
  j.fewer[2] = j.fewer[1] / (0.5 * (1 + PC_PILOT_LIGHT_MARGIN));
  run_script(&j, 2.0, &p);
  assert_int_equal(j.nbatch[11], 2);
  assert_int_equal(j.nbatch[12], 2);
  assert_int_equal(p.c[p.best].light_step, 1);
  assert_int_equal(p.c[p.best].set.light_paths, 256 * 256 / 4);
  assert_int_equal(p.c[p.best].set.pcbpt_k, 1);
  assert_false(p.c[p.best].counts);
  assert_true(pc_pilot_counted_share(&p) == 1.0 / 4); /* BDPT, K = 1, K = 2 and stage 4 */
  pc_pilot_free(&p);
  /* both steps past it: a sixteenth */
  script k = {.bdpt = 1.0, .k = {[1] = 0.2, [2] = 0.3}, .fewer = {[1] = 0.15, [2] = 0.1}};
  run_script(&k, 2.0, &p);
  assert_int_equal(p.c[p.best].light_step, 2);
  assert_int_equal(p.c[p.best].set.light_paths, 256 * 256 / 16);
  pc_pilot_free(&p);
  /* a quarter within the margin: the job's light paths, and a sixteenth is never tried however
   * good it would have been */
  script l = {.bdpt = 1.0, .k = {[1] = 0.2, [2] = 0.3}, .fewer = {[1] = 0.2 / (0.5 * (1 + PC_PILOT_LIGHT_MARGIN)), [2] = 0.01}};
  run_script(&l, 2.0, &p);
  assert_int_equal(l.nbatch[12], 0);
  assert_int_equal(p.c[p.best].light_step, 0);
  assert_int_equal(p.c[p.best].set.light_paths, 0);
  pc_pilot_free(&p);
  /* it starts from the chosen configuration: K = 1 with the raised count here */
  script m = {.bdpt = 1.0, .k = {[1] = 0.4, [2] = 0.5}, .raised = {[1] = 0.2}, .fewer = {[1] = 0.1}};
  run_script(&m, 2.0, &p);
  assert_true(p.c[p.best].mis_raised);
  assert_int_equal(p.c[p.best].light_step, 1);
  pc_pilot_free(&p);
  /* ... and K = 4 here; where it makes PCBPT beat BDPT, PCBPT */
  script n = {.bdpt = 0.25, .k = {[1] = 0.8, [2] = 0.3, [4] = 0.28, [8] = 0.5}, .fewer = {[1] = 0.1}};
  run_script(&n, 2.0, &p);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_PCBPT);
  assert_int_equal(p.c[p.best].set.pcbpt_k, 4);
  assert_int_equal(p.c[p.best].light_step, 1);
  pc_pilot_free(&p);
  /* where stage 1 took the budget, no stage 4, but stage 5 still (its gain is no refinement) */
  script o = {.bdpt = 1.0, .k = {[1] = 0.2, [2] = 0.3}, .raised = {[1] = 0.01}, .fewer = {[1] = 0.1, [2] = 0.05}};
  run_script(&o, 0.1, &p);
  assert_int_equal(o.raised_calls, 0);
  assert_int_equal(o.nbatch[11], 1);
  assert_int_equal(o.nbatch[12], 1);
  assert_int_equal(p.c[p.best].light_step, 2);
  pc_pilot_free(&p);
  /* a scene with caustics: never fewer light paths, however good they look */
  script q = {.bdpt = 1.0, .k = {[1] = 0.2, [2] = 0.3}, .fewer = {[1] = 0.01, [2] = 0.01}, .caustics = true};
  run_script(&q, 2.0, &p);
  assert_int_equal(q.nbatch[11], 0);
  assert_int_equal(p.c[p.best].light_step, 0);
  pc_pilot_free(&p);
}

/* Every candidate renders the same iterations: the first batch's floor, then what the rest of
 * stage 1's 5 slices buys at the four candidates' cost (here (5 x 2 - 4 x 1) / (4 x 0.5) = 3
 * iterations), and K = 4 and 8 and the raised count, tried later, the same two batches. */
static void test_matched(void **state) {
  (void)state;
  pc_pilot p;
  script b = {.bdpt = 1.0, .k = {[1] = 0.8, [2] = 0.3, [4] = 0.1, [8] = 0.25}};
  run_script(&b, 2.0, &p);
  assert_int_equal(b.calls, 16);
  assert_int_equal(p.n, 8);
  for (int key = 0; key <= 11; key = key == 8 ? 9 : key >= 9 ? key + 1 : key ? 2 * key : 1) {
    assert_int_equal(b.nbatch[key], 2);
    assert_int_equal(b.batch_it[key][0], 2);
    assert_int_equal(b.batch_it[key][1], 3);
    assert_int_equal(b.batch_salt[key][0], b.batch_salt[0][0]);
    assert_int_equal(b.batch_salt[key][1], b.batch_salt[0][1]);
  }
  assert_true(b.batch_salt[0][0] != b.batch_salt[0][1]);
  for (int i = 0; i < p.n; i++) assert_int_equal(p.c[i].iterations, 5);
  assert_int_equal(p.c[p.best].set.pcbpt_k, 4);
  pc_pilot_free(&p);
}

/* Candidates rendered in this process, one iteration at a time round robin, each into a film
 * of its own that is kept (films[k] for the k-th candidate the pilot made); the cost is the
 * process's CPU time per iteration, or with scripted_cost a fixed cost per method, so that the
 * choice depends on the pilot's images alone and is the same on every machine and load. */
typedef struct local {
  const pc_scene *scene;
  bool scripted_cost;
  int made;
  pc_film films[PC_PILOT_MAX];
} local;

/* Milliseconds per iteration that make the furnace's candidates near-equally efficient (its
 * pilots measure relMSE about 0.044 for BDPT, 0.11 for PT, 0.034 for PCBPT K = 1 and 0.029 with
 * the raised count), so that which one wins is decided by each seed's pilot images: the test
 * then sees whether that choice leaks into the image. */
static double scripted_ms(const pc_render_settings *s) {
  if (s->method == PC_METHOD_PT) return 0.35;
  /* stage 5's fewer light paths (relMSE about 0.02 and 0.017 at a quarter and a sixteenth)
   * are charged more than they cost, to stay near-equal too */
  if (s->method == PC_METHOD_PCBPT && s->light_paths > 0) return s->light_paths * 16 > (uint64_t)s->width * (uint64_t)s->height ? 1.75 : 2.1;
  if (s->method == PC_METHOD_PCBPT) return 1.4 + 0.05 * (s->pcbpt_k - 1);
  return 1.0;
}

static int local_render(void *user, const pc_pilot_candidate *c, int n, uint64_t iterations, uint64_t salt,
                        pc_pilot_candidate *out, pc_err *e) {
  local *l = user;
  for (int i = 0; i < n; i++) {
    pc_render_settings s = c[i].set;
    s.strategy_layers = 0;
    s.seed ^= salt;
    pc_film *f = &l->films[l->made++];
    pc_renderer *r = NULL;
    assert_int_equal(pc_film_init(f, s.width, s.height, 0, e), 0);
    assert_int_equal(pc_renderer_create(l->scene, &s, 2, &r, e), 0);
    pc_render_stats st = {0};
    assert_int_equal(pc_render_iterations(r, 0, iterations, f, &st, NULL, NULL, NULL, e), 0);
    /* the render threads' clocks: more than nothing, at most 2 threads' worth of the wall time */
    assert_true(st.t_cpu > 0 && st.t_cpu <= 2 * st.t_total + 1e-3);
    out[i].seconds = l->scripted_cost ? 1e-3 * scripted_ms(&s) * (double)iterations : st.t_total;
    out[i].cpu_seconds = l->scripted_cost ? out[i].seconds : st.t_cpu;
    out[i].iterations = iterations;
    pc_renderer_destroy(r);
    size_t nv = (size_t)f->w * f->h * 3;
    float *mean = malloc(nv * sizeof *mean), *var = malloc(nv * sizeof *var);
    assert_non_null(mean);
    assert_non_null(var);
    pc_film_beauty(f, mean);
    assert_int_equal(pc_pilot_keep_image(&out[i], f->w, f->h, mean, pc_film_variance(f, var) ? var : NULL, e), 0);
    free(mean);
    free(var);
  }
  return 0;
}

static void local_free(local *l) {
  for (int i = 0; i < l->made; i++) pc_film_free(&l->films[i]);
}

static void load(const char *name, int res, uint64_t seed, pc_render_request *req, pc_scene *scene) {
  pc_render_request_default(req);
  req->set.width = req->set.height = res;
  req->width_set = req->height_set = true;
  req->set.seed = seed;
  assert_int_equal(stat_load(name, req, scene), 0);
  req->set.method = PC_METHOD_PCBPT;
}

static void test_picks_winner(void **state) {
  (void)state;
  pc_render_request req;
  pc_scene scene = {0};
  load("ajar-door", 48, 5, &req, &scene);
  local l = {.scene = &scene};
  pc_pilot p;
  pc_err e = {0};
  assert_int_equal(pc_pilot_run(&p, &req.set, req.pt_complete, !req.caustics, 0, 4, local_render, &l, &e), 0);
  local_free(&l);
  char line[1024];
  pc_pilot_report(&p, line, sizeof line);
  printf("ajar-door 48x48: %s\n", line);
  assert_int_equal(p.c[p.best].set.method, PC_METHOD_PCBPT);
  /* the relMSE figures alone (time-free) say the same */
  assert_true(p.c[0].relmse > 1.5 * p.c[p.best].relmse);
  pc_pilot_free(&p);
  pc_scene_free(&scene);
}

#define SEEDS 64
#define ITERATIONS 12
#define RES 16

static void test_unbiased(void **state) {
  (void)state;
  double sum = 0, sum2 = 0;
  /* winners by label: a candidate's index is not the same configuration on every seed (stage 3
   * adds K = 4 and 8 only where doubling K paid) */
  char won[SEEDS][sizeof ((pc_pilot_candidate *)0)->label];
  for (int s = 0; s < SEEDS; s++) {
    pc_render_request req;
    pc_scene scene = {0};
    load("furnace", RES, 1000 + (uint64_t)s, &req, &scene);
    pc_render_settings base = req.set;
    base.pcbpt_m = 20;
    base.cache_fraction = 0.05f;
    local l = {.scene = &scene, .scripted_cost = true};
    pc_pilot p;
    pc_err e = {0};
    assert_int_equal(pc_pilot_run(&p, &base, req.pt_complete, !req.caustics, 0, 2, local_render, &l, &e), 0);
    pc_render_settings chosen = p.c[p.best].set;
    chosen.seed = base.seed;
    /* the job's film, then the mix: the counted candidates by iterations (as the coordinator
     * folds a pilot group), and that with weight a / (a + N), a their iterations times
     * pc_pilot_counted_share, N the spp */
    pc_film job, pilot, shown;
    assert_int_equal(pc_film_init(&job, RES, RES, 0, &e), 0);
    assert_int_equal(pc_film_init(&pilot, RES, RES, 0, &e), 0);
    assert_int_equal(pc_film_init(&shown, RES, RES, 0, &e), 0);
    pc_renderer *r = NULL;
    pc_render_stats rs = {0};
    assert_int_equal(pc_renderer_create(&scene, &chosen, 2, &r, &e), 0);
    assert_int_equal(pc_render_iterations(r, 0, ITERATIONS, &job, &rs, NULL, NULL, NULL, &e), 0);
    pc_renderer_destroy(r);
    pc_film_part counted[PC_PILOT_MAX];
    int nc = 0;
    double a = 0;
    for (int i = 0; i < p.n; i++)
      if (p.c[i].counts) a += (double)p.c[i].iterations;
    for (int i = 0; i < p.n; i++)
      if (p.c[i].counts) counted[nc++] = (pc_film_part){&l.films[i], (double)p.c[i].iterations / a};
    assert_int_equal(nc, 4); /* BDPT, K = 1, K = 2 and K = 1 with the raised count (no slice: room) */
    assert_int_equal(pc_film_mix(&pilot, counted, nc, &e), 0);
    assert_true(pc_pilot_counted_share(&p) == 0.25);
    a *= pc_pilot_counted_share(&p);
    pc_film_part parts[] = {{&pilot, a / (a + ITERATIONS)}, {&job, ITERATIONS / (a + ITERATIONS)}};
    assert_int_equal(pc_film_mix(&shown, parts, 2, &e), 0);
    size_t nv = (size_t)RES * RES * 3;
    float *img = malloc(nv * sizeof *img);
    assert_non_null(img);
    pc_film_beauty(&shown, img);
    double m = 0;
    for (size_t k = 0; k < nv; k++) m += img[k];
    m /= (double)nv;
    free(img);
    pc_film_free(&job);
    pc_film_free(&pilot);
    pc_film_free(&shown);
    local_free(&l);
    printf("furnace seed %d: chose %s, image mean %.5f\n", 1000 + s, p.c[p.best].label, m);
    snprintf(won[s], sizeof won[s], "%s", p.c[p.best].label);
    pc_pilot_free(&p);
    sum += m;
    sum2 += m * m;
    pc_scene_free(&scene);
  }
  double mean = sum / SEEDS, var = (sum2 / SEEDS - mean * mean) * SEEDS / (SEEDS - 1), se = sqrt(var / SEEDS);
  printf("furnace auto: mean over %d seeds %.5f (exact 2), standard error %.2e\n", SEEDS, mean, se);
  /* the choice did depend on the pilot's images: at least two configurations won an eighth of
   * the seeds each */
  int winners = 0;
  for (int s = 0; s < SEEDS; s++) {
    int first = 1, count = 0;
    for (int t = 0; t < SEEDS; t++) {
      if (strcmp(won[t], won[s]) != 0) continue;
      if (t < s) first = 0;
      count++;
    }
    if (first && count >= SEEDS / 8) {
      printf("furnace auto: %s won %d of %d seeds\n", won[s], count, SEEDS);
      winners++;
    }
  }
  assert_true(winners >= 2);
  assert_true(fabs(mean - 2.0) <= 4 * se + 1e-9);
  assert_true(fabs(mean - 2.0) < 0.015);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_choose),
      cmocka_unit_test(test_choose_raised),
      cmocka_unit_test(test_pooled),
      cmocka_unit_test(test_pooled_own_noise),
      cmocka_unit_test(test_pt_disagreement),
      cmocka_unit_test(test_grid),
      cmocka_unit_test(test_fewer_lights),
      cmocka_unit_test(test_matched),
      cmocka_unit_test(test_picks_winner),
      cmocka_unit_test(test_unbiased),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
