/* test_variance.c: every render knows its own error (docs/variance.md). Over R seeds, the
 * relMSE a film estimates from the spread of its own iterations (pc_film_relmse_estimate) and
 * the relMSE measured against the exact image with compare's definition (pc_metrics_rgb) must
 * have the same expectation, for pt, bdpt and pcbpt, on
 *   - the white furnace, whose exact image is Le/(1-a) = 2 everywhere, and
 *   - cornell-box, whose exact image is replaced, for seed r, by the mean of the other R-1
 *     seeds' renders (a reference of (R-1)*N iterations, independent of run r): its own
 *     variance adds 1/(R-1) of the run's, so the measurement is scaled by (R-1)/R. Rendering
 *     a separate long reference would cost minutes at any size where cornell-box is more than
 *     a few pixels; this one is free and exactly as good.
 * BDPT runs with N_L = 2 W*H light paths, so the light layer's own normalization is tested too.
 * The test statistic is the per-seed difference d_r = est_r - meas_r: its mean must be within
 * 4 standard errors of zero measured from the d_r themselves (fixed seeds: deterministic).
 * The estimate's denominator uses the rendered mean instead of the exact value (first order
 * relative bias about the per-pixel relMSE): N is chosen so that is well under that bound.
 *
 * The film's trace of single iterations (film_trace.h) is checked on the furnace too: the same
 * bits with 1 and 2 threads, each record the block means of that iteration rendered alone, and
 * the mean of the per-iteration errors pc_film_iteration_errors gives against the film's own
 * image equal, within 4 standard errors, to the mean of the same iterations' errors against the
 * exact image. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "metrics.h"
#include "stat_util.h"

#define RUNS 16

typedef struct scene_case {
  const char *scene;
  int res, iterations;
  bool analytic; /* furnace: exact image 2 everywhere */
} scene_case;

static void check(const scene_case *sc, pc_method method) {
  pc_render_request req;
  pc_render_request_default(&req);
  req.set.method = method;
  req.method_set = true;
  req.set.width = req.set.height = sc->res;
  req.width_set = req.height_set = true;
  req.set.pcbpt_m = 20;
  req.set.cache_fraction = 0.05f;
  /* BDPT traces twice W*H light paths, so the lt layer's scale W*H/N_L (1 by default) is
   * part of what each iteration's squared beauty must get right */
  if (method == PC_METHOD_BDPT) req.set.light_paths = 2 * (uint64_t)sc->res * sc->res;
  pc_scene scene = {0};
  assert_int_equal(stat_load(sc->scene, &req, &scene), 0);
  size_t n = (size_t)sc->res * sc->res * 3;
  float *img = malloc(sizeof(float) * n * RUNS), *ref = malloc(sizeof(float) * n);
  double *pool = calloc(n, sizeof(double)), est[RUNS], meas[RUNS];
  assert_non_null(img);
  assert_non_null(ref);
  assert_non_null(pool);
  pc_err e = {0};
  pc_renderer *r = NULL;
  assert_int_equal(pc_renderer_create(&scene, &req.set, 2, &r, &e), 0);
  for (int run = 0; run < RUNS; run++) {
    pc_film film;
    assert_int_equal(pc_film_init(&film, sc->res, sc->res, 0, &e), 0);
    /* seeds differ by run: iterations [run*N, (run+1)*N) of one job are independent runs */
    assert_int_equal(pc_render_iterations(r, (uint64_t)run * sc->iterations, (uint64_t)sc->iterations, &film, NULL,
                                          NULL, NULL, NULL, &e), 0);
    assert_true(pc_film_relmse_estimate(&film, &est[run]));
    pc_film_beauty(&film, img + n * run);
    for (size_t j = 0; j < n; j++) pool[j] += img[n * run + j];
    pc_film_free(&film);
  }
  pc_renderer_destroy(r);
  double scale = sc->analytic ? 1.0 : (RUNS - 1.0) / RUNS;
  double md = 0, md2 = 0, me = 0, mm = 0;
  for (int run = 0; run < RUNS; run++) {
    for (size_t j = 0; j < n; j++)
      ref[j] = sc->analytic ? 2.0f : (float)((pool[j] - img[n * run + j]) / (RUNS - 1));
    pc_metrics m;
    assert_int_equal(pc_metrics_rgb(img + n * run, ref, sc->res, sc->res, &m, &e), 0);
    meas[run] = m.relmse * scale;
    double d = est[run] - meas[run];
    md += d;
    md2 += d * d;
    me += est[run];
    mm += meas[run];
  }
  md /= RUNS;
  me /= RUNS;
  mm /= RUNS;
  double se = sqrt((md2 / RUNS - md * md) / (RUNS - 1));
  printf("%-11s %-5s %dx%d, %d iterations x %d seeds: estimated relMSE %.5f, measured %.5f, "
         "difference %+.5f +- %.5f (%+.1f se, %+.1f%%)\n",
         sc->scene, pc_method_name(method), sc->res, sc->res, sc->iterations, RUNS, me, mm, md, se, md / se,
         100 * md / mm);
  assert_true(fabs(md) <= 4 * se);
  free(img);
  free(ref);
  free(pool);
  pc_scene_free(&scene);
}

/* The luminance block means of a film's beauty (its one iteration's when it holds one). */
static void block_means(const pc_film *f, double *m) {
  int nb = pc_trace_blocks(f->w, f->h);
  uint32_t count[PC_TRACE_MAX_BLOCKS];
  float *img = malloc(sizeof(float) * 3 * (size_t)f->w * f->h);
  assert_non_null(img);
  pc_film_beauty(f, img);
  pc_trace_block_pixels(f->w, f->h, count);
  for (int k = 0; k < nb; k++) m[k] = 0;
  for (int y = 0; y < f->h; y++)
    for (int x = 0; x < f->w; x++) {
      const float *p = img + 3 * ((size_t)y * f->w + x);
      m[pc_trace_block_of(f->w, f->h, x, y)] += pc_luminance709(p[0], p[1], p[2]);
    }
  for (int k = 0; k < nb; k++) m[k] /= count[k];
  free(img);
}

static void check_trace(pc_method method) {
  enum { RES = 16, N = 96 };
  pc_render_request req;
  pc_render_request_default(&req);
  req.set.method = method;
  req.method_set = true;
  req.set.width = req.set.height = RES;
  req.width_set = req.height_set = true;
  req.set.pcbpt_m = 20;
  pc_scene scene = {0};
  assert_int_equal(stat_load("furnace", &req, &scene), 0);
  pc_err e = {0};
  pc_film two, one, alone;
  pc_renderer *r2 = NULL, *r1 = NULL;
  assert_int_equal(pc_renderer_create(&scene, &req.set, 2, &r2, &e), 0);
  assert_int_equal(pc_renderer_create(&scene, &req.set, 1, &r1, &e), 0);
  assert_int_equal(pc_film_init(&two, RES, RES, 0, &e), 0);
  assert_int_equal(pc_film_init(&one, RES, RES, 0, &e), 0);
  assert_int_equal(pc_film_init(&alone, RES, RES, 0, &e), 0);
  assert_int_equal(pc_render_iterations(r2, 0, N, &two, NULL, NULL, NULL, NULL, &e), 0);
  assert_int_equal(pc_render_iterations(r1, 0, N / 2, &one, NULL, NULL, NULL, NULL, &e), 0);
  assert_int_equal(pc_render_iterations(r1, N / 2, N - N / 2, &one, NULL, NULL, NULL, NULL, &e), 0);
  int nb = pc_trace_blocks(RES, RES);
  assert_int_equal(nb, 64);
  assert_int_equal(two.trace.n, N);
  assert_int_equal(one.trace.n, N);
  for (uint32_t i = 0; i < N; i++) assert_int_equal(two.trace.iteration[i], i);
  assert_memory_equal(two.trace.block, one.trace.block, sizeof(float) * N * (size_t)nb);
  int probe[] = {0, 7, N - 1};
  for (int p = 0; p < 3; p++) {
    double m[PC_TRACE_MAX_BLOCKS];
    pc_film_clear(&alone);
    assert_int_equal(pc_render_iterations(r1, (uint64_t)probe[p], 1, &alone, NULL, NULL, NULL, NULL, &e), 0);
    block_means(&alone, m);
    for (int k = 0; k < nb; k++)
      assert_true(fabs(two.trace.block[(size_t)probe[p] * nb + k] - m[k]) <= 1e-5 * (fabs(m[k]) + 1e-3));
  }
  pc_iteration_errors ie;
  assert_true(pc_film_iteration_errors(&two, &ie));
  assert_int_equal(ie.n, N);
  double sd = 0, sd2 = 0, exact_mean = 0, own[N];
  /* each iteration's error against the film's own image, recomputed; and against the exact 2 */
  double m[PC_TRACE_MAX_BLOCKS];
  block_means(&two, m);
  for (int i = 0; i < N; i++) {
    double eo = 0, ex = 0;
    for (int k = 0; k < nb; k++) {
      double b = two.trace.block[(size_t)i * nb + k];
      eo += (b - m[k]) * (b - m[k]) * N / (N - 1.0) / (m[k] * m[k] + PC_RELMSE_EPS);
      ex += (b - 2) * (b - 2) / (4 + PC_RELMSE_EPS);
    }
    own[i] = eo / nb;
    double d = own[i] - ex / nb;
    sd += d;
    sd2 += d * d;
    exact_mean += ex / nb;
  }
  sd /= N;
  exact_mean /= N;
  double se = sqrt((sd2 / N - sd * sd) / (N - 1));
  double own_mean = 0;
  for (int i = 0; i < N; i++) own_mean += own[i] / N;
  printf("furnace %-5s trace of %d iterations: mean error %.5f against the image, %.5f against the exact 2 "
         "(%+.1f se); p50 %.4f p99 %.4f max %.4f (iteration %u), top 1%% %.1f%%\n",
         pc_method_name(method), N, ie.mean, exact_mean, sd / se, ie.p50, ie.p99, ie.max, ie.worst, 100 * ie.top1);
  assert_true(fabs(ie.mean - own_mean) <= 1e-4 * own_mean); /* block means from floats here, doubles there */
  assert_true(fabs(sd) <= 4 * se);
  assert_true(ie.p50 <= ie.p99 && ie.p99 <= ie.max && ie.top1 >= 1.0 / N && ie.top1 <= 1.0);
  pc_film_free(&two);
  pc_film_free(&one);
  pc_film_free(&alone);
  pc_renderer_destroy(r1);
  pc_renderer_destroy(r2);
  pc_scene_free(&scene);
}

static void trace_pt(void **s) { (void)s; check_trace(PC_METHOD_PT); }
static void trace_pcbpt(void **s) { (void)s; check_trace(PC_METHOD_PCBPT); }

static const scene_case furnace = {"furnace", 16, 32, true};
static const scene_case cornell = {"cornell-box", 24, 32, false};

static void furnace_pt(void **s) { (void)s; check(&furnace, PC_METHOD_PT); }
static void furnace_bdpt(void **s) { (void)s; check(&furnace, PC_METHOD_BDPT); }
static void furnace_pcbpt(void **s) { (void)s; check(&furnace, PC_METHOD_PCBPT); }
static void cornell_pt(void **s) { (void)s; check(&cornell, PC_METHOD_PT); }
static void cornell_bdpt(void **s) { (void)s; check(&cornell, PC_METHOD_BDPT); }
static void cornell_pcbpt(void **s) { (void)s; check(&cornell, PC_METHOD_PCBPT); }

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(furnace_pt),  cmocka_unit_test(furnace_bdpt),  cmocka_unit_test(furnace_pcbpt),
      cmocka_unit_test(cornell_pt),  cmocka_unit_test(cornell_bdpt),  cmocka_unit_test(cornell_pcbpt),
      cmocka_unit_test(trace_pt),    cmocka_unit_test(trace_pcbpt),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
