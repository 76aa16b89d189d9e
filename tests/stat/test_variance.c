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
 * relative bias about the per-pixel relMSE): N is chosen so that is well under that bound. */
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
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
