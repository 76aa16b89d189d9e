/* study_run.c: the layer slots of a study and a run's storage. A run's points come from the
 * farm (study_measure.c): every method renders as a farm job, so a study on one machine goes
 * through the embedded farm like `render`. */
#include <stdlib.h>
#include <string.h>

#include "study.h"

static const char *const slot_names[PC_STUDY_NLAYERS] = {"beauty", "pt", "nee", "lt", "inner"};

const char *pc_study_layer_name(int slot) {
  return slot >= 0 && slot < PC_STUDY_NLAYERS ? slot_names[slot] : "?";
}

int pc_study_layer_parse(const char *name) {
  for (int i = 0; i < PC_STUDY_NLAYERS; i++)
    if (strcmp(name, slot_names[i]) == 0) return i;
  return -1;
}

void pc_study_run_free(pc_study_run *run) {
  if (!run) return;
  free(run->snaps);
  run->snaps = NULL;
  run->nsnaps = 0;
}
