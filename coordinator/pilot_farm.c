/* pilot_farm.c: --method auto's candidates as short farm jobs (pilot_farm.h). */
#include "pilot_farm.h"

#include <sodium.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "bundle.h"
#include "wire_settings.h"

int pc_pilot_farm_render(void *user, const pc_render_settings *set, double seconds, uint64_t min_iterations,
                         pc_pilot_candidate *c, pc_err *e) {
  pc_pilot_farm *fp = user;
  char name[200];
  snprintf(name, sizeof name, "%.120s [auto pilot: %s]", fp->name, c->label);
  Pcbpt__Settings ps;
  pc_wire_settings_buf psb;
  pc_wire_settings_to_proto(set, &ps, &psb);
  Pcbpt__Submit sub = PCBPT__SUBMIT__INIT;
  sub.name = name;
  sub.bundle_hash.data = (uint8_t *)fp->hash;
  sub.bundle_hash.len = PC_BUNDLE_HASH;
  sub.settings = &ps;
  sub.priority = fp->priority;
  if (seconds > 0 && fp->workers > 0) {
    /* a group of its own, so a study of a smaller farm than the one connected keeps its size */
    randombytes_buf(&ps.study_group, sizeof ps.study_group);
    ps.study_group |= 1;
    ps.group_workers = (uint32_t)fp->workers;
    ps.halt_worker_seconds = seconds * fp->workers;
  } else if (seconds > 0) {
    /* a farm job cannot be bound by "at least N iterations and T seconds": T, but at least 1 s
     * for the scheduling round trips */
    sub.halt_seconds = seconds > 1 ? seconds : 1;
  } else {
    sub.halt_iterations = min_iterations;
  }
  uint64_t job = 0;
  int rc = pc_client_submit(fp->cl, &sub, &job, e);
  while (!rc) {
    Pcbpt__Envelope *in = NULL;
    if ((rc = pc_client_status(fp->cl, job, &in, e)) != 0) break;
    if (in->status_reply->n_jobs != 1) {
      pcbpt__envelope__free_unpacked(in, NULL);
      return pc_errf(e, PC_EIO, "auto pilot: job %llu vanished", (unsigned long long)job);
    }
    const Pcbpt__JobStatus *j = in->status_reply->jobs[0];
    bool done = strcmp(j->state, "done") == 0;
    if (done || strcmp(j->state, "failed") == 0 || strcmp(j->state, "cancelled") == 0) {
      if (!done) rc = pc_errf(e, PC_EIO, "auto pilot: job %llu (%s) %s: %s", (unsigned long long)job, c->label, j->state, j->error);
      c->iterations = j->iterations_done;
      c->seconds = j->worker_seconds;
      c->relmse = j->relmse_estimate;
      fp->worker_seconds += j->worker_seconds;
      pcbpt__envelope__free_unpacked(in, NULL);
      break;
    }
    pcbpt__envelope__free_unpacked(in, NULL);
    struct timespec ts = {0, 50000000};
    nanosleep(&ts, NULL);
  }
  return rc;
}
