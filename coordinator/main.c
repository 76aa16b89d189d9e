/* main.c: pcbpt-coord: dispatches to the verbs (render, compare, and the farm's verbs). */
#include <stdio.h>
#include <string.h>

#include "verbs.h"

typedef struct verb {
  const char *name;
  int (*run)(int argc, char **argv);
  const char *summary;
} verb;

static const verb verbs[] = {
    {"render", pc_cmd_render, "render a scene on this machine"},
    {"compare", pc_cmd_compare, "RMSE, relMSE and L1 between two EXR images, per layer"},
};

static void usage(FILE *f) {
  fprintf(f, "usage: pcbpt-coord VERB [options]   (pcbpt-coord VERB --help for details)\n\nverbs:\n");
  for (size_t i = 0; i < sizeof verbs / sizeof verbs[0]; i++) fprintf(f, "  %-10s %s\n", verbs[i].name, verbs[i].summary);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
    usage(stdout);
    return 0;
  }
  if (strcmp(argv[1], "--version") == 0) {
    printf("pcbpt-coord %s\n", PCBPT_VERSION);
    return 0;
  }
  for (size_t i = 0; i < sizeof verbs / sizeof verbs[0]; i++)
    if (strcmp(argv[1], verbs[i].name) == 0) return verbs[i].run(argc - 2, argv + 2);
  fprintf(stderr, "pcbpt-coord: unknown verb '%s'\n", argv[1]);
  usage(stderr);
  return 2;
}
