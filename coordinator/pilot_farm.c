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
 * least worker time, so the farm's load falls on all of them alike. Bound by iterations, which
 * the scheduler never overruns (a worker-seconds budget halts only once the uploads carrying it
 * are merged, and the ranges then in flight finish: on a loaded machine 6 slices of 0.08 s
 * took 4 s). */
static int submit_candidate(pc_pilot_farm *fp, const pc_pilot_candidate *c, uint64_t seed, uint64_t group, int workers,
                            uint64_t iterations, uint64_t *job, pc_err *e) {
  char name[200];
  snprintf(name, sizeof name, "%.120s [auto pilot: %s]", fp->name, c->label);
  pc_render_settings set = c->set;
  set.seed = seed;
  Pcbpt__Settings ps;
  pc_wire_settings_buf psb;
  pc_wire_settings_to_proto(&set, &ps, &psb);
  ps.study_group = group;
  ps.group_workers = (uint32_t)workers;
  if (c->counts && fp->keep) ps.pilot_group = fp->pilot_group;
  Pcbpt__Submit sub = PCBPT__SUBMIT__INIT;
  sub.name = name;
  sub.bundle_hash.data = (uint8_t *)fp->hash;
  sub.bundle_hash.len = PC_BUNDLE_HASH;
  sub.settings = &ps;
  sub.priority = fp->priority;
  sub.halt_iterations = iterations;
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

/* Waits for candidate c's job to end and takes its figures into out. */
static int wait_candidate(pc_pilot_farm *fp, uint64_t job, const pc_pilot_candidate *c, pc_pilot_candidate *out,
                          pc_err *e) {
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
      out->iterations = j->iterations_done;
      out->seconds = j->worker_seconds;
      out->cpu_seconds = j->cpu_seconds;
      out->own_relmse = j->relmse_estimate;
      fp->worker_seconds += j->worker_seconds;
      if (c->counts && done) {
        fp->counted_worker_seconds += j->worker_seconds;
        fp->counted_iterations += j->iterations_done;
      }
      pcbpt__envelope__free_unpacked(in, NULL);
      return rc;
    }
    pcbpt__envelope__free_unpacked(in, NULL);
    struct timespec ts = {0, 10000000};
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

int pc_pilot_farm_render(void *user, const pc_pilot_candidate *c, int n, uint64_t iterations, uint64_t salt,
                         pc_pilot_candidate *out, pc_err *e) {
  pc_pilot_farm *fp = user;
  uint64_t jobs[PC_PILOT_MAX] = {0}, group;
  if (n > PC_PILOT_MAX) return pc_errf(e, PC_EINVAL, "auto pilot: %d candidates", n);
  int rc = PC_OK;
  if (!fp->farm_size) rc = farm_size(fp, &fp->farm_size, e);
  if (rc) return rc;
  while (fp->keep && !fp->pilot_group) randombytes_buf(&fp->pilot_group, sizeof fp->pilot_group);
  randombytes_buf(&group, sizeof group);
  group |= 1; /* never 0 (no group) */
  for (int i = 0; i < n && !rc; i++)
    rc = submit_candidate(fp, &c[i], c[i].set.seed ^ salt, group, fp->farm_size, iterations, &jobs[i], e);
  for (int i = 0; i < n && !rc; i++) rc = wait_candidate(fp, jobs[i], &c[i], &out[i], e);
  for (int i = 0; i < n && !rc; i++) rc = fetch_image(fp, jobs[i], &out[i], e);
  return rc;
}

int pc_pilot_farm_choose(pc_pilot_farm *fp, pc_render_request *req, char *report, size_t size, double *pilot_seconds,
                         double *prior_amount, pc_err *e) {
  double slice;
  uint64_t min_it;
  pc_pilot pilot;
  pc_pilot_budget(req->seconds, req->spp, &slice, &min_it);
  /* one budget fixes the pilot's weight before its values are seen; with --spp and --time both,
     which one stops the job depends on the chosen method's cost (docs/auto.md) */
  fp->keep = (req->spp > 0) != (req->seconds > 0);
  *prior_amount = 0;
  int rc = farm_size(fp, &fp->farm_size, e);
  if (rc) return rc;
  /* the slices in worker-seconds, the unit of a candidate's cost */
  rc = pc_pilot_run(&pilot, &req->set, req->pt_complete, !req->caustics, slice * fp->farm_size, min_it, pc_pilot_farm_render, fp, e);
  if (!rc) {
    uint64_t seed = req->set.seed;
    req->set = pilot.c[pilot.best].set;
    req->set.seed = seed;
    pc_pilot_report(&pilot, report, size);
    *pilot_seconds = pilot.seconds;
    /* in the unit of the job's budget (coordinator/job_prior.c), what the mix is worth */
    double share = pc_pilot_counted_share(&pilot);
    if (fp->pilot_group && req->spp > 0) *prior_amount = share * (double)fp->counted_iterations;
    else if (fp->pilot_group && fp->farm_size > 0) *prior_amount = share * fp->counted_worker_seconds / fp->farm_size;
    if (req->seconds > 0) req->seconds = pc_pilot_remaining(req->seconds, pilot.seconds);
  }
  pc_pilot_free(&pilot);
  return rc;
}
