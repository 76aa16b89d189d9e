/* fuzz_scene.c: libFuzzer target for the scene parser: the input is written to a file and
 * loaded (with a -D value and a warning sink, so substitution, includes and warnings are
 * reached too); any error must be a clean return, never a crash. */
#include <stdint.h>
#include <stdio.h>
#include <unistd.h>

#include "scene.h"

static void ignore(void *ud, const char *line) { (void)ud, (void)line; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  snprintf(path, sizeof path, "/tmp/pcbpt-fuzz-scene-%ld.xml", (long)getpid());
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  size_t w = fwrite(data, 1, size, f);
  if (fclose(f) != 0 || w != size) return 0;
  pc_scene s = {0};
  pc_err e;
  pc_scene_defines d = {0};
  (void)pc_scene_defines_add(&d, "p=0.5", &e);
  pc_scene_load_opts o = {.defines = &d, .warn = ignore};
  (void)pc_scene_load_with(path, &o, &s, &e); /* the result is irrelevant; only crashes matter */
  pc_scene_free(&s);
  unlink(path);
  return 0;
}
