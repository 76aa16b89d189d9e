/* farm_tool.c: helpers of the farm tests (not installed).
 *   farm_tool exact CKPT SCENE [render flags]   the job's merged sums (its last checkpoint)
 *       equal a single-process render of iterations [0, --spp) up to summation order:
 *       identical counts, relative 1e-9 on per-layer totals and on every pixel value
 *       (beauty_sq included, so the estimated relMSE agrees too: printed, relative 1e-6)
 *   farm_tool mean CKPT EXPECT TOL              |mean(beauty) - EXPECT| <= TOL * EXPECT
 *   farm_tool relmse CKPT W H EXACT             prints the film's estimated relMSE and the one
 *       measured against the constant image EXACT (compare's definition)
 *   farm_tool upload HOST:PORT TOKEN nan|size   speaks as a worker: takes a range and uploads
 *       a delta with a NaN sum or of the wrong size; exits 0 if the coordinator refuses it
 *   farm_tool bundle HOST:PORT TOKEN            sends a scene bundle whose content does not
 *       match its hash; exits 0 if the coordinator refuses it and will not run a job on it
 *   farm_tool fail HOST:PORT TOKEN              speaks as a worker: takes a range and reports
 *       that it cannot render it */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bundle.h"
#include "client.h"
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
  int rc = pc_scene_load(argv[1], &scene, &e);
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
    for (size_t k = 0; k < n; k++) {
      ta += mine.layers[l].sum[k];
      tb += farm.layers[l].sum[k];
      double d = rel(mine.layers[l].sum[k], farm.layers[l].sum[k]);
      if (d > worst) worst = d;
    }
    printf("layer %-6s count %llu/%llu total %.12e/%.12e rel %.2e\n", mine.layers[l].name,
           (unsigned long long)farm.layers[l].count, (unsigned long long)mine.layers[l].count, tb, ta, rel(ta, tb));
    if (mine.layers[l].count != farm.layers[l].count || rel(ta, tb) > 1e-9) bad = 1;
  }
  printf("worst per-pixel relative difference %.2e\n", worst);
  if (worst > 1e-9) bad = 1;
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

static int cmd_upload(int argc, char **argv) {
  if (argc != 4 || (strcmp(argv[3], "nan") && strcmp(argv[3], "size"))) { fprintf(stderr, "upload HOST:PORT TOKEN nan|size\n"); return 2; }
  pc_client cl;
  pc_err e = {0};
  Pcbpt__Envelope *in = NULL;
  int rc = 1;
  if (take_range(argv[1], argv[2], &cl, &in, &e)) { fprintf(stderr, "upload: %s\n", e.msg); return 1; }
  Pcbpt__Assign *a = in->assign;
  pc_render_settings s;
  if (pc_wire_settings_from_proto(a->settings, &s, &e)) goto fail;
  bool nan = strcmp(argv[3], "nan") == 0;
  pc_film f;
  if (pc_film_init(&f, s.width + (nan ? 0 : 1), s.height, s.strategy_layers, &e)) goto fail;
  for (int l = 0; l < f.nlayers; l++) f.layers[l].count = f.layers[l].norm != PC_NORM_LIGHT ? 1 : (uint64_t)s.width * s.height;
  if (nan) f.layers[PC_LAYER_PT].sum[7] = NAN;
  uint8_t *raw = NULL, *z = NULL;
  size_t rn, zn;
  int prc = pc_wire_film_pack(&f, &raw, &rn, &e);
  if (!prc) prc = pc_wire_compress(raw, rn, &z, &zn, &e);
  pc_film_free(&f);
  free(raw);
  if (prc) goto fail;
  uint32_t nchunks = (uint32_t)((zn + PC_WIRE_CHUNK - 1) / PC_WIRE_CHUNK);
  for (uint32_t i = 0; i < nchunks; i++) {
    Pcbpt__Envelope u = PCBPT__ENVELOPE__INIT;
    Pcbpt__UploadChunk c = PCBPT__UPLOAD_CHUNK__INIT;
    c.job_id = a->job_id;
    c.range_id = a->range_id;
    c.first = a->first;
    c.count = 1;
    c.index = i;
    c.nchunks = nchunks;
    c.raw_size = rn;
    c.final = true;
    c.data.data = z + (size_t)i * PC_WIRE_CHUNK;
    c.data.len = zn - (size_t)i * PC_WIRE_CHUNK < PC_WIRE_CHUNK ? zn - (size_t)i * PC_WIRE_CHUNK : PC_WIRE_CHUNK;
    u.msg_case = PCBPT__ENVELOPE__MSG_UPLOAD_CHUNK;
    u.upload_chunk = &c;
    if (pc_client_send(&cl, &u, &e)) { free(z); goto fail; }
  }
  free(z);
  printf("uploaded a %s delta for job %llu range %llu\n", argv[3], (unsigned long long)a->job_id, (unsigned long long)a->range_id);
  pcbpt__envelope__free_unpacked(in, NULL);
  in = NULL;
  for (;;) {
    if (pc_client_recv(&cl, 30, &in, &e)) goto fail;
    if (in->msg_case == PCBPT__ENVELOPE__MSG_UPLOAD_ACK) break;
    pcbpt__envelope__free_unpacked(in, NULL); /* heartbeat-free test peer: ignore anything else */
    in = NULL;
  }
  printf("ack: refused=%d reason: %s\n", in->upload_ack->refused, in->upload_ack->reason);
  rc = in->upload_ack->refused ? 0 : 1;
  pcbpt__envelope__free_unpacked(in, NULL);
  pc_client_close(&cl);
  return rc;
fail:
  if (in) pcbpt__envelope__free_unpacked(in, NULL);
  fprintf(stderr, "upload: %s\n", e.msg);
  pc_client_close(&cl);
  return 1;
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
  pc_render_settings s;
  pc_render_settings_default(&s);
  pc_wire_settings_to_proto(&s, &ps);
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
  if (argc >= 2 && strcmp(argv[1], "upload") == 0) return cmd_upload(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "bundle") == 0) return cmd_bundle(argc - 1, argv + 1);
  if (argc >= 2 && strcmp(argv[1], "fail") == 0) return cmd_fail(argc - 1, argv + 1);
  fprintf(stderr, "usage: farm_tool exact CKPT SCENE [flags] | mean CKPT W H EXPECT TOL | relmse CKPT W H EXACT | upload HOST:PORT TOKEN nan|size | bundle HOST:PORT TOKEN | fail HOST:PORT TOKEN\n");
  return 2;
}
