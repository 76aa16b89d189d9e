/* test_mesh.c: OBJ, PLY and Mitsuba serialized readers (fan triangulation, index forms, binary PLY, truncated and
 * oversized files, mutated files), mesh operations and method names. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <sys/stat.h>

#include "mesh.h"
#include "scene.h"
#include "test_helpers_fs.h"
#include "test_helpers_serialized.h"

static char g_dir[64];

static int setup(void **state) {
  (void)state;
  strcpy(g_dir, "/tmp/pcbpt_mesh_XXXXXX");
  return mkdtemp(g_dir) ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  th_rm_rf(g_dir);
  return 0;
}

static const char *put(const char *name, const void *data, size_t len) {
  static char p[256];
  snprintf(p, sizeof p, "%s/%s", g_dir, name);
  assert_int_equal(th_write(p, data, len), 0);
  return p;
}

static int load_obj_text(const char *text, pc_mesh *m, pc_err *e) {
  return pc_mesh_load_obj(put("m.obj", text, strlen(text)), m, e);
}

static int load_ply_bytes(const void *data, size_t len, pc_mesh *m, pc_err *e) {
  return pc_mesh_load_ply(put("m.ply", data, len), m, e);
}

static void expect_obj_error(const char *text, const char *where, const char *word) {
  pc_mesh m;
  pc_err e = {0};
  int rc = load_obj_text(text, &m, &e);
  if (rc == 0 || !strstr(e.msg, where) || !strstr(e.msg, word)) print_error("got '%s' for:\n%s\n", e.msg, text);
  assert_true(rc < 0);
  assert_non_null(strstr(e.msg, where));
  assert_non_null(strstr(e.msg, word));
}

static void test_obj_fan_and_indices(void **state) {
  (void)state;
  pc_mesh m;
  pc_err e = {0};
  /* a pentagon written with negative indices, then a triangle with a forward positive index */
  const char *text = "# comment\nv 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\n"
                     "f -5 -4 -3 -2 -1\nf 1 2 6\nv 3 3 0\n";
  assert_int_equal(load_obj_text(text, &m, &e), 0);
  assert_int_equal(m.nverts, 6);
  assert_int_equal(m.ntris, 4);
  uint32_t want[12] = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 1, 5};
  for (int i = 0; i < 12; i++) assert_int_equal(m.idx[i], want[i]);
  assert_null(m.n);
  assert_null(m.uv);
  pc_mesh_free(&m);
}

static void test_obj_forms_and_dedupe(void **state) {
  (void)state;
  pc_mesh m;
  pc_err e = {0};
  /* two triangles share positions 1 and 3 but one of them with another normal: 4 + 2 vertices,
   * with v/vt/vn; the same with v//vn and v/vt also load */
  const char *text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0 0\nvt 0 1\nvn 0 0 1\nvn 0 0 3\n"
                     "f 1/1/1 2/2/1 3/3/1\nf 2/2/2 4/1/2 3/3/2\n";
  assert_int_equal(load_obj_text(text, &m, &e), 0);
  assert_int_equal(m.nverts, 6);
  assert_int_equal(m.ntris, 2);
  assert_non_null(m.n);
  assert_non_null(m.uv);
  assert_true(m.n[3].z == 1.f); /* normalised */
  assert_true(m.uv[1].x == 1.f && m.uv[1].y == 0.f);
  pc_mesh_free(&m);
  assert_int_equal(load_obj_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n", &m, &e), 0);
  assert_non_null(m.n);
  assert_null(m.uv);
  pc_mesh_free(&m);
  assert_int_equal(load_obj_text("v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nvt 0 0\r\nf 1/1 2/1 3/1\r\n", &m, &e), 0);
  assert_null(m.n);
  assert_non_null(m.uv);
  assert_int_equal(m.nverts, 3);
  pc_mesh_free(&m);
}

static void test_obj_errors(void **state) {
  (void)state;
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "m.obj:4:", "out of range");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "m.obj:4:", "out of range");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "m.obj:4:", "index 0");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "m.obj:4:", "fewer than 3");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/2 2/1 3/1\n", "m.obj:5:", "texture coordinate index");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1 2 3\n", "m.obj:6:", "normals");
  expect_obj_error("v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "m.obj:1:", "non-finite");
  expect_obj_error("v 0 0 1e39\n", "m.obj:1:", "non-finite");
  expect_obj_error("v 0 0\n", "m.obj:1:", "at least 3");
  expect_obj_error("v 0 0 0 1 1\n", "m.obj:1:", "5 numbers");
  expect_obj_error("v 0 0 zero\n", "m.obj:1:", "malformed");
  expect_obj_error("vn 0 0 0\n", "m.obj:1:", "zero-length");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n", "m.obj:4:", "malformed");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", "m.obj:4:", "malformed");
  expect_obj_error("v 0 0 0\nl 1 2\n", "m.obj:2:", "'l'");
  expect_obj_error("v 0 0 0\n", "m.obj", "no faces");
  expect_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n", "m.obj:4:", "out of range");
  pc_mesh m;
  pc_err e = {0};
  assert_int_equal(pc_mesh_load_obj("/nonexistent/x.obj", &m, &e), PC_EIO);
  /* a FIFO or a folder is not a mesh, and opening the FIFO must not block */
  char fifo[128];
  snprintf(fifo, sizeof fifo, "%s/fifo.obj", g_dir);
  assert_int_equal(mkfifo(fifo, 0600), 0);
  assert_int_equal(pc_mesh_load_obj(fifo, &m, &e), PC_EIO);
  assert_non_null(strstr(e.msg, "not a regular file"));
  assert_int_equal(pc_mesh_load_ply(g_dir, &m, &e), PC_EIO);
}

static const char *PLY_HEAD =
    "ply\nformat ascii 1.0\ncomment c\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n"
    "property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nproperty int flags\n"
    "element edge 1\nproperty list uchar int verts\nend_header\n";

static void test_ply_ascii(void **state) {
  (void)state;
  char text[1024];
  snprintf(text, sizeof text, "%s%s", PLY_HEAD,
           "0 0 0 0 0 2 0 0 7\n1 0 0 0 0 1 1 0 7\n1 1 0 0 0 1 1 1 7\n0 1 0 0 0 1 0 1 7\n4 0 1 2 3 9\n2 0 1\n");
  pc_mesh m;
  pc_err e = {0};
  int rc = load_ply_bytes(text, strlen(text), &m, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(m.nverts, 4);
  assert_int_equal(m.ntris, 2);
  uint32_t want[6] = {0, 1, 2, 0, 2, 3};
  for (int i = 0; i < 6; i++) assert_int_equal(m.idx[i], want[i]);
  assert_true(m.n[0].z == 1.f);
  assert_true(m.uv[2].x == 1.f && m.uv[2].y == 1.f);
  pc_mesh_free(&m);
  /* index out of range, too short face, truncated data */
  snprintf(text, sizeof text, "%s%s", PLY_HEAD,
           "0 0 0 0 0 2 0 0 7\n1 0 0 0 0 1 1 0 7\n1 1 0 0 0 1 1 1 7\n0 1 0 0 0 1 0 1 7\n4 0 1 2 4 9\n2 0 1\n");
  assert_true(load_ply_bytes(text, strlen(text), &m, &e) < 0);
  if (!strstr(e.msg, "m.ply:24: face 0: vertex index out of range")) print_error("%s\n", e.msg);
  assert_non_null(strstr(e.msg, "m.ply:24: face 0: vertex index out of range"));
  snprintf(text, sizeof text, "%s%s", PLY_HEAD,
           "0 0 0 0 0 2 0 0 7\n1 0 0 0 0 1 1 0 7\n1 1 0 0 0 1 1 1 7\n0 1 0 0 0 1 0 1 7\n2 0 1 9\n2 0 1\n");
  assert_true(load_ply_bytes(text, strlen(text), &m, &e) < 0);
  assert_non_null(strstr(e.msg, "fewer than 3"));
  snprintf(text, sizeof text, "%s%s", PLY_HEAD, "0 0 0 0 0 2 0 0 7\n1 0 0 0 0 1 1 0 7\n1 1 0 0 0 1 1 1 7\n0 1 0 0 0 1 0 1 7\n4 0 1 2\n");
  assert_true(load_ply_bytes(text, strlen(text), &m, &e) < 0);
  assert_non_null(strstr(e.msg, "truncated"));
}

/* Little-endian byte writer for binary PLY fixtures. */
typedef struct wbuf { unsigned char b[4096]; size_t n; } wbuf;
static void put_u(wbuf *w, uint64_t v, int size) {
  for (int i = 0; i < size; i++) w->b[w->n++] = (unsigned char)(v >> (8 * i));
}
static void put_f(wbuf *w, float f) {
  uint32_t u;
  memcpy(&u, &f, 4);
  put_u(w, u, 4);
}
static void put_d(wbuf *w, double d) {
  uint64_t u;
  memcpy(&u, &d, 8);
  put_u(w, u, 8);
}
static void put_s(wbuf *w, const char *s) {
  memcpy(w->b + w->n, s, strlen(s));
  w->n += strlen(s);
}

static void binary_quad(wbuf *w, const char *format, uint32_t nverts_declared) {
  char head[512];
  snprintf(head, sizeof head,
           "ply\nformat %s 1.0\nelement vertex %u\nproperty double x\nproperty double y\nproperty double z\n"
           "property short extra\nproperty float u\nproperty float v\nelement face 1\n"
           "property list int uint vertex_indices\nend_header\n",
           format, nverts_declared);
  w->n = 0;
  put_s(w, head);
  const float q[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; i++) {
    put_d(w, q[i][0]);
    put_d(w, q[i][1]);
    put_d(w, 0);
    put_u(w, 0xBEEF, 2);
    put_f(w, q[i][0]);
    put_f(w, q[i][1]);
  }
  put_u(w, 4, 4);
  for (uint32_t i = 0; i < 4; i++) put_u(w, i, 4);
}

static void test_ply_binary(void **state) {
  (void)state;
  wbuf w;
  pc_mesh m;
  pc_err e = {0};
  binary_quad(&w, "binary_little_endian", 4);
  int rc = load_ply_bytes(w.b, w.n, &m, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(m.nverts, 4);
  assert_int_equal(m.ntris, 2);
  assert_true(m.p[2].x == 1.f && m.p[2].y == 1.f && m.uv[3].y == 1.f);
  assert_null(m.n);
  pc_mesh_free(&m);
  /* every truncation fails cleanly */
  size_t full = w.n;
  for (size_t cut = 1; cut < full; cut += 3) {
    assert_true(load_ply_bytes(w.b, cut, &m, &e) < 0);
    assert_true(strlen(e.msg) > 0);
  }
  binary_quad(&w, "binary_little_endian", 4);
  assert_true(load_ply_bytes(w.b, w.n - 4, &m, &e) < 0);
  assert_non_null(strstr(e.msg, "truncated"));
  /* big endian is refused */
  binary_quad(&w, "binary_big_endian", 4);
  assert_int_equal(load_ply_bytes(w.b, w.n, &m, &e), PC_EUNSUPPORTED);
  assert_non_null(strstr(e.msg, "binary_big_endian"));
  /* huge declared counts: over the limit, or more than the file can hold */
  binary_quad(&w, "binary_little_endian", 4000000000u);
  assert_int_equal(load_ply_bytes(w.b, w.n, &m, &e), PC_ELIMIT);
  binary_quad(&w, "binary_little_endian", 50000000u);
  assert_true(load_ply_bytes(w.b, w.n, &m, &e) < 0);
  assert_non_null(strstr(e.msg, "truncated"));
  /* a list length larger than the file */
  binary_quad(&w, "binary_little_endian", 4);
  w.n -= 20;
  put_u(&w, 0x7fffffff, 4);
  for (uint32_t i = 0; i < 4; i++) put_u(&w, i, 4);
  assert_true(load_ply_bytes(w.b, w.n, &m, &e) < 0);
  assert_non_null(strstr(e.msg, "list"));
}

static void test_ply_header_errors(void **state) {
  (void)state;
  static const struct { const char *text; const char *word; } cases[] = {
      {"plyx\n", "not a PLY"},
      {"ply\nformat ascii 1.0\nelement vertex 1\n", "end_header"},
      {"ply\nformat ascii 2.0\nend_header\n", "version"},
      {"ply\nproperty float x\nend_header\n", "before any element"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\nend_header\n", "malformed property"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n3 0 0 0\n", "integers"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
       "property float nx\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n", "nx, ny, nz"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n", "face"},
      {"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "count"},
      {"ply\nformat ascii 1.0\nbogus\nend_header\n", "bogus"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    pc_mesh m;
    pc_err e = {0};
    assert_true(load_ply_bytes(cases[i].text, strlen(cases[i].text), &m, &e) < 0);
    if (!strstr(e.msg, cases[i].word)) print_error("case %zu: '%s'\n", i, e.msg);
    assert_non_null(strstr(e.msg, cases[i].word));
  }
}


/* Mitsuba serialized files: versions 3 and 4, single and double precision, any shapeIndex,
 * normals and texture coordinates; hostile and broken files fail with one line. */
static void test_serialized(void **state) {
  (void)state;
  static const float tri_p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, quad_p[] = {0, 0, 1, 2, 0, 1, 2, 2, 1, 0, 2, 1};
  static const float tri_n[] = {0, 0, 1, 0, 0, 1, 0, 0, 1}, quad_uv[] = {0, 0, 1, 0, 1, 1, 0, 1};
  static const uint32_t tri_i[] = {0, 1, 2}, quad_i[] = {0, 1, 2, 0, 2, 3};
  th_ser_shape shapes[2] = {{3, 1, tri_p, tri_n, NULL, tri_i, 3, 1, 0}, {4, 2, quad_p, NULL, quad_uv, quad_i, 4, 2, 0}};
  char path[256];
  snprintf(path, sizeof path, "%s/m.serialized", g_dir);
  for (int version = 3; version <= 4; version++)
    for (int dbl = 0; dbl <= 1; dbl++) {
      assert_int_equal(th_write_serialized(path, shapes, 2, version, dbl), 0);
      pc_mesh m;
      pc_err e = {0};
      bool fn = true;
      int rc = pc_mesh_load_serialized(path, 1, &m, &fn, &e);
      if (rc) print_error("v%d dbl %d: %s\n", version, dbl, e.msg);
      assert_int_equal(rc, 0);
      assert_false(fn);
      assert_int_equal(m.nverts, 4);
      assert_int_equal(m.ntris, 2);
      assert_null(m.n);
      assert_non_null(m.uv);
      assert_true(m.p[2].x == 2 && m.p[2].y == 2 && m.p[2].z == 1 && m.uv[2].x == 1 && m.idx[5] == 3);
      pc_mesh_free(&m);
      assert_int_equal(pc_mesh_load_serialized(path, 0, &m, &fn, &e), 0);
      assert_int_equal(m.ntris, 1);
      assert_non_null(m.n);
      assert_true(m.n[1].z == 1 && m.p[1].x == 1);
      pc_mesh_free(&m);
      assert_int_equal(pc_mesh_load_serialized(path, 2, &m, &fn, &e), PC_EINVAL);
      assert_non_null(strstr(e.msg, "shapeIndex 2"));
    }
  pc_mesh m;
  pc_err e = {0};
  bool fn;
  /* the file's face-normals flag */
  th_ser_shape flat = {3, 1, tri_p, NULL, NULL, tri_i, 3, 1, 0x10};
  assert_int_equal(th_write_serialized(path, &flat, 1, 4, 0), 0);
  assert_int_equal(pc_mesh_load_serialized(path, 0, &m, &fn, &e), 0);
  assert_true(fn);
  pc_mesh_free(&m);
  /* a header claiming 2^40 vertices: one line, no allocation of that size */
  th_ser_shape huge = {(uint64_t)1 << 40, 1, tri_p, NULL, NULL, tri_i, 3, 1, 0};
  assert_int_equal(th_write_serialized(path, &huge, 1, 4, 0), 0);
  assert_int_equal(pc_mesh_load_serialized(path, 0, &m, &fn, &e), PC_ELIMIT);
  assert_non_null(strstr(e.msg, "1099511627776 vertices"));
  assert_null(strchr(e.msg, '\n'));
  /* fewer data than the counts claim */
  th_ser_shape shortd = {30, 1, tri_p, NULL, NULL, tri_i, 3, 1, 0};
  assert_int_equal(th_write_serialized(path, &shortd, 1, 4, 0), 0);
  assert_int_equal(pc_mesh_load_serialized(path, 0, &m, &fn, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "ends early"));
  /* an index out of range */
  static const uint32_t bad_i[] = {0, 1, 7};
  th_ser_shape badidx = {3, 1, tri_p, NULL, NULL, bad_i, 3, 1, 0};
  assert_int_equal(th_write_serialized(path, &badidx, 1, 4, 0), 0);
  assert_int_equal(pc_mesh_load_serialized(path, 0, &m, &fn, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "vertex 7"));
  /* not a serialized file, a bad dictionary, every truncation and byte flip of a good file */
  assert_int_equal(pc_mesh_load_serialized(put("x.serialized", "hello world!", 12), 0, &m, &fn, &e), PC_EPARSE);
  assert_int_equal(th_write_serialized(path, shapes, 2, 4, 0), 0);
  size_t len = 0;
  char *good = th_read(path, &len);
  assert_non_null(good);
  good[len - 4] = 9; /* 9 shapes */
  assert_int_equal(pc_mesh_load_serialized(put("d.serialized", good, len), 1, &m, &fn, &e), PC_EPARSE);
  assert_non_null(strstr(e.msg, "dictionary"));
  good[len - 4] = 2;
  for (size_t cut = 0; cut < len; cut++) {
    if (pc_mesh_load_serialized(put("t.serialized", good, cut), 1, &m, &fn, &e) == 0) pc_mesh_free(&m);
  }
  for (size_t i = 0; i < len; i++) {
    char *mut = malloc(len);
    memcpy(mut, good, len);
    mut[i] ^= (char)0x5a;
    if (pc_mesh_load_serialized(put("f.serialized", mut, len), (int)(i % 2), &m, &fn, &e) == 0) pc_mesh_free(&m);
    free(mut);
  }
  free(good);
}

static void test_mesh_ops(void **state) {
  (void)state;
  /* three right triangles meeting at the origin, one per coordinate plane, all facing out of
   * the octant's corner: the shared vertex gets normalize(1,1,1) (equal angles) */
  const char *corner = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\n";
  pc_mesh m;
  pc_err e = {0};
  assert_int_equal(load_obj_text(corner, &m, &e), 0);
  assert_int_equal(pc_mesh_compute_normals(&m), 0);
  float r = 1.f / sqrtf(3.f);
  assert_true(fabsf(m.n[0].x - r) < 1e-6f && fabsf(m.n[0].y - r) < 1e-6f && fabsf(m.n[0].z - r) < 1e-6f);
  assert_int_equal(pc_mesh_validate(&m, "x", &e), 0);
  /* a mirror keeps normals unit and the winding consistent with them */
  mat4 mirror = mat4_identity();
  mirror.m[0][0] = -1;
  mirror.m[1][1] = 3;
  pc_mesh_transform(&m, &mirror);
  for (uint32_t i = 0; i < m.nverts; i++) assert_true(fabsf(v3_len(m.n[i]) - 1.f) < 1e-6f);
  vec3 a = m.p[m.idx[0]], b = m.p[m.idx[1]], c = m.p[m.idx[2]];
  vec3 ng = v3_cross(v3_sub(b, a), v3_sub(c, a));
  assert_true(v3_dot(ng, m.n[0]) > 0);
  uint32_t i1 = m.idx[1];
  pc_mesh_flip(&m);
  assert_int_equal(m.idx[2], i1);
  assert_true(v3_dot(ng, m.n[0]) < 0);
  /* validation failures */
  m.p[1].x = NAN;
  assert_int_equal(pc_mesh_validate(&m, "here", &e), PC_ENUMERIC);
  assert_non_null(strstr(e.msg, "here"));
  m.p[1].x = 1;
  m.idx[0] = 99;
  assert_int_equal(pc_mesh_validate(&m, "here", &e), PC_EINVAL);
  pc_mesh_free(&m);
  /* built-in shapes */
  assert_int_equal(pc_mesh_rectangle(&m), 0);
  assert_int_equal(pc_mesh_validate(&m, "rect", &e), 0);
  pc_mesh_free(&m);
  assert_int_equal(pc_mesh_disk(&m, 8), 0);
  assert_int_equal(m.ntris, 8);
  assert_int_equal(pc_mesh_validate(&m, "disk", &e), 0);
  pc_mesh_free(&m);
  assert_int_equal(pc_mesh_disk(&m, 2), PC_EINVAL);
}

/* maxSmoothAngle on a cube (8 shared corners, 12 triangles): its 90-degree edges are creases at
 * 30 degrees (each corner splits into one vertex per face, normals the face normals) and are
 * smoothed over at 100 (8 vertices, normals along the diagonals); a flat quad stays one piece. */
static const char cube_obj[] = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                               "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                               "f 3 4 8\nf 3 8 7\nf 2 3 7\nf 2 7 6\nf 1 5 8\nf 1 8 4\n";

static void test_smooth_angle(void **state) {
  (void)state;
  pc_mesh m;
  pc_err e = {0};
  assert_int_equal(load_obj_text(cube_obj, &m, &e), 0);
  assert_int_equal(pc_mesh_compute_normals(&m), 0); /* discarded by the rebuild */
  assert_int_equal(pc_mesh_rebuild_topology(&m, 30.f), 0);
  assert_int_equal(m.nverts, 24);
  assert_int_equal(m.ntris, 12);
  assert_int_equal(pc_mesh_validate(&m, "cube30", &e), 0);
  for (uint32_t t = 0; t < m.ntris; t++) {
    const uint32_t *ix = &m.idx[3 * t];
    vec3 fn = v3_norm(v3_cross(v3_sub(m.p[ix[1]], m.p[ix[0]]), v3_sub(m.p[ix[2]], m.p[ix[0]])));
    for (int k = 0; k < 3; k++) assert_true(v3_dot(m.n[ix[k]], fn) > 1.f - 1e-6f);
  }
  pc_mesh_free(&m);
  assert_int_equal(load_obj_text(cube_obj, &m, &e), 0);
  assert_int_equal(pc_mesh_rebuild_topology(&m, 100.f), 0);
  assert_int_equal(m.nverts, 8);
  float r = 1.f / sqrtf(3.f);
  for (uint32_t i = 0; i < m.nverts; i++)
    assert_true(v3_dot(m.n[i], v3_scale(m.p[i], r)) > 1.f - 1e-6f); /* the corner's own diagonal */
  pc_mesh_free(&m);
  /* a flat quad of two triangles: one piece at any angle; a texture seam splits, as in Mitsuba */
  assert_int_equal(load_obj_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n", &m, &e), 0);
  assert_int_equal(pc_mesh_rebuild_topology(&m, 1.f), 0);
  assert_int_equal(m.nverts, 4);
  pc_mesh_free(&m);
  assert_int_equal(load_obj_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
                                 "f 1/1 2/2 3/3\nf 1/5 3/3 4/4\n", &m, &e), 0);
  assert_int_equal(pc_mesh_rebuild_topology(&m, 30.f), 0);
  assert_int_equal(m.nverts, 5);
  pc_mesh_free(&m);
  /* invalid data is refused, not read */
  assert_int_equal(load_obj_text(cube_obj, &m, &e), 0);
  assert_int_equal(pc_mesh_rebuild_topology(&m, NAN), PC_EINVAL);
  m.p[3].y = INFINITY;
  assert_int_equal(pc_mesh_rebuild_topology(&m, 30.f), PC_ENUMERIC);
  pc_mesh_free(&m);
}

static void test_methods(void **state) {
  (void)state;
  pc_method m;
  for (int i = PC_METHOD_PT; i <= PC_METHOD_PCBPT; i++) {
    assert_int_equal(pc_method_parse(pc_method_name((pc_method)i), &m), 0);
    assert_int_equal(m, i);
  }
  assert_int_equal(pc_method_parse("path", &m), 0);
  assert_int_equal(m, PC_METHOD_PT);
  assert_int_equal(pc_method_parse("mlt", &m), PC_EINVAL);
  assert_int_equal(pc_method_parse(NULL, &m), PC_EINVAL);
}

/* Random edits of good OBJ, ASCII PLY and binary PLY files never crash a reader. */
static void test_mutations(void **state) {
  (void)state;
  char ascii[1024];
  snprintf(ascii, sizeof ascii, "%s%s", PLY_HEAD,
           "0 0 0 0 0 2 0 0 7\n1 0 0 0 0 1 1 0 7\n1 1 0 0 0 1 1 1 7\n0 1 0 0 0 1 0 1 7\n4 0 1 2 3 9\n2 0 1\n");
  const char *obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/1/1 4/2/1\nf -1/-1/-1 -2/-2/-1 -3/-1/-1\n";
  wbuf bin;
  binary_quad(&bin, "binary_little_endian", 4);
  uint64_t seed = 99;
  unsigned char buf[4200];
  for (int it = 0; it < 600; it++) {
    int kind = it % 3;
    const unsigned char *src = kind == 0 ? (const unsigned char *)obj : kind == 1 ? (const unsigned char *)ascii : bin.b;
    size_t n = kind == 0 ? strlen(obj) : kind == 1 ? strlen(ascii) : bin.n;
    memcpy(buf, src, n);
    for (int k = 0; k < 1 + it % 3; k++) {
      seed = seed * 6364136223846793005ull + 1442695040888963407ull;
      size_t pos = (size_t)(seed >> 33) % n;
      int op = (int)((seed >> 20) % 3);
      if (op == 0) buf[pos] = (unsigned char)(seed >> 8);
      else if (op == 1) buf[pos] = "0123456789-/ \n.e"[(seed >> 8) % 16];
      else n = pos + 1;
    }
    pc_mesh m;
    pc_err e = {0};
    int rc = kind == 0 ? pc_mesh_load_obj(put("f.obj", buf, n), &m, &e) : pc_mesh_load_ply(put("f.ply", buf, n), &m, &e);
    if (rc == 0) {
      /* whatever loads is well-formed */
      for (uint32_t i = 0; i < 3 * m.ntris; i++) assert_true(m.idx[i] < m.nverts);
      pc_mesh_free(&m);
    } else {
      assert_true(strlen(e.msg) > 0);
    }
  }
}

/* A repository cloned without Git LFS holds pointers where its meshes should be: each reader
 * says so, not that the file is malformed. */
static void test_lfs_pointer(void **state) {
  (void)state;
  const char *ptr = "version https://git-lfs.github.com/spec/v1\noid sha256:534331e9438284caf604721d76be1a2313277cb4e645cb0123456789abcdef01\nsize 1048576\n";
  pc_mesh m;
  pc_err e = {0};
  bool fn;
  assert_int_equal(pc_mesh_load_obj(put("p.obj", ptr, strlen(ptr)), &m, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "p.obj: a Git LFS pointer, not the file itself"));
  assert_int_equal(pc_mesh_load_ply(put("p.ply", ptr, strlen(ptr)), &m, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "p.ply: a Git LFS pointer"));
  assert_int_equal(pc_mesh_load_serialized(put("p.serialized", ptr, strlen(ptr)), 0, &m, &fn, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "p.serialized: a Git LFS pointer"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_obj_fan_and_indices), cmocka_unit_test(test_obj_forms_and_dedupe),
      cmocka_unit_test(test_obj_errors),          cmocka_unit_test(test_ply_ascii),
      cmocka_unit_test(test_ply_binary),          cmocka_unit_test(test_ply_header_errors),
      cmocka_unit_test(test_mesh_ops),            cmocka_unit_test(test_methods),
      cmocka_unit_test(test_mutations),           cmocka_unit_test(test_serialized),
      cmocka_unit_test(test_smooth_angle),        cmocka_unit_test(test_lfs_pointer),
  };
  return cmocka_run_group_tests(tests, setup, teardown);
}
