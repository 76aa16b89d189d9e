/* test_no_nan.c: no method produces a NaN or Inf on any shipped scene (DESIGN.md §4.8): every
 * sample of a few iterations at low resolution must be finite and none may have been dropped. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "stat_util.h"

static const char *const scenes[] = {"cornell-box", "furnace", "ajar-door", "slit-room", "open-room", "glossy-glass"};
static const pc_method methods[] = {PC_METHOD_PT};

static void test_all_scenes_finite(void **state) {
  (void)state;
  for (size_t si = 0; si < sizeof scenes / sizeof scenes[0]; si++)
    for (size_t mi = 0; mi < sizeof methods / sizeof methods[0]; mi++) {
      pc_render_request req;
      pc_render_request_default(&req);
      req.set.method = methods[mi];
      req.method_set = true;
      req.set.width = 48;
      req.set.height = 40;
      req.width_set = req.height_set = true;
      req.set.strategy_layers = 4;
      pc_scene scene = {0};
      assert_int_equal(stat_load(scenes[si], &req, &scene), 0);
      pc_film film;
      pc_err e = {0};
      pc_renderer *r = NULL;
      assert_int_equal(pc_film_init(&film, req.set.width, req.set.height, req.set.strategy_layers, &e), 0);
      assert_int_equal(pc_renderer_create(&scene, &req.set, 2, &r, &e), 0);
      assert_int_equal(pc_render_iterations(r, 0, 8, &film, NULL, NULL, NULL, NULL, &e), 0);
      printf("%-13s %-5s dropped %llu\n", scenes[si], pc_method_name(methods[mi]),
             (unsigned long long)film.dropped_nonfinite);
      assert_true(pc_film_is_finite(&film));
      assert_int_equal(film.dropped_nonfinite, 0);
      pc_renderer_destroy(r);
      pc_film_free(&film);
      pc_scene_free(&scene);
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_all_scenes_finite)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
