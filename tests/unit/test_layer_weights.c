/* test_layer_weights.c: what an image's header says of how it weighs its strategies
 * (pc_render_settings_weights), which layers that concerns, and the JSON text the verbs print
 * from untrusted headers and layer names (base/text_out). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "text_out.h"
#include "render.h"

static void weights_of(pc_method m, void (*change)(pc_render_settings *), char *buf, size_t n) {
  pc_render_settings s;
  pc_render_settings_default(&s);
  s.method = m;
  if (change) change(&s);
  pc_render_settings_weights(&s, buf, n);
}

static void mis_one(pc_render_settings *s) { s->mis_mode = PC_MIS_UPPER_BOUND; }
static void mis_count_one(pc_render_settings *s) { s->mis_count = 1.f; }
static void power(pc_render_settings *s) { s->mis_heuristic = PC_MIS_POWER; }
static void quarter_lt(pc_render_settings *s) { s->light_paths = (uint64_t)s->width * (uint64_t)s->height / 4; }
static void standard(pc_render_settings *s) { s->mis_mode = PC_MIS_STANDARD; }

static void weightings(void **st) {
  (void)st;
  char bdpt[96], pcbpt[96], w[96];
  weights_of(PC_METHOD_BDPT, NULL, bdpt, sizeof bdpt);
  assert_string_equal(bdpt, "bidirectional balance n_lt=1 n_inner=1");
  weights_of(PC_METHOD_PCBPT, NULL, pcbpt, sizeof pcbpt);
  assert_string_equal(pcbpt, "bidirectional balance n_lt=1 n_inner=2");
  assert_true(pc_weights_unlike(pcbpt, bdpt));
  /* the inner count 1, however it is asked for, weighs PCBPT's and CBDPT's strategies as BDPT's */
  weights_of(PC_METHOD_PCBPT, mis_one, w, sizeof w);
  assert_string_equal(w, bdpt);
  weights_of(PC_METHOD_CBDPT, mis_count_one, w, sizeof w);
  assert_string_equal(w, bdpt);
  /* standard weights: count M, what PCBPT's inner strategies would count as independent paths */
  weights_of(PC_METHOD_PCBPT, standard, w, sizeof w);
  assert_string_equal(w, "bidirectional balance n_lt=1 n_inner=100");
  weights_of(PC_METHOD_BDPT, power, w, sizeof w);
  assert_string_equal(w, "bidirectional power n_lt=1 n_inner=1");
  weights_of(PC_METHOD_BDPT, quarter_lt, w, sizeof w);
  assert_string_equal(w, "bidirectional balance n_lt=0.25 n_inner=1");
  weights_of(PC_METHOD_PT, quarter_lt, w, sizeof w); /* PT traces no light paths */
  assert_string_equal(w, "pt balance");
  weights_of(PC_METHOD_LT, NULL, w, sizeof w);
  assert_string_equal(w, "lt balance n_lt=1");
  /* unknown (NULL: no header attribute) compares with anything */
  assert_false(pc_weights_unlike(NULL, bdpt));
  assert_false(pc_weights_unlike(bdpt, NULL));
  assert_false(pc_weights_unlike(bdpt, "bidirectional balance n_lt=1 n_inner=1"));
}

static void strategy_layers(void **st) {
  (void)st;
  const char *yes[] = {"pt", "nee", "lt", "inner", "s2t3", "s0t2", "s10t1"};
  const char *no[] = {"", "beauty", "beauty_max", "variance", "s2t", "s2t3x", "st3", "innerx", "s2t3 "};
  for (size_t i = 0; i < sizeof yes / sizeof yes[0]; i++) assert_true(pc_weights_layer(yes[i]));
  for (size_t i = 0; i < sizeof no / sizeof no[0]; i++) assert_false(pc_weights_layer(no[i]));
}

static void json_text(void **st) {
  (void)st;
  char *buf = NULL;
  size_t n = 0;
  FILE *f = open_memstream(&buf, &n);
  assert_non_null(f);
  pc_json_string(f, "a\"b\\c\nd\x01");
  fputc(' ', f);
  pc_json_number(f, 0.25);
  fputc(' ', f);
  pc_json_number(f, NAN);
  fputc(' ', f);
  pc_json_number(f, INFINITY);
  fputc(' ', f);
  pc_json_number(f, -INFINITY);
  assert_int_equal(fclose(f), 0);
  assert_string_equal(buf, "\"a\\\"b\\\\c\\u000ad\\u0001\" 0.25 null null null");
  free(buf);
  /* for a terminal: no escape sequence gets through, and the length is bounded */
  char out[8];
  assert_string_equal(pc_text_printable("a\x1b[2Jb\x7f", out, sizeof out), "a?[2Jb?");
  assert_string_equal(pc_text_printable("0123456789", out, sizeof out), "0123456");
  assert_string_equal(pc_text_printable("", out, sizeof out), "");
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(weightings),
    cmocka_unit_test(strategy_layers),
    cmocka_unit_test(json_text),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
