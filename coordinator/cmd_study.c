/* cmd_study.c: `pcbpt-coord study`: the equal-time study (DESIGN.md §6) on this machine. Parses
 * the flags, loads the reference and the scene once, renders each method in turn for the same
 * render time on the same threads with the same seed (study_run.c), then writes each method's
 * image, study.csv, study.json and the charts into the output folder and prints the table. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "film.h"
#include "image.h"
#include "render_flags.h"
#include "cli_scene.h"
#include "scene.h"
#include "study.h"
#include "verbs.h"

static const char study_help[] =
    "usage: pcbpt-coord study SCENE.xml --methods M1,M2,... --seconds S [--reference REF.exr] --out DIR [flags]\n"
    "Renders SCENE with each method in turn for S seconds of render time on the same threads and seed,\n"
    "measures relMSE, RMSE and L1 against REF at logarithmically spaced snapshots (from 1/64 of S to S)\n"
    "for the beauty and every standard layer (pt, nee, lt, inner) present in REF, and writes into DIR:\n"
    "<method>.exr and .png, study.csv, study.json, study_beauty.png/.svg and study_inner.png/.svg.\n"
    "Ratios are to the first method listed: put the method to compare against first.\n"
    "Per-layer errors compare like with like only when the methods share the reference's strategies\n"
    "(e.g. inner of bdpt and pcbpt against a bdpt reference); a method that leaves a layer empty is\n"
    "left out of that layer's comparison.\n"
    "Without --reference the beauty's relMSE and RMSE are each image's own estimates from the spread of\n"
    "its iterations (docs/variance.md; L1 and the other layers are not measured), and the output says so.\n\n"
    "  --methods LIST        comma-separated, from pt, lt, bdpt, cbdpt, pcbpt (each at most once)\n"
    "  --seconds S           render time per method (snapshots and metrics are not counted)\n"
    "  --reference REF.exr   reference image of the same size (its layers are compared by name);\n"
    "                        without it, errors are estimated\n"
    "  --out DIR             output folder (created if missing)\n"
    "  --threads N           render threads (default 0 = every core)\n"
    "  --snapshots K         snapshots per method (default 12)\n"
    "  --target-error E      target relMSE of the --layer comparison (default: the worst method's final)\n"
    "  --layer NAME          layer of the headline comparison: beauty (default), pt, nee, lt, inner\n"
    "Render flags (apply to every method; --method, --spp and --time are not accepted):\n"
    "%s";

typedef struct study_args {
  pc_render_request req;
  const char *scene, *reference, *out;
  pc_method methods[PC_STUDY_MAX_METHODS];
  int nmethods;
  double seconds, target_error;
  long long threads, snapshots;
  int layer;
} study_args;

static int parse_methods(study_args *a, const char *list, pc_err *e) {
  char buf[256];
  if (strlen(list) >= sizeof buf) return pc_errf(e, PC_EINVAL, "--methods: list too long");
  strcpy(buf, list);
  a->nmethods = 0;
  char *save = NULL;
  for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
    pc_method m;
    if (pc_method_parse(tok, &m) != PC_OK)
      return pc_errf(e, PC_EINVAL, "--methods: unknown method '%s' (pt, lt, bdpt, cbdpt, pcbpt)", tok);
    for (int i = 0; i < a->nmethods; i++)
      if (a->methods[i] == m) return pc_errf(e, PC_EINVAL, "--methods: '%s' given twice", tok);
    a->methods[a->nmethods++] = m;
  }
  if (a->nmethods == 0) return pc_errf(e, PC_EINVAL, "--methods: empty list");
  return PC_OK;
}

/* 1: parsed, 0: --help printed, <0: error in e. */
static int parse_args(study_args *a, int argc, char **argv, pc_err *e) {
  memset(a, 0, sizeof *a);
  pc_render_request_default(&a->req);
  a->snapshots = 12;
  a->layer = PC_STUDY_BEAUTY;
  for (int i = 0; i < argc; i++) {
    const char *f = argv[i];
    const char *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (strcmp(f, "--method") == 0) return pc_errf(e, PC_EINVAL, "--method: a study takes --methods LIST");
    if (strcmp(f, "--spp") == 0 || strcmp(f, "--time") == 0)
      return pc_errf(e, PC_EINVAL, "%s: a study is bound by --seconds per method", f);
    int r = pc_render_flag_parse(&a->req, argc, argv, &i, e);
    if (r < 0) return r;
    if (r > 0) continue;
    if (strcmp(f, "--help") == 0 || strcmp(f, "-h") == 0) {
      printf(study_help, pc_render_flags_help);
      return 0;
    }
    bool takes_value = strcmp(f, "--methods") == 0 || strcmp(f, "--seconds") == 0 || strcmp(f, "--reference") == 0 ||
                       strcmp(f, "--out") == 0 || strcmp(f, "--threads") == 0 || strcmp(f, "--snapshots") == 0 ||
                       strcmp(f, "--target-error") == 0 || strcmp(f, "--layer") == 0;
    if (takes_value && (!v || !*v)) return pc_errf(e, PC_EINVAL, "%s: missing value", f);
    if (takes_value) i++;
    if (strcmp(f, "--methods") == 0) {
      int rc = parse_methods(a, v, e);
      if (rc != PC_OK) return rc;
    } else if (strcmp(f, "--seconds") == 0) {
      if (!pc_parse_f64(v, 1e-3, 1e7, &a->seconds)) return pc_errf(e, PC_EINVAL, "--seconds: '%s' is not a number of seconds > 0", v);
    } else if (strcmp(f, "--reference") == 0) {
      a->reference = v;
    } else if (strcmp(f, "--out") == 0) {
      a->out = v;
    } else if (strcmp(f, "--threads") == 0) {
      if (!pc_parse_i64(v, 0, 1024, &a->threads)) return pc_errf(e, PC_EINVAL, "--threads: '%s' is not 0..1024", v);
    } else if (strcmp(f, "--snapshots") == 0) {
      if (!pc_parse_i64(v, 1, PC_STUDY_MAX_SNAPSHOTS, &a->snapshots))
        return pc_errf(e, PC_EINVAL, "--snapshots: '%s' is not 1..%d", v, PC_STUDY_MAX_SNAPSHOTS);
    } else if (strcmp(f, "--target-error") == 0) {
      if (!pc_parse_f64(v, 1e-300, 1e300, &a->target_error)) return pc_errf(e, PC_EINVAL, "--target-error: '%s' is not a relMSE > 0", v);
    } else if (strcmp(f, "--layer") == 0) {
      if ((a->layer = pc_study_layer_parse(v)) < 0)
        return pc_errf(e, PC_EINVAL, "--layer: '%s' is not beauty, pt, nee, lt or inner", v);
    } else if (f[0] == '-') {
      return pc_errf(e, PC_EINVAL, "unknown flag '%s' (see --help)", f);
    } else if (!a->scene) {
      a->scene = f;
    } else {
      return pc_errf(e, PC_EINVAL, "unexpected argument '%s' (one scene only)", f);
    }
  }
  if (!a->scene) return pc_errf(e, PC_EINVAL, "missing SCENE.xml (see --help)");
  if (!a->nmethods) return pc_errf(e, PC_EINVAL, "--methods: required (e.g. --methods pcbpt,bdpt,pt)");
  if (!(a->seconds > 0)) return pc_errf(e, PC_EINVAL, "--seconds: required");
  if (!a->reference && a->layer != PC_STUDY_BEAUTY)
    return pc_errf(e, PC_EINVAL, "--layer: only the beauty's error is estimated without --reference");
  if (!a->out) return pc_errf(e, PC_EINVAL, "--out: required");
  a->req.method_set = true; /* the scene's integrator element does not choose the methods */
  a->req.set.method = a->methods[0];
  return 1;
}

/* The scene's folder name for ".../cornell-box/scene.xml", else the file name without ".xml". */
static void scene_name(const char *path, char *out, size_t size) {
  char buf[4096];
  snprintf(buf, sizeof buf, "%s", path);
  char *slash = strrchr(buf, '/'), *stem = buf;
  if (slash && strcmp(slash + 1, "scene.xml") == 0) {
    *slash = '\0';
    char *prev = strrchr(buf, '/');
    stem = prev ? prev + 1 : buf;
  } else {
    if (slash) stem = slash + 1;
    char *dot = strrchr(stem, '.');
    if (dot && dot != stem) *dot = '\0';
  }
  if (!*stem) stem = "scene";
  size_t n = strnlen(stem, size - 1); /* a long name is cut: it is only a chart title */
  memcpy(out, stem, n);
  out[n] = '\0';
}

static int make_dir(const char *dir, pc_err *e) {
  if (mkdir(dir, 0777) == 0) return PC_OK;
  struct stat st;
  if (errno == EEXIST && stat(dir, &st) == 0 && S_ISDIR(st.st_mode)) return PC_OK;
  return pc_errf(e, PC_EIO, "--out: cannot create folder %s: %s", dir, errno == EEXIST ? "a file is in the way" : strerror(errno));
}

static int reference_slots(const pc_exr_file *ref, const char *path, pc_study_ref *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  out->w = ref->w;
  out->h = ref->h;
  for (int i = 0; i < ref->nlayers; i++) {
    int slot = ref->names[i][0] ? pc_study_layer_parse(ref->names[i]) : PC_STUDY_BEAUTY;
    if (slot >= 0 && strcmp(ref->names[i], "beauty") != 0) out->rgb[slot] = ref->layers[i].rgb;
  }
  if (!out->rgb[PC_STUDY_BEAUTY]) return pc_errf(e, PC_EINVAL, "%s: the reference has no beauty R,G,B channels", path);
  return PC_OK;
}

/* A reference rendered with the study's seed shares its first iterations' samples with every
 * method of the same kind, so their early errors would be biased low: say so. */
static void warn_same_seed(const pc_exr_file *ref, const char *path, uint64_t seed) {
  char mine[32];
  snprintf(mine, sizeof mine, "%llu", (unsigned long long)seed);
  for (int i = 0; i < ref->nattrs; i++)
    if (strcmp(ref->attr_names[i], "pcbpt.seed") == 0 && strcmp(ref->attr_values[i], mine) == 0)
      fprintf(stderr, "pcbpt-coord study: warning: %s was rendered with seed %s too; use another --seed for one of them\n",
              path, mine);
}

/* Writes <dir>/<method>.exr and its PNG preview. */
static int write_images(const study_args *a, const pc_film *film, const pc_study_run *run, pc_err *e) {
  const char *name = pc_method_name(run->method);
  char exr[4096], png[4096];
  int n1 = snprintf(exr, sizeof exr, "%s/%s.exr", a->out, name), n2 = snprintf(png, sizeof png, "%s/%s.png", a->out, name);
  if (n1 < 0 || n2 < 0 || (size_t)n1 >= sizeof exr || (size_t)n2 >= sizeof png)
    return pc_errf(e, PC_EINVAL, "--out: path too long");
  const pc_study_snap *last = &run->snaps[run->nsnaps - 1];
  char version[64], seed[32];
  snprintf(version, sizeof version, "pcbpt %s", PCBPT_VERSION);
  snprintf(seed, sizeof seed, "%llu", (unsigned long long)a->req.set.seed);
  pc_exr_attr attrs[] = {
      {.name = "pcbpt.method", .type = PC_ATTR_STRING, .s = name},
      {.name = "pcbpt.iterations", .type = PC_ATTR_DOUBLE, .d = (double)last->iterations},
      {.name = "pcbpt.seed", .type = PC_ATTR_STRING, .s = seed},
      {.name = "pcbpt.max_depth", .type = PC_ATTR_DOUBLE, .d = a->req.set.max_depth},
      {.name = "pcbpt.render_seconds", .type = PC_ATTR_DOUBLE, .d = last->seconds},
      {.name = "pcbpt.rays", .type = PC_ATTR_DOUBLE, .d = (double)run->stats.rays},
      {.name = "pcbpt.scene", .type = PC_ATTR_STRING, .s = a->scene},
      {.name = "software", .type = PC_ATTR_STRING, .s = version},
  };
  int rc = pc_film_write_exr(film, exr, attrs, (int)(sizeof attrs / sizeof attrs[0]), e);
  if (rc != PC_OK) return rc;
  float *beauty = malloc((size_t)film->w * film->h * 3 * sizeof *beauty);
  if (!beauty) return pc_errf(e, PC_ENOMEM, "out of memory for the preview");
  pc_film_beauty(film, beauty);
  rc = pc_png_write_preview(png, film->w, film->h, beauty, 0, e);
  free(beauty);
  return rc;
}

/* Every method must be renderable before any budget is spent: an unimplemented one is an
 * error naming it, found in a second rather than after the other methods' renders. */
static int check_methods(const study_args *a, const pc_scene *scene, pc_err *e) {
  for (int m = 0; m < a->nmethods; m++) {
    pc_render_settings set = a->req.set;
    set.method = a->methods[m];
    pc_renderer *r = NULL;
    int rc = pc_renderer_create(scene, &set, (int)a->threads, &r, e);
    pc_renderer_destroy(r);
    if (rc != PC_OK) return rc;
  }
  return PC_OK;
}

static int run_study(study_args *a, pc_err *e) {
  pc_exr_file ref_file = {0};
  pc_scene scene = {0};
  pc_film film = {0};
  pc_study_run runs[PC_STUDY_MAX_METHODS] = {0};
  pc_study_ref ref;
  pc_render_request *req = &a->req;
  int nruns = 0;
  int rc = PC_OK;
  memset(&ref, 0, sizeof ref);
  ref.estimated = !a->reference;
  if (a->reference) rc = pc_exr_read_layers(a->reference, &ref_file, e);
  if (rc == PC_OK && a->reference) rc = reference_slots(&ref_file, a->reference, &ref, e);
  if (rc == PC_OK && !pc_study_ref_has(&ref, a->layer))
    rc = pc_errf(e, PC_EINVAL, "--layer: %s has no '%s' layer", a->reference, pc_study_layer_name(a->layer));
  if (rc == PC_OK) rc = pc_cli_load_scene("study", req, a->scene, &scene, e);
  if (rc == PC_OK) rc = pc_render_settings_check(&req->set, e);
  if (rc == PC_OK && ref.estimated) {
    ref.w = req->set.width;
    ref.h = req->set.height;
    printf("no --reference: every error below is estimated from the spread of each image's own iterations\n");
  }
  if (rc == PC_OK && (req->set.width != ref.w || req->set.height != ref.h))
    rc = pc_errf(e, PC_EINVAL, "--reference: %s is %dx%d but the study renders %dx%d (set --width/--height to match)",
                 a->reference, ref.w, ref.h, req->set.width, req->set.height);
  if (rc == PC_OK && a->reference) warn_same_seed(&ref_file, a->reference, req->set.seed);
  if (rc == PC_OK) rc = pc_scene_build(&scene, e);
  if (rc == PC_OK) rc = check_methods(a, &scene, e);
  if (rc == PC_OK) rc = make_dir(a->out, e);

  char name[256];
  scene_name(a->scene, name, sizeof name);
  for (int m = 0; rc == PC_OK && m < a->nmethods; m++) {
    pc_render_settings set = req->set;
    set.method = a->methods[m];
    rc = pc_film_init(&film, set.width, set.height, set.strategy_layers, e);
    if (rc == PC_OK) {
      nruns++;
      rc = pc_study_render(&scene, &set, (int)a->threads, a->seconds, (int)a->snapshots, &ref, &film, &runs[m], e);
    }
    if (rc == PC_OK) rc = write_images(a, &film, &runs[m], e);
    if (rc == PC_OK) {
      const pc_study_snap *last = &runs[m].snaps[runs[m].nsnaps - 1];
      printf("%s: %llu iterations in %.2f s on %d threads, %d snapshots, final beauty relMSE%s %.4e -> %s/%s.exr\n",
             pc_method_name(set.method), (unsigned long long)last->iterations, last->seconds, runs[m].threads,
             runs[m].nsnaps, ref.estimated ? " (estimated)" : "", last->m[PC_STUDY_BEAUTY].relmse, a->out,
             pc_method_name(set.method));
      fflush(stdout);
      if (film.dropped_nonfinite)
        fprintf(stderr, "pcbpt-coord study: warning: %s dropped %llu non-finite samples\n", pc_method_name(set.method),
                (unsigned long long)film.dropped_nonfinite);
    }
    pc_film_free(&film);
  }

  if (rc == PC_OK) {
    pc_study_table table;
    pc_study_table_build(runs, nruns, &ref, a->layer, a->target_error, &table);
    pc_study_info info = {.scene_path = a->scene, .scene_name = name, .reference_path = a->reference,
                          .seconds = a->seconds, .width = req->set.width, .height = req->set.height,
                          .max_snaps = (int)a->snapshots, .seed = req->set.seed};
    char path[4096];
    int n = snprintf(path, sizeof path, "%s/study.csv", a->out);
    rc = n > 0 && (size_t)n < sizeof path ? pc_study_write_csv(path, runs, nruns, &ref, e)
                                         : pc_errf(e, PC_EINVAL, "--out: path too long");
    if (rc == PC_OK) {
      snprintf(path, sizeof path, "%s/study.json", a->out);
      rc = pc_study_write_json(path, &info, runs, nruns, &ref, &table, e);
    }
    if (rc == PC_OK) rc = pc_study_write_chart(a->out, &info, runs, nruns, PC_STUDY_BEAUTY, e);
    if (rc == PC_OK && ref.rgb[1 + PC_LAYER_INNER])
      rc = pc_study_write_chart(a->out, &info, runs, nruns, 1 + PC_LAYER_INNER, e);
    if (rc == PC_OK) {
      printf("\n");
      if (ref.estimated) printf("relMSE estimated from each image's own iterations (no reference):\n");
      pc_study_table_print(stdout, &table);
      for (int m = 1; m < table.nmethods; m++) {
        char line[512];
        pc_study_headline(&table, m, line, sizeof line);
        printf("%s\n", line);
      }
    }
  }
  for (int m = 0; m < nruns; m++) pc_study_run_free(&runs[m]);
  pc_scene_free(&scene);
  pc_exr_file_free(&ref_file);
  return rc;
}

int pc_cmd_study(int argc, char **argv) {
  study_args a;
  pc_err e = {0};
  int r = parse_args(&a, argc, argv, &e);
  if (r == 0) return 0;
  if (r < 0) {
    fprintf(stderr, "pcbpt-coord study: %s\n", e.msg);
    return 2;
  }
  if (run_study(&a, &e) != PC_OK) {
    fprintf(stderr, "pcbpt-coord study: %s\n", e.msg[0] ? e.msg : pc_strerror(e.code));
    return 1;
  }
  return 0;
}
