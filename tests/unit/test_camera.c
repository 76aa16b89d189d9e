/* test_camera.c: the pinhole camera's importance function and pdfs integrate correctly, ray
 * generation and raster projection are inverse (for a thin lens too, from every lens point),
 * and the Mitsuba lookat frame renders unmirrored. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "camera.h"
#include "rng.h"

/* shear: how far the up axis leans toward the view direction and left (0: the lookat frame) */
static pc_camera make_sheared_camera(int w, int h, float fov, char axis, float shear) {
  pc_camera c = {0};
  /* Mitsuba lookat origin (0,1,6.8), target (0,1,0), up +y: columns (left, up, dir, origin). */
  vec3 dir = v3(0, 0, -1), up = v3(0, 1, 0);
  vec3 left = v3_norm(v3_cross(up, dir));
  vec3 nup = v3_norm(v3_add(v3_cross(dir, left), v3_scale(v3_add(dir, left), shear)));
  c.to_world = mat4_identity();
  vec3 cols[4] = {left, nup, dir, v3(0, 1, 6.8f)};
  for (int k = 0; k < 4; k++) {
    c.to_world.m[0][k] = cols[k].x;
    c.to_world.m[1][k] = cols[k].y;
    c.to_world.m[2][k] = cols[k].z;
  }
  c.width = w;
  c.height = h;
  c.fov_deg = fov;
  c.fov_axis = axis;
  pc_camera_prepare(&c);
  return c;
}

static pc_camera make_camera(int w, int h, float fov, char axis) { return make_sheared_camera(w, h, fov, axis, 0.f); }

/* Integrates We*cos and the direction pdf over the sphere by uniform sampling; both must be 1.
 * Standard error of a uniform-sphere estimate of these peaked integrands is measured and the
 * assertion uses 5 of them. */
/* The ray through (px, py), checked to project back there. */
static vec3 ray_back_to(const pc_camera *c, float px, float py) {
  vec3 d = pc_camera_ray_dir(c, px, py);
  float rx, ry;
  assert_true(pc_camera_raster(c, d, &rx, &ry));
  assert_true(fabsf(rx - px) < 1e-3f && fabsf(ry - py) < 1e-3f);
  return d;
}

static void importance_integrates_to_one(float shear) {
  pc_camera c = make_sheared_camera(64, 48, 40.f, 'x', shear);
  pc_rng rng = pc_rng_make(7, 0, PC_STREAM_MISC, 0);
  const int n = 4000000;
  double s_we = 0, s_we2 = 0, s_pdf = 0, s_pdf2 = 0;
  for (int i = 0; i < n; i++) {
    float z = 1.f - 2.f * pc_rng_f(&rng), phi = 2.f * PC_PI * pc_rng_f(&rng);
    float r = sqrtf(fmaxf(0.f, 1.f - z * z));
    vec3 d = v3(r * cosf(phi), r * sinf(phi), z);
    double we = pc_camera_we(&c, d) * fmax(0.0, v3_dot(d, c.dir)) * 4.0 * PC_PI;
    double pdf = pc_camera_pdf_dir(&c, d) * 4.0 * PC_PI;
    s_we += we;
    s_we2 += we * we;
    s_pdf += pdf;
    s_pdf2 += pdf * pdf;
  }
  double m_we = s_we / n, se_we = sqrt((s_we2 / n - m_we * m_we) / n);
  double m_pdf = s_pdf / n, se_pdf = sqrt((s_pdf2 / n - m_pdf * m_pdf) / n);
  assert_true(fabs(m_we - 1.0) < 5 * se_we);
  assert_true(fabs(m_pdf - 1.0) < 5 * se_pdf);
  assert_true(se_we < 0.01);
}

static void test_importance_integrates_to_one(void **state) {
  (void)state;
  importance_integrates_to_one(0.f);
}

/* A frame whose up axis leans (a published matrix that Mitsuba accepts leans up to 1e-3; 0.2
 * here, to see it): rays and raster positions still invert each other, the direction pdf is the
 * rays' own density (against the solid angle of a small raster square, measured), and the
 * importance and pdf still integrate to one. */
static void test_sheared_frame(void **state) {
  (void)state;
  pc_camera c = make_sheared_camera(64, 48, 40.f, 'x', 0.2f);
  assert_true(c.inv_det != 1.f && fabsf(v3_dot(c.up, c.dir)) > 0.1f);
  for (float py = 0.5f; py < 48; py += 4.3f)
    for (float px = 0.5f; px < 64; px += 5.1f) {
      vec3 d = ray_back_to(&c, px, py);
      /* the solid angle of a raster square of side h, against its share of the image: the pdf */
      const float h = 0.05f;
      vec3 a = pc_camera_ray_dir(&c, px - h / 2, py - h / 2), b = pc_camera_ray_dir(&c, px + h / 2, py - h / 2),
           e = pc_camera_ray_dir(&c, px - h / 2, py + h / 2);
      double omega = v3_len(v3_cross(v3_sub(b, a), v3_sub(e, a)));
      double want = (h * h / (64.0 * 48.0)) / omega, got = pc_camera_pdf_dir(&c, d);
      if (fabs(got / want - 1) > 2e-3) print_error("(%g, %g): pdf %g, measured %g\n", px, py, got, want);
      assert_true(fabs(got / want - 1) < 2e-3);
      assert_true(fabsf(pc_camera_we(&c, d) * v3_dot(d, c.dir) / (float)got - 1.f) < 1e-5f);
    }
  importance_integrates_to_one(0.2f);
}

static void test_raster_roundtrip(void **state) {
  (void)state;
  const char axes[] = {'x', 'y', 'd', 's', 'l'};
  for (int a = 0; a < 5; a++) {
    pc_camera c = make_camera(80, 30, 35.f, axes[a]);
    for (float py = 0.5f; py < 30; py += 3.7f)
      for (float px = 0.5f; px < 80; px += 5.3f) {
        ray_back_to(&c, px, py);
      }
  }
}

/* A thin lens: rays from any lens point through a raster position meet at one point of the
 * plane in focus, and project back to that raster position; the pinhole draws no lens sample. */
static void thin_lens(float shear) {
  pc_camera c = make_sheared_camera(64, 48, 40.f, 'x', shear);
  pc_rng rng = pc_rng_make(3, 0, PC_STREAM_MISC, 0), before = rng;
  vec3 d, o = pc_camera_sample_ray(&c, 10.5f, 20.25f, &rng, &d);
  assert_true(o.x == c.pos.x && o.y == c.pos.y && o.z == c.pos.z);
  vec3 d0 = pc_camera_ray_dir(&c, 10.5f, 20.25f);
  assert_true(d.x == d0.x && d.y == d0.y && d.z == d0.z);
  assert_true(rng.state == before.state);
  c.aperture_radius = 0.3f;
  c.focus_distance = 5.f;
  float far = 0.f;
  for (int i = 0; i < 1000; i++) {
    float px = 64 * pc_rng_f(&rng), py = 48 * pc_rng_f(&rng), rx, ry;
    o = pc_camera_sample_ray(&c, px, py, &rng, &d);
    /* the lens point on the disk of radius 0.3 in the frame's own coordinates */
    vec3 off = v3_sub(o, c.pos);
    float lx = v3_dot(off, c.inv_right), ly = v3_dot(off, c.inv_up), r = sqrtf(lx * lx + ly * ly);
    assert_true(r <= 0.3f * 1.0001f && fabsf(v3_dot(off, c.inv_dir)) < 1e-5f);
    far = fmaxf(far, r);
    /* the ray reaches the focus plane (depth 5 in the frame's coordinates) where the pinhole ray
       of the pixel does */
    vec3 p = v3_madd(o, d, 5.f / v3_dot(d, c.inv_dir));
    vec3 q = pc_camera_ray_dir(&c, px, py);
    q = v3_madd(c.pos, q, 5.f / v3_dot(q, c.inv_dir));
    assert_true(v3_len(v3_sub(p, q)) < 1e-4f);
    assert_true(pc_camera_raster_from(&c, o, d, &rx, &ry));
    assert_true(fabsf(rx - px) < 2e-3f && fabsf(ry - py) < 2e-3f);
  }
  assert_true(far > 0.29f);
}

/* The same for a frame whose up axis leans (see test_sheared_frame). */
static void test_thin_lens(void **state) {
  (void)state;
  thin_lens(0.f);
  thin_lens(0.2f);
}

static void test_fov_axes(void **state) {
  (void)state;
  pc_camera c = make_camera(80, 40, 60.f, 'x');
  assert_true(fabsf(c.tan_half_x - tanf(PC_PI / 6)) < 1e-6f && fabsf(c.tan_half_y - 0.5f * c.tan_half_x) < 1e-6f);
  c = make_camera(80, 40, 60.f, 'y');
  assert_true(fabsf(c.tan_half_y - tanf(PC_PI / 6)) < 1e-6f && fabsf(c.tan_half_x - 2.f * c.tan_half_y) < 1e-6f);
  c = make_camera(80, 40, 60.f, 's'); /* smaller axis is y */
  assert_true(fabsf(c.tan_half_y - tanf(PC_PI / 6)) < 1e-6f);
  c = make_camera(80, 40, 60.f, 'l'); /* larger axis is x */
  assert_true(fabsf(c.tan_half_x - tanf(PC_PI / 6)) < 1e-6f);
}

/* Looking down -z with +y up, world +x must appear on the right and +y at the top. */
static void test_lookat_orientation(void **state) {
  (void)state;
  pc_camera c = make_camera(64, 64, 19.5f, 'x');
  float px, py;
  assert_true(pc_camera_raster(&c, v3_norm(v3_sub(v3(0.5f, 1.f, 0.f), c.pos)), &px, &py));
  assert_true(px > 32.f && fabsf(py - 32.f) < 1e-3f);
  assert_true(pc_camera_raster(&c, v3_norm(v3_sub(v3(0.f, 1.5f, 0.f), c.pos)), &px, &py));
  assert_true(py < 32.f && fabsf(px - 32.f) < 1e-3f);
  assert_false(pc_camera_raster(&c, v3(0, 0, 1), &px, &py)); /* behind */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_importance_integrates_to_one), cmocka_unit_test(test_sheared_frame),
      cmocka_unit_test(test_raster_roundtrip),
      cmocka_unit_test(test_thin_lens),
      cmocka_unit_test(test_fov_axes),
      cmocka_unit_test(test_lookat_orientation),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
