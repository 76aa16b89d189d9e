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

#include <zstd.h>

#include "auth.h"
#include "bundle.h"
#include "pcbpt.pb-c.h"
#include "scene.h"
#include "wire_film.h"

static char dir[256];
/* a mesh the loader accepts */
#define SENSOR "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>"
#define TRI "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"

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
  /* a symlinked token (how Kubernetes mounts secrets) is read; its target's mode is judged */
  char target[300], link[300];
  snprintf(target, sizeof target, "%s/token-target", dir);
  snprintf(link, sizeof link, "%s/token-link", dir);
  write_text(target, "correct horse battery", 0600);
  assert_int_equal(symlink(target, link), 0);
  assert_int_equal(pc_auth_load_token(link, k2, &e), 0);
  assert_memory_equal(k1, k2, PC_AUTH_KEY);
  chmod(target, 0644);
  assert_int_equal(pc_auth_load_token(link, k2, &e), PC_EINVAL);
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
  /* the files as the scene loader lists them: real paths and names below the root, the scene first */
  char rscene[PATH_MAX], rmesh[PATH_MAX];
  assert_non_null(realpath(scene, rscene));
  assert_non_null(realpath(mesh, rmesh));
  const char *files[] = {rscene, rmesh}, *names[] = {"s.xml", "meshes/m.obj"};
  uint8_t *blob, hash[PC_BUNDLE_HASH], h2[PC_BUNDLE_HASH];
  size_t n;
  pc_err e;
  assert_int_equal(pc_bundle_create(files, names, 2, &blob, &n, hash, &e), 0);
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
  /* a name outside the root is refused */
  const char *outside[] = {"s.xml", "../passwd"};
  assert_int_equal(pc_bundle_create(files, outside, 2, &blob, &n, hash, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "../passwd"));
  assert_int_equal(pc_bundle_create(files, names, 0, &blob, &n, hash, &e), PC_EINVAL);
}

/* The bundle of a scene, as submit makes it: the files the loader read. */
static int scene_bundle(const char *path, uint8_t **blob, size_t *n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e) {
  pc_scene s;
  int rc = pc_scene_load(path, &s, e);
  if (!rc) rc = pc_bundle_create((const char *const *)s.files, (const char *const *)s.file_names, s.nfiles, blob, n, hash, e);
  pc_scene_free(&s);
  if (rc) print_message("%s\n", e->msg);
  return rc;
}

/* The files of a bundle, decoded (the test's own decoder of what workers receive). */
static Pcbpt__Bundle *open_bundle(const uint8_t *blob, size_t n) {
  uint8_t *raw = NULL;
  pc_err e;
  unsigned long long cs = ZSTD_getFrameContentSize(blob, n);
  assert_true(cs < PC_BUNDLE_MAX);
  assert_int_equal(pc_wire_decompress(blob, n, (size_t)cs, PC_BUNDLE_MAX, &raw, &e), 0);
  Pcbpt__Bundle *b = pcbpt__bundle__unpack(NULL, (size_t)cs, raw);
  free(raw);
  assert_non_null(b);
  return b;
}

/* X/scene.xml links to Y/scene.xml; X/mesh.obj links to a secret outside both. The scene's
 * folder is Y (where the loader looks too), so Y/mesh.obj is bundled, never the secret; and
 * a link from Y out of Y is refused, one within Y followed. (Issue 10, failure 3.) */
static void bundle_symlinks(void **st) {
  (void)st;
  char x[300], y[300], p[400], q[400], scene[400];
  snprintf(x, sizeof x, "%s/X", dir);
  snprintf(y, sizeof y, "%s/Y", dir);
  assert_int_equal(mkdir(x, 0700), 0);
  assert_int_equal(mkdir(y, 0700), 0);
  snprintf(p, sizeof p, "%s/secret", dir);
  write_text(p, "SECRET-LINE\n", 0600);
  snprintf(q, sizeof q, "%s/mesh.obj", x);
  assert_int_equal(symlink(p, q), 0);
  snprintf(p, sizeof p, "%s/mesh.obj", y);
  write_text(p, TRI, 0600);
  snprintf(p, sizeof p, "%s/scene.xml", y);
  write_text(p, "<scene version=\"0.6.0\">" SENSOR "<shape type=\"obj\"><string name=\"filename\" value=\"mesh.obj\"/></shape>"
                "<shape type=\"obj\"><string name=\"filename\" value=\"sub/m.obj\"/></shape></scene>", 0600);
  snprintf(q, sizeof q, "%s/sub", y);
  assert_int_equal(mkdir(q, 0700), 0);
  snprintf(q, sizeof q, "%s/sub/m.obj", y);
  assert_int_equal(symlink("../mesh.obj", q), 0); /* a link within the folder */
  snprintf(scene, sizeof scene, "%s/scene.xml", x);
  assert_int_equal(symlink(p, scene), 0);
  uint8_t *blob, hash[PC_BUNDLE_HASH];
  size_t n;
  pc_err e;
  assert_int_equal(scene_bundle(scene, &blob, &n, hash, &e), 0);
  Pcbpt__Bundle *b = open_bundle(blob, n);
  assert_int_equal(b->n_files, 3);
  assert_string_equal(b->files[1]->path, "mesh.obj");
  assert_string_equal(b->files[2]->path, "sub/m.obj");
  for (size_t i = 0; i < b->n_files; i++) assert_null(memmem(b->files[i]->data.data, b->files[i]->data.len, "SECRET", 6));
  assert_memory_equal(b->files[1]->data.data, TRI, strlen(TRI));
  assert_memory_equal(b->files[2]->data.data, TRI, strlen(TRI)); /* under the name the scene uses */
  pcbpt__bundle__free_unpacked(b, NULL);
  free(blob);
  /* Y/mesh.obj itself a link out of Y */
  snprintf(p, sizeof p, "%s/mesh.obj", y);
  assert_int_equal(unlink(p), 0);
  snprintf(q, sizeof q, "%s/secret", dir);
  assert_int_equal(symlink(q, p), 0);
  assert_int_equal(scene_bundle(scene, &blob, &n, hash, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "lies outside the scene folder"));
  assert_null(strstr(e.msg, "SECRET"));
}

/* "./m.obj" and "sub//m.obj" are files the loader finds: bundled under their plain names;
 * an absolute path and ".." are refused with a message that says so. */
static void bundle_path_forms(void **st) {
  (void)st;
  char d[300], p[400];
  snprintf(d, sizeof d, "%s/forms", dir);
  assert_int_equal(mkdir(d, 0700), 0);
  snprintf(p, sizeof p, "%s/sub", d);
  assert_int_equal(mkdir(p, 0700), 0);
  snprintf(p, sizeof p, "%s/m.obj", d);
  write_text(p, TRI, 0600);
  snprintf(p, sizeof p, "%s/sub/m.obj", d);
  write_text(p, TRI "v 1 0 0\n", 0600);
  snprintf(p, sizeof p, "%s/scene.xml", d);
#define OBJ(f) "<shape type=\"obj\"><string name=\"filename\" value=\"" f "\"/></shape>"
  write_text(p, "<scene version=\"0.6.0\">" SENSOR OBJ("./m.obj") OBJ("sub//m.obj") OBJ("m.obj") "</scene>", 0600);
  uint8_t *blob, hash[PC_BUNDLE_HASH];
  size_t n;
  pc_err e;
  assert_int_equal(scene_bundle(p, &blob, &n, hash, &e), 0);
  Pcbpt__Bundle *b = open_bundle(blob, n);
  assert_int_equal(b->n_files, 3);
  assert_string_equal(b->files[1]->path, "m.obj");
  assert_string_equal(b->files[2]->path, "sub/m.obj");
  pcbpt__bundle__free_unpacked(b, NULL);
  free(blob);
  write_text(p, "<scene version=\"0.6.0\">" SENSOR OBJ("/etc/passwd") "</scene>", 0600);
  assert_int_equal(scene_bundle(p, &blob, &n, hash, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "absolute path"));
  write_text(p, "<scene version=\"0.6.0\">" SENSOR OBJ("sub/../../forms/m.obj") "</scene>", 0600);
  assert_int_equal(scene_bundle(p, &blob, &n, hash, &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "lies outside the scene folder"));
}

int main(void) {
  pc_err e;
  if (pc_auth_init(&e) != 0) return 1;
  snprintf(dir, sizeof dir, "/tmp/pcbpt-test-auth-XXXXXX");
  if (!mkdtemp(dir)) return 1;
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(token_rules), cmocka_unit_test(challenge_response), cmocka_unit_test(paths),
    cmocka_unit_test(bundle_roundtrip), cmocka_unit_test(bundle_symlinks),
    cmocka_unit_test(bundle_path_forms),
  };
  int r = cmocka_run_group_tests(tests, NULL, NULL);
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) return 1;
  return r;
}
