/* test_bdpt_mis.c: the recursive MIS weights of the bidirectional integrators against a brute
 * force. Random light and eye sub-paths are traced in scenes/glossy-glass (its glass sphere made
 * a perfect mirror, so delta vertices occur and their lobe probabilities are known; optionally a
 * point or spot light added, the spot's light paths leaving over its cutoff cone); every connection the integrator makes (s=0 hits, s=1, t=1 and inner) gives
 * a complete path whose strategies' pdfs are then evaluated explicitly, vertex by vertex, in
 * double precision, with Russian roulette, sample counts and the heuristic. The weight the
 * integrator computed must equal the explicit one, and re-deriving the weight of every other
 * strategy of the same path through the production routines (pc_mis_extend, pc_connect,
 * pc_mis_weight_hit) must give the explicit weights too, summing to 1. The same on
 * scenes/env-objects, lit by an envmap: the environment vertex at infinity has solid-angle
 * densities from both sides and the first vertex of its light paths the disk's area density
 * times its cosine (path_vertex.h); the explicit evaluation places it far along its direction.
 * A directional light is such a vertex too, with a Dirac in direction: no eye path reaches it
 * (s=0 impossible), and its light paths start on the same disk. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bidir.h"

#define MAXV 12
#define MAX_SEGMENTS 8

typedef struct fixture {
  pc_scene scene;
  pc_render_settings set;
  pc_tctx c;
  pc_path_vertex *lbuf, *ebuf;
  int checked, strategies_checked, env_checked, at_point_checked; /* at_point: from a point or spot light */
  int directional_checked; /* counted in env_checked too */
  int filtered_pixels;     /* t = 1 paths weighed for a pixel of a filter's footprint */
} fixture;

/* The light added to a scene: none, a point light, a spot (60 degree cutoff, 40 degree beam) or
 * a directional light. */
typedef enum { NO_EXTRA, EXTRA_POINT, EXTRA_SPOT, EXTRA_DIRECTIONAL } extra_light;
#define SPOT_CUTOFF_DEG 60.0

static void load_scene(fixture *f, const char *name, extra_light extra) {
  const char *src = getenv("PCBPT_SOURCE_DIR");
  char path[4096];
  snprintf(path, sizeof path, "%s/scenes/%s/scene.xml", src ? src : ".", name);
  pc_err e = {0};
  memset(&f->scene, 0, sizeof f->scene);
  assert_int_equal(pc_scene_load(path, &f->scene, &e), PC_OK);
  int mirrors = 0;
  for (int i = 0; i < f->scene.nmaterials; i++) {
    pc_material *m = &f->scene.materials[i];
    if (m->type != PC_MAT_DIELECTRIC) continue;
    memset(m, 0, sizeof *m);
    m->type = PC_MAT_CONDUCTOR;
    assert_true(pc_conductor_ior("none", &m->eta, &m->k));
    m->specular.tex = -1;
    m->specular.value = v3s(1.f);
    mirrors++;
  }
  assert_int_equal(mirrors, strcmp(name, "glossy-glass") == 0);
  if (extra != NO_EXTRA) {
    pc_scene *s = &f->scene;
    s->lights = realloc(s->lights, sizeof(pc_light) * (size_t)(s->nlights + 1));
    pc_light *l = &s->lights[s->nlights++];
    memset(l, 0, sizeof *l);
    l->type = extra == EXTRA_SPOT ? PC_LIGHT_SPOT : PC_LIGHT_POINT;
    l->intensity = v3s(30.f);
    l->spot_frame = frame_from_normal(v3_norm(v3(-0.3f, -1.f, -0.2f)));
    pc_spot_set_angles(l, (float)SPOT_CUTOFF_DEG, 40.f);
    l->shape = -1;
    l->position = v3_add(s->scene_center, v3(0.3f, 0.2f, 0.1f));
    if (extra == EXTRA_DIRECTIONAL) {
      l->type = PC_LIGHT_DIRECTIONAL;
      l->irradiance = v3s(3.f);
      l->direction = v3_norm(v3(-0.3f, -1.f, -0.2f));
    }
  }
  f->scene.camera.width = f->scene.camera.height = 32;
  assert_int_equal(pc_scene_build(&f->scene, &e), PC_OK);
  if (extra != NO_EXTRA) { /* scene_center is known only after the build: move the light inside */
    f->scene.lights[f->scene.nlights - 1].position = v3_add(f->scene.scene_center, v3(0.3f, 0.2f, 0.1f));
  }
  pc_render_settings_default(&f->set);
  f->set.method = PC_METHOD_BDPT;
  f->set.width = f->set.height = 32;
  f->set.max_depth = MAX_SEGMENTS;
  f->lbuf = calloc(MAXV, sizeof(pc_path_vertex));
  f->ebuf = calloc(MAXV, sizeof(pc_path_vertex));
  memset(&f->c, 0, sizeof f->c);
  f->c.scene = &f->scene;
  f->c.set = &f->set;
  f->c.max_segments = MAX_SEGMENTS;
  f->c.light_path = f->lbuf;
  f->c.eye_path = f->ebuf;
  f->c.weighted = true;
}

static void load(fixture *f, extra_light extra) { load_scene(f, "glossy-glass", extra); }

static void unload(fixture *f) {
  free(f->lbuf);
  free(f->ebuf);
  pc_scene_free(&f->scene);
}

/* ---- The explicit evaluation. A complete path x_0 (light) .. x_k (camera). ---- */

typedef struct fpath {
  int k;
  pc_path_vertex x[2 * MAXV]; /* x[0]: kind LIGHT (p, ng, light); others SURFACE or CAMERA */
  int pixel_x, pixel_y;       /* the pixel whose measurement the path is weighed for */
  double density;             /* that pixel's filter density where the camera sees x[k-1] */
} fpath;

static bool is_delta(const fpath *fp, int i) { return i > 0 && i < fp->k && fp->x[i].delta; }

static double qv(const fixture *f, const fpath *fp, int i) {
  const pc_path_vertex *v = &fp->x[i];
  return pc_bsdf_continuation(&f->scene.materials[v->material], f->scene.textures, &v->sh);
}

static vec3 unit(vec3 a, vec3 b) { return v3_norm(v3_sub(b, a)); }

/* The environment vertex x_0 stands this far along the direction light arrives from. */
#define ENV_FAR 1e4f
static bool env_at(const fpath *fp, int i) { return fp->x[i].kind == PC_VTX_ENV; }
static bool directional_at(const fixture *f, const fpath *fp) {
  return env_at(fp, 0) && f->scene.lights[fp->x[0].light].type == PC_LIGHT_DIRECTIONAL;
}

/* Solid-angle pdf of scattering at x_i from `from` toward `to` (q included). */
static double dir_pdf(const fixture *f, const fpath *fp, int i, int from, int to) {
  const pc_path_vertex *v = &fp->x[i];
  if (is_delta(fp, i)) return qv(f, fp, i); /* mirror: lobe probability 1, Dirac dropped */
  const pc_material *m = &f->scene.materials[v->material];
  return pc_bsdf_pdf(m, f->scene.textures, &v->sh, unit(v->p, fp->x[from].p), unit(v->p, fp->x[to].p)) * qv(f, fp, i);
}

static double geo(const fpath *fp, int from, int to) { /* |cos at to| / d^2 */
  vec3 d = v3_sub(fp->x[to].p, fp->x[from].p);
  double d2 = v3_len2(d);
  return fabs((double)v3_dot(fp->x[to].ng, d)) / sqrt(d2) / d2;
}

static void brute(const fixture *f, const pc_mis_counts *n, const fpath *fp, double *w) {
  int k = fp->k;
  const pc_scene *s = &f->scene;
  const pc_light *l = &s->lights[fp->x[0].light];
  bool point = pc_light_is_delta_pos(l), env = env_at(fp, 0), directional = directional_at(f, fp);
  double fwd[2 * MAXV], bwd[2 * MAXV];
  /* Area pdfs from the light side (solid angle at the environment, whose light paths start
   * on the disk). */
  fwd[0] = pc_light_choose_pdf(s, fp->x[0].light) / (point ? 1.0 : l->area);
  if (env) fwd[0] = pc_light_choose_pdf(s, fp->x[0].light) * (directional ? 1.0 : pc_env_pdf(l, v3_neg(fp->x[0].wo)));
  for (int i = 1; i <= k; i++) {
    double pd;
    if (i == 1 && env) {
      fwd[1] = pc_env_disk_pdf(s) * fabs((double)v3_dot(fp->x[1].ng, fp->x[0].wo));
      continue;
    }
    if (i - 1 == 0) {
      vec3 d = unit(fp->x[0].p, fp->x[1].p);
      pd = point ? 0.25 / M_PI : fmax(0.0, v3_dot(fp->x[0].ng, d)) / M_PI;
      if (l->type == PC_LIGHT_SPOT) { /* uniform over the cutoff cone, in double */
        double cc = cos(SPOT_CUTOFF_DEG * M_PI / 180.0);
        pd = v3_dot(d, l->spot_frame.n) > cc ? 1.0 / (2.0 * M_PI * (1.0 - cc)) : 0.0;
      }
    } else {
      pd = dir_pdf(f, fp, i - 1, i - 2, i);
    }
    fwd[i] = pd * (i == k ? 1.0 : geo(fp, i - 1, i));
  }
  /* Area pdfs from the eye side. */
  bwd[k] = 1.0;
  for (int i = k - 1; i >= 0; i--) {
    double pd;
    if (i + 1 == k) {
      const pc_camera *cam = &s->camera;
      double cz = v3_dot(unit(cam->pos, fp->x[i].p), cam->dir);
      pd = fp->density / (cam->image_area * cz * cz * cz);
    } else {
      pd = dir_pdf(f, fp, i + 1, i + 2, i);
    }
    bwd[i] = pd * (i == 0 && env ? 1.0 : geo(fp, i + 1, i));
  }
  if (point || directional) bwd[0] = 0.0; /* no eye path reaches them */
  double beta = n->power ? 2.0 : 1.0, sum = 0.0;
  for (int j = 0; j <= k; j++) {
    double p = 1.0;
    for (int i = 0; i < j; i++) p *= fwd[i];
    for (int i = j; i <= k; i++) p *= bwd[i];
    if ((j >= 1 && is_delta(fp, j - 1)) || is_delta(fp, j)) p = 0.0;
    int t = k + 1 - j;
    double cnt = t == 1 ? n->n_lt : (j <= 1 ? 1.0 : n->n_inner);
    w[j] = pow(cnt * p, beta);
    sum += w[j];
  }
  for (int j = 0; j <= k; j++) w[j] /= sum;
}

/* ---- Re-deriving strategy j of the path through the production routines. ---- */

static void extend(const fixture *f, const pc_mis_counts *n, const fpath *fp, pc_path_vertex *sub, int u, bool light_side,
                   int ifrom2, int ifrom, int ito) {
  /* sub[u-1] is x[ifrom] (reached from x[ifrom2], or an endpoint if ifrom2 < 0); sub[u] is x[ito]. */
  const pc_path_vertex *a = &fp->x[ifrom];
  pc_path_vertex *v = &sub[u];
  *v = fp->x[ito];
  bool to_env = env_at(fp, ito), from_env = a->kind == PC_VTX_ENV;
  v->kind = fp->x[ito].kind == PC_VTX_CAMERA ? PC_VTX_CAMERA : (to_env ? PC_VTX_ENV : PC_VTX_SURFACE);
  v->wo = from_env ? v3_neg(a->wo) : unit(v->p, a->p);
  if (to_env) v->wo = fp->x[ito].wo;
  if (v->kind == PC_VTX_SURFACE && v->material >= 0) pc_bsdf_out_make(&v->out, &f->scene.materials[v->material], f->scene.textures, &v->sh, v->wo);
  v->depth = u + 1;
  v->beta = v3s(1.f);
  vec3 dir = from_env ? a->wo : unit(a->p, v->p);
  float d2 = to_env || from_env ? 1.f : v3_len2(v3_sub(v->p, a->p));
  float cos_in = to_env ? 1.f : v3_absdot(v->ng, dir);
  float pf, pr, cos_out;
  bool delta = false;
  if (ifrom2 < 0) {
    if (from_env) {
      pf = pc_env_disk_pdf(&f->scene);
      cos_out = directional_at(f, fp) ? 0.f : 1.f;
    } else if (a->kind == PC_VTX_CAMERA) {
      float cz = v3_dot(dir, f->scene.camera.dir);
      pf = 1.f / (f->scene.camera.image_area * cz * cz * cz);
      if (fp->density != 1.0) pf *= (float)fp->density;
      cos_out = 0.f;
    } else {
      const pc_light *l = &f->scene.lights[a->light];
      bool point = pc_light_is_delta_pos(l);
      pf = point ? pc_light_pdf_dir(l, a->ng, dir) : v3_dot(a->ng, dir) * PC_INV_PI;
      cos_out = point ? 0.f : v3_dot(a->ng, dir);
    }
    pr = 0.f;
  } else {
    delta = is_delta(fp, ifrom);
    pf = (float)dir_pdf(f, fp, ifrom, ifrom2, ito);
    pr = (float)dir_pdf(f, fp, ifrom, ito, ifrom2);
    cos_out = v3_absdot(a->ng, dir);
  }
  pc_mis_extend(n, &sub[u - 1], light_side, v, pf, pr, delta, cos_out, cos_in, d2);
}

static double replay(fixture *f, const pc_mis_counts *n, const fpath *fp, int j) {
  int k = fp->k;
  pc_path_vertex lv[2 * MAXV], ev[2 * MAXV];
  if (j >= 1) {
    float pick = pc_light_choose_pdf(&f->scene, fp->x[0].light);
    const pc_light *l = &f->scene.lights[fp->x[0].light];
    lv[0] = fp->x[0];
    lv[0].kind = env_at(fp, 0) ? PC_VTX_ENV : PC_VTX_LIGHT;
    lv[0].depth = 1;
    lv[0].beta = v3s(1.f);
    lv[0].delta = false;
    lv[0].mis_near = pc_mis(n, 1.f / (pick * (pc_light_is_delta_pos(l) ? 1.f : 1.f / l->area)));
    if (env_at(fp, 0))
      lv[0].mis_near = pc_mis(n, 1.f / (pick * (directional_at(f, fp) ? 1.f : pc_env_pdf(l, v3_neg(fp->x[0].wo)))));
    lv[0].mis_far = 0.f;
    for (int i = 1; i < j; i++) extend(f, n, fp, lv, i, true, i - 2, i - 1, i);
  }
  ev[0] = fp->x[k];
  ev[0].depth = 1;
  ev[0].mis_near = ev[0].mis_far = 0.f;
  for (int u = 1; u <= k - j; u++) extend(f, n, fp, ev, u, false, u >= 2 ? k - u + 2 : -1, k - u + 1, k - u);
  if (j == 0) {
    if (pc_light_is_delta(&f->scene.lights[fp->x[0].light])) return 0.0;
    return pc_mis_weight_hit(&f->scene, n, &ev[k], fp->x[0].light);
  }
  pc_connection con;
  if (!pc_connect(&f->c, n, &lv[j - 1], &ev[k - j], true, &con)) return 0.0;
  return j == k ? pc_lt_pixel_weight(n, &con, (float)fp->density) : con.weight;
}

static void check_path(fixture *f, const pc_mis_counts *n, const fpath *fp, int s, double w_integrator) {
  double w[2 * MAXV];
  brute(f, n, fp, w);
  double tol = 1e-4;
  if (fabs(w_integrator - w[s]) > tol * w[s] + 1e-6) {
    fprintf(stderr, "k=%d s=%d: integrator weight %.7g, explicit %.7g mats:", fp->k, s, w_integrator, w[s]);
    for (int i = 0; i <= fp->k; i++) fprintf(stderr, " %d%s", fp->x[i].material >= 0 ? (int)f->scene.materials[fp->x[i].material].type : -1, fp->x[i].delta ? "D" : "");
    fprintf(stderr, "\n");
    fail();
  }
  double sum = 0.0;
  for (int j = 0; j <= fp->k; j++) {
    double r = replay(f, n, fp, j);
    /* A strategy whose connection is occluded is impossible only in the replay: there is none,
     * every edge of the path is visible. */
    if (fabs(r - w[j]) > tol * w[j] + 1e-6) {
      fprintf(stderr, "k=%d s=%d (path from s=%d): recursive %.7g, explicit %.7g\n", fp->k, j, s, r, w[j]);
      fail();
    }
    sum += r;
    f->strategies_checked++;
  }
  assert_true(fabs(sum - 1.0) < 1e-4);
  f->checked++;
  f->env_checked += env_at(fp, 0);
  f->at_point_checked += !env_at(fp, 0) && pc_light_is_delta_pos(&f->scene.lights[fp->x[0].light]);
  f->directional_checked += directional_at(f, fp);
}

typedef struct hits {
  const pc_mis_counts *counts;
  int n;
  int t[MAXV];
  float w[MAXV];
} hits;

static void record_hit(pc_tctx *c, void *user, const pc_path_vertex *v, int light, vec3 le) {
  (void)le;
  hits *h = user;
  h->t[h->n] = v->depth;
  h->w[h->n++] = pc_mis_weight_hit(c->scene, h->counts, v, light);
}

static void place_env(fpath *fp) {
  if (env_at(fp, 0)) fp->x[0].p = v3_madd(fp->x[1].p, fp->x[0].wo, -ENV_FAR);
}

/* The pixels a filter spreads the camera's view of x[k-1] over, and their densities there. */
static int footprint(const fixture *f, const fpath *fp, int *xs, int *ys, double *density) {
  const pc_camera *cam = &f->scene.camera;
  float px, py;
  if (!pc_camera_raster(cam, v3_sub(fp->x[fp->k - 1].p, cam->pos), &px, &py)) return 0;
  int x0, y0, nx, ny, n = 0;
  float wx[PC_CAMERA_FOOTPRINT_MAX], wy[PC_CAMERA_FOOTPRINT_MAX];
  pc_camera_footprint(cam, px, py, &x0, &nx, wx, &y0, &ny, wy);
  for (int j = 0; j < ny; j++)
    for (int i = 0; i < nx; i++)
      if (wx[i] * wy[j] > 0.f) xs[n] = x0 + i, ys[n] = y0 + j, density[n++] = (double)(wx[i] * wy[j]);
  return n;
}

/* Weighs fp for pixel (x, y), its eye sub-path's: under a filter, the density there. */
static void for_pixel(const fixture *f, fpath *fp, int x, int y) {
  fp->pixel_x = x, fp->pixel_y = y, fp->density = 1.0;
  if (pc_rfilter_is_pixel(&f->scene.camera.filter)) return;
  int xs[PC_CAMERA_FOOTPRINT_MAX * PC_CAMERA_FOOTPRINT_MAX], ys[PC_CAMERA_FOOTPRINT_MAX * PC_CAMERA_FOOTPRINT_MAX];
  double d[PC_CAMERA_FOOTPRINT_MAX * PC_CAMERA_FOOTPRINT_MAX];
  int n = footprint(f, fp, xs, ys, d);
  fp->density = 0.0;
  for (int i = 0; i < n; i++)
    if (xs[i] == x && ys[i] == y) fp->density = d[i];
  assert_true(fp->density > 0.0); /* the eye sample was drawn from this pixel's filter */
}

static void run(fixture *f, pc_mis_counts n, int npaths) {
  f->c.counts = n;
  f->checked = f->strategies_checked = f->env_checked = f->at_point_checked = f->directional_checked = 0;
  f->filtered_pixels = 0;
  for (int it = 0; it < npaths; it++) {
    f->c.iteration = (uint64_t)it;
    int nl = pc_light_subpath(&f->c, &n, (uint64_t)it, f->lbuf);
    pc_rng rng = pc_rng_make(99, (uint64_t)it, PC_STREAM_EYE, 7);
    int x = (int)(pc_rng_f(&rng) * 32), y = (int)(pc_rng_f(&rng) * 32);
    hits h = {.counts = &n};
    int ne = pc_eye_subpath(&f->c, &n, &rng, x, y, MAX_SEGMENTS + 1, f->ebuf, record_hit, &h);
    assert_true(nl >= 1 && nl <= MAX_SEGMENTS && ne >= 1 && ne <= MAX_SEGMENTS + 1);
    fpath fp;
    /* s = 0: the eye sub-path reversed, x_0 the emitter point it hit. */
    for (int i = 0; i < h.n; i++) {
      int t = h.t[i];
      fp.k = t - 1;
      for (int u = 0; u < t; u++) fp.x[u] = f->ebuf[t - 1 - u];
      if (fp.x[0].kind != PC_VTX_ENV) fp.x[0].kind = PC_VTX_LIGHT;
      place_env(&fp);
      for_pixel(f, &fp, x, y);
      check_path(f, &n, &fp, 0, h.w[i]);
    }
    /* s >= 1 with t >= 1, including s=1 with the light sub-path's own first vertex. */
    for (int s = 1; s <= nl; s++)
      for (int t = 1; t <= ne && s + t - 1 <= MAX_SEGMENTS; t++) {
        pc_connection con;
        if (!pc_connect(&f->c, &n, &f->lbuf[s - 1], &f->ebuf[t - 1], true, &con)) continue;
        assert_true(v3_is_finite(con.f));
        fp.k = s + t - 1;
        for (int i = 0; i < s; i++) fp.x[i] = f->lbuf[i];
        for (int u = 0; u < t; u++) fp.x[s + u] = f->ebuf[t - 1 - u];
        place_env(&fp);
        if (t > 1 || pc_rfilter_is_pixel(&f->scene.camera.filter)) {
          for_pixel(f, &fp, x, y);
          check_path(f, &n, &fp, s, con.weight);
          continue;
        }
        /* t = 1 under a filter: weighed for every pixel it reaches */
        int xs[PC_CAMERA_FOOTPRINT_MAX * PC_CAMERA_FOOTPRINT_MAX], ys[PC_CAMERA_FOOTPRINT_MAX * PC_CAMERA_FOOTPRINT_MAX];
        double d[PC_CAMERA_FOOTPRINT_MAX * PC_CAMERA_FOOTPRINT_MAX];
        int np = footprint(f, &fp, xs, ys, d);
        assert_true(np >= 1);
        for (int i = 0; i < np; i++) {
          fp.pixel_x = xs[i], fp.pixel_y = ys[i], fp.density = d[i];
          check_path(f, &n, &fp, s, pc_lt_pixel_weight(&n, &con, (float)d[i]));
          f->filtered_pixels++;
        }
      }
  }
  printf("counts n_lt %.3g n_inner %.3g %s: %d paths (%d from the environment or a directional light, %d from a point or spot,"
         " %d from a directional light), %d strategy weights checked, %d light-traced pixels of a filter\n",
         n.n_lt, n.n_inner, n.power ? "power" : "balance", f->checked, f->env_checked, f->at_point_checked,
         f->directional_checked, f->strategies_checked, f->filtered_pixels);
  assert_true(f->checked > 50);
}

static void test_mis_balance(void **state) {
  (void)state;
  fixture f;
  load(&f, NO_EXTRA);
  run(&f, (pc_mis_counts){1.f, 1.f, false}, 400);
  unload(&f);
}

static void test_mis_power_nl(void **state) {
  (void)state;
  fixture f;
  load(&f, NO_EXTRA);
  run(&f, (pc_mis_counts){0.37f, 1.f, true}, 400);
  unload(&f);
}

static void test_mis_point_light_counts(void **state) {
  (void)state;
  fixture f;
  load(&f, EXTRA_POINT);
  run(&f, (pc_mis_counts){2.5f, 1.f, false}, 400);
  run(&f, (pc_mis_counts){0.25f, 3.f, true}, 400);
  unload(&f);
}

/* A spot: its light paths leave uniformly over the cutoff cone, and connections to it see its
 * falloff and that cone pdf. */
static void test_mis_spot_light(void **state) {
  (void)state;
  fixture f;
  load(&f, EXTRA_SPOT);
  run(&f, (pc_mis_counts){1.f, 1.f, false}, 400);
  assert_true(f.at_point_checked > 300);
  run(&f, (pc_mis_counts){0.25f, 3.f, true}, 400);
  unload(&f);
}

static void test_mis_environment(void **state) {
  (void)state;
  fixture f;
  load_scene(&f, "env-objects", NO_EXTRA);
  run(&f, (pc_mis_counts){1.f, 1.f, false}, 400);
  assert_true(f.env_checked > 400);
  run(&f, (pc_mis_counts){0.37f, 2.f, true}, 400);
  unload(&f);
  /* With a point light too: the choice between the environment and it by power. */
  load_scene(&f, "env-objects", EXTRA_POINT);
  run(&f, (pc_mis_counts){1.f, 1.f, false}, 400);
  assert_true(f.env_checked > 100 && f.env_checked < f.checked);
  unload(&f);
}

/* A directional light: with outdoor's area light (glossy-glass is closed), and beside
 * env-objects' environment (the two at infinity, one with a Dirac direction). */
static void test_mis_directional(void **state) {
  (void)state;
  fixture f;
  load_scene(&f, "outdoor", EXTRA_DIRECTIONAL);
  run(&f, (pc_mis_counts){1.f, 1.f, false}, 400);
  assert_true(f.directional_checked > 100 && f.directional_checked < f.checked);
  run(&f, (pc_mis_counts){0.25f, 3.f, true}, 400);
  unload(&f);
  load_scene(&f, "env-objects", EXTRA_DIRECTIONAL);
  run(&f, (pc_mis_counts){0.37f, 2.f, false}, 400);
  assert_true(f.directional_checked > 50 && f.env_checked > f.directional_checked);
  unload(&f);
}

/* Under a reconstruction filter each pixel's eye strategies sample the camera ray from its
 * filter (a density other than 1 in their camera pdf) while light tracing splats over the
 * filter's footprint: the weights, per pixel, against the brute force with that density; the
 * eye samples' pixels lie at the film's corner (x, y < 32), where the film cuts the filter. */
static void test_mis_filtered(void **state) {
  (void)state;
  fixture f;
  load(&f, EXTRA_POINT);
  assert_true(pc_rfilter_make(&f.scene.camera.filter, PC_RFILTER_GAUSSIAN, 0.5f));
  run(&f, (pc_mis_counts){1.f, 1.f, false}, 300);
  assert_true(f.filtered_pixels > 1000);
  assert_true(pc_rfilter_make(&f.scene.camera.filter, PC_RFILTER_TENT, 0.f));
  run(&f, (pc_mis_counts){0.37f, 2.f, true}, 300);
  assert_true(f.filtered_pixels > 300);
  unload(&f);
  load_scene(&f, "env-objects", NO_EXTRA);
  assert_true(pc_rfilter_make(&f.scene.camera.filter, PC_RFILTER_BOX, 1.3f));
  run(&f, (pc_mis_counts){1.f, 1.f, true}, 800);
  assert_true(f.filtered_pixels > 150);
  unload(&f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mis_filtered),
      cmocka_unit_test(test_mis_directional),
      cmocka_unit_test(test_mis_environment),
      cmocka_unit_test(test_mis_balance),
      cmocka_unit_test(test_mis_power_nl),
      cmocka_unit_test(test_mis_point_light_counts),
      cmocka_unit_test(test_mis_spot_light),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
