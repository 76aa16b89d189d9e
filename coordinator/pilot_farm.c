/* pilot_farm.c: --method auto's candidates as short farm jobs (pilot_farm.h). */
#include "pilot_farm.h"

#include <errno.h>
#include <sodium.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bundle.h"
#include "wire_settings.h"

/* Every candidate of a batch in one study group: the coordinator interleaves their ranges by
 * least worker time, so the farm's load falls on all of them alike. */
static int submit_candidate(pc_pilot_farm *fp, const pc_pilot_candidate *c, uint64_t group, int workers, double seconds,
                            uint64_t min_iterations, uint64_t *job, pc_err *e) {
  char name[200];
  snprintf(name, sizeof name, "%.120s [auto pilot: %s]", fp->name, c->label);
  Pcbpt__Settings ps;
  pc_wire_settings_buf psb;
  pc_wire_settings_to_proto(&c->set, &ps, &psb);
  ps.study_group = group;
  ps.group_workers = (uint32_t)workers;
  Pcbpt__Submit sub = PCBPT__SUBMIT__INIT;
  sub.name = name;
  sub.bundle_hash.data = (uint8_t *)fp->hash;
  sub.bundle_hash.len = PC_BUNDLE_HASH;
  sub.settings = &ps;
  sub.priority = fp->priority;
  if (seconds > 0) {
    ps.halt_worker_seconds = seconds * workers;
    ps.min_iterations = min_iterations; /* the variance needs 2 however slow an iteration is */
  } else {
    sub.halt_iterations = min_iterations;
  }
  return pc_client_submit(fp->cl, &sub, job, e);
}

static int farm_size(pc_pilot_farm *fp, int *n, pc_err *e) {
  *n = fp->workers;
  if (*n > 0) return PC_OK;
  Pcbpt__Envelope *env = NULL;
  int rc = pc_client_status(fp->cl, (uint64_t)-1, &env, e);
  if (!rc) *n = env->status_reply->n_workers > 0 ? (int)env->status_reply->n_workers : 1;
  if (env) pcbpt__envelope__free_unpacked(env, NULL);
  return rc;
}

/* Waits for job to end and takes its figures into c. */
static int wait_candidate(pc_pilot_farm *fp, uint64_t job, pc_pilot_candidate *c, pc_err *e) {
  for (;;) {
    Pcbpt__Envelope *in = NULL;
    int rc = pc_client_status(fp->cl, job, &in, e);
    if (rc) return rc;
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
      c->own_relmse = j->relmse_estimate;
      fp->worker_seconds += j->worker_seconds;
      pcbpt__envelope__free_unpacked(in, NULL);
      return rc;
    }
    pcbpt__envelope__free_unpacked(in, NULL);
    struct timespec ts = {0, 50000000};
    nanosleep(&ts, NULL);
  }
}

static const pc_image *layer_named(const pc_exr_file *x, const char *name) {
  for (int i = 0; i < x->nlayers; i++)
    if (strcmp(x->names[i], name) == 0) return &x->layers[i];
  return NULL;
}

/* Fetches the candidate's image (beauty and variance layers) into c. */
static int fetch_image(pc_pilot_farm *fp, uint64_t job, pc_pilot_candidate *c, pc_err *e) {
  char dir[] = "/tmp/pcbpt-pilot.XXXXXX", path[64];
  if (!mkdtemp(dir)) return pc_errf(e, PC_EIO, "auto pilot: temporary folder: %s", strerror(errno));
  snprintf(path, sizeof path, "%s/c.exr", dir);
  uint64_t bytes = 0;
  pc_exr_file x = {0};
  int rc = pc_client_fetch(fp->cl, job, path, &bytes, e);
  if (!rc) rc = pc_exr_read_layers(path, &x, e);
  if (!rc) {
    const pc_image *beauty = layer_named(&x, ""), *var = layer_named(&x, "variance");
    if (!beauty) rc = pc_errf(e, PC_EPARSE, "auto pilot: job %llu's image has no beauty", (unsigned long long)job);
    else rc = pc_pilot_keep_image(c, x.w, x.h, beauty->rgb, var ? var->rgb : NULL, e);
  }
  pc_exr_file_free(&x);
  unlink(path);
  rmdir(dir);
  return rc;
}

int pc_pilot_farm_render(void *user, pc_pilot_candidate *c, int n, double seconds, uint64_t min_iterations, pc_err *e) {
  pc_pilot_farm *fp = user;
  uint64_t jobs[PC_PILOT_MAX] = {0}, group;
  int workers = 0;
  if (n > PC_PILOT_MAX) return pc_errf(e, PC_EINVAL, "auto pilot: %d candidates", n);
  int rc = farm_size(fp, &workers, e);
  randombytes_buf(&group, sizeof group);
  group |= 1; /* never 0 (no group) */
  for (int i = 0; i < n && !rc; i++) rc = submit_candidate(fp, &c[i], group, workers, seconds, min_iterations, &jobs[i], e);
  for (int i = 0; i < n && !rc; i++) rc = wait_candidate(fp, jobs[i], &c[i], e);
  for (int i = 0; i < n && !rc; i++) rc = fetch_image(fp, jobs[i], &c[i], e);
  return rc;
}
