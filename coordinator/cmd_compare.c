/* cmd_compare.c: `pcbpt-coord compare A.exr B.exr` (placeholder until metrics land). */
#include <stdio.h>

#include "verbs.h"

int pc_cmd_compare(int argc, char **argv) {
  (void)argc;
  (void)argv;
  fprintf(stderr, "pcbpt-coord compare: not built yet\n");
  return 2;
}
