/* study_auto.c: method auto in an equal-time study: the pilot, then the winner for what is
 * left of the budget, with the pilot's time counted (study.h). */
#include <stdio.h>
#include <string.h>

#include "pilot.h"
#include "study.h"

int pc_study_render_auto(const pc_scene *scene, const pc_render_settings *set, int threads, double seconds,
                         int max_snaps, const pc_study_ref *ref, pc_film *film, pc_study_run *run, pc_err *e) {
  pc_pilot pilot;
  pc_pilot_local local = {.scene = scene, .threads = threads};
  double slice;
  uint64_t min_it;
  pc_pilot_budget(seconds, 0, &slice, &min_it);
  pc_render_settings base = *set;
  base.method = PC_METHOD_PCBPT;
  int rc = pc_pilot_run(&pilot, &base, slice, min_it, pc_pilot_local_render, &local, e);
  if (rc != PC_OK) return rc;
  pc_render_settings chosen = pilot.c[pilot.best].set;
  chosen.seed = set->seed;
  rc = pc_study_render(scene, &chosen, threads, pc_pilot_remaining(seconds, pilot.seconds), max_snaps, ref, film, run, e);
  if (rc != PC_OK) return rc;
  for (int i = 0; i < run->nsnaps; i++) run->snaps[i].seconds += pilot.seconds;
  run->method = PC_METHOD_AUTO;
  pc_pilot_report(&pilot, run->auto_report, sizeof run->auto_report);
  return PC_OK;
}
