/* cmd_render.c: `pcbpt-coord render`: renders a scene on this machine until an iteration count
 * or a time budget is reached, then writes the EXR (beauty + per-strategy layers + counts) and
 * an sRGB PNG preview, and prints one summary line. The render runs on an embedded farm
 * (embedded.c): the scene is submitted as a job over the real protocol to a loopback
 * coordinator with one local worker, and the merged image is fetched back. */
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bundle.h"
#include "client.h"
#include "embedded.h"
#include "image.h"
#include "pilot_farm.h"
#include "render.h"
#include "thread_pool.h"
#include "wire_settings.h"
#include "render_flags.h"
#include "cli_scene.h"
#include "scene.h"
#include "verbs.h"

static const char render_help[] =
    "usage: pcbpt-coord render SCENE.xml [flags]\n"
    "Renders SCENE on this machine and writes an EXR plus a PNG preview.\n\n"
    "%s"
    "  --threads N           render threads (default 0 = every core)\n"
    "  --out FILE.exr        output image (default: <scene folder name>.exr); the preview is FILE.png\n"
    "  --exposure E          preview exposure in stops (default 0)\n"
    "  --quiet               no progress bar\n"
    "Without --spp, --time or --halt-noise, renders 64 iterations.\n";

/* SIGINT/SIGTERM so far: the first stops the render and writes what it has, the second
 * abandons that and ends without an image, and any after it kill the process (the handler
 * gives the signals back their default action). Asynchronous-signal state must be global;
 * this counter is the only such state. */
static atomic_int g_interrupts;

static void on_sigint(int sig) {
  (void)sig;
  if (atomic_fetch_add(&g_interrupts, 1) >= 1) {
    struct sigaction dfl = {0};
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    sigaction(SIGINT, &dfl, NULL);
    sigaction(SIGTERM, &dfl, NULL);
  }
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static char *default_out(const char *scene_path) {
  char *copy = strdup(scene_path);
  if (!copy) return NULL;
  char *slash = strrchr(copy, '/');
  const char *stem;
  if (slash) {
    *slash = '\0';
    char *prev = strrchr(copy, '/');
    stem = prev ? prev + 1 : copy;
  } else {
    char *dot = strrchr(copy, '.');
    if (dot) *dot = '\0';
    stem = copy;
  }
  if (!*stem || strcmp(stem, ".") == 0 || strcmp(stem, "..") == 0) stem = "render";
  size_t n = strlen(stem) + 5;
  char *out = malloc(n);
  if (out) snprintf(out, n, "%s.exr", stem);
  free(copy);
  return out;
}

static char *preview_path(const char *exr) {
  size_t n = strlen(exr);
  char *p = malloc(n + 5);
  if (!p) return NULL;
  memcpy(p, exr, n + 1);
  if (n >= 4 && strcasecmp(p + n - 4, ".exr") == 0) p[n - 4] = '\0';
  strcat(p, ".png");
  return p;
}

typedef struct progress_state {
  bool show;
  uint64_t target;  /* 0 when time-bound */
  double seconds, t0;
  uint64_t done_before;
} progress_state;

/* relmse: the merged image's estimated relMSE (< 0: not known yet). */
static void draw_progress(progress_state *p, int fd, uint64_t done, double relmse) {
  if (!p->show) return;
  double el = now_s() - p->t0;
  double frac = p->target ? (double)done / (double)p->target : (p->seconds > 0 ? el / p->seconds : 0);
  if (frac > 1) frac = 1;
  int bar = (int)(frac * 30);
  dprintf(fd, "\r[%.*s%*s] %3d%%  %llu it  %.1fs ", bar, "==============================", 30 - bar, "",
          (int)(frac * 100), (unsigned long long)done, el);
  if (relmse >= 0) dprintf(fd, " relMSE~%.3g ", relmse);
}

static void sleep_s(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  nanosleep(&ts, NULL);
}

/* Status of one job; *st is owned by *env. */
static int job_status(pc_client *cl, uint64_t job, Pcbpt__Envelope **env, Pcbpt__JobStatus **st, pc_err *e) {
  int rc = pc_client_status(cl, job, env, e);
  if (rc) return rc;
  if ((*env)->status_reply->n_jobs != 1) {
    pcbpt__envelope__free_unpacked(*env, NULL);
    *env = NULL;
    return pc_errf(e, PC_EPARSE, "embedded farm: unexpected status reply");
  }
  *st = (*env)->status_reply->jobs[0];
  return 0;
}

/* Asks the coordinator to finish the job with what is rendered (Ctrl-C). */
static int halt_job(pc_client *cl, uint64_t job, pc_err *e) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT, *in = NULL;
  Pcbpt__CancelRequest cr = PCBPT__CANCEL_REQUEST__INIT;
  cr.job_id = job;
  cr.finish = true;
  env.msg_case = PCBPT__ENVELOPE__MSG_CANCEL_REQUEST;
  env.cancel_request = &cr;
  int rc = pc_client_send(cl, &env, e);
  if (!rc) rc = pc_client_recv(cl, 30, &in, e);
  if (in) pcbpt__envelope__free_unpacked(in, NULL);
  return rc;
}

/* Runs --method auto's pilot on the embedded farm (its candidates are jobs there, like a
 * farm's: pilot_farm.h), submits the job, shows progress until it ends and fetches the image
 * to `out`. *secs is the wall time from submission to the end of the job, *pilot_s the
 * pilot's. */
static int run_job(pc_embedded *farm, int threads, const char *scene_path, const uint8_t *blob, size_t blob_n,
                   const uint8_t *hash, pc_render_request *req, const char *out, progress_state *prog, double *secs,
                   double *pilot_s, pc_err *e) {
  pc_client cl;
  int rc = pc_client_connect(farm->hostport, farm->token, &cl, e);
  if (rc) return rc;
  uint64_t job = 0;
  bool halted = false;
  char auto_report[1024] = "";
  pc_pilot_farm fp = {.cl = &cl, .hash = hash, .name = scene_path};
  double prior_amount = 0;
  rc = pc_client_send_bundle(&cl, blob, blob_n, hash, e);
  double share = req->halt_noise > 0 ? PC_EMBEDDED_UPLOAD_SHARE_LIVE : PC_EMBEDDED_UPLOAD_SHARE_SPARSE;
  if (!rc) rc = pc_embedded_start_worker(farm, threads, share, e);
  if (!rc && req->method_auto && (rc = pc_pilot_farm_choose(&fp, req, auto_report, sizeof auto_report, pilot_s, &prior_amount, e)) == 0) {
    printf("auto: %s\n", auto_report);
    fflush(stdout);
    prog->seconds = req->seconds;
  }
  double t0 = now_s();
  prog->t0 = t0;
  if (!rc) rc = pc_client_submit_request(&cl, scene_path, hash, req, auto_report, fp.pilot_group, prior_amount, 0, &job, e);
  while (!rc) {
    Pcbpt__Envelope *env = NULL;
    Pcbpt__JobStatus *st = NULL;
    if (atomic_load(&g_interrupts) >= 2) {
      rc = pc_errf(e, PC_ECANCELED, "interrupted twice: aborted, no image written");
      break;
    }
    if ((rc = job_status(&cl, job, &env, &st, e)) != 0) break;
    bool done = strcmp(st->state, "done") == 0;
    if (done || strcmp(st->state, "failed") == 0 || strcmp(st->state, "cancelled") == 0) {
      *secs = now_s() - t0;
      if (!done) rc = pc_errf(e, PC_EIO, "%s", *st->error ? st->error : "the render was cancelled");
      else if (st->iterations_done == 0) rc = pc_errf(e, PC_ECANCELED, "no iteration finished; nothing written");
      pcbpt__envelope__free_unpacked(env, NULL);
      break;
    }
    draw_progress(prog, farm->term_fd, st->iterations_rendered > st->iterations_done ? st->iterations_rendered : st->iterations_done,
                  st->relmse_estimate);
    pcbpt__envelope__free_unpacked(env, NULL);
    if (atomic_load(&g_interrupts) && !halted) {
      halted = true;
      if (prog->show) dprintf(farm->term_fd, "\ninterrupted: finishing with what is rendered (Ctrl-C again to abort)\n");
      if ((rc = halt_job(&cl, job, e)) != 0) break;
      continue;
    }
    sleep_s(0.02);
  }
  uint64_t bytes;
  if (!rc) rc = pc_client_fetch(&cl, job, out, &bytes, e);
  pc_client_close(&cl);
  return rc;
}

/* A numeric header attribute of an image written by the farm (0 when absent). */
static double attr_number(const pc_exr_file *x, const char *name) {
  for (int i = 0; i < x->nattrs; i++)
    if (strcmp(x->attr_names[i], name) == 0) return strtod(x->attr_values[i], NULL);
  return 0;
}

static bool has_attr(const pc_exr_file *x, const char *name) {
  for (int i = 0; i < x->nattrs; i++)
    if (strcmp(x->attr_names[i], name) == 0) return true;
  return false;
}

int pc_cmd_render(int argc, char **argv) {
  pc_render_request req;
  pc_render_request_default(&req);
  const char *scene_path = NULL, *out = NULL;
  long long threads = 0;
  double exposure = 0;
  bool quiet = false;
  pc_err err = {0};
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    int r = pc_render_flag_parse(&req, argc, argv, &i, &err);
    if (r < 0) {
      fprintf(stderr, "pcbpt-coord render: %s\n", err.msg);
      return 2;
    }
    if (r > 0) continue;
    if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
      printf(render_help, pc_render_flags_help);
      return 0;
    } else if (strcmp(a, "--threads") == 0) {
      if (i + 1 >= argc || !pc_parse_i64(argv[i + 1], 0, 1024, &threads)) {
        fprintf(stderr, "pcbpt-coord render: --threads: expected 0..1024\n");
        return 2;
      }
      i++;
    } else if (strcmp(a, "--out") == 0) {
      if (i + 1 >= argc || !*argv[i + 1]) {
        fprintf(stderr, "pcbpt-coord render: --out: missing file name\n");
        return 2;
      }
      out = argv[++i];
    } else if (strcmp(a, "--exposure") == 0) {
      if (i + 1 >= argc || !pc_parse_f64(argv[i + 1], -64, 64, &exposure)) {
        fprintf(stderr, "pcbpt-coord render: --exposure: expected a number of stops in -64..64\n");
        return 2;
      }
      i++;
    } else if (strcmp(a, "--quiet") == 0) {
      quiet = true;
    } else if (a[0] == '-') {
      fprintf(stderr, "pcbpt-coord render: unknown flag '%s' (see --help)\n", a);
      return 2;
    } else if (!scene_path) {
      scene_path = a;
    } else {
      fprintf(stderr, "pcbpt-coord render: unexpected argument '%s' (one scene only)\n", a);
      return 2;
    }
  }
  if (!scene_path) {
    fprintf(stderr, "pcbpt-coord render: missing SCENE.xml (see --help)\n");
    return 2;
  }
  int status = 1;
  pc_scene scene = {0};
  pc_exr_file img = {0};
  uint8_t *blob = NULL, hash[PC_BUNDLE_HASH];
  size_t blob_n = 0;
  pc_embedded farm;
  bool farm_up = false;
  char *out_owned = NULL, *png = NULL;
  /* the scene is checked here so a bad one is one clear line, before any farm starts */
  if (pc_cli_load_scene("render", &req, scene_path, &scene, &err) != PC_OK) goto fail;
  pc_cli_warn_method("render", scene_path, req.set.method, &req);
  if (pc_cli_scene_bundle(&scene, &blob, &blob_n, hash, &err) != PC_OK) goto fail;
  if (pc_render_settings_check(&req.set, &err) != PC_OK) goto fail;
  if (pc_scene_check(&scene, &err) != PC_OK) goto fail;
  /* settings the renderer refuses (e.g. a method not built in) are refused here too */
  if (pc_renderer_check(&scene, &req.set, &err) != PC_OK) goto fail;
  if (pc_embedded_check_memory(&req.set, (int)threads, 1, &err) != PC_OK) goto fail;
  pc_cli_warn_backs("render", &scene);
  double pilot_s = 0;
  pc_scene_free(&scene);
  memset(&scene, 0, sizeof scene);
  if (!out) out = out_owned = default_out(scene_path);
  png = out ? preview_path(out) : NULL;
  if (!out || !png) {
    pc_errf(&err, PC_ENOMEM, "out of memory");
    goto fail;
  }

  struct sigaction sa = {0};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  /* SIGTERM too: the render finishes with what it has and removes its temporary farm */
  if (sigaction(SIGINT, &sa, NULL) != 0 || sigaction(SIGTERM, &sa, NULL) != 0) perror("pcbpt-coord render: sigaction");

  progress_state prog = {.show = !quiet && isatty(STDERR_FILENO), .target = req.spp, .seconds = req.seconds, .t0 = now_s()};
  if (pc_embedded_start(&farm, &err) != PC_OK) goto fail;
  farm_up = true;
  double secs = 0;
  int rc = run_job(&farm, (int)threads, scene_path, blob, blob_n, hash, &req, out, &prog, &secs, &pilot_s, &err);

  pc_embedded_stop(&farm);
  farm_up = false;
  if (prog.show) fputc('\n', stderr);
  if (rc != PC_OK) goto fail;

  if (pc_exr_read_beauty_attrs(out, &img, &err) != PC_OK) goto fail;
  int beauty = -1;
  for (int i = 0; i < img.nlayers; i++)
    if (img.names[i][0] == '\0') beauty = i;
  if (beauty < 0) {
    pc_errf(&err, PC_EPARSE, "%s: the farm's image has no beauty layer", out);
    goto fail;
  }
  if (pc_png_write_preview(png, img.w, img.h, img.layers[beauty].rgb, (float)exposure, &err) != PC_OK) goto fail;
  double it = attr_number(&img, "pcbpt.iterations"), rays = attr_number(&img, "pcbpt.rays");
  double dropped = attr_number(&img, "pcbpt.dropped_nonfinite");
  double samples = it * img.w * img.h;
  char est[48] = "";
  if (has_attr(&img, "pcbpt.relmse_estimate"))
    snprintf(est, sizeof est, ", est. relMSE %.4g", attr_number(&img, "pcbpt.relmse_estimate"));
  char pilot_note[48] = "";
  if (req.method_auto) snprintf(pilot_note, sizeof pilot_note, " (+ %.2f s pilot)", pilot_s);
  printf("%s: %.0f iterations, %.2f s%s, %.0f samples/s, %.2f Mrays/s, %d threads%s%s -> %s, %s\n",
         pc_method_name(req.set.method), it, secs, pilot_note, samples / secs, rays / secs * 1e-6,
         threads ? (int)threads : pc_cpu_count(), est, dropped > 0 ? " (non-finite samples dropped)" : "", out, png);
  if (it > 0) {
    printf("per iteration (ms): path generation %.1f, light tracing %.1f, PMF build %.1f, sample+connect %.1f",
           1e3 * attr_number(&img, "pcbpt.time_paths") / it, 1e3 * attr_number(&img, "pcbpt.time_lt") / it,
           1e3 * attr_number(&img, "pcbpt.time_pmf") / it, 1e3 * attr_number(&img, "pcbpt.time_connect") / it);
    /* the render threads' CPU time against their wall time: below ~95% they waited for one
       another (a serial phase, or a thread that lost its core to other work) */
    double cpu = attr_number(&img, "pcbpt.cpu_seconds"), wall = attr_number(&img, "pcbpt.worker_seconds");
    int nthreads = threads ? (int)threads : pc_cpu_count();
    if (cpu > 0 && wall > 0)
      printf("; CPU %.1f, render threads busy %.0f%%", 1e3 * cpu / it, 100 * cpu / (wall * nthreads));
    putchar('\n');
  }
  if (has_attr(&img, "pcbpt.iteration_error.n"))
    printf("error of single iterations (%.0f of them, %dx%d blocks): median %.3g, mean %.3g, worst %.3g (iteration %.0f); "
           "the worst 1%% carry %.1f%% of it\n",
           attr_number(&img, "pcbpt.iteration_error.n"), img.w < PC_TRACE_GRID ? img.w : PC_TRACE_GRID,
           img.h < PC_TRACE_GRID ? img.h : PC_TRACE_GRID,
           attr_number(&img, "pcbpt.iteration_error.p50"), attr_number(&img, "pcbpt.iteration_error.mean"),
           attr_number(&img, "pcbpt.iteration_error.max"), attr_number(&img, "pcbpt.iteration_error.worst"),
           100 * attr_number(&img, "pcbpt.iteration_error.top1"));
  double pmf_bytes = attr_number(&img, "pcbpt.pmf_bytes");
  if (pmf_bytes > 0) printf("importance records: %.2f MiB\n", pmf_bytes / (1024.0 * 1024.0));
  if (dropped > 0) fprintf(stderr, "pcbpt-coord render: warning: %.0f non-finite samples were dropped\n", dropped);
  status = 0;
  goto done;
fail:
  if (farm_up) pc_embedded_stop(&farm);
  fprintf(stderr, "pcbpt-coord render: %s\n", err.msg[0] ? err.msg : pc_strerror(err.code));
done:
  pc_exr_file_free(&img);
  pc_scene_free(&scene);
  free(blob);
  free(out_owned);
  free(png);
  return status;
}
