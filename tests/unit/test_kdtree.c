/* test_kdtree.c: k-nearest-neighbour queries of the kd-tree equal a brute-force scan exactly
 * (indices, distances and tie order) on random, clustered and duplicated point sets. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <cmocka.h>

#include "kdtree.h"
#include "rng.h"

/* The k best of a brute-force scan by (d2, index): selection sort over a copy. */
static int brute_knn(const vec3 *pts, int n, vec3 q, int k, int *idx, float *d2) {
  float *all = malloc((size_t)n * sizeof *all);
  char *used = calloc((size_t)n, 1);
  assert_non_null(all);
  assert_non_null(used);
  for (int i = 0; i < n; i++) {
    float dx = q.x - pts[i].x, dy = q.y - pts[i].y, dz = q.z - pts[i].z;
    all[i] = dx * dx + dy * dy + dz * dz;
  }
  int m = k < n ? k : n;
  for (int j = 0; j < m; j++) {
    int best = -1;
    for (int i = 0; i < n; i++)
      if (!used[i] && (best < 0 || all[i] < all[best])) best = i; /* first index wins ties */
    used[best] = 1;
    idx[j] = best;
    d2[j] = all[best];
  }
  free(all);
  free(used);
  return m;
}

static void check_against_brute(const vec3 *pts, int n, int queries, uint64_t seed) {
  pc_kdtree t = {0};
  pc_err e = {0};
  assert_int_equal(pc_kdtree_build(&t, pts, n, &e), PC_OK);
  pc_rng rng = pc_rng_make(seed, 0, PC_STREAM_MISC, 1);
  const int ks[] = {1, 2, 6, 17, 64};
  for (int qi = 0; qi < queries; qi++) {
    vec3 q = v3(pc_rng_f(&rng) * 1.2f - 0.1f, pc_rng_f(&rng) * 1.2f - 0.1f, pc_rng_f(&rng) * 1.2f - 0.1f);
    if (qi % 7 == 0 && n > 0) q = pts[pc_rng_u32(&rng) % (uint32_t)n]; /* exactly on a point */
    for (size_t ki = 0; ki < sizeof ks / sizeof ks[0]; ki++) {
      int k = ks[ki];
      int ia[PC_KDTREE_MAX_K], ib[PC_KDTREE_MAX_K];
      float da[PC_KDTREE_MAX_K], db[PC_KDTREE_MAX_K];
      int na = pc_kdtree_knn(&t, q, k, ia, da);
      int nb = brute_knn(pts, n, q, k, ib, db);
      assert_int_equal(na, nb);
      for (int j = 0; j < na; j++) {
        assert_int_equal(ia[j], ib[j]);
        assert_true(da[j] == db[j]);
      }
    }
  }
  pc_kdtree_free(&t);
}

static void test_random_points(void **state) {
  (void)state;
  const int n = 3000;
  vec3 *pts = malloc(n * sizeof *pts);
  pc_rng rng = pc_rng_make(11, 0, PC_STREAM_MISC, 0);
  for (int i = 0; i < n; i++) pts[i] = v3(pc_rng_f(&rng), pc_rng_f(&rng), pc_rng_f(&rng));
  check_against_brute(pts, n, 300, 1);
  check_against_brute(pts, 1, 20, 2);
  check_against_brute(pts, 5, 20, 3);
  check_against_brute(pts, 64, 50, 4);
  free(pts);
}

/* Points on a coarse grid (many equal distances and equal coordinates) and on a plane:
 * exercises the (distance, index) tie order and degenerate extents. */
static void test_ties_and_duplicates(void **state) {
  (void)state;
  const int n = 2000;
  vec3 *pts = malloc(n * sizeof *pts);
  pc_rng rng = pc_rng_make(12, 0, PC_STREAM_MISC, 0);
  for (int i = 0; i < n; i++)
    pts[i] = v3((float)(pc_rng_u32(&rng) % 5) * 0.25f, (float)(pc_rng_u32(&rng) % 5) * 0.25f, 0.5f);
  check_against_brute(pts, n, 200, 5);
  for (int i = 0; i < n; i++) pts[i] = v3(0.3f, 0.3f, 0.3f);
  check_against_brute(pts, n, 20, 6);
  free(pts);
}

static void test_empty_and_rebuild(void **state) {
  (void)state;
  pc_kdtree t = {0};
  pc_err e = {0};
  int idx[4];
  float d2[4];
  assert_int_equal(pc_kdtree_knn(&t, v3s(0), 4, idx, d2), 0);
  vec3 a[3] = {v3(0, 0, 0), v3(1, 0, 0), v3(2, 0, 0)};
  assert_int_equal(pc_kdtree_build(&t, a, 3, &e), PC_OK);
  assert_int_equal(pc_kdtree_knn(&t, v3(1.9f, 0, 0), 4, idx, d2), 3);
  assert_int_equal(idx[0], 2);
  assert_int_equal(idx[1], 1);
  assert_int_equal(idx[2], 0);
  assert_int_equal(pc_kdtree_knn(&t, v3s(0), 0, idx, d2), 0);
  assert_int_equal(pc_kdtree_knn(&t, v3s(0), PC_KDTREE_MAX_K + 1, idx, d2), 0);
  /* Rebuild smaller reuses memory; a non-finite point is refused. */
  assert_int_equal(pc_kdtree_build(&t, a + 1, 2, &e), PC_OK);
  assert_int_equal(pc_kdtree_knn(&t, v3s(0), 4, idx, d2), 2);
  assert_int_equal(idx[0], 0);
  vec3 bad[2] = {v3(0, 0, 0), v3(NAN, 0, 0)};
  assert_int_equal(pc_kdtree_build(&t, bad, 2, &e), PC_EINVAL);
  assert_true(pc_kdtree_bytes(&t) > 0);
  pc_kdtree_free(&t);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_random_points),
      cmocka_unit_test(test_ties_and_duplicates),
      cmocka_unit_test(test_empty_and_rebuild),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
