/* main.c: pcbpt-coord: dispatches to the verbs (render, compare, and the farm's verbs). */
#include <signal.h>
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
    {"study", pc_cmd_study, "equal-time study: error against time for several methods"},
    {"serve", pc_cmd_serve, "run the farm coordinator"},
    {"submit", pc_cmd_submit, "submit a scene as a farm job (prints the job id)"},
    {"status", pc_cmd_status, "progress of one job or all"},
    {"list", pc_cmd_list, "list the jobs"},
    {"workers", pc_cmd_workers, "list the connected workers"},
    {"wait", pc_cmd_wait, "wait for a job (exit 0 when done)"},
    {"cancel", pc_cmd_cancel, "cancel a job"},
    {"fetch", pc_cmd_fetch, "download a job's image (--snapshot K: a study job's K-th snapshot)"},
};

static void usage(FILE *f) {
  fprintf(f, "usage: pcbpt-coord VERB [options]   (pcbpt-coord VERB --help for details)\n\nverbs:\n");
  for (size_t i = 0; i < sizeof verbs / sizeof verbs[0]; i++) fprintf(f, "  %-10s %s\n", verbs[i].name, verbs[i].summary);
}

int main(int argc, char **argv) {
  /* a peer that goes away mid-write must be an error return, not a fatal signal */
  if (signal(SIGPIPE, SIG_IGN) == SIG_ERR) perror("signal");
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
  fprintf(stderr, "pcbpt-coord: unknown verb '%s' (see pcbpt-coord --help)\n", argv[1]);
  return 2;
}
