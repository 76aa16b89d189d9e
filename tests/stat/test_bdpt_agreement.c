/* test_bdpt_agreement.c: PT, LT and BDPT converge to the same images on the shipped scenes, and
 * every BDPT strategy on its own estimates the same thing. Standard errors come from the spread
 * of independent iterations (fixed seeds: the test is deterministic):
 *  - per 8x8-pixel block means of the beauty, PT vs BDPT on every scene and LT vs BDPT where
 *    light tracing sees everything the camera sees (no delta surface in view), and PCBPT vs
 *    BDPT on a few (on ajar-door with resampled connections whose target traces visibility);
 *  - with the debug switch `unweighted`, each strategy (s,t) of path lengths 2 and 3 alone
 *    estimates the whole path-length term, so their image totals agree; and the weighted
 *    strategies of one length add up to the same total;
 *  - no strategy produces NaN or Inf on any scene (film drop counters stay 0), including a
 *    camera that sees the Cornell box light exactly edge-on. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stat_util.h"

#define MAXL 8

/* Per-iteration block means of several layers (-1 = beauty); index nl holds their sum. */
typedef struct multi {
  int nl, nb, bw, n;
  double sum[MAXL][64 * 64], sum2[MAXL][64 * 64];
} multi;

static void render_multi(const char *name, pc_render_settings set, int iters, const int *layers, int nl, int bs,
                         void (*tweak)(pc_scene *), multi *out) {
  pc_render_request req;
  pc_render_request_default(&req);
  req.set = set;
  req.method_set = req.depth_set = req.width_set = req.height_set = true;
  pc_scene scene = {0};
  char *path = stat_scene_path(name);
  pc_err e = {0};
  assert_int_equal(pc_scene_load(path, &scene, &e), PC_OK);
  free(path);
  pc_render_request_apply_scene(&req, &scene);
  if (tweak) tweak(&scene);
  assert_int_equal(pc_scene_build(&scene, &e), PC_OK);
  pc_renderer *r = NULL;
  pc_film film;
  assert_int_equal(pc_film_init(&film, set.width, set.height, set.strategy_layers, &e), PC_OK);
  if (pc_renderer_create(&scene, &req.set, 2, &r, &e) != PC_OK) {
    fprintf(stderr, "%s\n", e.msg);
    fail();
  }
  memset(out, 0, sizeof *out);
  out->nl = nl;
  out->bw = (set.width + bs - 1) / bs;
  out->nb = out->bw * ((set.height + bs - 1) / bs);
  float *img = malloc(sizeof(float) * 3 * (size_t)set.width * set.height);
  double blk[64 * 64], tot[64 * 64];
  for (int it = 0; it < iters; it++) {
    memset(tot, 0, sizeof tot);
    pc_film_clear(&film);
    assert_int_equal(pc_render_iterations(r, (uint64_t)it, 1, &film, NULL, NULL, NULL, NULL, &e), PC_OK);
    assert_int_equal(film.dropped_nonfinite, 0);
    assert_true(pc_film_is_finite(&film));
    for (int l = 0; l < nl; l++) {
      if (layers[l] < 0) pc_film_beauty(&film, img);
      else pc_film_layer_image(&film, layers[l], img);
      memset(blk, 0, sizeof blk);
      for (int y = 0; y < set.height; y++)
        for (int x = 0; x < set.width; x++) {
          const float *p = img + 3 * ((size_t)y * set.width + x);
          blk[(y / bs) * out->bw + x / bs] += (p[0] + p[1] + p[2]) / (3.0 * bs * bs);
        }
      for (int b = 0; b < out->nb; b++) {
        out->sum[l][b] += blk[b];
        out->sum2[l][b] += blk[b] * blk[b];
        tot[b] += blk[b];
      }
    }
    for (int b = 0; b < out->nb; b++) {
      out->sum[nl][b] += tot[b];
      out->sum2[nl][b] += tot[b] * tot[b];
    }
    out->n++;
  }
  free(img);
  pc_renderer_destroy(r);
  pc_film_free(&film);
  pc_scene_free(&scene);
}

static double mean_of(const multi *m, int l, int b) { return m->sum[l][b] / m->n; }
static double se_of(const multi *m, int l, int b) {
  double mu = mean_of(m, l, b);
  double var = (m->sum2[l][b] / m->n - mu * mu) * m->n / (m->n - 1);
  return sqrt(var > 0 ? var / m->n : 0);
}

static pc_render_settings settings(pc_method method, int res, int depth, uint64_t seed) {
  pc_render_settings s;
  pc_render_settings_default(&s);
  s.method = method;
  s.width = s.height = res;
  s.max_depth = depth;
  s.seed = seed;
  return s;
}

/* Block-by-block comparison: every |z| < zmax and the mean z^2 (a chi-square per degree of
 * freedom) below 2, which catches a small bias spread over all blocks. */
static void compare_blocks(const char *what, const multi *a, int la, const multi *b, int lb, double zmax) {
  double z2 = 0, worst = 0;
  int nz = 0;
  for (int k = 0; k < a->nb; k++) {
    double d = mean_of(a, la, k) - mean_of(b, lb, k);
    double se = sqrt(se_of(a, la, k) * se_of(a, la, k) + se_of(b, lb, k) * se_of(b, lb, k));
    if (se == 0) {
      assert_true(fabs(d) < 1e-9);
      continue;
    }
    double z = d / se;
    z2 += z * z;
    nz++;
    if (fabs(z) > fabs(worst)) worst = z;
  }
  printf("%-40s blocks %3d  mean z^2 %.2f  worst z %+.2f\n", what, nz, nz ? z2 / nz : 0, worst);
  assert_true(fabs(worst) < zmax);
  assert_true(nz == 0 || z2 / nz < 2.0);
}

/* pcbpt: 0 none, 1 PCBPT with its defaults, 2 PCBPT with resampled connections whose target
 * traces the candidates' shadow rays (what matters behind the ajar door). */
static void agree(const char *scene, int iters, bool lt, int pcbpt) {
  int beauty = -1;
  multi *pt = malloc(sizeof *pt), *bd = malloc(sizeof *bd), *l = malloc(sizeof *l);
  /* PT is cheaper and its caustics (s=0 only) heavy-tailed: 4x the iterations keep its
   * measured standard error honest. */
  render_multi(scene, settings(PC_METHOD_PT, 64, 6, 11), 4 * iters, &beauty, 1, 8, NULL, pt);
  render_multi(scene, settings(PC_METHOD_BDPT, 64, 6, 12), iters, &beauty, 1, 8, NULL, bd);
  char what[128];
  snprintf(what, sizeof what, "%s pt vs bdpt", scene);
  compare_blocks(what, pt, 0, bd, 0, 5.0);
  if (lt) {
    render_multi(scene, settings(PC_METHOD_LT, 64, 6, 13), iters, &beauty, 1, 8, NULL, l);
    snprintf(what, sizeof what, "%s lt vs bdpt", scene);
    compare_blocks(what, l, 0, bd, 0, 5.0);
  }
  if (pcbpt) {
    pc_render_settings set = settings(PC_METHOD_PCBPT, 64, 6, 14);
    set.pcbpt_m = 50;
    set.pcbpt_k = 2;
    set.cache_fraction = 0.02f;
    if (pcbpt == 2) {
      set.pcbpt_candidates = 4;
      set.candidate_visibility = PC_CANDVIS_TRACED;
    }
    render_multi(scene, set, iters, &beauty, 1, 8, NULL, l);
    snprintf(what, sizeof what, "%s pcbpt%s vs bdpt", scene, pcbpt == 2 ? " traced" : "");
    compare_blocks(what, l, 0, bd, 0, 5.0);
  }
  free(pt);
  free(bd);
  free(l);
}

static void test_agree_cornell(void **state) {
  (void)state;
  agree("cornell-box", 128, true, 0);
}
static void test_agree_glossy_glass(void **state) {
  (void)state;
  agree("glossy-glass", 128, false, 0); /* the glass sphere in view: light tracing cannot see it */
}
static void test_agree_open_room(void **state) {
  (void)state;
  agree("open-room", 96, true, 0);
}
static void test_agree_slit_room(void **state) {
  (void)state;
  agree("slit-room", 96, false, 0);
}
static void test_agree_ajar_door(void **state) {
  (void)state;
  agree("ajar-door", 96, false, 2);
}

/* The environment (a sky envmap with a sun) seen directly and lighting Beckmann rough
 * conductor and plastic: PT, LT, BDPT and PCBPT agree. */
static void test_agree_env_objects(void **state) {
  (void)state;
  agree("env-objects", 128, true, 1);
}

/* env-objects with its rough glass made near-specular (alpha 1e-4, as published scenes write
 * smooth-looking glass) and the scene moved away from the origin (the offset of ray origins
 * grows with the coordinates): the lobe is then narrower than the angle by which the offsets
 * turn the sub-paths' edges, so the sub-paths must keep their sampled pdfs there (subpath.c;
 * before, BDPT lost most of the light through the glass). The environment does not move. */
static void near_specular(pc_scene *s) {
  vec3 t = v3(4.f, -3.f, 4.f);
  for (int i = 0; i < s->nmaterials; i++)
    if (s->materials[i].type == PC_MAT_ROUGHDIELECTRIC) s->materials[i].alpha = 1e-4f;
  for (int i = 0; i < s->nshapes; i++) {
    pc_shape *sh = &s->shapes[i];
    sh->center = v3_add(sh->center, t);
    for (uint32_t k = 0; k < sh->mesh.nverts; k++) sh->mesh.p[k] = v3_add(sh->mesh.p[k], t);
  }
  s->camera.to_world.m[0][3] += t.x;
  s->camera.to_world.m[1][3] += t.y;
  s->camera.to_world.m[2][3] += t.z;
}

static void test_agree_near_specular(void **state) {
  (void)state;
  int beauty = -1;
  multi *pt = malloc(sizeof *pt), *bd = malloc(sizeof *bd);
  render_multi("env-objects", settings(PC_METHOD_PT, 64, 6, 15), 256, &beauty, 1, 8, near_specular, pt);
  render_multi("env-objects", settings(PC_METHOD_BDPT, 64, 6, 16), 64, &beauty, 1, 8, near_specular, bd);
  compare_blocks("env-objects alpha 1e-4 pt vs bdpt", pt, 0, bd, 0, 5.0);
  free(pt);
  free(bd);
}

/* A thin glass pane (delta, so light tracing cannot see through it), a rough glass cube and a
 * Ward sphere. */
static void test_agree_thin_glass(void **state) {
  (void)state;
  agree("thin-glass", 96, false, 1);
}

/* The Cornell box dressed in Mitsuba's wrappers: the floor and the tall box (twosided) bump-mapped
 * (a smooth height field, so the bumped frames vary across every triangle), the back wall under a
 * rough coating, the right wall an anisotropic rough conductor (alphaU 0.05, alphaV 0.4 along the
 * Mitsuba frame's tangents) bump-mapped too, and, when `smooth`, the short box under an absorbing
 * smooth coating (a delta lobe in view: no light tracing then). */
static bool with_smooth_coating;
static int append_material(pc_scene *s, pc_material m) {
  pc_material *q = realloc(s->materials, sizeof *q * (size_t)(s->nmaterials + 1));
  assert_non_null(q);
  s->materials = q;
  s->materials[s->nmaterials] = m;
  return s->nmaterials++;
}
static pc_material wrapper(pc_mat_type type, int nested) {
  pc_material m;
  memset(&m, 0, sizeof m);
  m.type = type;
  m.nested = nested;
  m.bump_tex = 0;
  m.specular = (pc_tex_slot){-1, v3s(1.f)};
  m.sigma_a = (pc_tex_slot){-1, v3s(0.f)};
  m.int_ior = 1.5f;
  m.ext_ior = 1.f;
  m.thickness = 1.f;
  m.alpha = 0.2f;
  m.distribution = PC_MF_GGX;
  return m;
}
static void layered_cornell(pc_scene *s) {
  enum { N = 32 };
  pc_texture t;
  memset(&t, 0, sizeof t);
  t.type = PC_TEX_BITMAP;
  t.uscale = t.vscale = 1.f;
  t.img = (pc_image){.w = N, .h = N, .rgb = malloc(sizeof(float) * 3 * N * N)};
  assert_non_null(t.img.rgb);
  for (int y = 0; y < N; y++)
    for (int x = 0; x < N; x++)
      for (int c = 0; c < 3; c++)
        t.img.rgb[3 * (y * N + x) + c] = 0.05f * (sinf(2 * PC_PI * 2 * x / N) + cosf(2 * PC_PI * 3 * y / N));
  pc_texture *q = realloc(s->textures, sizeof *q * (size_t)(s->ntextures + 1));
  assert_non_null(q);
  s->textures = q;
  s->textures[s->ntextures++] = t;
  assert_int_equal(s->ntextures, 1);
  int floor = s->shapes[0].material, back = s->shapes[2].material, right = s->shapes[3].material;
  int tall = s->shapes[6].material, shortbox = s->shapes[5].material;
  s->shapes[0].material = append_material(s, wrapper(PC_MAT_BUMPMAP, floor));
  /* the tall box: Mitsuba's twosided around the bumpmap (its frame mirrored behind) */
  s->materials[tall].twosided = false;
  pc_material tb = wrapper(PC_MAT_BUMPMAP, tall);
  tb.twosided = true;
  s->shapes[6].material = append_material(s, tb);
  s->shapes[2].material = append_material(s, wrapper(PC_MAT_ROUGHCOATING, back));
  pc_material *r = &s->materials[right];
  r->type = PC_MAT_ROUGHCONDUCTOR;
  r->distribution = PC_MF_BECKMANN;
  r->alpha = 0.05f;
  r->alpha_v = 0.4f;
  assert_true(pc_conductor_ior("Cu", &r->eta, &r->k));
  s->shapes[3].material = append_material(s, wrapper(PC_MAT_BUMPMAP, right));
  if (with_smooth_coating) {
    pc_material c = wrapper(PC_MAT_COATING, shortbox);
    c.sigma_a = (pc_tex_slot){-1, v3(0.1f, 0.3f, 0.6f)};
    s->shapes[5].material = append_material(s, c);
  }
}

static void test_agree_layered(void **state) {
  (void)state;
  int beauty = -1;
  for (int smooth = 0; smooth < 2; smooth++) {
    with_smooth_coating = smooth;
    multi *pt = malloc(sizeof *pt), *bd = malloc(sizeof *bd), *l = malloc(sizeof *l);
    render_multi("cornell-box", settings(PC_METHOD_PT, 64, 6, 31), 256, &beauty, 1, 8, layered_cornell, pt);
    render_multi("cornell-box", settings(PC_METHOD_BDPT, 64, 6, 42), 64, &beauty, 1, 8, layered_cornell, bd);
    compare_blocks(smooth ? "cornell layered+coating pt vs bdpt" : "cornell layered pt vs bdpt", pt, 0, bd, 0, 5.0);
    if (!smooth) {
      render_multi("cornell-box", settings(PC_METHOD_LT, 64, 6, 43), 64, &beauty, 1, 8, layered_cornell, l);
      compare_blocks("cornell layered lt vs bdpt", l, 0, bd, 0, 5.0);
    }
    pc_render_settings set = settings(PC_METHOD_PCBPT, 64, 6, 34);
    set.pcbpt_m = 50;
    set.pcbpt_k = 2;
    set.cache_fraction = 0.02f;
    render_multi("cornell-box", set, 64, &beauty, 1, 8, layered_cornell, l);
    compare_blocks(smooth ? "cornell layered+coating pcbpt vs bdpt" : "cornell layered pcbpt vs bdpt", l, 0, bd, 0, 5.0);
    free(pt);
    free(bd);
    free(l);
  }
}

/* The Cornell box with Mitsuba's combining BSDFs: the back wall a blendbsdf (weight 0.4) of its
 * diffuse and a rough conductor, the right wall a mixturebsdf (weights 0.5 0.3 0.4, rescaled) of
 * diffuse, difftrans and rough conductor, the short box difftrans (light enters it and leaves
 * through its other faces), and, when `masked`, the tall box behind a mask whose opacity is a
 * checkerboard of 0.8 and 0.3 (a delta pass-through in view: no light tracing then). */
static bool with_mask;
static void mixed_cornell(pc_scene *s) {
  pc_texture t;
  memset(&t, 0, sizeof t);
  t.type = PC_TEX_CHECKER;
  t.color0 = v3s(0.8f);
  t.color1 = v3s(0.3f);
  t.uscale = t.vscale = 4.f;
  pc_texture *q = realloc(s->textures, sizeof *q * (size_t)(s->ntextures + 1));
  assert_non_null(q);
  s->textures = q;
  s->textures[s->ntextures++] = t;
  int back = s->shapes[2].material, right = s->shapes[3].material, tall = s->shapes[6].material;
  pc_material rc = wrapper(PC_MAT_ROUGHCONDUCTOR, -1);
  rc.alpha = 0.3f;
  assert_true(pc_conductor_ior("Au", &rc.eta, &rc.k));
  int irc = append_material(s, rc);
  pc_material dt = wrapper(PC_MAT_DIFFTRANS, -1);
  dt.transmittance = (pc_tex_slot){-1, v3(0.7f, 0.6f, 0.4f)};
  int idt = append_material(s, dt);
  pc_material bl = wrapper(PC_MAT_BLEND, -1);
  bl.nmix = 2;
  bl.mix_nested[0] = back;
  bl.mix_nested[1] = irc;
  bl.weight = (pc_tex_slot){-1, v3s(0.4f)};
  s->shapes[2].material = append_material(s, bl);
  pc_material mx = wrapper(PC_MAT_MIXTURE, -1);
  const float w[3] = {0.5f, 0.3f, 0.4f};
  const int comp[3] = {right, idt, irc};
  mx.nmix = 3;
  for (int k = 0; k < 3; k++) mx.mix_nested[k] = comp[k], mx.mix_w[k] = w[k] / 1.2f, mx.mix_p[k] = w[k] / 1.2f;
  s->shapes[3].material = append_material(s, mx);
  s->shapes[5].material = idt;
  if (with_mask) {
    pc_material mk = wrapper(PC_MAT_MASK, tall);
    mk.weight = (pc_tex_slot){s->ntextures - 1, v3s(0.5f)};
    s->shapes[6].material = append_material(s, mk);
  }
}

static void test_agree_mixed(void **state) {
  (void)state;
  int beauty = -1;
  for (int masked = 0; masked < 2; masked++) {
    with_mask = masked;
    multi *pt = malloc(sizeof *pt), *bd = malloc(sizeof *bd), *l = malloc(sizeof *l);
    render_multi("cornell-box", settings(PC_METHOD_PT, 64, 6, 51), 256, &beauty, 1, 8, mixed_cornell, pt);
    render_multi("cornell-box", settings(PC_METHOD_BDPT, 64, 6, 52), 64, &beauty, 1, 8, mixed_cornell, bd);
    compare_blocks(masked ? "cornell mixed+mask pt vs bdpt" : "cornell mixed pt vs bdpt", pt, 0, bd, 0, 5.0);
    if (!masked) {
      render_multi("cornell-box", settings(PC_METHOD_LT, 64, 6, 53), 64, &beauty, 1, 8, mixed_cornell, l);
      compare_blocks("cornell mixed lt vs bdpt", l, 0, bd, 0, 5.0);
    }
    render_multi("cornell-box", settings(PC_METHOD_CBDPT, 64, 6, 55), 64, &beauty, 1, 8, mixed_cornell, l);
    compare_blocks(masked ? "cornell mixed+mask cbdpt vs bdpt" : "cornell mixed cbdpt vs bdpt", l, 0, bd, 0, 5.0);
    pc_render_settings set = settings(PC_METHOD_PCBPT, 64, 6, 54);
    set.pcbpt_m = 50;
    set.pcbpt_k = 2;
    set.cache_fraction = 0.02f;
    render_multi("cornell-box", set, 64, &beauty, 1, 8, mixed_cornell, l);
    compare_blocks(masked ? "cornell mixed+mask pcbpt vs bdpt" : "cornell mixed pcbpt vs bdpt", l, 0, bd, 0, 5.0);
    free(pt);
    free(bd);
    free(l);
  }
}

/* Totals of every strategy of path lengths 2 and 3 (segments) on a scene. */
static void strategies(const char *scene) {
  pc_render_settings set = settings(PC_METHOD_BDPT, 32, 3, 21);
  set.strategy_layers = 3;
  pc_film probe;
  pc_err e = {0};
  assert_int_equal(pc_film_init(&probe, 1, 1, 3, &e), PC_OK);
  for (int k = 2; k <= 3; k++) {
    int layers[MAXL], nl = 0;
    for (int t = 1; t <= k + 1; t++) layers[nl++] = pc_film_strategy_layer(&probe, k + 1 - t, t);
    multi *un = malloc(sizeof *un), *wt = malloc(sizeof *wt);
    set.unweighted = true;
    set.seed = 21;
    render_multi(scene, set, 96, layers, nl, 32, NULL, un);
    set.unweighted = false;
    set.seed = 22;
    render_multi(scene, set, 96, layers, nl, 32, NULL, wt);
    /* Reference: the unweighted s=1 estimate (NEE, the least noisy here). */
    int ref = nl - 2;
    for (int l = 0; l < nl; l++) {
      double d = mean_of(un, l, 0) - mean_of(un, ref, 0);
      double se = sqrt(se_of(un, l, 0) * se_of(un, l, 0) + se_of(un, ref, 0) * se_of(un, ref, 0));
      printf("%s length %d  %-5s unweighted %.5f +- %.5f  (z %+.2f)  weighted %.5f\n", scene, k, probe.layers[layers[l]].name,
             mean_of(un, l, 0), se_of(un, l, 0), se > 0 ? d / se : 0.0, mean_of(wt, l, 0));
      assert_true(mean_of(un, l, 0) > 0);
      assert_true(fabs(d) < 4.5 * se);
    }
    /* The weighted strategies of one length add up to the same term (their per-iteration sum,
     * from another seed than the reference). */
    double sw = mean_of(wt, nl, 0);
    double se = sqrt(se_of(wt, nl, 0) * se_of(wt, nl, 0) + se_of(un, ref, 0) * se_of(un, ref, 0));
    printf("%s length %d  weighted sum %.5f vs %.5f (z %+.2f)\n", scene, k, sw, mean_of(un, ref, 0), (sw - mean_of(un, ref, 0)) / se);
    assert_true(fabs(sw - mean_of(un, ref, 0)) < 4.5 * se);
    free(un);
    free(wt);
  }
  pc_film_free(&probe);
}

static void test_strategies(void **state) {
  (void)state;
  strategies("cornell-box");
  strategies("env-objects"); /* s=0 escapes, s=1 and t=1 at infinity, light paths from the disk */
}

/* The furnace (exact radiance Le * sum_{k<d} a^k, see test_furnace.c) with the power heuristic
 * and with N_L != W*H: fewer light paths than pixels (pairing modulo N_L) and more (a light
 * pass of unpaired light paths), 64 iterations as in the acceptance criterion. */
static void test_furnace_counts(void **state) {
  (void)state;
  static const struct {
    pc_method method;
    pc_mis_heuristic h;
    uint64_t light_paths;
    int depth;
  } cases[] = {
      {PC_METHOD_BDPT, PC_MIS_POWER, 341, -1},  {PC_METHOD_BDPT, PC_MIS_BALANCE, 2560, 3},
      {PC_METHOD_BDPT, PC_MIS_POWER, 3000, 4},  {PC_METHOD_LT, PC_MIS_POWER, 2048, -1},
      {PC_METHOD_LT, PC_MIS_BALANCE, 300, 2},
  };
  int beauty = -1;
  multi *m = malloc(sizeof *m);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    pc_render_settings set = settings(cases[i].method, 32, cases[i].depth, 51 + i);
    set.mis_heuristic = cases[i].h;
    set.light_paths = cases[i].light_paths;
    render_multi("furnace", set, 64, &beauty, 1, 32, NULL, m);
    double exact = 0, ak = 1;
    for (int k = 0; k < (cases[i].depth < 0 ? 200 : cases[i].depth); k++, ak *= 0.5) exact += ak;
    double mu = mean_of(m, 0, 0), se = se_of(m, 0, 0);
    printf("furnace %-4s %-7s N_L %5llu maxDepth %2d: %.5f exact %.5f se %.5f (%.2f%%)\n",
           pc_method_name(cases[i].method), cases[i].h == PC_MIS_POWER ? "power" : "balance",
           (unsigned long long)cases[i].light_paths, cases[i].depth, mu, exact, se, 100 * fabs(mu - exact) / exact);
    assert_true(fabs(mu - exact) < 4 * se);
    assert_true(fabs(mu - exact) < 0.015 * exact);
  }
  free(m);
}

/* The Cornell box camera moved to the height of the light: its plane is seen exactly edge-on. */
static void edge_on(pc_scene *s) {
  const pc_shape *sh = &s->shapes[s->lights[0].shape];
  double y = 0;
  for (uint32_t i = 0; i < sh->mesh.nverts; i++) y += sh->mesh.p[i].y;
  s->camera.to_world.m[1][3] = y / sh->mesh.nverts;
}

static void test_finite(void **state) {
  (void)state;
  static const char *const scenes[] = {"cornell-box", "furnace", "ajar-door", "slit-room", "open-room", "glossy-glass",
                                       "env-constant", "env-white-map", "env-objects", "thin-glass"};
  static const pc_method methods[] = {PC_METHOD_PT, PC_METHOD_LT, PC_METHOD_BDPT};
  int beauty = -1;
  multi *m = malloc(sizeof *m);
  for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++)
    for (size_t j = 0; j < 3; j++)
      for (int h = 0; h < 2; h++) {
        pc_render_settings set = settings(methods[j], 16, -1, 31);
        set.mis_heuristic = h ? PC_MIS_POWER : PC_MIS_BALANCE;
        set.light_paths = h ? 97 : 0; /* fewer light paths than pixels: pairing modulo N_L */
        render_multi(scenes[i], set, 4, &beauty, 1, 16, NULL, m);
      }
  for (size_t j = 0; j < 3; j++) {
    render_multi("cornell-box", settings(methods[j], 32, -1, 41), 8, &beauty, 1, 32, edge_on, m);
    assert_true(mean_of(m, 0, 0) > 0);
  }
  free(m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_finite),         cmocka_unit_test(test_furnace_counts),
      cmocka_unit_test(test_strategies),
      cmocka_unit_test(test_agree_cornell),  cmocka_unit_test(test_agree_glossy_glass),
      cmocka_unit_test(test_agree_open_room), cmocka_unit_test(test_agree_ajar_door),
      cmocka_unit_test(test_agree_slit_room), cmocka_unit_test(test_agree_env_objects),
      cmocka_unit_test(test_agree_thin_glass), cmocka_unit_test(test_agree_near_specular),
      cmocka_unit_test(test_agree_layered),  cmocka_unit_test(test_agree_mixed),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
