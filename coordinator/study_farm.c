/* study_farm.c: an equal-time study's renders as farm jobs (see study_farm.h): submits a
 * group's jobs, follows them with status requests, then fetches every job's snapshots and
 * final image and measures them into the study's curves. */
#include "study_farm.h"

#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "client.h"
#include "pilot_farm.h"
#include "wire_settings.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sleep_s(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  nanosleep(&ts, NULL);
}

int pc_study_farm_open(pc_study_farm *f, const char *host, const char *token_file, int threads, pc_err *e) {
  memset(f, 0, sizeof *f);
  f->threads = threads;
  f->log_fd = 2;
  if (host) {
    snprintf(f->hostport, sizeof f->hostport, "%s", host);
    f->token = token_file;
    return PC_OK;
  }
  int rc = pc_embedded_start(&f->emb, e);
  if (rc) return rc;
  f->embedded = true;
  f->log_fd = f->emb.term_fd;
  snprintf(f->hostport, sizeof f->hostport, "%s", f->emb.hostport);
  f->token = f->emb.token;
  return PC_OK;
}

void pc_study_farm_close(pc_study_farm *f) {
  if (f->embedded) pc_embedded_stop(&f->emb);
  f->embedded = false;
}

int pc_study_farm_workers(pc_study_farm *f, int *n, pc_err *e) {
  if (f->embedded) {
    *n = 1;
    return PC_OK;
  }
  pc_client cl;
  Pcbpt__Envelope *env = NULL;
  int rc = pc_client_connect(f->hostport, f->token, &cl, e);
  if (!rc) rc = pc_client_status(&cl, (uint64_t)-1, &env, e);
  if (!rc) *n = (int)env->status_reply->n_workers;
  if (env) pcbpt__envelope__free_unpacked(env, NULL);
  pc_client_close(&cl); /* (connect leaves fd -1 when it fails) */
  return rc;
}

/* What method auto renders in a group: the pilot's choice, for what the pilot left of the budget. */
typedef struct auto_choice {
  pc_render_settings set;
  double pilot_worker_seconds;
  uint64_t pilot_group; /* its films the job's image mixes in, with this many worker-seconds */
  double prior_amount;
  char report[1024];
} auto_choice;

/* Runs --method auto's pilot as farm jobs of the group's farm size, charged to auto's budget
 * of worker-seconds (pilot_farm.h): the group's other methods start after it, so the pilot's
 * jobs have the farm to themselves. */
static int run_pilot(pc_client *cl, const pc_study_group *g, auto_choice *ac, pc_err *e) {
  pc_render_settings base = g->req->set;
  base.method = PC_METHOD_PCBPT;
  base.seed = g->seed;
  double slice;
  uint64_t min_it;
  pc_pilot_budget(g->seconds, 0, &slice, &min_it);
  pc_pilot_farm fp = {.cl = cl, .hash = g->hash, .name = g->scene_path, .workers = g->workers, .keep = true};
  pc_pilot pilot;
  int rc = pc_pilot_run(&pilot, &base, g->req->pt_complete, !g->req->caustics, slice * g->workers, min_it, pc_pilot_farm_render, &fp, e);
  if (rc) {
    pc_pilot_free(&pilot);
    return rc;
  }
  ac->set = pilot.c[pilot.best].set;
  ac->set.seed = g->seed;
  ac->pilot_worker_seconds = fp.worker_seconds;
  ac->pilot_group = fp.pilot_group;
  /* auto's budget is worker-seconds; what the mix is worth */
  ac->prior_amount = pc_pilot_counted_share(&pilot) * fp.counted_worker_seconds;
  pilot.seconds = fp.worker_seconds; /* the report gives the cost charged to the budget */
  pc_pilot_report(&pilot, ac->report, sizeof ac->report);
  pc_pilot_free(&pilot);
  return PC_OK;
}

static int submit(pc_client *cl, const pc_study_group *g, const pc_study_method *method, const auto_choice *ac,
                  uint64_t group, uint64_t *job, pc_err *e) {
  pc_render_settings set = g->req->set;
  pc_study_method_apply(method, &set);
  set.seed = g->seed;
  double budget = g->seconds * g->workers;
  if (method->method == PC_METHOD_AUTO) {
    set = ac->set;
    budget = g->workers * pc_pilot_remaining(g->seconds, ac->pilot_worker_seconds / g->workers);
  }
  Pcbpt__Settings ps;
  pc_wire_settings_buf psb;
  pc_wire_settings_to_proto(&set, &ps, &psb);
  if (method->method == PC_METHOD_AUTO) {
    ps.auto_report = (char *)ac->report;
    ps.prior_group = ac->prior_amount > 0 ? ac->pilot_group : 0;
    ps.prior_amount = ac->prior_amount > 0 ? ac->prior_amount : 0;
  }
  ps.study_group = group;
  ps.halt_worker_seconds = budget;
  ps.snapshots = (uint32_t)g->snapshots;
  ps.group_workers = (uint32_t)g->workers;
  Pcbpt__Submit sub = PCBPT__SUBMIT__INIT;
  sub.name = (char *)g->scene_path;
  sub.bundle_hash.data = (uint8_t *)g->hash;
  sub.bundle_hash.len = PC_BUNDLE_HASH;
  sub.settings = &ps;
  return pc_client_submit(cl, &sub, job, e);
}

static const Pcbpt__JobStatus *find_job(const Pcbpt__StatusReply *r, uint64_t id) {
  for (size_t i = 0; i < r->n_jobs; i++)
    if (r->jobs[i]->job_id == id) return r->jobs[i];
  return NULL;
}

/* A coordinator that went away (restarted: its jobs resume from their checkpoints) is
 * reconnected to for up to RECONNECT_SECONDS. */
#define RECONNECT_SECONDS 120
static int reconnect(pc_study_farm *f, pc_client *cl, pc_err *e) {
  pc_client_close(cl);
  dprintf(f->log_fd, "  lost the coordinator (%s): reconnecting for up to %d s\n", e->msg, RECONNECT_SECONDS);
  double until = now_s() + RECONNECT_SECONDS;
  for (;;) {
    pc_err ce = {0};
    if (pc_client_connect(f->hostport, f->token, cl, &ce) == PC_OK) return PC_OK;
    if (now_s() > until) return pc_errf(e, ce.code ? ce.code : PC_EIO, "coordinator gone: %s", ce.msg);
    sleep_s(1);
  }
}

/* Waits for every job of the group to end; a failed or cancelled one is an error. */
static int wait_group(pc_study_farm *f, pc_client *cl, const pc_study_group *g, const uint64_t *jobs, uint32_t *rerun,
                      pc_err *e) {
  double last_line = now_s(), budget = g->seconds * g->workers;
  for (;;) {
    Pcbpt__Envelope *env = NULL;
    int rc = pc_client_status(cl, 0, &env, e);
    if (rc && !f->embedded && (rc = reconnect(f, cl, e)) == PC_OK) continue;
    if (rc) return rc;
    bool all_done = true, show = now_s() - last_line >= 10;
    if (show) dprintf(f->log_fd, "  %s:", g->label);
    for (int m = 0; m < g->nmethods && !rc; m++) {
      const Pcbpt__JobStatus *st = find_job(env->status_reply, jobs[m]);
      if (!st) {
        rc = pc_errf(e, PC_EIO, "job %llu is gone from the farm", (unsigned long long)jobs[m]);
        break;
      }
      if (strcmp(st->state, "failed") == 0 || strcmp(st->state, "cancelled") == 0)
        rc = pc_errf(e, PC_EIO, "%s job %llu %s: %s", g->methods[m].name, (unsigned long long)jobs[m], st->state,
                     st->error && *st->error ? st->error : "(no reason given)");
      all_done = all_done && strcmp(st->state, "done") == 0;
      rerun[m] = st->ranges_rerun;
      if (show)
        dprintf(f->log_fd, " %s %.1f/%.0f worker-s (%u snapshots)", g->methods[m].name, st->worker_seconds,
                budget, st->snapshots);
    }
    if (show) {
      dprintf(f->log_fd, "\n");
      last_line = now_s();
    }
    pcbpt__envelope__free_unpacked(env, NULL);
    if (rc || all_done) return rc;
    sleep_s(0.25);
  }
}

static int write_png(const pc_exr_file *x, const char *exr, pc_err *e) {
  char png[4096];
  size_t n = strlen(exr);
  if (n < 4 || n + 1 > sizeof png) return pc_errf(e, PC_EINVAL, "%s: path too long", exr);
  memcpy(png, exr, n - 4);
  strcpy(png + n - 4, ".png");
  for (int i = 0; i < x->nlayers; i++)
    if (x->names[i][0] == '\0') return pc_png_write_preview(png, x->w, x->h, x->layers[i].rgb, 0, e);
  return pc_errf(e, PC_EPARSE, "%s: no beauty layer", exr);
}

/* Fetches one image of a job (snapshot k, 0: the final one) to path and measures it. */
static int fetch_point(pc_client *cl, const pc_study_group *g, uint64_t job, uint32_t k, const char *path, bool keep,
                       pc_study_run *run, pc_err *e) {
  uint64_t bytes;
  int rc = pc_client_fetch_snapshot(cl, job, k, path, &bytes, e);
  if (rc) return rc;
  pc_exr_file x = {0};
  rc = pc_exr_read_layers(path, &x, e);
  if (!rc && g->ref) {
    pc_study_snap *s = &run->snaps[run->nsnaps];
    rc = pc_study_measure_exr(&x, path, g->ref, g->workers, s, k == 0 ? run->layer_empty : NULL, e);
    /* the final image replaces a last snapshot of the same film (taken as the budget ran out) */
    if (!rc && k == 0 && run->nsnaps && run->snaps[run->nsnaps - 1].iterations == s->iterations) {
      run->snaps[run->nsnaps - 1] = *s;
      s = &run->snaps[run->nsnaps - 1];
    } else if (!rc && (k == 0 || !g->ref->estimated || s->m[PC_STUDY_BEAUTY].relmse >= 0)) {
      /* an estimate needs 2 iterations: a film of one tells nothing (the final image always counts) */
      run->nsnaps++;
    }
    if (!rc && k == 0) run->stats.rays = (uint64_t)pc_study_exr_number(&x, "pcbpt.rays");
    if (!rc && k == 0) rc = pc_study_tails_exr(&x, &run->tails, e);
    if (!rc && k == 0) pc_study_shares_exr(&x, &run->shares);
    if (!rc && k == 0) pc_study_weights_exr(&x, g->ref, run);
  }
  if (!rc && keep) rc = write_png(&x, path, e);
  pc_exr_file_free(&x);
  if (!keep) unlink(path);
  return rc;
}

static int start_worker(pc_study_farm *f, pc_err *e) {
  if (!f->embedded || f->worker_started) return PC_OK;
  int rc = pc_embedded_start_worker(&f->emb, f->threads, PC_EMBEDDED_UPLOAD_SHARE_LIVE, e);
  f->worker_started = rc == PC_OK;
  return rc;
}

int pc_study_farm_group(pc_study_farm *f, const pc_study_group *g, pc_study_run *runs, pc_err *e) {
  uint64_t jobs[PC_STUDY_MAX_METHODS] = {0}, group;
  uint32_t rerun[PC_STUDY_MAX_METHODS] = {0};
  if (g->nmethods < 1 || g->nmethods > PC_STUDY_MAX_METHODS) return pc_errf(e, PC_EINVAL, "study: bad method count");
  /* the group's jobs run at once, each with its film */
  if (f->embedded && pc_embedded_check_memory(&g->req->set, f->threads, g->nmethods, e) != PC_OK) return e->code;
  pc_client cl;
  int rc = pc_client_connect(f->hostport, f->token, &cl, e); /* (initialises libsodium) */
  if (rc) return rc;
  randombytes_buf(&group, sizeof group);
  group |= 1; /* never 0 (no group) */
  rc = pc_client_send_bundle(&cl, g->blob, g->blob_n, g->hash, e);
  auto_choice ac = {0};
  bool with_auto = false;
  for (int m = 0; m < g->nmethods; m++) with_auto = with_auto || g->methods[m].method == PC_METHOD_AUTO;
  double t0 = now_s();
  if (!rc && with_auto) {
    rc = start_worker(f, e);
    if (!rc) rc = run_pilot(&cl, g, &ac, e);
    if (!rc) dprintf(f->log_fd, "  %s: auto %s\n", g->label, ac.report);
  }
  for (int m = 0; !rc && m < g->nmethods; m++) rc = submit(&cl, g, &g->methods[m], &ac, group, &jobs[m], e);
  if (!rc) rc = start_worker(f, e);
  if (!rc) rc = wait_group(f, &cl, g, jobs, rerun, e);
  double group_wall = now_s() - t0;
  for (int m = 0; !rc && m < g->nmethods; m++) {
    pc_study_run *run = &runs[m];
    memset(run, 0, sizeof *run);
    run->method = g->methods[m];
    run->workers = g->workers;
    run->seed = g->seed;
    run->ranges_rerun = rerun[m];
    run->group_wall = group_wall;
    run->threads = f->embedded ? f->threads : 0;
    if (!(run->snaps = calloc((size_t)g->snapshots + 1, sizeof *run->snaps))) {
      rc = pc_errf(e, PC_ENOMEM, "out of memory for the snapshots");
      break;
    }
    Pcbpt__Envelope *env = NULL;
    rc = pc_client_status(&cl, jobs[m], &env, e);
    uint32_t nsnaps = rc || env->status_reply->n_jobs != 1 ? 0 : env->status_reply->jobs[0]->snapshots;
    if (env) pcbpt__envelope__free_unpacked(env, NULL);
    if (nsnaps > (uint32_t)g->snapshots) nsnaps = (uint32_t)g->snapshots;
    char tmp[4096], keep[4096] = "";
    const char *dir = g->work_dir ? g->work_dir : g->keep_dir ? g->keep_dir : ".";
    snprintf(tmp, sizeof tmp, "%s/.snapshot.%ld.exr", dir, (long)getpid());
    if (g->keep_path) snprintf(keep, sizeof keep, "%s", g->keep_path);
    else if (g->keep_dir) snprintf(keep, sizeof keep, "%s/%s.exr", g->keep_dir, run->method.name);
    for (uint32_t k = 1; !rc && k <= nsnaps; k++) rc = fetch_point(&cl, g, jobs[m], k, tmp, false, run, e);
    if (!rc) rc = fetch_point(&cl, g, jobs[m], 0, keep[0] ? keep : tmp, keep[0] != 0, run, e);
    if (!rc && run->method.method == PC_METHOD_AUTO) {
      /* the pilot's cost counts: every point of auto's curve comes after it */
      for (int k = 0; k < run->nsnaps; k++) {
        run->snaps[k].worker_seconds += ac.pilot_worker_seconds;
        run->snaps[k].seconds += ac.pilot_worker_seconds / g->workers;
      }
      snprintf(run->auto_report, sizeof run->auto_report, "%s", ac.report);
    }
  }
  pc_client_close(&cl);
  return rc;
}
