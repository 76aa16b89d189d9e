/* fuzz_scene.c: libFuzzer target for the scene parser: the input is written to a file and
 * loaded (with a -D value and a warning sink, so substitution, includes and warnings are
 * reached too); any error must be a clean return, never a crash. An input starting with "OBJ\n"
 * is instead the OBJ file of a fixed scene with a fixed material library, and one starting with
 * "MTL\n" that library for a fixed OBJ of several groups and materials (mesh_obj.c and
 * scene_obj_xml.c, which the XML alone never reaches). */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz_dir.h"
#include "scene.h"

static void ignore(void *ud, const char *line) { (void)ud, (void)line; }

static const char *SCENE = "<scene version=\"0.6.0\"><shape type=\"obj\"><string name=\"filename\" value=\"g.obj\"/>"
                           "<bsdf type=\"conductor\" name=\"b\"/></shape></scene>\n";
static const char *OBJ = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl a\nf 1/1 2/2 3/3\n"
                         "g x\nusemtl b\nf 1 3 4\nusemtl c\nf 1 2 4\nusemtl d\nf 2 3 4\n";
static const char *MTL = "newmtl a\nKd 0.5 0.5 0.5\nnewmtl c\nKs 1 1 1\nNs 10\nillum 2\nd 0.5\nnewmtl d\nillum 7\n";

/* The inputs' folder: made once (mkdtemp, under TMPDIR) and removed with its three files at exit
 * (libFuzzer exits through exit() at -max_total_time), so runs leave nothing behind. */
static char dir[4096];

static void remove_dir(void) {
  static const char *const files[] = {"scene.xml", "g.obj", "m.mtl"};
  char path[4200];
  for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
    snprintf(path, sizeof path, "%s/%s", dir, files[i]);
    (void)unlink(path);
  }
  (void)rmdir(dir);
}

static int put(const char *name, const void *data, size_t size) {
  char path[4200];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  size_t w = fwrite(data, 1, size, f);
  return fclose(f) != 0 || w != size ? -1 : 0;
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  fuzz_make_dir("fuzz-scene", dir, sizeof dir, remove_dir);
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[4200];
  bool obj = size >= 4 && memcmp(data, "OBJ\n", 4) == 0, mtl = size >= 4 && memcmp(data, "MTL\n", 4) == 0;
  int rc;
  if (obj || mtl) {
    rc = put("scene.xml", SCENE, strlen(SCENE));
    if (!rc) rc = obj ? put("g.obj", data + 4, size - 4) : put("g.obj", OBJ, strlen(OBJ));
    if (!rc) rc = mtl ? put("m.mtl", data + 4, size - 4) : put("m.mtl", MTL, strlen(MTL));
  } else {
    rc = put("scene.xml", data, size);
  }
  snprintf(path, sizeof path, "%s/scene.xml", dir);
  if (rc) return 0;
  pc_scene s = {0};
  pc_err e;
  pc_scene_defines d = {0};
  (void)pc_scene_defines_add(&d, "p=0.5", &e);
  pc_scene_load_opts o = {.defines = &d, .warn = ignore};
  (void)pc_scene_load_with(path, &o, &s, &e); /* the result is irrelevant; only crashes matter */
  pc_scene_free(&s);
  return 0;
}
