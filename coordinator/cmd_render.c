/* cmd_render.c: `pcbpt-coord render`: renders a scene on this machine until an iteration count
 * or a time budget is reached, then writes the EXR (beauty + per-strategy layers + counts) and
 * an sRGB PNG preview, and prints one summary line. */
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "film.h"
#include "image.h"
#include "render.h"
#include "render_flags.h"
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
    "Without --spp or --time, renders 64 iterations.\n";

static atomic_bool g_interrupted; /* set by SIGINT: the render stops and writes what it has */

static void on_sigint(int sig) {
  (void)sig;
  atomic_store(&g_interrupted, true);
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

static void draw_progress(progress_state *p, uint64_t done) {
  if (!p->show) return;
  double el = now_s() - p->t0;
  double frac = p->target ? (double)done / (double)p->target : (p->seconds > 0 ? el / p->seconds : 0);
  if (frac > 1) frac = 1;
  int bar = (int)(frac * 30);
  fprintf(stderr, "\r[%.*s%*s] %3d%%  %llu it  %.1fs ", bar, "==============================", 30 - bar, "",
          (int)(frac * 100), (unsigned long long)done, el);
  fflush(stderr);
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
  if (req.spp == 0 && req.seconds == 0) req.spp = 64;

  int status = 1;
  pc_scene scene = {0};
  pc_renderer *rend = NULL;
  pc_film film = {0};
  char *out_owned = NULL, *png = NULL;
  if (pc_scene_load(scene_path, &scene, &err) != PC_OK) goto fail;
  pc_render_request_apply_scene(&req, &scene);
  if (pc_render_settings_check(&req.set, &err) != PC_OK) goto fail;
  if (pc_scene_build(&scene, &err) != PC_OK) goto fail;
  if (pc_film_init(&film, req.set.width, req.set.height, req.set.strategy_layers, &err) != PC_OK) goto fail;
  if (pc_renderer_create(&scene, &req.set, (int)threads, &rend, &err) != PC_OK) goto fail;
  if (!out) out = out_owned = default_out(scene_path);
  png = out ? preview_path(out) : NULL;
  if (!out || !png) {
    pc_errf(&err, PC_ENOMEM, "out of memory");
    goto fail;
  }

  struct sigaction sa = {0};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  if (sigaction(SIGINT, &sa, NULL) != 0) perror("pcbpt-coord render: sigaction");

  progress_state prog = {.show = !quiet && isatty(STDERR_FILENO), .target = req.spp, .seconds = req.seconds, .t0 = now_s()};
  pc_render_stats stats = {0};
  uint64_t it = 0;
  double t0 = now_s();
  while (!atomic_load(&g_interrupted)) {
    if (req.spp && it >= req.spp) break;
    if (req.seconds > 0 && now_s() - t0 >= req.seconds) break;
    int rc = pc_render_iterations(rend, it, 1, &film, &stats, &g_interrupted, NULL, NULL, &err);
    if (rc == PC_ECANCELED) break;
    if (rc != PC_OK) goto fail;
    it++;
    draw_progress(&prog, it);
  }
  double secs = now_s() - t0;
  if (prog.show) fputc('\n', stderr);
  if (it == 0) {
    pc_errf(&err, PC_ECANCELED, "no iteration finished; nothing written");
    goto fail;
  }

  char version[64];
  snprintf(version, sizeof version, "pcbpt %s", PCBPT_VERSION);
  char seed[32];
  snprintf(seed, sizeof seed, "%llu", (unsigned long long)req.set.seed);
  pc_exr_attr attrs[] = {
      {.name = "pcbpt.method", .type = PC_ATTR_STRING, .s = pc_method_name(req.set.method)},
      {.name = "pcbpt.iterations", .type = PC_ATTR_DOUBLE, .d = (double)it},
      {.name = "pcbpt.seed", .type = PC_ATTR_STRING, .s = seed},
      {.name = "pcbpt.max_depth", .type = PC_ATTR_DOUBLE, .d = req.set.max_depth},
      {.name = "pcbpt.render_seconds", .type = PC_ATTR_DOUBLE, .d = secs},
      {.name = "pcbpt.rays", .type = PC_ATTR_DOUBLE, .d = (double)stats.rays},
      {.name = "pcbpt.time_paths", .type = PC_ATTR_DOUBLE, .d = stats.t_paths},
      {.name = "pcbpt.time_lt", .type = PC_ATTR_DOUBLE, .d = stats.t_lt},
      {.name = "pcbpt.time_pmf", .type = PC_ATTR_DOUBLE, .d = stats.t_pmf},
      {.name = "pcbpt.time_connect", .type = PC_ATTR_DOUBLE, .d = stats.t_connect},
      {.name = "pcbpt.scene", .type = PC_ATTR_STRING, .s = scene_path},
      {.name = "software", .type = PC_ATTR_STRING, .s = version},
  };
  if (pc_film_write_exr(&film, out, attrs, (int)(sizeof attrs / sizeof attrs[0]), &err) != PC_OK) goto fail;
  {
    size_t n = (size_t)film.w * film.h * 3;
    float *beauty = malloc(n * sizeof(float));
    if (!beauty) {
      pc_errf(&err, PC_ENOMEM, "out of memory for the preview");
      goto fail;
    }
    pc_film_beauty(&film, beauty);
    int rc = pc_png_write_preview(png, film.w, film.h, beauty, (float)exposure, &err);
    free(beauty);
    if (rc != PC_OK) goto fail;
  }
  double samples = (double)it * film.w * film.h;
  printf("%s: %llu iterations, %.2f s, %.0f samples/s, %.2f Mrays/s, %d threads%s -> %s, %s\n",
         pc_method_name(req.set.method), (unsigned long long)it, secs, samples / secs, (double)stats.rays / secs * 1e-6,
         pc_renderer_threads(rend), film.dropped_nonfinite ? " (non-finite samples dropped)" : "", out, png);
  if (film.dropped_nonfinite)
    fprintf(stderr, "pcbpt-coord render: warning: %llu non-finite samples were dropped\n",
            (unsigned long long)film.dropped_nonfinite);
  status = 0;
  goto done;
fail:
  fprintf(stderr, "pcbpt-coord render: %s\n", err.msg[0] ? err.msg : pc_strerror(err.code));
done:
  pc_renderer_destroy(rend);
  pc_film_free(&film);
  pc_scene_free(&scene);
  free(out_owned);
  free(png);
  return status;
}
