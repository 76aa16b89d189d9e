/* cmd_client.c: the client verbs of pcbpt-coord: submit, status, list, workers, wait, cancel,
 * fetch. Human-readable output by default, --json for scripts. The coordinator is --host
 * (or $PCBPT_HOST, default 127.0.0.1:7878), the secret --token-file (or $PCBPT_TOKEN_FILE). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bundle.h"
#include "client.h"
#include "text_out.h"
#include "pilot_farm.h"
#include "render.h"
#include "render_flags.h"
#include "cli_scene.h"
#include "scene.h"
#include "verbs.h"
#include "wire_settings.h"

typedef struct common_opts {
  const char *host, *token;
  bool json;
  const char *out;
  const char *name;
  long long priority;
} common_opts;

/* Consumes the flags every client verb shares; returns 1 if argv[*i] was one, <0 on error. */
static int common_flag(common_opts *o, int argc, char **argv, int *i) {
  const char *a = argv[*i];
  const char **dst = strcmp(a, "--host") == 0 ? &o->host : strcmp(a, "--token-file") == 0 ? &o->token
                   : strcmp(a, "--out") == 0 ? &o->out : strcmp(a, "--name") == 0 ? &o->name : NULL;
  if (strcmp(a, "--json") == 0) { o->json = true; return 1; }
  if (strcmp(a, "--priority") == 0) {
    if (*i + 1 >= argc || !pc_parse_i64(argv[*i + 1], -1000, 1000, &o->priority)) return -1;
    (*i)++;
    return 1;
  }
  if (!dst) return 0;
  if (*i + 1 >= argc) return -1;
  *dst = argv[++*i];
  return 1;
}

static void opts_default(common_opts *o) {
  memset(o, 0, sizeof *o);
  o->host = getenv("PCBPT_HOST") ? getenv("PCBPT_HOST") : "127.0.0.1:7878";
  o->token = getenv("PCBPT_TOKEN_FILE");
}

static int connect_or_say(const char *verb, const common_opts *o, pc_client *cl) {
  pc_err e = {0};
  if (!o->token) { fprintf(stderr, "pcbpt-coord %s: --token-file (or PCBPT_TOKEN_FILE) is required\n", verb); return 2; }
  if (pc_client_connect(o->host, o->token, cl, &e) != 0) { fprintf(stderr, "pcbpt-coord %s: %s\n", verb, e.msg); return 1; }
  return 0;
}

static int parse_job_id(const char *s, uint64_t *id) { return pc_parse_u64(s, 1, UINT64_MAX, id) ? 0 : -1; }

int pc_cmd_submit(int argc, char **argv) {
  common_opts o;
  opts_default(&o);
  pc_render_request req;
  pc_render_request_default(&req);
  const char *scene_path = NULL;
  pc_err e = {0};
  for (int i = 0; i < argc; i++) {
    int r = pc_render_flag_parse(&req, argc, argv, &i, &e);
    if (r < 0) { fprintf(stderr, "pcbpt-coord submit: %s\n", e.msg); return 2; }
    if (r > 0) continue;
    if ((r = common_flag(&o, argc, argv, &i)) < 0) { fprintf(stderr, "pcbpt-coord submit: %s: bad value\n", argv[i]); return 2; }
    if (r > 0) continue;
    if (strcmp(argv[i], "--help") == 0) {
      printf("usage: pcbpt-coord submit SCENE.xml [render flags] --host H:P --token-file F [--name N] [--priority P] [--json]\n%s",
             pc_render_flags_help);
      return 0;
    }
    if (argv[i][0] == '-' || scene_path) { fprintf(stderr, "pcbpt-coord submit: unexpected argument '%s'\n", argv[i]); return 2; }
    scene_path = argv[i];
  }
  if (!scene_path) { fprintf(stderr, "pcbpt-coord submit: missing SCENE.xml\n"); return 2; }
  /* the scene supplies what the flags left open, so every worker gets complete settings */
  pc_scene scene = {0};
  if (pc_cli_load_scene("submit", &req, scene_path, &scene, &e) != 0) { fprintf(stderr, "pcbpt-coord submit: %s\n", e.msg); return 1; }
  pc_cli_warn_method("submit", scene_path, req.set.method, &req);
  if (pc_render_settings_check(&req.set, &e) != 0) {
    pc_scene_free(&scene);
    fprintf(stderr, "pcbpt-coord submit: %s\n", e.msg);
    return 2;
  }
  /* what the workers would refuse (no emitter, a light of zero area, a method not built in) is
     one line here, not a job that fails on every worker */
  if (pc_scene_check(&scene, &e) != 0 || pc_renderer_check(&scene, &req.set, &e) != 0) {
    pc_scene_free(&scene);
    fprintf(stderr, "pcbpt-coord submit: %s\n", e.msg);
    return 1;
  }
  pc_cli_warn_backs("submit", &scene);
  uint8_t *blob, hash[PC_BUNDLE_HASH];
  size_t n;
  int brc = pc_cli_scene_bundle(&scene, &blob, &n, hash, &e);
  pc_scene_free(&scene);
  if (brc != 0) { fprintf(stderr, "pcbpt-coord submit: %s\n", e.msg); return 1; }
  pc_client cl;
  int rc = connect_or_say("submit", &o, &cl);
  if (rc) { free(blob); return rc; }
  rc = pc_client_send_bundle(&cl, blob, n, hash, &e);
  free(blob);
  const char *base = strrchr(scene_path, '/');
  pc_pilot_farm fp = {.cl = &cl, .hash = hash, .name = o.name ? o.name : base ? base + 1 : scene_path, .priority = (int)o.priority};
  char report[1024] = "";
  double prior_amount = 0;
  if (!rc && req.method_auto) {
    /* the pilot's candidates are short jobs of their own on the farm, so every worker renders
     * them; the client waits for them and takes each one's cost from their render threads' CPU seconds */
    double pilot_s;
    rc = pc_pilot_farm_choose(&fp, &req, report, sizeof report, &pilot_s, &prior_amount, &e);
    if (!rc) fprintf(stderr, "pcbpt-coord submit: auto: %s\n", report);
  }
  uint64_t job = 0;
  if (!rc) rc = pc_client_submit_request(&cl, fp.name, hash, &req, report, fp.pilot_group, prior_amount, fp.priority, &job, &e);
  pc_client_close(&cl);
  if (rc) {
    fprintf(stderr, "pcbpt-coord submit: %s\n", e.msg);
    return 1;
  }
  if (o.json) printf("{\"job\": %llu}\n", (unsigned long long)job);
  else printf("%llu\n", (unsigned long long)job);
  return 0;
}

static void print_job(const Pcbpt__JobStatus *j, bool json) {
  if (json) {
    printf("{\"job\": %llu, \"name\": ", (unsigned long long)j->job_id);
    pc_json_string(stdout, j->name);
    printf(", \"state\": \"%s\", \"method\": \"%s\", \"iterations\": %llu, \"halt_iterations\": %llu, "
           "\"halt_seconds\": %.3f, \"elapsed\": %.3f, \"iterations_per_second\": %.3f, \"eta_seconds\": %.3f, "
           "\"workers\": %u, \"error\": ",
           j->state, j->method, (unsigned long long)j->iterations_done, (unsigned long long)j->halt_iterations,
           j->halt_seconds, j->elapsed, j->iterations_per_second, j->eta_seconds, j->workers);
    pc_json_string(stdout, j->error);
    printf(", \"image\": ");
    pc_json_string(stdout, j->image);
    /* null while the image cannot tell its error (fewer than 2 iterations ...) */
    if (j->relmse_estimate >= 0) printf(", \"relmse_estimate\": %.6g", j->relmse_estimate);
    else printf(", \"relmse_estimate\": null");
    printf(", \"iterations_rendered\": %llu, \"halt_noise\": %.6g, \"worker_seconds\": %.6g, \"cpu_seconds\": %.6g, "
           "\"snapshots\": %u, \"ranges_rerun\": %u, \"auto\": ",
           (unsigned long long)j->iterations_rendered, j->halt_noise, j->worker_seconds, j->cpu_seconds, j->snapshots,
           j->ranges_rerun);
    if (*j->auto_report) pc_json_string(stdout, j->auto_report);
    else printf("null");
    printf("}");
    return;
  }
  char est[32] = "-";
  if (j->relmse_estimate >= 0) snprintf(est, sizeof est, "%.4g", j->relmse_estimate);
  printf("%-6llu %-10s %-6s %8llu/%-8llu %6.1fs %8.2f it/s  eta %6.1fs  relMSE~%-9s %u workers  %s%s%s\n",
         (unsigned long long)j->job_id, j->state, j->method, (unsigned long long)j->iterations_done,
         (unsigned long long)j->halt_iterations, j->elapsed, j->iterations_per_second, j->eta_seconds, est, j->workers, j->name,
         *j->error ? "  error: " : "", j->error);
  if (*j->auto_report) printf("       auto: %s\n", j->auto_report);
}

static int status_like(const char *verb, int argc, char **argv, bool workers) {
  common_opts o;
  opts_default(&o);
  uint64_t job = 0;
  for (int i = 0; i < argc; i++) {
    int r = common_flag(&o, argc, argv, &i);
    if (r < 0) { fprintf(stderr, "pcbpt-coord %s: %s: bad value\n", verb, argv[i]); return 2; }
    if (r > 0) continue;
    if (workers || parse_job_id(argv[i], &job) != 0) { fprintf(stderr, "pcbpt-coord %s: unexpected argument '%s'\n", verb, argv[i]); return 2; }
  }
  pc_client cl;
  int rc = connect_or_say(verb, &o, &cl);
  if (rc) return rc;
  pc_err e;
  Pcbpt__Envelope *in = NULL;
  rc = pc_client_status(&cl, job, &in, &e);
  pc_client_close(&cl);
  if (rc) { fprintf(stderr, "pcbpt-coord %s: %s\n", verb, e.msg); return 1; }
  Pcbpt__StatusReply *s = in->status_reply;
  if (job && s->n_jobs == 0) {
    fprintf(stderr, "pcbpt-coord %s: no job %llu\n", verb, (unsigned long long)job);
    pcbpt__envelope__free_unpacked(in, NULL);
    return 1;
  }
  if (workers) {
    if (o.json) printf("[");
    for (size_t i = 0; i < s->n_workers; i++) {
      Pcbpt__WorkerStatus *w = s->workers[i];
      if (o.json) {
        printf("%s{\"name\": ", i ? ", " : "");
        pc_json_string(stdout, w->name);
        printf(", \"address\": \"%s\", \"threads\": %u, \"iterations_per_second\": %.3f, \"job\": %llu, \"range\": %llu}",
               w->address, w->threads, w->iterations_per_second, (unsigned long long)w->job_id, (unsigned long long)w->range_id);
      } else {
        printf("%-20s %-22s %3u threads %8.2f it/s  job %llu range %llu\n", w->name, w->address, w->threads,
               w->iterations_per_second, (unsigned long long)w->job_id, (unsigned long long)w->range_id);
      }
    }
    if (o.json) printf("]\n");
  } else {
    if (o.json && !job) printf("[");
    for (size_t i = 0; i < s->n_jobs; i++) {
      if (o.json && i) printf(", ");
      print_job(s->jobs[i], o.json);
    }
    if (o.json) printf(job ? "\n" : "]\n");
  }
  pcbpt__envelope__free_unpacked(in, NULL);
  return 0;
}

int pc_cmd_status(int argc, char **argv) { return status_like("status", argc, argv, false); }
int pc_cmd_list(int argc, char **argv) { return status_like("list", argc, argv, false); }
int pc_cmd_workers(int argc, char **argv) { return status_like("workers", argc, argv, true); }

static int one_job_args(const char *verb, int argc, char **argv, common_opts *o, uint64_t *job) {
  opts_default(o);
  *job = 0;
  for (int i = 0; i < argc; i++) {
    int r = common_flag(o, argc, argv, &i);
    if (r < 0) { fprintf(stderr, "pcbpt-coord %s: %s: bad value\n", verb, argv[i]); return 2; }
    if (r > 0) continue;
    if (*job || parse_job_id(argv[i], job) != 0) { fprintf(stderr, "pcbpt-coord %s: unexpected argument '%s'\n", verb, argv[i]); return 2; }
  }
  if (!*job) { fprintf(stderr, "pcbpt-coord %s: missing JOB id\n", verb); return 2; }
  return 0;
}

int pc_cmd_wait(int argc, char **argv) {
  common_opts o;
  uint64_t job;
  int rc = one_job_args("wait", argc, argv, &o, &job);
  if (rc) return rc;
  pc_client cl;
  if ((rc = connect_or_say("wait", &o, &cl)) != 0) return rc;
  bool tty = isatty(2);
  for (;;) {
    pc_err e;
    Pcbpt__Envelope *in = NULL;
    if (pc_client_status(&cl, job, &in, &e) != 0) { fprintf(stderr, "pcbpt-coord wait: %s\n", e.msg); pc_client_close(&cl); return 1; }
    if (in->status_reply->n_jobs != 1) {
      fprintf(stderr, "pcbpt-coord wait: no job %llu\n", (unsigned long long)job);
      pcbpt__envelope__free_unpacked(in, NULL);
      pc_client_close(&cl);
      return 1;
    }
    Pcbpt__JobStatus *j = in->status_reply->jobs[0];
    const char *st = j->state;
    if (strcmp(st, "done") == 0 || strcmp(st, "failed") == 0 || strcmp(st, "cancelled") == 0) {
      if (tty) fprintf(stderr, "\n");
      print_job(j, o.json);
      if (o.json) printf("\n");
      rc = strcmp(st, "done") == 0 ? 0 : 1;
      pcbpt__envelope__free_unpacked(in, NULL);
      pc_client_close(&cl);
      return rc;
    }
    fprintf(stderr, "%sjob %llu %s: %llu iterations, %.1f it/s, %u workers, eta %.0f s%s", tty ? "\r" : "",
            (unsigned long long)job, st, (unsigned long long)j->iterations_done, j->iterations_per_second, j->workers,
            j->eta_seconds, tty ? "   " : "\n");
    pcbpt__envelope__free_unpacked(in, NULL);
    struct timespec ts = {0, 500000000};
    nanosleep(&ts, NULL);
  }
}

int pc_cmd_cancel(int argc, char **argv) {
  common_opts o;
  uint64_t job;
  int rc = one_job_args("cancel", argc, argv, &o, &job);
  if (rc) return rc;
  pc_client cl;
  if ((rc = connect_or_say("cancel", &o, &cl)) != 0) return rc;
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT, *in = NULL;
  Pcbpt__CancelRequest cr = PCBPT__CANCEL_REQUEST__INIT;
  cr.job_id = job;
  env.msg_case = PCBPT__ENVELOPE__MSG_CANCEL_REQUEST;
  env.cancel_request = &cr;
  pc_err e;
  rc = pc_client_send(&cl, &env, &e);
  if (!rc) rc = pc_client_recv(&cl, 30, &in, &e);
  pc_client_close(&cl);
  if (rc) { fprintf(stderr, "pcbpt-coord cancel: %s\n", e.msg); return 1; }
  if (in->msg_case == PCBPT__ENVELOPE__MSG_STATUS_REPLY && in->status_reply->n_jobs == 1) print_job(in->status_reply->jobs[0], o.json);
  if (o.json) printf("\n");
  pcbpt__envelope__free_unpacked(in, NULL);
  return 0;
}

int pc_cmd_fetch(int argc, char **argv) {
  common_opts o;
  uint64_t job;
  /* --partial: a job that is not done has at most a periodic, partial image;
   * --snapshot K: a study job's K-th kept snapshot (docs/farm-study.md) */
  bool partial = false;
  long long snapshot = 0;
  char *rest[64];
  int nrest = 0;
  for (int i = 0; i < argc && nrest < 64; i++)
    if (strcmp(argv[i], "--partial") == 0) partial = true;
    else if (strcmp(argv[i], "--snapshot") == 0) {
      if (i + 1 >= argc || !pc_parse_i64(argv[i + 1], 1, 1000000, &snapshot)) {
        fprintf(stderr, "pcbpt-coord fetch: --snapshot: expected a snapshot number >= 1\n");
        return 2;
      }
      i++;
    } else rest[nrest++] = argv[i];
  int rc = one_job_args("fetch", nrest, rest, &o, &job);
  if (rc) return rc;
  if (!o.out) { fprintf(stderr, "pcbpt-coord fetch: --out F.exr is required\n"); return 2; }
  pc_client cl;
  if ((rc = connect_or_say("fetch", &o, &cl)) != 0) return rc;
  pc_err e = {0};
  Pcbpt__Envelope *in = NULL;
  if (pc_client_status(&cl, job, &in, &e) != 0) { fprintf(stderr, "pcbpt-coord fetch: %s\n", e.msg); pc_client_close(&cl); return 1; }
  if (in->status_reply->n_jobs != 1) {
    fprintf(stderr, "pcbpt-coord fetch: no job %llu\n", (unsigned long long)job);
    rc = 1;
  } else if (snapshot > in->status_reply->jobs[0]->snapshots) {
    fprintf(stderr, "pcbpt-coord fetch: job %llu has %u snapshots\n", (unsigned long long)job, in->status_reply->jobs[0]->snapshots);
    rc = 1;
  } else if (!snapshot && strcmp(in->status_reply->jobs[0]->state, "done") != 0 && !partial) {
    const Pcbpt__JobStatus *st = in->status_reply->jobs[0];
    fprintf(stderr, "pcbpt-coord fetch: job %llu is %s (%llu iterations): %s\n", (unsigned long long)job, st->state,
            (unsigned long long)st->iterations_done,
            *st->image ? "its image is partial; pass --partial to fetch it anyway" : "it has no image");
    rc = 1;
  }
  pcbpt__envelope__free_unpacked(in, NULL);
  uint64_t got = 0;
  if (!rc && (rc = pc_client_fetch_snapshot(&cl, job, (uint32_t)snapshot, o.out, &got, &e)) != 0)
    fprintf(stderr, "pcbpt-coord fetch: %s\n", e.msg);
  pc_client_close(&cl);
  if (rc) return 1;
  if (o.json) printf("{\"job\": %llu, \"out\": \"%s\", \"bytes\": %llu}\n", (unsigned long long)job, o.out, (unsigned long long)got);
  else printf("%s\n", o.out);
  return 0;
}
