/* test_study_method.c: a study's method names (study_method.c): "pcbpt-kN" and "pcbpt-kN-rR"
 * give PCBPT its own K and connection rate, which replace the study's settings and leave the
 * rest alone; malformed K or rate values are refused with a message naming the method. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>

#include "study.h"

static void test_plain_and_k(void **state) {
  (void)state;
  pc_study_method m;
  pc_err e = {0};
  assert_int_equal(pc_study_method_parse("bdpt", &m, &e), PC_OK);
  assert_int_equal(m.method, PC_METHOD_BDPT);
  assert_int_equal(m.pcbpt_k, 0);
  assert_true(m.pcbpt_rate == 0.f);
  assert_int_equal(pc_study_method_parse("pcbpt-k8", &m, &e), PC_OK);
  assert_int_equal(m.method, PC_METHOD_PCBPT);
  assert_int_equal(m.pcbpt_k, 8);
  assert_true(m.pcbpt_rate == 0.f);
  assert_string_equal(m.name, "pcbpt-k8");
}

static void test_rate(void **state) {
  (void)state;
  pc_study_method m;
  pc_err e = {0};
  assert_int_equal(pc_study_method_parse("pcbpt-k64-r0.125", &m, &e), PC_OK);
  assert_int_equal(m.pcbpt_k, 64);
  assert_true(m.pcbpt_rate == 0.125f);
  assert_string_equal(m.name, "pcbpt-k64-r0.125");
  pc_render_settings set;
  pc_render_settings_default(&set);
  set.pcbpt_m = 50;
  pc_study_method_apply(&m, &set);
  assert_int_equal(set.method, PC_METHOD_PCBPT);
  assert_int_equal(set.pcbpt_k, 64);
  assert_true(set.pcbpt_rate == 0.125f);
  assert_int_equal(set.pcbpt_m, 50);
  /* Without a rate of its own the study's stays. */
  set.pcbpt_rate = 0.5f;
  assert_int_equal(pc_study_method_parse("pcbpt-k2", &m, &e), PC_OK);
  pc_study_method_apply(&m, &set);
  assert_int_equal(set.pcbpt_k, 2);
  assert_true(set.pcbpt_rate == 0.5f);
  /* small rates are rates (the bound is 0, not a guess above it) */
  assert_int_equal(pc_study_method_parse("pcbpt-k1-r1e-7", &m, &e), PC_OK);
  assert_true(m.pcbpt_rate == 1e-7f);
}

static void test_refusals(void **state) {
  (void)state;
  const char *bad[] = {"pcbpt-k0", "pcbpt-k65", "pcbpt-k", "pcbpt-kx", "pcbpt-k-r0.5", "pcbpt-k12345678-r0.5",
                       "pcbpt-k1-r", "pcbpt-k1-r0", "pcbpt-k1-r1.5", "pcbpt-k1-rx", "pcbpt-k1-r-0.5", "pcbpt-k1-r1e-300", "magic"};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    pc_study_method m;
    pc_err e = {0};
    assert_int_not_equal(pc_study_method_parse(bad[i], &m, &e), PC_OK);
    assert_non_null(strstr(e.msg, bad[i]));
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_plain_and_k),
      cmocka_unit_test(test_rate),
      cmocka_unit_test(test_refusals),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
