/* fuzz_scene.c: libFuzzer target for the scene parser: the input is written to a file and
 * loaded; any error must be a clean return, never a crash. */
#include <stdint.h>
#include <stdio.h>
#include <unistd.h>

#include "scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  snprintf(path, sizeof path, "/tmp/pcbpt-fuzz-scene-%ld.xml", (long)getpid());
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  size_t w = fwrite(data, 1, size, f);
  if (fclose(f) != 0 || w != size) return 0;
  pc_scene s = {0};
  pc_err e;
  (void)pc_scene_load(path, &s, &e); /* the result is irrelevant; only crashes matter */
  pc_scene_free(&s);
  unlink(path);
  return 0;
}
