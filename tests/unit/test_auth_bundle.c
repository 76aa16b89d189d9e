/* test_auth_bundle.c: token file rules, the challenge/response MACs, and scene bundles
 * (collect, hash, refuse a wrong hash, refuse escaping paths, unpack into a cache). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <limits.h>
#include <stdlib.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "auth.h"
#include "bundle.h"

static char dir[256];

static void write_text(const char *path, const char *text, mode_t mode) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
  chmod(path, mode);
}

static void token_rules(void **st) {
  (void)st;
  char p[300];
  uint8_t k1[PC_AUTH_KEY], k2[PC_AUTH_KEY];
  pc_err e;
  snprintf(p, sizeof p, "%s/token", dir);
  write_text(p, "correct horse battery\n", 0644);
  assert_int_equal(pc_auth_load_token(p, k1, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "group or others"));
  chmod(p, 0600);
  assert_int_equal(pc_auth_load_token(p, k1, &e), 0);
  write_text(p, "correct horse battery", 0600);
  assert_int_equal(pc_auth_load_token(p, k2, &e), 0);
  assert_memory_equal(k1, k2, PC_AUTH_KEY);
  write_text(p, "short", 0600);
  assert_int_equal(pc_auth_load_token(p, k2, &e), PC_EINVAL);
  snprintf(p, sizeof p, "%s/missing", dir);
  assert_int_equal(pc_auth_load_token(p, k2, &e), PC_EIO);
}

static void challenge_response(void **st) {
  (void)st;
  uint8_t key[PC_AUTH_KEY] = {1}, other[PC_AUTH_KEY] = {2}, n1[PC_AUTH_NONCE], n2[PC_AUTH_NONCE], mac[PC_AUTH_MAC];
  pc_auth_nonce(n1);
  pc_auth_nonce(n2);
  assert_int_equal(pc_auth_mac(key, false, n1, n2, mac), 0);
  assert_true(pc_auth_verify(key, false, n1, n2, mac, PC_AUTH_MAC));
  assert_false(pc_auth_verify(other, false, n1, n2, mac, PC_AUTH_MAC));
  assert_false(pc_auth_verify(key, true, n1, n2, mac, PC_AUTH_MAC)); /* no reflection */
  assert_false(pc_auth_verify(key, false, n2, n1, mac, PC_AUTH_MAC));
  assert_false(pc_auth_verify(key, false, n1, n2, mac, PC_AUTH_MAC - 1));
}

static void paths(void **st) {
  (void)st;
  assert_true(pc_bundle_path_ok("a.obj"));
  assert_true(pc_bundle_path_ok("meshes/a.obj"));
  assert_false(pc_bundle_path_ok("../a.obj"));
  assert_false(pc_bundle_path_ok("meshes/../../a"));
  assert_false(pc_bundle_path_ok("/etc/passwd"));
  assert_false(pc_bundle_path_ok("a//b"));
  assert_false(pc_bundle_path_ok("./a"));
  assert_false(pc_bundle_path_ok("a\\b"));
  assert_false(pc_bundle_path_ok(""));
}

static void bundle_roundtrip(void **st) {
  (void)st;
  char scene[300], sub[300], mesh[300], cache[300], out[1024], out2[1024];
  snprintf(sub, sizeof sub, "%s/scene", dir);
  mkdir(sub, 0700);
  snprintf(mesh, sizeof mesh, "%s/scene/meshes", dir);
  mkdir(mesh, 0700);
  snprintf(mesh, sizeof mesh, "%s/scene/meshes/m.obj", dir);
  write_text(mesh, "v 0 0 0\n", 0600);
  snprintf(scene, sizeof scene, "%s/scene/s.xml", dir);
  write_text(scene, "<scene version=\"0.6.0\"><shape type=\"obj\"><string name=\"filename\" value=\"meshes/m.obj\"/></shape>"
                    "<shape type=\"obj\"><string name=\"filename\" value=\"meshes/m.obj\"/></shape></scene>", 0600);
  /* the files as the scene loader lists them: real paths below the root, the scene first */
  char root[PATH_MAX], rscene[PATH_MAX], rmesh[PATH_MAX];
  assert_non_null(realpath(sub, root));
  assert_non_null(realpath(scene, rscene));
  assert_non_null(realpath(mesh, rmesh));
  const char *files[] = {rscene, rmesh};
  uint8_t *blob, hash[PC_BUNDLE_HASH], h2[PC_BUNDLE_HASH];
  size_t n;
  pc_err e;
  assert_int_equal(pc_bundle_create(root, files, 2, &blob, &n, hash, &e), 0);
  snprintf(cache, sizeof cache, "%s/cache", dir);
  assert_int_equal(pc_bundle_lookup(cache, hash, out, sizeof out), 0);
  memcpy(h2, hash, sizeof h2);
  h2[0] ^= 1;
  assert_int_equal(pc_bundle_unpack(blob, n, h2, cache, out, sizeof out, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "hash does not match"));
  assert_int_equal(pc_bundle_unpack(blob, n, hash, cache, out, sizeof out, &e), 0);
  assert_int_equal(pc_bundle_lookup(cache, hash, out2, sizeof out2), 1);
  assert_string_equal(out, out2);
  char m2[1200];
  snprintf(m2, sizeof m2, "%.*s/meshes/m.obj", (int)(strrchr(out, '/') - out), out);
  assert_int_equal(access(m2, R_OK), 0);
  /* unpacking again is a no-op */
  assert_int_equal(pc_bundle_unpack(blob, n, hash, cache, out2, sizeof out2, &e), 0);
  free(blob);
  /* a file outside the root is refused */
  const char *outside[] = {rscene, "/etc/passwd"};
  assert_int_equal(pc_bundle_create(root, outside, 2, &blob, &n, hash, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "/etc/passwd"));
  assert_int_equal(pc_bundle_create(root, files, 0, &blob, &n, hash, &e), PC_EINVAL);
}

int main(void) {
  pc_err e;
  if (pc_auth_init(&e) != 0) return 1;
  snprintf(dir, sizeof dir, "/tmp/pcbpt-test-auth-XXXXXX");
  if (!mkdtemp(dir)) return 1;
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(token_rules), cmocka_unit_test(challenge_response), cmocka_unit_test(paths),
    cmocka_unit_test(bundle_roundtrip),
  };
  int r = cmocka_run_group_tests(tests, NULL, NULL);
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) return 1;
  return r;
}
