/* test_film.c: per-strategy layers keep their own counts and normalizations (DESIGN.md §4.2):
 * eye layers divide by iterations, light layers by light paths / (W*H); adding films adds sums
 * and counts (beauty_max: their max, in any order); non-finite samples are dropped and counted;
 * the EXR carries layers and counts; a mix of films (the pilot's and the job's) has the weighted
 * images and the weighted variance; the trace of single iterations concatenates, refuses an
 * iteration twice, and gives the per-iteration errors of a hand-made case exactly; the layers'
 * big buffers (pc_big_alloc) come zeroed and 2 MiB-aligned. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "big_alloc.h"
#include "film.h"
#include "thread_pool.h"
#include "image.h"

static void test_layers_and_normalization(void **state) {
  (void)state;
  pc_film f;
  pc_err e = {0};
  assert_int_equal(pc_film_init(&f, 4, 2, 2, &e), 0);
  /* 4 standard + path length 1 (s1t1, s0t2) + length 2 (s2t1, s1t2, s0t3) + beauty_sq, beauty_max */
  assert_int_equal(f.nlayers, 11);
  assert_int_equal(pc_film_square_layer(&f), 9);
  assert_int_equal(f.layers[9].norm, PC_NORM_SQUARE);
  assert_int_equal(pc_film_max_layer(&f), 10);
  assert_int_equal(f.layers[10].norm, PC_NORM_MAX);
  assert_int_equal(pc_film_per_iteration_first(&f), 9);
  assert_string_equal(f.layers[PC_LAYER_LT].name, "lt");
  assert_int_equal(f.layers[PC_LAYER_LT].norm, PC_NORM_LIGHT);
  int l = pc_film_strategy_layer(&f, 1, 2);
  assert_true(l >= 4);
  assert_string_equal(f.layers[l].name, "s1t2");
  assert_int_equal(f.layers[pc_film_strategy_layer(&f, 2, 1)].norm, PC_NORM_LIGHT);
  assert_int_equal(pc_film_strategy_layer(&f, 3, 1), -1);

  pc_film_add_sample(&f, PC_LAYER_PT, 1, 0, v3(2, 4, 6));
  pc_film_add_sample(&f, PC_LAYER_LT, 1, 0, v3(1, 1, 1));
  pc_film_add_sample(&f, PC_LAYER_NEE, 0, 0, v3(NAN, 0, 0));
  pc_film_add_sample(&f, PC_LAYER_NEE, 0, 0, v3(INFINITY, 0, 0));
  assert_int_equal(f.dropped_nonfinite, 2);
  f.layers[PC_LAYER_PT].count = 2;
  f.layers[PC_LAYER_NEE].count = 2;
  f.layers[PC_LAYER_INNER].count = 2;
  f.layers[PC_LAYER_LT].count = 16; /* two iterations of 8 = W*H light paths */
  float img[4 * 2 * 3];
  pc_film_layer_image(&f, PC_LAYER_PT, img);
  assert_true(fabsf(img[3] - 1.f) < 1e-6f && fabsf(img[5] - 3.f) < 1e-6f);
  pc_film_layer_image(&f, PC_LAYER_LT, img);
  assert_true(fabsf(img[3] - 0.5f) < 1e-6f); /* 1 * (W*H=8) / 16 */
  pc_film_beauty(&f, img);
  assert_true(fabsf(img[3] - 1.5f) < 1e-6f && fabsf(img[4] - 2.5f) < 1e-6f);
  assert_true(pc_film_is_finite(&f));

  pc_film g;
  assert_int_equal(pc_film_init(&g, 4, 2, 2, &e), 0);
  assert_int_equal(pc_film_add(&g, &f, &e), 0);
  assert_int_equal(pc_film_add(&g, &f, &e), 0);
  assert_int_equal(g.layers[PC_LAYER_LT].count, 32);
  assert_int_equal(g.dropped_nonfinite, 4);
  pc_film_beauty(&g, img);
  assert_true(fabsf(img[3] - 1.5f) < 1e-6f); /* merging leaves normalized values unchanged */

  pc_film h;
  assert_int_equal(pc_film_init(&h, 4, 3, 0, &e), 0);
  assert_int_not_equal(pc_film_add(&h, &f, &e), 0);
  pc_film_free(&h);
  pc_film_free(&g);

  char dir[] = "/tmp/pcbpt-film-XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256];
  snprintf(path, sizeof path, "%s/f.exr", dir);
  assert_int_equal(pc_film_write_exr(&f, path, NULL, 0, &e), 0);
  pc_exr_file x;
  assert_int_equal(pc_exr_read_layers(path, &x, &e), 0);
  /* the beauty and every layer but beauty_sq and beauty_max; no variance and no maximum:
   * beauty_sq and beauty_max saw no iteration */
  assert_int_equal(x.nlayers, f.nlayers - 1);
  double v = 0;
  assert_false(pc_film_relmse_estimate(&f, &v));
  assert_true(isnan(v));
  int found = 0;
  for (int i = 0; i < x.nattrs; i++)
    if (strcmp(x.attr_names[i], "pcbpt.count.lt") == 0) found = atoi(x.attr_values[i]) == 16;
  assert_true(found);
  pc_exr_file_free(&x);
  unlink(path);
  rmdir(dir);
  pc_film_free(&f);
}

/* Three "iterations" of known beauty at every pixel: the variance of the mean is the sample
 * variance over 3, and the relMSE estimate is its mean over (mean^2 - variance + 0.01); the EXR carries
 * both. */
static void test_variance(void **state) {
  (void)state;
  pc_film f;
  pc_err e = {0};
  assert_int_equal(pc_film_init(&f, 2, 1, 0, &e), 0);
  int q = pc_film_square_layer(&f);
  assert_int_equal(q, PC_LAYER_STD_COUNT);
  /* iteration beauties at value j: pt gives j+1, 2j+1, 4j+1; lt adds 0.5 each time with
   * W*H = 2 light paths per iteration (scale 1) */
  for (int it = 0; it < 3; it++)
    for (int j = 0; j < 6; j++) {
      double b = (double)(1 << it) * j + 1;
      f.layers[PC_LAYER_PT].sum[j] += b;
      f.layers[PC_LAYER_LT].sum[j] += 0.5;
      f.layers[q].sum[j] += (b + 0.5) * (b + 0.5);
    }
  f.layers[PC_LAYER_PT].count = f.layers[PC_LAYER_NEE].count = f.layers[PC_LAYER_INNER].count = 3;
  f.layers[PC_LAYER_LT].count = 6;
  f.layers[q].count = 3;
  float var[6];
  assert_true(pc_film_variance(&f, var));
  double rel = 0;
  for (int j = 0; j < 6; j++) {
    double x[3] = {j + 1.5, 2.0 * j + 1.5, 4.0 * j + 1.5}, m = (x[0] + x[1] + x[2]) / 3, s2 = 0;
    for (int k = 0; k < 3; k++) s2 += (x[k] - m) * (x[k] - m);
    double want = s2 / 2 / 3;
    assert_true(fabs(var[j] - want) <= 1e-6 * (want + 1));
    rel += want / (fmax(m * m - want, 0) + PC_RELMSE_EPS);
  }
  double est;
  assert_true(pc_film_relmse_estimate(&f, &est));
  assert_true(fabs(est - rel / 6) < 1e-12);
  /* beauty_sq behind the sums (a job resumed from an old checkpoint): cannot tell */
  f.layers[q].count = 2;
  assert_false(pc_film_variance(&f, var));
  f.layers[q].count = 3;

  char dir[] = "/tmp/pcbpt-film-XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256];
  snprintf(path, sizeof path, "%s/v.exr", dir);
  assert_int_equal(pc_film_write_exr(&f, path, NULL, 0, &e), 0);
  pc_exr_file x;
  assert_int_equal(pc_exr_read_layers(path, &x, &e), 0);
  int found = -1;
  for (int i = 0; i < x.nlayers; i++) {
    assert_string_not_equal(x.names[i], "beauty_sq");
    if (strcmp(x.names[i], "variance") == 0) found = i;
  }
  assert_true(found >= 0);
  assert_true(fabsf(x.layers[found].rgb[5] - var[5]) <= 1e-6f * var[5]);
  bool attr = false;
  for (int i = 0; i < x.nattrs; i++)
    if (strcmp(x.attr_names[i], "pcbpt.relmse_estimate") == 0) attr = fabs(strtod(x.attr_values[i], NULL) - est) < 1e-9 * est;
  assert_true(attr);
  pc_exr_file_free(&x);
  unlink(path);
  rmdir(dir);
  pc_film_free(&f);
}

/* Three films of per-iteration maxima: merged in any order, beauty_max is the same max bit for
 * bit (and the sums the same sums); the EXR carries it unscaled once it has seen every
 * iteration, and not while it lags behind the sums (a job resumed from an older checkpoint). */
static void fill_max_film(pc_film *f, int seed) {
  int m = pc_film_max_layer(f);
  for (int j = 0; j < 6; j++) {
    f->layers[PC_LAYER_PT].sum[j] = seed + j;
    f->layers[m].sum[j] = (double)((seed * 7 + j * 5) % 11) + 0.125 * seed;
  }
  for (int l = 0; l < f->nlayers; l++) f->layers[l].count = l == PC_LAYER_LT ? 2u * (unsigned)seed : (unsigned)seed;
}

static void test_max_merge(void **state) {
  (void)state;
  pc_err e = {0};
  pc_film part[3], abc, cba;
  for (int i = 0; i < 3; i++) {
    assert_int_equal(pc_film_init(&part[i], 2, 1, 0, &e), 0);
    fill_max_film(&part[i], i + 1);
  }
  assert_int_equal(pc_film_init(&abc, 2, 1, 0, &e), 0);
  assert_int_equal(pc_film_init(&cba, 2, 1, 0, &e), 0);
  for (int i = 0; i < 3; i++) assert_int_equal(pc_film_add(&abc, &part[i], &e), 0);
  for (int i = 2; i >= 0; i--) assert_int_equal(pc_film_add(&cba, &part[i], &e), 0);
  int m = pc_film_max_layer(&abc);
  assert_int_equal(m, PC_LAYER_STD_COUNT + 1);
  for (int j = 0; j < 6; j++) {
    double want = 0;
    for (int i = 0; i < 3; i++) want = fmax(want, part[i].layers[m].sum[j]);
    assert_true(abc.layers[m].sum[j] == want && cba.layers[m].sum[j] == want);
    assert_true(abc.layers[PC_LAYER_PT].sum[j] == 3 * j + 6);
  }
  assert_int_equal(abc.layers[m].count, 6);
  assert_true(pc_film_max_complete(&abc));

  char dir[] = "/tmp/pcbpt-film-XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[256];
  snprintf(path, sizeof path, "%s/m.exr", dir);
  for (int lag = 0; lag < 2; lag++) {
    abc.layers[m].count = 6 - lag;
    assert_int_equal(pc_film_max_complete(&abc), lag == 0);
    assert_int_equal(pc_film_write_exr(&abc, path, NULL, 0, &e), 0);
    pc_exr_file x;
    assert_int_equal(pc_exr_read_layers(path, &x, &e), 0);
    int found = -1;
    for (int i = 0; i < x.nlayers; i++)
      if (strcmp(x.names[i], "beauty_max") == 0) found = i;
    if (lag) assert_int_equal(found, -1);
    else {
      assert_true(found >= 0);
      for (int j = 0; j < 6; j++) assert_true(x.layers[found].rgb[j] == (float)abc.layers[m].sum[j]);
    }
    pc_exr_file_free(&x);
    unlink(path);
  }
  rmdir(dir);
  for (int i = 0; i < 3; i++) pc_film_free(&part[i]);
  pc_film_free(&abc);
  pc_film_free(&cba);
}


/* A film of `it` iterations at value j: pt gives a_it*j + 1 at iteration i (a_it = 1, 2, 4, ...),
 * lt adds `l` per iteration with `lp` light paths per iteration (W*H = 2). */
static void fill_iterations(pc_film *f, int it, double l, unsigned lp) {
  int q = pc_film_square_layer(f), m = pc_film_max_layer(f);
  for (int i = 0; i < it; i++)
    for (int j = 0; j < 6; j++) {
      double b = (double)(1 << i) * j + 1, lt = l * lp / 2.0; /* the splats' sum, scaled by W*H/lp */
      f->layers[PC_LAYER_PT].sum[j] += b;
      f->layers[PC_LAYER_LT].sum[j] += lt;
      f->layers[q].sum[j] += (b + l) * (b + l);
      if (b + l > f->layers[m].sum[j]) f->layers[m].sum[j] = b + l;
    }
  for (int k = 0; k < f->nlayers; k++) f->layers[k].count = k == PC_LAYER_LT ? (uint64_t)it * lp : (uint64_t)it;
}

static void test_mix(void **state) {
  (void)state;
  pc_err e = {0};
  pc_film a, b, out;
  assert_int_equal(pc_film_init(&a, 2, 1, 0, &e), 0);
  assert_int_equal(pc_film_init(&b, 2, 1, 0, &e), 0);
  assert_int_equal(pc_film_init(&out, 2, 1, 0, &e), 0);
  fill_iterations(&a, 3, 0.5, 2);  /* light paths counted differently in the two: each layer */
  fill_iterations(&b, 4, 0.25, 6); /* is mixed as an image, not as sums */
  float ia[6], ib[6], io[6], va[6], vb[6], vo[6];
  assert_true(pc_film_variance(&a, va));
  assert_true(pc_film_variance(&b, vb));
  const double w = 0.3;
  pc_film_part parts[] = {{&a, w}, {&b, 1 - w}};
  assert_int_equal(pc_film_mix(&out, parts, 2, &e), 0);
  assert_int_equal(out.layers[PC_LAYER_PT].count, 7);
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) {
    pc_film_layer_image(&a, l, ia);
    pc_film_layer_image(&b, l, ib);
    pc_film_layer_image(&out, l, io);
    for (int j = 0; j < 6; j++) assert_true(fabs(io[j] - (w * ia[j] + (1 - w) * ib[j])) <= 1e-5 * (fabs(io[j]) + 1));
  }
  assert_true(pc_film_variance(&out, vo));
  for (int j = 0; j < 6; j++) {
    double want = w * w * va[j] + (1 - w) * (1 - w) * vb[j];
    assert_true(fabs(vo[j] - want) <= 1e-5 * (want + 1));
  }
  double est, est_mix;
  assert_true(pc_film_relmse_estimate(&out, &est));
  assert_true(pc_film_mix_relmse_estimate(parts, 2, &est_mix));
  assert_true(fabs(est - est_mix) <= 1e-5 * est);
  int m = pc_film_max_layer(&out);
  assert_true(pc_film_max_complete(&out));
  for (int j = 0; j < 6; j++) assert_true(out.layers[m].sum[j] == fmax(a.layers[m].sum[j], b.layers[m].sum[j]));
  /* a part of weight 0 is left out, counts included: the mix is the other part */
  parts[0].weight = 0;
  parts[1].weight = 1;
  assert_int_equal(pc_film_mix(&out, parts, 2, &e), 0);
  assert_int_equal(out.layers[PC_LAYER_PT].count, 4);
  pc_film_beauty(&b, ib);
  pc_film_beauty(&out, io);
  for (int j = 0; j < 6; j++) assert_true(fabs(io[j] - ib[j]) <= 1e-5 * (ib[j] + 1));
  /* a part that cannot tell its variance (1 iteration) leaves the mix unable to tell */
  pc_film_clear(&a);
  fill_iterations(&a, 1, 0.5, 2);
  parts[0].weight = 0.5;
  parts[1].weight = 0.5;
  assert_int_equal(pc_film_mix(&out, parts, 2, &e), 0);
  assert_false(pc_film_variance(&out, vo));
  /* refused: a negative weight, another shape */
  parts[0].weight = -0.1;
  assert_int_not_equal(pc_film_mix(&out, parts, 2, &e), 0);
  pc_film c;
  assert_int_equal(pc_film_init(&c, 1, 2, 0, &e), 0);
  pc_film_part bad[] = {{&c, 1}};
  assert_int_not_equal(pc_film_mix(&out, bad, 1, &e), 0);
  assert_non_null(strstr(e.msg, "film mix"));
  pc_film_free(&c);
  pc_film_free(&a);
  pc_film_free(&b);
  pc_film_free(&out);
}

/* 16x2 pixels: 16 blocks of 2x1. 100 iterations of a constant image, 1 but 101 in iteration 7
 * (a firefly): the image is 2, e_i = (v_i - 2)^2 (100/99) / (4 + eps), so the firefly carries 99%
 * of the summed error. */
static void put_iteration(pc_film *f, uint32_t it, double v) {
  float blk[PC_TRACE_MAX_BLOCKS];
  int nb = pc_trace_blocks(f->w, f->h);
  for (int k = 0; k < nb; k++) blk[k] = (float)v;
  pc_err e = {0};
  assert_int_equal(pc_trace_reserve(&f->trace, f->trace.n + 1, nb, &e), 0);
  pc_trace_put(&f->trace, nb, it, blk);
  for (size_t j = 0; j < (size_t)f->w * f->h * 3; j++) f->layers[PC_LAYER_PT].sum[j] += v;
  for (int l = 0; l < f->nlayers; l++) f->layers[l].count++;
}

static void test_trace(void **state) {
  (void)state;
  pc_err e = {0};
  pc_film f[3];
  for (int i = 0; i < 3; i++) assert_int_equal(pc_film_init(&f[i], 16, 2, 0, &e), 0);
  pc_film *a = &f[0], *b = &f[1], *out = &f[2];
  assert_int_equal(pc_trace_blocks(16, 2), 16);
  uint32_t count[PC_TRACE_MAX_BLOCKS];
  pc_trace_block_pixels(16, 2, count);
  for (int k = 0; k < 16; k++) assert_int_equal(count[k], 2);
  pc_trace_block_pixels(20, 3, count); /* uneven: 8 x 3 blocks of 2 or 3 columns, all 60 pixels */
  uint32_t total = 0;
  for (int k = 0; k < pc_trace_blocks(20, 3); k++) total += count[k];
  assert_int_equal(total, 60);
  for (uint32_t it = 0; it < 60; it++) put_iteration(a, it, it == 7 ? 101 : 1);
  for (uint32_t it = 60; it < 100; it++) put_iteration(b, it, 1);
  assert_int_equal(pc_film_add(a, b, &e), 0);
  assert_int_equal(a->trace.n, 100);
  assert_true(pc_trace_has(&a->trace, 99) && !pc_trace_has(&a->trace, 100));
  pc_iteration_errors ie;
  assert_true(pc_film_iteration_errors(a, &ie));
  double eps = PC_RELMSE_EPS, small = (100.0 / 99) / (4 + eps), big = 99.0 * 99 * (100.0 / 99) / (4 + eps);
  assert_int_equal(ie.n, 100);
  assert_int_equal(ie.worst, 7);
  assert_true(fabs(ie.max - big) <= 1e-9 * big);
  assert_true(fabs(ie.p50 - small) <= 1e-9 && fabs(ie.p99 - small) <= 1e-9);
  assert_true(fabs(ie.mean - (99 * small + big) / 100) <= 1e-9 * big);
  assert_true(fabs(ie.top1 - big / (99 * small + big)) <= 1e-9);
  assert_int_equal(ie.ntail, 6); /* 2^-1 .. 2^-6 of 100 iterations */
  /* the same iterations again are refused, and a is unchanged */
  assert_int_equal(pc_film_add(a, b, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "iteration 60"));
  assert_int_equal(a->trace.n, 100);
  assert_int_equal(a->layers[PC_LAYER_PT].count, 100);
  /* a mix keeps the heaviest part's trace */
  pc_film_part parts[] = {{a, 0.3}, {b, 0.7}};
  assert_int_equal(pc_film_mix(out, parts, 2, &e), 0);
  assert_int_equal(out->trace.n, 40);
  assert_int_equal(out->trace.iteration[0], 60);
  /* one iteration cannot tell; clearing empties the trace */
  pc_film_clear(a);
  put_iteration(a, 3, 1);
  assert_false(pc_film_iteration_errors(a, &ie));
  assert_true(pc_trace_has(&a->trace, 3) && !pc_trace_has(&a->trace, 7));
  for (int i = 0; i < 3; i++) pc_film_free(&f[i]);
}

static void test_bad_sizes(void **state) {
  (void)state;
  pc_film f;
  pc_err e = {0};
  for (int d = 0; d <= 8; d++) { /* what a worker sizes its kept renderers by */
    assert_int_equal(pc_film_init(&f, 2, 2, d, &e), 0);
    assert_int_equal(f.nlayers, pc_film_layer_count(d));
    pc_film_free(&f);
  }
  assert_int_not_equal(pc_film_init(&f, 0, 4, 0, &e), 0);
  assert_int_not_equal(pc_film_init(&f, 4, 4, 9, &e), 0);
}

/* A film only rendered into has every layer of pc_film_init's, with storage only for the
 * norms asked for (the renderer's light splats: lt and the t = 1 strategy layers). */
static void test_stored_norms(void **state) {
  (void)state;
  pc_film all, light;
  pc_err e = {0};
  assert_int_equal(pc_film_init(&all, 3, 2, 2, &e), 0);
  assert_int_equal(pc_film_init_stored(&light, 3, 2, 2, PC_FILM_NORM(PC_NORM_LIGHT), &e), 0);
  assert_int_equal(light.nlayers, all.nlayers);
  int stored = 0;
  for (int i = 0; i < all.nlayers; i++) {
    assert_string_equal(light.layers[i].name, all.layers[i].name);
    assert_int_equal(light.layers[i].norm, all.layers[i].norm);
    assert_non_null(all.layers[i].sum);
    if (light.layers[i].norm == PC_NORM_LIGHT) {
      assert_non_null(light.layers[i].sum);
      stored++;
    } else {
      assert_null(light.layers[i].sum);
    }
  }
  assert_int_equal(stored, 3); /* lt, s1t1, s2t1 */
  /* what the worker's memory bound counts, against what pc_film_init_stored allocates */
  for (int d = 0; d <= 8; d++)
    for (unsigned mask = 0; mask <= PC_FILM_NORMS_ALL; mask++) {
      pc_film g;
      assert_int_equal(pc_film_init_stored(&g, 1, 1, d, mask, &e), 0);
      int n = 0;
      for (int i = 0; i < g.nlayers; i++) n += g.layers[i].sum != NULL;
      assert_int_equal(pc_film_stored_layer_count(d, mask), n);
      pc_film_free(&g);
    }
  assert_int_equal(light.layers[PC_LAYER_LT].sum[5], 0.0);
  pc_film_clear(&light);
  pc_film_free(&light);
  pc_film_free(&all);
}

/* The spare buffer keeps the larger of what it is given (the other freed: ASan and LSan see a
 * leak or a double free), ignores NULL, and is empty once taken or freed. */
static void test_big_spare(void **state) {
  (void)state;
  pc_big_spare s = {0};
  size_t cap;
  assert_null(pc_big_spare_take(&s, &cap));
  assert_int_equal(cap, 0);
  void *a = malloc(100), *b = malloc(50), *c = malloc(200);
  pc_big_spare_keep(&s, a, 100);
  pc_big_spare_keep(&s, b, 50); /* smaller: freed */
  pc_big_spare_keep(&s, NULL, 500);
  assert_ptr_equal(s.p, a);
  pc_big_spare_keep(&s, c, 200); /* larger: a freed */
  assert_ptr_equal(pc_big_spare_take(&s, &cap), c);
  assert_int_equal(cap, 200);
  assert_null(pc_big_spare_take(&s, &cap));
  pc_big_spare_keep(&s, c, 200);
  pc_big_spare_free(&s); /* c freed */
  assert_true(s.p == NULL && s.cap == 0);
  pc_big_spare_free(&s); /* and nothing twice */
}

/* The memory limit is the machine's RAM or less (its cgroup's), and sizes in messages round up. */
static void test_big_memory_limit(void **state) {
  (void)state;
  size_t limit = pc_big_memory_limit();
  long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  assert_true(limit > 0);
  assert_true(limit <= (size_t)pages * (size_t)page);
  assert_int_equal(pc_big_mb(0), 0);
  assert_int_equal(pc_big_mb(1), 1);
  assert_int_equal(pc_big_mb(1048576), 1);
  assert_int_equal(pc_big_mb(1048577), 2);
}

/* The films' big buffers: whole, PC_BIG_ALLOC_SLACK bytes readable past the end,
 * 2 MiB-aligned from 2 MiB on, NULL for sizes that cannot be rounded up to a whole huge page,
 * and a pointer to free for 0 bytes. */
static void test_big_alloc(void **state) {
  (void)state;
  const size_t sizes[] = {1, 4095, ((size_t)2 << 20) - 1, (size_t)2 << 20, ((size_t)5 << 20) + 3};
  for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
    size_t n = sizes[i];
    unsigned char *p = pc_big_alloc(n);
    assert_non_null(p);
    if (n >= ((size_t)2 << 20)) assert_int_equal((uintptr_t)p % ((uintptr_t)2 << 20), 0);
    memset(p, 7, n); /* the whole of it is ours */
    volatile unsigned char past = 0; /* and PC_BIG_ALLOC_SLACK more readable (ASan checks the reads) */
    for (size_t k = 0; k < PC_BIG_ALLOC_SLACK; k++) past |= p[n + k];
    (void)past;
    free(p);
  }
  void *none = pc_big_alloc(0); /* 0 bytes is not out of memory: callers need no guard */
  assert_non_null(none);
  free(none);
  assert_null(pc_big_alloc(SIZE_MAX));
  assert_null(pc_big_alloc(SIZE_MAX - ((size_t)1 << 20)));
  pc_film f;
  pc_err e = {0};
  assert_int_equal(pc_film_init(&f, 512, 512, 0, &e), 0);
  for (int l = 0; l < f.nlayers; l++) {
    assert_int_equal((uintptr_t)f.layers[l].sum % ((uintptr_t)2 << 20), 0);
    assert_true(f.layers[l].sum[0] == 0.0 && f.layers[l].sum[512 * 512 * 3 - 1] == 0.0);
  }
  pc_film_free(&f);
}

/* A film made unzeroed is zeroed piece by piece: the pieces cover every stored sum once, lie
 * within their layer (ASan checks the writes), and a pool's threads zero them as one thread
 * would; pc_film_init_threads makes the film pc_film_init does. Sizes: a layer smaller than a
 * piece, and one a piece and a bit (the last piece short). */
static void test_film_pieces(void **state) {
  (void)state;
  const int sizes[][2] = {{7, 5}, {300, 300}, {1, 1}};
  pc_pool *pool = NULL;
  pc_err e = {0};
  assert_int_equal(pc_pool_create(3, &pool, &e), PC_OK);
  for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
    int w = sizes[i][0], h = sizes[i][1];
    size_t n = (size_t)w * h * 3, per = (n * sizeof(double) + PC_FILM_PIECE_BYTES - 1) / PC_FILM_PIECE_BYTES;
    pc_film f;
    assert_int_equal(pc_film_alloc_stored(&f, w, h, 1, PC_FILM_NORM(PC_NORM_EYE) | PC_FILM_NORM(PC_NORM_MAX), &e), PC_OK);
    int held = 0;
    for (int l = 0; l < f.nlayers; l++)
      if (f.layers[l].sum) {
        held++;
        memset(f.layers[l].sum, 0xff, n * sizeof(double));
      }
    assert_int_equal(pc_film_pieces(&f), held * (int)per);
    pc_film_zero_on(pool, &f);
    for (int l = 0; l < f.nlayers; l++)
      for (size_t k = 0; f.layers[l].sum && k < n; k++) assert_true(f.layers[l].sum[k] == 0.0);
    pc_film_free(&f);
    pc_film g, ref;
    assert_int_equal(pc_film_init_threads(&g, w, h, 2, 0, &e), PC_OK);
    assert_int_equal(pc_film_init(&ref, w, h, 2, &e), PC_OK);
    assert_int_equal(g.nlayers, ref.nlayers);
    for (int l = 0; l < g.nlayers; l++) {
      assert_string_equal(g.layers[l].name, ref.layers[l].name);
      assert_non_null(g.layers[l].sum);
      for (size_t k = 0; k < n; k++) assert_true(g.layers[l].sum[k] == 0.0);
    }
    pc_film_free(&g);
    pc_film_free(&ref);
  }
  pc_pool_destroy(pool);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_layers_and_normalization),
      cmocka_unit_test(test_variance),
      cmocka_unit_test(test_max_merge),
      cmocka_unit_test(test_mix),
      cmocka_unit_test(test_trace),
      cmocka_unit_test(test_bad_sizes),
      cmocka_unit_test(test_stored_norms),
      cmocka_unit_test(test_big_alloc),
      cmocka_unit_test(test_film_pieces),
      cmocka_unit_test(test_big_spare),
      cmocka_unit_test(test_big_memory_limit),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
