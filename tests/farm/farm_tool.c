/* farm_tool.c: helpers of the farm tests (not installed).
 *   farm_tool exact CKPT SCENE [render flags]   the job's merged sums (its last checkpoint)
 *       equal a single-process render of iterations [0, --spp) up to summation order:
 *       identical counts, relative 1e-9 on per-layer totals and on every pixel value
 *       (beauty_sq included, so the estimated relMSE agrees too: printed, relative 1e-6);
 *       beauty_max, merged by max, and the trace of each iteration below the trace's bound,
 *       bit for bit
 *   farm_tool mean CKPT EXPECT TOL              |mean(beauty) - EXPECT| <= TOL * EXPECT
 *   farm_tool relmse CKPT W H EXACT             prints the film's estimated relMSE and the one
 *       measured against the constant image EXACT (compare's definition)
 *   farm_tool upload HOST:PORT TOKEN nan|size|huge|wrap|trace   speaks as a worker: takes a
 *       range and uploads a delta with a NaN sum, of the wrong size, with a finite sum no
 *       radiance reaches (1.7e308), of 2^64-1 iterations (first + count wraps), or whose trace
 *       holds an iteration of another range; exits 0 if the coordinator refuses it
 *   farm_tool bundle HOST:PORT TOKEN            sends a scene bundle whose content does not
 *       match its hash; exits 0 if the coordinator refuses it and will not run a job on it
 *   farm_tool fail HOST:PORT TOKEN              speaks as a worker: takes a range and reports
 *       that it cannot render it
 *   farm_tool cancelack HOST:PORT TOKEN         an upload merged, the job cancelled before its
 *       checkpoint: exits 0 if the upload is still answered
 *   farm_tool hoard HOST:PORT TOKEN JOB SECONDS claims 1e8 iterations/s, takes a range and
 *       only sends heartbeats; exits 0 if the range is taken back and a late upload refused
 *   farm_tool badbundle HOST:PORT TOKEN KIND    submits a job on a bundle workers must refuse
 *       (dotdot, absolute, noscene, dup, clash, notproto); prints the job id */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bundle.h"
#include "client.h"
#include "image.h"
#include "render.h"
#include "render_flags.h"
#include "scene.h"
#include "wire_film.h"
#include "wire_settings.h"

static int load_ckpt(const char *path, pc_film *f, int w, int h, int depth, pc_err *e) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return pc_errf(e, PC_EIO, "%s: cannot open", path);
  uint8_t *z = NULL;
  long n = -1;
  int rc = PC_EIO;
  if (fseek(fp, 0, SEEK_END) == 0) n = ftell(fp);
  if (n > 0 && fseek(fp, 0, SEEK_SET) == 0 && (z = malloc((size_t)n)) && fread(z, 1, (size_t)n, fp) == (size_t)n) {
    rc = pc_film_init(f, w, h, depth, e);
    if (!rc) rc = pc_wire_film_load(z, (size_t)n, f, e);
  } else {
    pc_errf(e, PC_EIO, "%s: cannot read", path);
  }
  fclose(fp);
  free(z);
  return rc;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double rel(double a, double b) {
  double m = fmax(fabs(a), fabs(b));
  return m > 0 ? fabs(a - b) / m : 0;
}

static int cmd_exact(int argc, char **argv) {
  pc_render_request req;
  pc_render_request_default(&req);
  pc_err e = {0};
  for (int i = 2; i < argc; i++)
    if (pc_render_flag_parse(&req, argc, argv, &i, &e) <= 0) { fprintf(stderr, "exact: bad flag %s %s\n", argv[i], e.msg); return 2; }
  if (!req.spp) { fprintf(stderr, "exact: --spp is required\n"); return 2; }
  pc_scene scene = {0};
  pc_renderer *r = NULL;
  pc_film mine = {0}, farm = {0};
  pc_render_stats st = {0};
  pc_scene_load_opts lo;
  pc_render_request_load_opts(&req, &lo);
  int rc = pc_scene_load_with(argv[1], &lo, &scene, &e);
  if (!rc) {
    pc_render_request_apply_scene(&req, &scene);
    rc = pc_scene_build(&scene, &e);
  }
  if (!rc) rc = pc_renderer_create(&scene, &req.set, 1, &r, &e);
  if (!rc) rc = pc_film_init(&mine, req.set.width, req.set.height, req.set.strategy_layers, &e);
  if (!rc) rc = pc_render_iterations(r, 0, req.spp, &mine, &st, NULL, NULL, NULL, &e);
  if (!rc) rc = load_ckpt(argv[0], &farm, req.set.width, req.set.height, req.set.strategy_layers, &e);
  if (rc) { fprintf(stderr, "exact: %s\n", e.msg); return 1; }
  int bad = 0;
  double worst = 0;
  size_t n = (size_t)mine.w * mine.h * 3;
  for (int l = 0; l < mine.nlayers; l++) {
    double ta = 0, tb = 0;
    size_t differ = 0; /* values not bit-identical */
    for (size_t k = 0; k < n; k++) {
      ta += mine.layers[l].sum[k];
      tb += farm.layers[l].sum[k];
      differ += mine.layers[l].sum[k] != farm.layers[l].sum[k];
      double d = rel(mine.layers[l].sum[k], farm.layers[l].sum[k]);
      if (d > worst) worst = d;
    }
    printf("layer %-6s count %llu/%llu total %.12e/%.12e rel %.2e, %zu values differ\n", mine.layers[l].name,
           (unsigned long long)farm.layers[l].count, (unsigned long long)mine.layers[l].count, tb, ta, rel(ta, tb),
           differ);
    if (mine.layers[l].count != farm.layers[l].count || rel(ta, tb) > 1e-9) bad = 1;
    if (mine.layers[l].norm == PC_NORM_MAX && differ) bad = 1; /* a maximum does not depend on the order */
  }
  printf("worst per-pixel relative difference %.2e\n", worst);
  if (worst > 1e-9) bad = 1;
  /* the trace: the same iterations, each bit for bit (its order is the uploads') */
  int nb = pc_trace_blocks(mine.w, mine.h);
  uint32_t trace_differ = mine.trace.n != farm.trace.n;
  for (uint32_t k = 0; k < farm.trace.n && !trace_differ; k++) {
    uint32_t it = farm.trace.iteration[k], i = 0;
    while (i < mine.trace.n && mine.trace.iteration[i] != it) i++;
    trace_differ += i == mine.trace.n ||
                    memcmp(mine.trace.block + (size_t)i * nb, farm.trace.block + (size_t)k * nb, (size_t)nb * sizeof(float)) != 0;
  }
  printf("trace %u/%u iterations, %s\n", farm.trace.n, mine.trace.n, trace_differ ? "differ" : "identical");
  if (trace_differ) bad = 1;
  double em, ef;
  bool hm = pc_film_relmse_estimate(&mine, &em), hf = pc_film_relmse_estimate(&farm, &ef);
  printf("estimated relMSE %.9g/%.9g\n", ef, em);
  if (hm != hf || (hm && rel(em, ef) > 1e-6)) bad = 1;
  pc_renderer_destroy(r);
  pc_film_free(&mine);
  pc_film_free(&farm);
  pc_scene_free(&scene);
  puts(bad ? "MISMATCH" : "EXACT");
  return bad;
}

static int cmd_mean(int argc, char **argv) {
  if (argc != 6) { fprintf(stderr, "mean CKPT W H EXPECT TOL\n"); return 2; }
  pc_film f = {0};
  pc_err e = {0};
  if (load_ckpt(argv[1], &f, atoi(argv[2]), atoi(argv[3]), 0, &e)) { fprintf(stderr, "mean: %s\n", e.msg); return 1; }
  size_t n = (size_t)f.w * f.h * 3;
  float *b = malloc(n * sizeof *b);
  if (!b) return 1;
  pc_film_beauty(&f, b);
  double s = 0;
  for (size_t k = 0; k < n; k++) s += b[k];
  double mean = s / (double)n, want = atof(argv[4]), tol = atof(argv[5]);
  printf("mean %.5f expected %.5f (%.2f%% off, %llu iterations)\n", mean, want, 100 * fabs(mean - want) / want,
         (unsigned long long)f.layers[PC_LAYER_PT].count);
  free(b);
  pc_film_free(&f);
  return fabs(mean - want) <= tol * want ? 0 : 1;
}

static int cmd_relmse(int argc, char **argv) {
  if (argc != 5) { fprintf(stderr, "relmse CKPT W H EXACT\n"); return 2; }
  pc_film f = {0};
  pc_err e = {0};
  if (load_ckpt(argv[1], &f, atoi(argv[2]), atoi(argv[3]), 0, &e)) { fprintf(stderr, "relmse: %s\n", e.msg); return 1; }
  size_t n = (size_t)f.w * f.h * 3;
  float *b = malloc(n * sizeof *b);
  if (!b) return 1;
  pc_film_beauty(&f, b);
  double exact = atof(argv[4]), meas = 0, est;
  for (size_t k = 0; k < n; k++) meas += (b[k] - exact) * (b[k] - exact) / (exact * exact + PC_RELMSE_EPS);
  int rc = pc_film_relmse_estimate(&f, &est) ? 0 : 1;
  printf("%.9g %.9g\n", est, meas / (double)n);
  free(b);
  pc_film_free(&f);
  return rc;
}

/* An EXR the farm wrote: the beauty's mean over pixels and channels, then the values of the
 * header attributes named. */
static int cmd_exr(int argc, char **argv) {
  if (argc < 2) { fprintf(stderr, "exr FILE [ATTR...]\n"); return 2; }
  pc_exr_file x = {0};
  pc_err e = {0};
  if (pc_exr_read_layers(argv[1], &x, &e)) { fprintf(stderr, "exr: %s\n", e.msg); return 1; }
  int rc = 1;
  for (int i = 0; i < x.nlayers; i++)
    if (x.names[i][0] == '\0') {
      double s = 0;
      size_t n = (size_t)x.w * x.h * 3;
      for (size_t k = 0; k < n; k++) s += x.layers[i].rgb[k];
      printf("%.9g", s / (double)n);
      rc = 0;
    }
  for (int a = 2; a < argc && !rc; a++) {
    const char *v = "-";
    for (int i = 0; i < x.nattrs; i++)
      if (strcmp(x.attr_names[i], argv[a]) == 0) v = x.attr_values[i];
    printf(" %s", v);
  }
  printf("\n");
  pc_exr_file_free(&x);
  return rc;
}

/* Connects as a worker and asks until the coordinator assigns a range (*in holds it). */
static int take_range(const char *hostport, const char *token, pc_client *cl, Pcbpt__Envelope **in, pc_err *e) {
  if (pc_client_connect_as(hostport, token, PCBPT__ROLE__ROLE_WORKER, cl, e)) return 1;
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__WorkRequest wr = PCBPT__WORK_REQUEST__INIT;
  env.msg_case = PCBPT__ENVELOPE__MSG_WORK_REQUEST;
  env.work_request = &wr;
  for (int tries = 0; tries < 100; tries++) {
    if (pc_client_send(cl, &env, e) || pc_client_recv(cl, 10, in, e)) break;
    if ((*in)->msg_case == PCBPT__ENVELOPE__MSG_ASSIGN) return 0;
    pcbpt__envelope__free_unpacked(*in, NULL);
    *in = NULL;
    struct timespec ts = {0, 100000000};
    nanosleep(&ts, NULL);
  }
  if (!e->code) pc_errf(e, PC_EIO, "no range assigned");
  pc_client_close(cl);
  return 1;
}

/* Takes a range and reports that it cannot render it. */
static int cmd_fail(int argc, char **argv) {
  if (argc != 3) { fprintf(stderr, "fail HOST:PORT TOKEN\n"); return 2; }
  pc_client cl;
  pc_err e = {0};
  Pcbpt__Envelope *in = NULL;
  if (take_range(argv[1], argv[2], &cl, &in, &e)) { fprintf(stderr, "fail: %s\n", e.msg); return 1; }
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__RangeFailed f = PCBPT__RANGE_FAILED__INIT;
  f.job_id = in->assign->job_id;
  f.range_id = in->assign->range_id;
  f.reason = "farm_tool: refusing on purpose";
  env.msg_case = PCBPT__ENVELOPE__MSG_RANGE_FAILED;
  env.range_failed = &f;
  int rc = pc_client_send(&cl, &env, &e);
  pcbpt__envelope__free_unpacked(in, NULL);
  pc_client_close(&cl);
  if (rc) fprintf(stderr, "fail: %s\n", e.msg);
  return rc ? 1 : 0;
}

/* Uploads a delta of iterations [first, first+count) of an assigned range, shaped like a
 * real one (eye layers count the iterations, light layers w*h light paths per iteration, the
 * trace its iterations below the bound) with zero sums but for the pt layer's first value; dw
 * widens the film (a wrong size); trace_shift moves its traced iterations (another range's). */
static int send_delta(pc_client *cl, const Pcbpt__Assign *a, uint64_t first, uint64_t count, bool final, int dw,
                      double value, uint32_t trace_shift, pc_err *e) {
  pc_render_settings s;
  pc_film f;
  if (pc_wire_settings_from_proto(a->settings, &s, e) || pc_film_init(&f, s.width + dw, s.height, s.strategy_layers, e)) return 1;
  float zero[PC_TRACE_MAX_BLOCKS] = {0};
  int nb = pc_trace_blocks(f.w, f.h);
  for (uint64_t it = first; it < PC_TRACE_ITERATIONS && it - first < count; it++) {
    if (pc_trace_reserve(&f.trace, f.trace.n + 1, nb, e)) { pc_film_free(&f); return 1; }
    pc_trace_put(&f.trace, nb, (uint32_t)((it + trace_shift) % PC_TRACE_ITERATIONS), zero);
  }
  /* beauty_sq and beauty_max count iterations like an eye layer */
  for (int l = 0; l < f.nlayers; l++) f.layers[l].count = f.layers[l].norm != PC_NORM_LIGHT ? count : count * (uint64_t)s.width * s.height;
  f.layers[PC_LAYER_PT].sum[7] = value;
  uint8_t *raw = NULL, *z = NULL;
  size_t rn, zn;
  int rc = pc_wire_film_pack(&f, &raw, &rn, e);
  if (!rc) rc = pc_wire_compress(raw, rn, &z, &zn, e);
  pc_film_free(&f);
  free(raw);
  uint32_t nchunks = (uint32_t)((zn + PC_WIRE_CHUNK - 1) / PC_WIRE_CHUNK);
  for (uint32_t i = 0; !rc && i < nchunks; i++) {
    Pcbpt__Envelope u = PCBPT__ENVELOPE__INIT;
    Pcbpt__UploadChunk c = PCBPT__UPLOAD_CHUNK__INIT;
    c.job_id = a->job_id;
    c.range_id = a->range_id;
    c.first = first;
    c.count = count;
    c.index = i;
    c.nchunks = nchunks;
    c.raw_size = rn;
    c.final = final;
    c.data.data = z + (size_t)i * PC_WIRE_CHUNK;
    c.data.len = zn - (size_t)i * PC_WIRE_CHUNK < PC_WIRE_CHUNK ? zn - (size_t)i * PC_WIRE_CHUNK : PC_WIRE_CHUNK;
    u.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK;
    u.upload_chunk = &c;
    rc = pc_client_send(cl, &u, e);
  }
  free(z);
  return rc ? 1 : 0;
}

/* Waits up to `seconds` for the acknowledgement of an upload to `range` (anything else is
 * skipped); 0 with *refused and its reason printed, 1 when none came. */
static int wait_ack(pc_client *cl, uint64_t range, double seconds, bool *refused, pc_err *e) {
  double end = now_s() + seconds;
  while (now_s() < end) {
    Pcbpt__Envelope *in = NULL;
    if (pc_client_recv(cl, end - now_s(), &in, e)) return 1;
    bool hit = in->msg_case == PCBPT__ENVELOPE__MSG_UPLOAD_ACK && in->upload_ack->range_id == range;
    if (hit) {
      *refused = in->upload_ack->refused;
      printf("ack for range %llu: refused=%d reason: %s\n", (unsigned long long)range, *refused, in->upload_ack->reason);
    }
    pcbpt__envelope__free_unpacked(in, NULL);
    if (hit) return 0;
  }
  pc_errf(e, PC_EIO, "no acknowledgement within %.0f s", seconds);
  return 1;
}

static int send_heartbeat(pc_client *cl, uint64_t job, uint64_t range, double rate, uint64_t done, pc_err *e) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Heartbeat h = PCBPT__HEARTBEAT__INIT;
  h.job_id = job;
  h.range_id = range;
  h.iterations_per_second = rate;
  h.iterations_done = done;
  env.msg_case = PCBPT__ENVELOPE__MSG_HEARTBEAT;
  env.heartbeat = &h;
  return pc_client_send(cl, &env, e);
}

/* Asks for a range claiming `rate` and waits for the assignment (skipping anything else). */
static int request_range(pc_client *cl, double rate, Pcbpt__Envelope **in, pc_err *e) {
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__WorkRequest wr = PCBPT__WORK_REQUEST__INIT;
  wr.iterations_per_second = rate;
  env.msg_case = PCBPT__ENVELOPE__MSG_WORK_REQUEST;
  env.work_request = &wr;
  if (pc_client_send(cl, &env, e)) return 1;
  for (;;) {
    if (pc_client_recv(cl, 10, in, e)) return 1;
    if ((*in)->msg_case == PCBPT__ENVELOPE__MSG_ASSIGN) return 0;
    pcbpt__envelope__free_unpacked(*in, NULL);
    *in = NULL;
  }
}

static int cmd_upload(int argc, char **argv) {
  if (argc != 4 || (strcmp(argv[3], "nan") && strcmp(argv[3], "size") && strcmp(argv[3], "huge") && strcmp(argv[3], "wrap") &&
                    strcmp(argv[3], "trace"))) {
    fprintf(stderr, "upload HOST:PORT TOKEN nan|size|huge|wrap|trace\n");
    return 2;
  }
  pc_client cl;
  pc_err e = {0};
  Pcbpt__Envelope *in = NULL;
  if (take_range(argv[1], argv[2], &cl, &in, &e)) { fprintf(stderr, "upload: %s\n", e.msg); return 1; }
  Pcbpt__Assign *a = in->assign;
  bool size = strcmp(argv[3], "size") == 0, refused = false;
  double value = strcmp(argv[3], "nan") == 0 ? NAN : strcmp(argv[3], "huge") == 0 ? 1.7e308 : 0;
  /* wrap: 2^64-1 iterations from first + 1, so first + count wraps round to first */
  bool wrap = strcmp(argv[3], "wrap") == 0;
  int rc = send_delta(&cl, a, wrap ? a->first + 1 : a->first, wrap ? UINT64_MAX : 1, true, size ? 1 : 0, value,
                      strcmp(argv[3], "trace") == 0 ? PC_TRACE_ITERATIONS / 2 : 0, &e);
  if (!rc) printf("uploaded a %s delta for job %llu range %llu\n", argv[3], (unsigned long long)a->job_id, (unsigned long long)a->range_id);
  if (!rc) rc = wait_ack(&cl, a->range_id, 30, &refused, &e);
  if (rc) fprintf(stderr, "upload: %s\n", e.msg);
  pcbpt__envelope__free_unpacked(in, NULL);
  pc_client_close(&cl);
  return rc || !refused;
}

/* A merge acknowledged at the next checkpoint, then the job cancelled before that
 * checkpoint: the upload must still be answered, or a worker would wait for it forever. */
static int cmd_cancelack(int argc, char **argv) {
  if (argc != 3) { fprintf(stderr, "cancelack HOST:PORT TOKEN\n"); return 2; }
  pc_client cl, cc;
  pc_err e = {0};
  Pcbpt__Envelope *in = NULL, *in2 = NULL;
  bool refused = false;
  if (take_range(argv[1], argv[2], &cl, &in, &e)) { fprintf(stderr, "cancelack: %s\n", e.msg); return 1; }
  Pcbpt__Assign *a = in->assign;
  /* the probe range, committed at once (its last upload); then a range of 100 iterations */
  int rc = send_heartbeat(&cl, a->job_id, a->range_id, 100, 0, &e);
  if (!rc) rc = send_delta(&cl, a, a->first, a->count, true, 0, 0, 0, &e);
  if (!rc) rc = wait_ack(&cl, a->range_id, 10, &refused, &e);
  if (!rc) rc = request_range(&cl, 100, &in2, &e);
  if (!rc && in2->assign->count < 2) rc = pc_errf(&e, PC_EINVAL, "a range of %llu iterations", (unsigned long long)in2->assign->count);
  /* one iteration of it: merged, its acknowledgement waits for the next checkpoint */
  if (!rc) rc = send_delta(&cl, in2->assign, in2->assign->first, 1, false, 0, 0, 0, &e);
  struct timespec ts = {0, 200000000};
  nanosleep(&ts, NULL);
  if (!rc && !(rc = pc_client_connect(argv[1], argv[2], &cc, &e))) {
    Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT, *rep = NULL;
    Pcbpt__CancelRequest cr = PCBPT__CANCEL_REQUEST__INIT;
    cr.job_id = a->job_id;
    env.msg_case = PCBPT__ENVELOPE__MSG_CANCEL_REQUEST;
    env.cancel_request = &cr;
    rc = pc_client_send(&cc, &env, &e);
    if (!rc) rc = pc_client_recv(&cc, 10, &rep, &e);
    if (rep) pcbpt__envelope__free_unpacked(rep, NULL);
    pc_client_close(&cc);
    printf("cancelled job %llu\n", (unsigned long long)a->job_id);
  }
  if (!rc) rc = wait_ack(&cl, in2->assign->range_id, 5, &refused, &e);
  if (rc) fprintf(stderr, "cancelack: %s\n", e.msg);
  pcbpt__envelope__free_unpacked(in, NULL);
  if (in2) pcbpt__envelope__free_unpacked(in2, NULL);
  pc_client_close(&cl);
  return rc ? 1 : 0;
}

/* Claims a rate of 1e8 iterations/s for job JOB (a heartbeat naming it), takes a range and
 * then only sends heartbeats, until the coordinator takes the range back (a Cancel of it)
 * or SECONDS pass; then uploads the whole range, which must be refused. */
static int cmd_hoard(int argc, char **argv) {
  if (argc != 5) { fprintf(stderr, "hoard HOST:PORT TOKEN JOB SECONDS\n"); return 2; }
  pc_client cl;
  pc_err e = {0};
  Pcbpt__Envelope *in = NULL;
  bool refused = false, revoked = false;
  uint64_t job = strtoull(argv[3], NULL, 10);
  if (pc_client_connect_as(argv[1], argv[2], PCBPT__ROLE__ROLE_WORKER, &cl, &e)) { fprintf(stderr, "hoard: %s\n", e.msg); return 1; }
  int rc = send_heartbeat(&cl, job, 999999999, 1e8, 0, &e);
  if (!rc) rc = request_range(&cl, 1e8, &in, &e);
  if (rc) { fprintf(stderr, "hoard: %s\n", e.msg); pc_client_close(&cl); return 1; }
  Pcbpt__Assign *a = in->assign;
  printf("hoarding range %llu [%llu,+%llu)\n", (unsigned long long)a->range_id, (unsigned long long)a->first, (unsigned long long)a->count);
  double end = now_s() + atof(argv[4]);
  while (!rc && !revoked && now_s() < end) {
    rc = send_heartbeat(&cl, a->job_id, a->range_id, 1e8, 0, &e);
    Pcbpt__Envelope *m = NULL;
    pc_err te;
    if (!rc && pc_client_recv(&cl, 0.5, &m, &te) == 0) {
      revoked = m->msg_case == PCBPT__ENVELOPE__MSG_CANCEL && m->cancel->range_id == a->range_id && !m->cancel->upload_partial;
      pcbpt__envelope__free_unpacked(m, NULL);
    }
  }
  printf("%s after %.1f s; uploading the range anyway\n", revoked ? "taken back" : "not taken back", atof(argv[4]) - (end - now_s()));
  if (!rc) rc = send_delta(&cl, a, a->first, a->count, true, 0, 0, 0, &e);
  if (!rc) rc = wait_ack(&cl, a->range_id, 10, &refused, &e);
  if (rc) fprintf(stderr, "hoard: %s\n", e.msg);
  pcbpt__envelope__free_unpacked(in, NULL);
  pc_client_close(&cl);
  return rc || !revoked || !refused;
}

/* Uploads a scene bundle its worker must refuse to unpack (its hash is right) and submits a
 * job on it; prints the job id. */
static int cmd_badbundle(int argc, char **argv) {
  if (argc != 4) { fprintf(stderr, "badbundle HOST:PORT TOKEN dotdot|absolute|noscene|dup|clash|notproto\n"); return 2; }
  const char *kind = argv[3];
  Pcbpt__BundleFile f[2] = {PCBPT__BUNDLE_FILE__INIT, PCBPT__BUNDLE_FILE__INIT}, *fp[2] = {&f[0], &f[1]};
  Pcbpt__Bundle b = PCBPT__BUNDLE__INIT;
  static const char xml[] = "<scene version=\"0.6.0\"/>";
  b.scene = "scene.xml";
  b.files = fp;
  b.n_files = 2;
  f[0].path = "scene.xml";
  f[0].data.data = (uint8_t *)xml;
  f[0].data.len = sizeof xml - 1;
  f[1].path = strcmp(kind, "dotdot") == 0 ? "../escape.obj" : strcmp(kind, "absolute") == 0 ? "/tmp/escape.obj"
            : strcmp(kind, "dup") == 0 ? "scene.xml" : strcmp(kind, "clash") == 0 ? "scene.xml/m.obj" : "m.obj";
  f[1].data.data = (uint8_t *)"v 0 0 0\n";
  f[1].data.len = 8;
  if (strcmp(kind, "noscene") == 0) b.scene = "other.xml";
  size_t rn = pcbpt__bundle__get_packed_size(&b);
  uint8_t *raw = malloc(rn + 32), *z = NULL, hash[PC_BUNDLE_HASH];
  size_t zn;
  pc_err e = {0};
  if (!raw) return 1;
  if (strcmp(kind, "notproto") == 0) rn = (size_t)snprintf((char *)raw, rn + 32, "\xff\xff\xff not a protobuf");
  else pcbpt__bundle__pack(&b, raw);
  int rc = pc_wire_compress(raw, rn, &z, &zn, &e);
  free(raw);
  if (!rc) rc = pc_bundle_hash(z, zn, hash, &e);
  pc_client cl;
  if (!rc) rc = pc_client_connect(argv[1], argv[2], &cl, &e);
  if (!rc) {
    rc = pc_client_send_bundle(&cl, z, zn, hash, &e);
    Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT, *in = NULL;
    Pcbpt__Submit sub = PCBPT__SUBMIT__INIT;
    Pcbpt__Settings ps;
    pc_wire_settings_buf psb;
    pc_render_settings s;
    pc_render_settings_default(&s);
    s.width = s.height = 16;
    pc_wire_settings_to_proto(&s, &ps, &psb);
    sub.name = (char *)kind;
    sub.bundle_hash.data = hash;
    sub.bundle_hash.len = PC_BUNDLE_HASH;
    sub.settings = &ps;
    sub.halt_iterations = 100;
    env.msg_case = PCBPT__ENVELOPE__MSG_SUBMIT;
    env.submit = &sub;
    if (!rc) rc = pc_client_send(&cl, &env, &e);
    if (!rc) rc = pc_client_recv(&cl, 10, &in, &e);
    if (!rc && in->msg_case == PCBPT__ENVELOPE__MSG_SUBMIT_REPLY) printf("%llu\n", (unsigned long long)in->submit_reply->job_id);
    else if (!rc) rc = pc_errf(&e, PC_EPARSE, "unexpected reply to submit");
    if (in) pcbpt__envelope__free_unpacked(in, NULL);
    pc_client_close(&cl);
  }
  free(z);
  if (rc) fprintf(stderr, "badbundle: %s\n", e.msg);
  return rc ? 1 : 0;
}

static int cmd_bundle(int argc, char **argv) {
  if (argc != 3) { fprintf(stderr, "bundle HOST:PORT TOKEN\n"); return 2; }
  pc_client cl;
  pc_err e = {0};
  if (pc_client_connect(argv[1], argv[2], &cl, &e)) { fprintf(stderr, "bundle: %s\n", e.msg); return 1; }
  uint8_t blob[100], hash[PC_BUNDLE_HASH];
  memset(blob, 'x', sizeof blob);
  memset(hash, 0x5a, sizeof hash);
  Pcbpt__Envelope *in = NULL;
  int rc = pc_client_send_bundle(&cl, blob, sizeof blob, hash, &e);
  if (!rc) rc = pc_client_recv(&cl, 10, &in, &e);
  pc_client_close(&cl);
  if (in) pcbpt__envelope__free_unpacked(in, NULL);
  printf("bundle: %s\n", rc ? e.msg : "accepted");
  if (!rc || !strstr(e.msg, "hash does not match")) return 1;
  /* and a job naming it is refused */
  if (pc_client_connect(argv[1], argv[2], &cl, &e)) return 1;
  Pcbpt__Envelope env = PCBPT__ENVELOPE__INIT;
  Pcbpt__Submit sub = PCBPT__SUBMIT__INIT;
  Pcbpt__Settings ps;
  pc_wire_settings_buf psb;
  pc_render_settings s;
  pc_render_settings_default(&s);
  pc_wire_settings_to_proto(&s, &ps, &psb);
  sub.name = "bad-bundle";
  sub.bundle_hash.data = hash;
  sub.bundle_hash.len = PC_BUNDLE_HASH;
  sub.settings = &ps;
  sub.halt_iterations = 1;
  env.msg_case = PCBPT__ENVELOPE__MSG_SUBMIT;
  env.submit = &sub;
  in = NULL;
  rc = pc_client_send(&cl, &env, &e);
  if (!rc) rc = pc_client_recv(&cl, 10, &in, &e);
  pc_client_close(&cl);
  if (in) pcbpt__envelope__free_unpacked(in, NULL);
  printf("submit: %s\n", rc ? e.msg : "accepted");
  return rc && strstr(e.msg, "was not uploaded") ? 0 : 1;
}

int main(int argc, char **argv) {
  if (argc >= 4 && strcmp(argv[1], "exact") == 0) return cmd_exact(argc - 2, argv + 2);
  if (argc >= 2 && strcmp(argv[1], "mean") == 0) return cmd_mean(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "relmse") == 0) return cmd_relmse(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "exr") == 0) return cmd_exr(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "upload") == 0) return cmd_upload(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "bundle") == 0) return cmd_bundle(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "fail") == 0) return cmd_fail(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "cancelack") == 0) return cmd_cancelack(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "hoard") == 0) return cmd_hoard(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "badbundle") == 0) return cmd_badbundle(argc - 1, argv + 1);
  fprintf(stderr, "usage: farm_tool exact CKPT SCENE [flags] | mean CKPT W H EXPECT TOL | relmse CKPT W H EXACT | exr FILE [ATTR...]"
                  " | upload HOST:PORT TOKEN nan|size|huge|wrap | bundle HOST:PORT TOKEN | fail HOST:PORT TOKEN"
                  " | cancelack HOST:PORT TOKEN | hoard HOST:PORT TOKEN JOB SECONDS | badbundle HOST:PORT TOKEN KIND\n");
  return 2;
}
