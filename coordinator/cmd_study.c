/* cmd_study.c: `pcbpt-coord study`: the equal-time study (DESIGN.md §6, docs/farm-study.md) on
 * a farm. Parses the flags; per scene loads the scene and its reference (given, rendered on
 * the farm first, or none: estimated errors), runs the study once per farm size and seed as a
 * group of interleaved farm jobs (study_farm.c), then writes the scene's images, study.csv,
 * study.json and the charts into its folder and prints the tables; last, the HTML report. */
#include <errno.h>
#include <math.h>
#include <unistd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "film.h"
#include "image.h"
#include "text_out.h"
#include "render_flags.h"
#include "cli_scene.h"
#include "scene.h"
#include "study.h"
#include "study_farm.h"
#include "study_report.h"
#include "verbs.h"
#include "coord.h"
#include "chart.h"
#include "bundle.h"

static const char study_help[] =
    "usage: pcbpt-coord study SCENE.xml [SCENE2.xml ...] --methods M1,M2,... --seconds S --out DIR [flags]\n"
    "Renders each SCENE with each method for S seconds on a farm (docs/farm-study.md): every method is\n"
    "a farm job of one study group, interleaved with the others in short slices on the same workers,\n"
    "each halting at the same S x workers worker-seconds. The coordinator keeps each job's merged film\n"
    "at logarithmically spaced worker-seconds (from 1/64 of the budget); the study fetches them and\n"
    "measures relMSE, RMSE and L1 against the reference for the beauty and every standard layer (pt,\n"
    "nee, lt, inner) present in it. Times are render seconds of the farm: summed worker-seconds / the\n"
    "number of workers (the time the farm would take rendering that method alone); the jobs' wall\n"
    "times are recorded too. Without --host the study runs on the embedded one-machine farm.\n"
    "Writes DIR/<scene>/: <method>.exr and .png, study.csv, study.json, study_beauty.png/.svg,\n"
    "study_inner.png/.svg, with --workers study_scaling.png/.svg, and DIR/report.html (every scene:\n"
    "charts, images side by side with the reference, a zoomed crop of the noisiest region, tables).\n"
    "Ratios are to the first method listed: put the method to compare against first.\n"
    "The strategy layers (pt, nee, lt, inner) are the shares of the image the method's MIS weights give\n"
    "each kind of strategy, so they compare only between images that weigh their strategies alike\n"
    "(the headers' pcbpt.weights): PT against a BDPT reference does not, nor PCBPT, whose inner\n"
    "strategies count 2 by default where BDPT's count 1 (--mis 1 weighs them alike). A method weighted\n"
    "unlike the reference is left out of those layers' comparisons (said before it renders), as one\n"
    "that leaves a layer empty is; the beauty always compares.\n"
    "Without a reference the beauty's relMSE and RMSE are each image's own estimates from the spread of\n"
    "its iterations (docs/variance.md; L1 and the other layers are not measured), and the output says so.\n\n"
    "  --methods LIST        comma-separated, from pt, lt, bdpt, cbdpt, pcbpt, pcbpt-kN (pcbpt with K=N),\n"
    "                        pcbpt-kN-rR (and --pcbpt-rate R), auto (each at most once, at most 8;\n"
    "                        auto: --method auto's pilot as farm jobs charged to its budget, then the\n"
    "                        winner for the rest; docs/auto.md)\n"
    "  --seconds S           render time per method on the farm (S x workers worker-seconds)\n"
    "  --reference REF.exr   reference image of the same size (its layers are compared by name); once\n"
    "                        per scene, in the scenes' order; without one, errors are estimated\n"
    "  --reference-render M:S  render each scene's reference first with method M for S seconds on the\n"
    "                        farm (another seed), kept as DIR/<scene>/reference-M-Ss.exr and reused\n"
    "  --out DIR             output folder (created if missing)\n"
    "  --host HOST[:PORT]    run on this coordinator's workers (default: the embedded farm)\n"
    "  --token-file F        the farm's token (with --host)\n"
    "  --runs N              N independent seeds per method (default 1): medians and spreads\n"
    "  --workers LIST        farm sizes to repeat the study on, e.g. 1,2 (default: every worker connected)\n"
    "  --threads N           embedded farm: render threads (default 0 = every core)\n"
    "  --snapshots K         points per curve (default 12)\n"
    "  --target-error E      target relMSE of the --layer comparison (default: the worst method's final)\n"
    "  --layer NAME          layer of the headline comparison: beauty (default), pt, nee, lt, inner\n"
    "Render flags (apply to every method; --method, --spp, --time and --halt-noise are not accepted):\n"
    "%s";

#define MAX_SCENES 16
#define MAX_SIZES 8

typedef struct study_args {
  pc_render_request req;
  const char *scenes[MAX_SCENES], *references[MAX_SCENES], *out, *host, *token;
  int nscenes, nreferences;
  pc_study_method methods[PC_STUDY_MAX_METHODS];
  int nmethods;
  double seconds, target_error;
  long long threads, snapshots, runs;
  int workers[MAX_SIZES], nsizes; /* farm sizes, ascending */
  pc_study_method ref_method;     /* --reference-render */
  double ref_seconds;             /* 0: none */
  int layer;
} study_args;

static int parse_methods(study_args *a, const char *list, pc_err *e) {
  char buf[256];
  if (strlen(list) >= sizeof buf) return pc_errf(e, PC_EINVAL, "--methods: list too long");
  strcpy(buf, list);
  a->nmethods = 0;
  char *save = NULL;
  for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
    if (a->nmethods == PC_STUDY_MAX_METHODS)
      return pc_errf(e, PC_EINVAL, "--methods: at most %d methods in one study", PC_STUDY_MAX_METHODS);
    pc_study_method m;
    pc_err me = {0};
    if (pc_study_method_parse(tok, &m, &me) != PC_OK) return pc_errf(e, PC_EINVAL, "--methods: %s", me.msg);
    for (int i = 0; i < a->nmethods; i++)
      if (strcmp(a->methods[i].name, m.name) == 0) return pc_errf(e, PC_EINVAL, "--methods: '%s' given twice", tok);
    a->methods[a->nmethods++] = m;
  }
  if (a->nmethods == 0) return pc_errf(e, PC_EINVAL, "--methods: empty list");
  return PC_OK;
}

/* "1,2,4": distinct sizes, kept ascending. */
static int parse_workers(study_args *a, const char *list, pc_err *e) {
  char buf[128];
  if (strlen(list) >= sizeof buf) return pc_errf(e, PC_EINVAL, "--workers: list too long");
  strcpy(buf, list);
  a->nsizes = 0;
  char *save = NULL;
  for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
    long long n;
    if (!pc_parse_i64(tok, 1, 100000, &n)) return pc_errf(e, PC_EINVAL, "--workers: '%s' is not a number of workers >= 1", tok);
    if (a->nsizes == MAX_SIZES) return pc_errf(e, PC_EINVAL, "--workers: at most %d farm sizes", MAX_SIZES);
    int k = a->nsizes++;
    while (k > 0 && a->workers[k - 1] > n) { a->workers[k] = a->workers[k - 1]; k--; }
    if (k > 0 && a->workers[k - 1] == n) return pc_errf(e, PC_EINVAL, "--workers: %lld given twice", n);
    a->workers[k] = (int)n;
  }
  if (!a->nsizes) return pc_errf(e, PC_EINVAL, "--workers: empty list");
  return PC_OK;
}

/* "bdpt:600" */
static int parse_reference_render(study_args *a, const char *v, pc_err *e) {
  char buf[64];
  const char *colon = strchr(v, ':');
  if (!colon || (size_t)(colon - v) >= sizeof buf)
    return pc_errf(e, PC_EINVAL, "--reference-render: '%s' is not METHOD:SECONDS", v);
  memcpy(buf, v, (size_t)(colon - v));
  buf[colon - v] = '\0';
  pc_err me = {0};
  if (pc_study_method_parse(buf, &a->ref_method, &me) != PC_OK) return pc_errf(e, PC_EINVAL, "--reference-render: %s", me.msg);
  if (!pc_parse_f64(colon + 1, 1e-3, 1e7, &a->ref_seconds))
    return pc_errf(e, PC_EINVAL, "--reference-render: '%s' is not a number of seconds > 0", colon + 1);
  return PC_OK;
}

/* 1: parsed, 0: --help printed, <0: error in e. */
static int parse_args(study_args *a, int argc, char **argv, pc_err *e) {
  memset(a, 0, sizeof *a);
  pc_render_request_default(&a->req);
  a->snapshots = 12;
  a->runs = 1;
  a->layer = PC_STUDY_BEAUTY;
  for (int i = 0; i < argc; i++) {
    const char *f = argv[i];
    const char *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (strcmp(f, "--method") == 0) return pc_errf(e, PC_EINVAL, "--method: a study takes --methods LIST");
    if (strcmp(f, "--spp") == 0 || strcmp(f, "--time") == 0 || strcmp(f, "--halt-noise") == 0)
      return pc_errf(e, PC_EINVAL, "%s: a study is bound by --seconds per method", f);
    int r = pc_render_flag_parse(&a->req, argc, argv, &i, e);
    if (r < 0) return r;
    if (r > 0) continue;
    if (strcmp(f, "--help") == 0 || strcmp(f, "-h") == 0) {
      printf(study_help, pc_render_flags_help);
      return 0;
    }
    static const char *const valued[] = {"--methods", "--seconds", "--reference", "--out", "--threads", "--snapshots",
                                         "--target-error", "--layer", "--host", "--token-file", "--runs", "--workers",
                                         "--reference-render"};
    bool takes_value = false;
    for (size_t k = 0; k < sizeof valued / sizeof valued[0]; k++) takes_value = takes_value || strcmp(f, valued[k]) == 0;
    if (takes_value && (!v || !*v)) return pc_errf(e, PC_EINVAL, "%s: missing value", f);
    if (takes_value) i++;
    int rc = PC_OK;
    if (strcmp(f, "--methods") == 0) {
      rc = parse_methods(a, v, e);
    } else if (strcmp(f, "--seconds") == 0) {
      if (!pc_parse_f64(v, 1e-3, 1e7, &a->seconds)) return pc_errf(e, PC_EINVAL, "--seconds: '%s' is not a number of seconds > 0", v);
    } else if (strcmp(f, "--reference") == 0) {
      if (a->nreferences == MAX_SCENES) return pc_errf(e, PC_EINVAL, "--reference: at most %d", MAX_SCENES);
      a->references[a->nreferences++] = v;
    } else if (strcmp(f, "--reference-render") == 0) {
      rc = parse_reference_render(a, v, e);
    } else if (strcmp(f, "--out") == 0) {
      a->out = v;
    } else if (strcmp(f, "--host") == 0) {
      a->host = v;
    } else if (strcmp(f, "--token-file") == 0) {
      a->token = v;
    } else if (strcmp(f, "--workers") == 0) {
      rc = parse_workers(a, v, e);
    } else if (strcmp(f, "--runs") == 0) {
      if (!pc_parse_i64(v, 1, PC_STUDY_MAX_RUNS, &a->runs)) return pc_errf(e, PC_EINVAL, "--runs: '%s' is not 1..%d", v, PC_STUDY_MAX_RUNS);
    } else if (strcmp(f, "--threads") == 0) {
      if (!pc_parse_i64(v, 0, 1024, &a->threads)) return pc_errf(e, PC_EINVAL, "--threads: '%s' is not 0..1024", v);
    } else if (strcmp(f, "--snapshots") == 0) {
      if (!pc_parse_i64(v, 1, PC_JOB_MAX_SNAPSHOTS, &a->snapshots))
        return pc_errf(e, PC_EINVAL, "--snapshots: '%s' is not 1..%d", v, PC_JOB_MAX_SNAPSHOTS);
    } else if (strcmp(f, "--target-error") == 0) {
      if (!pc_parse_f64(v, 1e-300, 1e300, &a->target_error)) return pc_errf(e, PC_EINVAL, "--target-error: '%s' is not a relMSE > 0", v);
    } else if (strcmp(f, "--layer") == 0) {
      if ((a->layer = pc_study_layer_parse(v)) < 0)
        return pc_errf(e, PC_EINVAL, "--layer: '%s' is not beauty, pt, nee, lt or inner", v);
    } else if (f[0] == '-') {
      return pc_errf(e, PC_EINVAL, "unknown flag '%s' (see --help)", f);
    } else if (a->nscenes == MAX_SCENES) {
      return pc_errf(e, PC_EINVAL, "'%s': at most %d scenes in one study", f, MAX_SCENES);
    } else {
      a->scenes[a->nscenes++] = f;
    }
    if (rc != PC_OK) return rc;
  }
  if (!a->nscenes) return pc_errf(e, PC_EINVAL, "missing SCENE.xml (see --help)");
  if (!a->nmethods) return pc_errf(e, PC_EINVAL, "--methods: required (e.g. --methods pcbpt,bdpt,pt)");
  if (!(a->seconds > 0)) return pc_errf(e, PC_EINVAL, "--seconds: required");
  if (a->nreferences && a->ref_seconds > 0)
    return pc_errf(e, PC_EINVAL, "--reference-render: not with --reference (one reference per scene)");
  if (a->nreferences && a->nreferences != a->nscenes)
    return pc_errf(e, PC_EINVAL, "--reference: %d given for %d scenes (one per scene, in order)", a->nreferences, a->nscenes);
  bool estimated = !a->nreferences && !(a->ref_seconds > 0);
  if (estimated && a->layer != PC_STUDY_BEAUTY)
    return pc_errf(e, PC_EINVAL, "--layer: only the beauty's error is estimated without a reference");
  if (!a->out) return pc_errf(e, PC_EINVAL, "--out: required");
  if (!a->host != !a->token) return pc_errf(e, PC_EINVAL, "%s: needs %s", a->host ? "--host" : "--token-file", a->host ? "--token-file" : "--host");
  if (!a->host && a->nsizes && (a->nsizes > 1 || a->workers[0] != 1))
    return pc_errf(e, PC_EINVAL, "--workers: the embedded farm has one worker (use --host for a farm)");
  if (a->host && a->threads) return pc_errf(e, PC_EINVAL, "--threads: the farm's workers choose their threads");
  a->req.method_set = true; /* the scene's integrator element does not choose the methods */
  a->req.set.method = a->methods[0].method == PC_METHOD_AUTO ? PC_METHOD_PCBPT : a->methods[0].method;
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
  out->weights = pc_exr_attr_get(ref, PC_WEIGHTS_ATTR);
  return PC_OK;
}

/* A reference rendered with the study's seed shares its first iterations' samples with every
 * method of the same kind, so their early errors would be biased low: say so. */
static void warn_same_seed(int fd, const pc_exr_file *ref, const char *path, uint64_t seed) {
  char mine[32];
  snprintf(mine, sizeof mine, "%llu", (unsigned long long)seed);
  const char *theirs = pc_exr_attr_get(ref, "pcbpt.seed");
  if (theirs && strcmp(theirs, mine) == 0)
    dprintf(fd, "pcbpt-coord study: warning: %s was rendered with seed %s too; use another --seed for one of them\n", path,
            mine);
}

/* Every method must be renderable before any budget is spent: an unimplemented one is an
 * error naming it, found in a second rather than after the other methods' renders. */
static int check_methods(const study_args *a, const pc_render_request *req, const pc_scene *scene, pc_err *e) {
  for (int m = 0; m <= a->nmethods; m++) {
    pc_render_settings set = req->set;
    if (m == a->nmethods && !(a->ref_seconds > 0)) break;
    const pc_study_method *sm = m < a->nmethods ? &a->methods[m] : &a->ref_method;
    pc_study_method_apply(sm, &set);
    if (set.method == PC_METHOD_AUTO) set.method = PC_METHOD_PCBPT; /* its candidates: bdpt and pcbpt */
    int rc = pc_renderer_check(scene, &set, e);
    if (rc != PC_OK) return rc;
  }
  return PC_OK;
}

/* What one scene's study holds while it runs and is written. */
typedef struct scene_study {
  char name[256], dir[4096];
  const char *path;
  pc_render_request req;
  uint8_t *blob, hash[PC_BUNDLE_HASH];
  size_t blob_n;
  pc_exr_file ref_file;
  char ref_path[4096];
  pc_study_ref ref;
  /* runs[size][run][method] */
  pc_study_run *runs;
  bool shares_chart; /* study_shares.svg was written */
  bool iterations_chart; /* study_iterations.svg was written */
} scene_study;

static pc_study_run *run_at(const study_args *a, scene_study *s, int size, int run, int m) {
  return &s->runs[((size_t)size * (size_t)a->runs + (size_t)run) * (size_t)a->nmethods + (size_t)m];
}

/* Seeds: run r of the study uses seed + r; the reference render a seed no run uses. */
static uint64_t run_seed(const study_args *a, int r) { return a->req.set.seed + (uint64_t)r; }

/* How a reference is of something else than the study renders (pc_image_kind_differs). */
static void reference_differs(const pc_exr_file *ref, const scene_study *s, char *why, size_t n) {
  char bundle[2 * PC_BUNDLE_HASH + 1], defines[PC_SCENE_DEFINES_TEXT];
  pc_bundle_hex(s->hash, bundle);
  pc_scene_defines_text(&s->req.set.defines, defines, sizeof defines);
  pc_image_kind theirs = pc_image_kind_exr(ref), mine = {s->req.set.max_depth, bundle, defines};
  pc_image_kind_differs(&theirs, &mine, why, n);
}

/* Before any budget is spent: the methods whose strategy layers the reference weighs otherwise
 * (auto's image is told from its header when it is done: its pilot's films are in it). */
static void say_unlike(const study_args *a, const scene_study *s) {
  for (int m = 0; m < a->nmethods; m++) {
    if (a->methods[m].method == PC_METHOD_AUTO) continue;
    pc_render_settings set = s->req.set;
    pc_study_method_apply(&a->methods[m], &set);
    char w[96], shown[256];
    pc_render_settings_weights(&set, w, sizeof w);
    if (!pc_weights_unlike(w, s->ref.weights)) continue;
    bool inner_count = set.method == PC_METHOD_PCBPT || set.method == PC_METHOD_CBDPT;
    printf("%s: %s weighs its strategies unlike the reference (%s against %s): its pt, nee, lt and inner layers are "
           "left out of those layers' comparisons, the beauty compares%s\n",
           s->name, a->methods[m].name, w, pc_text_printable(s->ref.weights, shown, sizeof shown),
           inner_count ? " (--mis sets the count PCBPT's inner strategies carry; BDPT's is 1)" : "");
  }
}

static int load_reference(const study_args *a, pc_study_farm *farm, scene_study *s, int k, int farm_size, pc_err *e) {
  const char *path = NULL;
  if (a->nreferences) {
    path = a->references[k];
  } else if (a->ref_seconds > 0) {
    int n = snprintf(s->ref_path, sizeof s->ref_path, "%s/reference-%s-%gs.exr", s->dir, a->ref_method.name,
                     a->ref_seconds);
    if (n < 0 || (size_t)n >= sizeof s->ref_path) return pc_errf(e, PC_EINVAL, "--out: path too long");
    path = s->ref_path;
    /* A kept reference of another scene, -D or max depth (the study's earlier run with other
     * flags, or the scene edited since) is rendered again, not reused. */
    pc_exr_file kept = {0};
    pc_err ignored = {0};
    char why[1024] = "";
    bool reuse = access(path, R_OK) == 0 && pc_exr_read_beauty_attrs(path, &kept, &ignored) == PC_OK;
    if (reuse) reference_differs(&kept, s, why, sizeof why);
    pc_exr_file_free(&kept);
    if (reuse && why[0]) {
      dprintf(farm->log_fd, "%s: the kept reference %s is of something else than the study renders (%s): rendering it again\n",
              s->name, path, why);
      reuse = false;
    }
    if (reuse) {
      dprintf(farm->log_fd, "%s: reusing the reference %s\n", s->name, path);
    } else {
      pc_study_run run = {0};
      char label[300];
      snprintf(label, sizeof label, "%s reference", s->name);
      pc_study_group g = {.scene_path = s->path, .blob = s->blob, .hash = s->hash, .blob_n = s->blob_n, .req = &s->req,
                          .methods = &a->ref_method, .nmethods = 1, .seed = a->req.set.seed + 0x5eed0000u,
                          .seconds = a->ref_seconds, .workers = farm_size, .keep_dir = s->dir, .keep_path = path,
                          .label = label};
      dprintf(farm->log_fd, "%s: rendering the reference (%s, %g s on %d worker%s)\n", s->name,
              a->ref_method.name, a->ref_seconds, farm_size, farm_size > 1 ? "s" : "");
      int rc = pc_study_farm_group(farm, &g, &run, e);
      pc_study_run_free(&run);
      if (rc) return rc;
    }
  }
  memset(&s->ref, 0, sizeof s->ref);
  if (!path) {
    s->ref.estimated = true;
    s->ref.w = s->req.set.width;
    s->ref.h = s->req.set.height;
    printf("%s: no reference: every error below is estimated from the spread of each image's own iterations\n", s->name);
    return PC_OK;
  }
  int rc = pc_exr_read_layers(path, &s->ref_file, e);
  if (!rc) rc = reference_slots(&s->ref_file, path, &s->ref, e);
  if (!rc && !pc_study_ref_has(&s->ref, a->layer))
    rc = pc_errf(e, PC_EINVAL, "--layer: %s has no '%s' layer", path, pc_study_layer_name(a->layer));
  if (!rc && (s->req.set.width != s->ref.w || s->req.set.height != s->ref.h))
    rc = pc_errf(e, PC_EINVAL, "reference %s is %dx%d but the study renders %dx%d (set --width/--height to match)", path,
                 s->ref.w, s->ref.h, s->req.set.width, s->req.set.height);
  /* the embedded farm's log has stderr meanwhile: the warnings go where the user reads */
  for (int r = 0; !rc && r < a->runs; r++) warn_same_seed(farm->log_fd, &s->ref_file, path, run_seed(a, r));
  char why[1024];
  if (!rc) reference_differs(&s->ref_file, s, why, sizeof why);
  if (!rc && why[0])
    dprintf(farm->log_fd, "pcbpt-coord study: warning: %s is of something else than the study renders (%s): the errors measured "
            "compare different images\n", path, why);
  if (!rc) say_unlike(a, s);
  snprintf(s->ref_path, sizeof s->ref_path, "%s", path);
  return rc;
}

static int scene_path_join(char *out, size_t n, const char *dir, const char *leaf, pc_err *e) {
  int k = snprintf(out, n, "%s/%s", dir, leaf);
  return k < 0 || (size_t)k >= n ? pc_errf(e, PC_EINVAL, "--out: path too long") : PC_OK;
}

static void print_spread(FILE *f, const study_args *a, const scene_study *s, int size, const pc_study_table *t) {
  fprintf(f, "over %lld run%s on %d worker%s (median [min..max]; time = farm render seconds; final = at the budget):\n", a->runs,
          a->runs > 1 ? "s" : "", a->workers[size], a->workers[size] > 1 ? "s" : "");
  fprintf(f, "%-7s %-6s %30s %34s %24s\n", "layer", "method", "final relMSE", "time to target", "time ratio per run");
  for (int row = 0; row < t->nlayers; row++)
    for (int m = 0; m < a->nmethods; m++) {
      pc_study_run runs[PC_STUDY_MAX_RUNS], first[PC_STUDY_MAX_RUNS];
      for (int r = 0; r < a->runs; r++) {
        runs[r] = *run_at(a, (scene_study *)s, size, r, m);
        first[r] = *run_at(a, (scene_study *)s, size, r, 0);
      }
      pc_study_spread c;
      pc_study_spread_cell(runs, (int)a->runs, first, t->slot[row], t->target[row], false, a->seconds, &c);
      if (pc_study_excluded(&runs[0], t->slot[row])) {
        fprintf(f, "%-7s %-6s  (%s)\n", pc_study_layer_name(t->slot[row]), a->methods[m].name,
                runs[0].layer_empty[t->slot[row]] ? "layer empty" : "weighted unlike the reference");
        continue;
      }
      char fin[64], tim[64], rat[64] = "-";
      snprintf(fin, sizeof fin, "%.4e [%.3g..%.3g]", c.final_med, c.final_lo, c.final_hi);
      if (c.reached) snprintf(tim, sizeof tim, "%.3g s [%.3g..%.3g] %d/%d", c.time_med, c.time_lo, c.time_hi, c.reached, c.n);
      else snprintf(tim, sizeof tim, "not reached");
      if (isfinite(c.ratio_med)) snprintf(rat, sizeof rat, "%.2fx [%.2f..%.2f]", c.ratio_med, c.ratio_lo, c.ratio_hi);
      fprintf(f, "%-7s %-6s %30s %34s %24s\n", pc_study_layer_name(t->slot[row]), a->methods[m].name, fin, tim, rat);
    }
}

/* Lost slices: what the figures say about workers that went away. */
static void print_reruns(FILE *f, const study_args *a, scene_study *s) {
  for (int size = 0; size < a->nsizes; size++)
    for (int r = 0; r < a->runs; r++)
      for (int m = 0; m < a->nmethods; m++) {
        const pc_study_run *run = run_at(a, s, size, r, m);
        if (run->ranges_rerun)
          fprintf(f, "%s, run %d on %d workers: %u range%s re-run after a worker went away; only the merged uploads' "
                     "worker-seconds count, so the lost slice is not charged to the method (its wall time is)\n",
                  run->method.name, r + 1, a->workers[size], run->ranges_rerun, run->ranges_rerun > 1 ? "s" : "");
      }
}

/* Heavy tails of every run's final image on the largest farm (study.h, docs/variance.md). */
static void print_tails(FILE *f, const study_args *a, scene_study *s, int big) {
  fprintf(f, "heavy tails of the final images: per pixel brighter than %g of the image mean, its largest single "
             "iteration / its mean (1: every iteration alike; N: one iteration carried the pixel)\n",
          PC_STUDY_TAILS_LIT);
  fprintf(f, "%-10s %4s %10s %8s %10s %10s %10s  %s\n", "method", "run", "N", "pixels", "p50", "p99", "max", "at");
  for (int r = 0; r < a->runs; r++)
    for (int m = 0; m < a->nmethods; m++) {
      const pc_study_run *run = run_at(a, s, big, r, m);
      const pc_study_tails *t = &run->tails;
      if (!t->known) {
        fprintf(f, "%-10s %4d  (cannot tell: the image has no beauty_max over all its iterations)\n", run->method.name, r + 1);
        continue;
      }
      fprintf(f, "%-10s %4d %10llu %8zu %10.3g %10.3g %10.3g  (%d, %d)\n", run->method.name, r + 1,
              (unsigned long long)t->iterations, t->pixels, t->p50, t->p99, t->max, t->max_x, t->max_y);
    }
  fprintf(f, "error of each iteration: its image's relMSE against the final image over a %dx%d grid of blocks, of the "
             "first %u iterations; top 1%%: the share of their summed error its worst 1%% carry (1%%: all alike)\n",
          PC_TRACE_GRID, PC_TRACE_GRID, PC_TRACE_ITERATIONS);
  fprintf(f, "%-10s %4s %8s %10s %10s %10s %10s %9s %8s %10s\n", "method", "run", "n", "mean", "p50", "p99", "max",
          "max/mean", "top 1%", "worst");
  for (int r = 0; r < a->runs; r++)
    for (int m = 0; m < a->nmethods; m++) {
      const pc_study_run *run = run_at(a, s, big, r, m);
      const pc_iteration_errors *ie = &run->tails.iter;
      if (!run->tails.iter_known) {
        fprintf(f, "%-10s %4d  (cannot tell: the image traced fewer than 2 iterations)\n", run->method.name, r + 1);
        continue;
      }
      fprintf(f, "%-10s %4d %8u %10.3g %10.3g %10.3g %10.3g %9.3g %7.1f%% %10u\n", run->method.name, r + 1, ie->n,
              ie->mean, ie->p50, ie->p99, ie->max, ie->mean > 0 ? ie->max / ie->mean : NAN, 100 * ie->top1, ie->worst);
    }
}

/* Which strategies carry every run's final image on the largest farm (study.h). */
static void print_shares(FILE *f, const study_args *a, scene_study *s, int big) {
  fprintf(f, "strategies carrying the final images: share of the mean luminance (pt: emitter hits, nee: s=1, "
             "lt: t=1, inner: s,t>=2)\n");
  fprintf(f, "%-10s %4s %8s %8s %8s %8s\n", "method", "run", "pt", "nee", "lt", "inner");
  for (int r = 0; r < a->runs; r++)
    for (int m = 0; m < a->nmethods; m++) {
      const pc_study_run *run = run_at(a, s, big, r, m);
      const pc_study_shares *sh = &run->shares;
      if (!sh->known) {
        fprintf(f, "%-10s %4d  (cannot tell: the image is black or lacks a strategy layer)\n", run->method.name, r + 1);
        continue;
      }
      fprintf(f, "%-10s %4d %8.3f %8.3f %8.3f %8.3f\n", run->method.name, r + 1, sh->share[PC_LAYER_PT],
              sh->share[PC_LAYER_NEE], sh->share[PC_LAYER_LT], sh->share[PC_LAYER_INNER]);
    }
}

/* The scaling summary: per method, wall time to the same error at each farm size. */
static int scaling(const study_args *a, scene_study *s, FILE *f, pc_err *e) {
  int slot = a->layer;
  pc_chart_series series[PC_STUDY_MAX_METHODS * MAX_SIZES];
  pc_study_run med[PC_STUDY_MAX_METHODS * MAX_SIZES];
  pc_study_band band[PC_STUDY_MAX_METHODS * MAX_SIZES][PC_STUDY_NLAYERS];
  char names[PC_STUDY_MAX_METHODS * MAX_SIZES][64];
  int ns = 0, rc = PC_OK;
  memset(med, 0, sizeof med);
  memset(band, 0, sizeof band);
  fprintf(f, "scaling (%s relMSE, wall time of the jobs, median of %lld run%s):\n", pc_study_layer_name(slot), a->runs,
          a->runs > 1 ? "s" : "");
  for (int m = 0; m < a->nmethods && !rc; m++) {
    pc_study_run per[MAX_SIZES][PC_STUDY_MAX_RUNS];
    double target = -INFINITY;
    for (int size = 0; size < a->nsizes; size++) {
      double fin[PC_STUDY_MAX_RUNS];
      for (int r = 0; r < a->runs; r++) {
        per[size][r] = *run_at(a, s, size, r, m);
        fin[r] = per[size][r].nsnaps ? per[size][r].snaps[per[size][r].nsnaps - 1].m[slot].relmse : NAN;
      }
      double fm = pc_study_median(fin, (int)a->runs, NULL, NULL);
      if (isfinite(fm)) target = fmax(target, fm);
    }
    if (pc_study_excluded(&per[0][0], slot)) continue;
    double t_base = NAN;
    for (int size = 0; size < a->nsizes; size++) {
      pc_study_spread c;
      pc_study_spread_cell(per[size], (int)a->runs, per[0], slot, target, true, 0, &c);
      if (size == 0) t_base = c.time_med;
      /* why a speed-up falls short: workers idle (busy < size) or slower per second (it/ws) */
      double busy[PC_STUDY_MAX_RUNS], speed[PC_STUDY_MAX_RUNS];
      for (int r = 0; r < a->runs; r++) {
        double ws = 0;
        for (int k = 0; k < a->nmethods; k++) {
          const pc_study_run *o = run_at(a, s, size, r, k);
          if (o->nsnaps) ws += o->snaps[o->nsnaps - 1].worker_seconds;
        }
        const pc_study_run *o = &per[size][r];
        busy[r] = o->group_wall > 0 ? ws / o->group_wall : NAN;
        speed[r] = o->nsnaps ? (double)o->snaps[o->nsnaps - 1].iterations / o->snaps[o->nsnaps - 1].worker_seconds : NAN;
      }
      double busy_med = pc_study_median(busy, (int)a->runs, NULL, NULL), speed_med = pc_study_median(speed, (int)a->runs, NULL, NULL);
      fprintf(f, "  %-6s %3d worker%s: %.3g s [%.3g..%.3g] to relMSE %.3g; vs %d worker%s %.2fx (ideal %.2fx), speed-up %.2fx; "
                 "%.2f workers busy, %.3g iterations per worker-second\n",
              a->methods[m].name, a->workers[size], a->workers[size] > 1 ? "s" : " ", c.time_med, c.time_lo,
              c.time_hi, target, a->workers[0], a->workers[0] > 1 ? "s" : "", c.time_med / t_base,
              (double)a->workers[0] / a->workers[size], t_base / c.time_med, busy_med, speed_med);
      double t_end = 0;
      for (int r = 0; r < a->runs; r++)
        if (per[size][r].nsnaps) t_end = fmax(t_end, per[size][r].snaps[per[size][r].nsnaps - 1].wall);
      rc = pc_study_median_run(per[size], (int)a->runs, 2 * (int)a->snapshots, t_end, true, &med[ns], band[ns], e);
      if (rc) break;
      for (int i = 0; i < med[ns].nsnaps; i++) med[ns].snaps[i].wall = med[ns].snaps[i].seconds;
      snprintf(names[ns], sizeof names[ns], "%s, %d worker%s", a->methods[m].name, a->workers[size],
               a->workers[size] > 1 ? "s" : "");
      double *x = malloc((size_t)(med[ns].nsnaps + 1) * 2 * sizeof *x);
      if (!x) { rc = pc_errf(e, PC_ENOMEM, "out of memory for the chart"); ns++; break; }
      for (int i = 0; i < med[ns].nsnaps; i++) {
        x[i] = med[ns].snaps[i].seconds;
        x[med[ns].nsnaps + i] = med[ns].snaps[i].m[slot].relmse;
      }
      series[ns] = (pc_chart_series){.name = names[ns], .x = x, .y = x + med[ns].nsnaps, .n = med[ns].nsnaps,
                                     .lo = a->runs > 1 ? band[ns][slot].lo : NULL, .hi = a->runs > 1 ? band[ns][slot].hi : NULL};
      ns++;
    }
  }
  char title[512], path[4096];
  snprintf(title, sizeof title, "%s: %s relMSE against wall time per farm size", s->name, pc_study_layer_name(slot));
  pc_chart c = {.title = title, .x_label = "wall time of the job (s)", .y_label = s->ref.estimated ? "estimated relMSE" : "relMSE",
                .width = 800, .height = 560, .series = series, .nseries = ns};
  for (int k = 0; k < 2 && !rc; k++) {
    rc = scene_path_join(path, sizeof path, s->dir, k ? "study_scaling.svg" : "study_scaling.png", e);
    if (!rc) rc = k ? pc_chart_write_svg(&c, path, e) : pc_chart_write_png(&c, path, e);
  }
  for (int i = 0; i < ns; i++) {
    free((void *)series[i].x);
    pc_study_run_free(&med[i]);
    pc_study_band_free(band[i]);
  }
  return rc;
}

/* Summarises the runs of the largest farm size (the median curves go through the one-run
 * table), writes the scene's files and prints its tables to f. */
static int write_scene(const study_args *a, scene_study *s, FILE *f, pc_err *e) {
  int big = a->nsizes - 1, rc = PC_OK;
  pc_study_run med[PC_STUDY_MAX_METHODS];
  pc_study_band band[PC_STUDY_MAX_METHODS][PC_STUDY_NLAYERS];
  memset(med, 0, sizeof med);
  memset(band, 0, sizeof band);
  for (int m = 0; m < a->nmethods && !rc; m++) {
    pc_study_run per[PC_STUDY_MAX_RUNS];
    for (int r = 0; r < a->runs; r++) per[r] = *run_at(a, s, big, r, m);
    rc = pc_study_median_run(per, (int)a->runs, 2 * (int)a->snapshots, a->seconds, false, &med[m], band[m], e);
  }
  pc_study_table table;
  if (!rc) pc_study_table_build(med, a->nmethods, &s->ref, a->layer, a->target_error, &table);
  pc_study_info info = {.scene_path = s->path, .scene_name = s->name, .reference_path = s->ref.estimated ? NULL : s->ref_path,
                        .seconds = a->seconds, .width = s->req.set.width, .height = s->req.set.height,
                        .max_snaps = (int)a->snapshots, .seed = a->req.set.seed, .workers = a->workers[big],
                        .runs = (int)a->runs, .host = a->host};
  char path[4096];
  size_t nall = (size_t)a->nsizes * (size_t)a->runs * (size_t)a->nmethods;
  if (!rc) rc = scene_path_join(path, sizeof path, s->dir, "study.csv", e);
  if (!rc) rc = pc_study_write_csv(path, s->runs, (int)nall, &s->ref, e);
  if (!rc) rc = scene_path_join(path, sizeof path, s->dir, "study.json", e);
  if (!rc) rc = pc_study_write_json(path, &info, s->runs, (int)nall, &s->ref, &table, e);
  const pc_study_band *bands[PC_STUDY_MAX_METHODS];
  for (int m = 0; m < a->nmethods; m++) bands[m] = a->runs > 1 ? band[m] : NULL;
  if (!rc) rc = pc_study_write_chart(s->dir, &info, med, a->nmethods, PC_STUDY_BEAUTY, bands, e);
  if (!rc && s->ref.rgb[1 + PC_LAYER_INNER]) rc = pc_study_write_chart(s->dir, &info, med, a->nmethods, 1 + PC_LAYER_INNER, bands, e);
  if (!rc) rc = pc_study_write_shares_chart(s->dir, &info, run_at(a, s, big, 0, 0), a->nmethods, &s->shares_chart, e);
  if (!rc) rc = pc_study_write_iterations_chart(s->dir, &info, run_at(a, s, big, 0, 0), a->nmethods, &s->iterations_chart, e);
  if (!rc) {
    fprintf(f, "%s (%s), %d worker%s, %lld run%s, %g s per method:\n", s->name, s->path, a->workers[big],
            a->workers[big] > 1 ? "s" : "", a->runs, a->runs > 1 ? "s" : "", a->seconds);
    if (s->ref.estimated) fprintf(f, "relMSE estimated from each image's own iterations (no reference):\n");
    if (a->runs > 1) fprintf(f, "median curves:\n");
    pc_study_table_print(f, &table);
    for (int m = 1; m < table.nmethods; m++) {
      char line[512];
      pc_study_headline(&table, m, line, sizeof line);
      fprintf(f, "%s%s\n", line, a->runs > 1 ? " (median curves)" : "");
    }
    if (a->runs > 1) {
      fprintf(f, "\n");
      print_spread(f, a, s, big, &table);
    }
    print_reruns(f, a, s);
    fprintf(f, "\n");
    print_tails(f, a, s, big);
    print_shares(f, a, s, big);
  }
  if (!rc && a->nsizes > 1) {
    fprintf(f, "\n");
    rc = scaling(a, s, f, e);
  }
  for (int m = 0; m < a->nmethods; m++) {
    pc_study_run_free(&med[m]);
    pc_study_band_free(band[m]);
  }
  return rc;
}

static void scene_free(const study_args *a, scene_study *s) {
  if (s->runs)
    for (size_t i = 0; i < (size_t)a->nsizes * (size_t)a->runs * (size_t)a->nmethods; i++) pc_study_run_free(&s->runs[i]);
  free(s->runs);
  free(s->blob);
  pc_exr_file_free(&s->ref_file);
}

static int study_scene(const study_args *a, pc_study_farm *farm, int k, pc_report *report, pc_err *e) {
  scene_study s;
  memset(&s, 0, sizeof s);
  s.path = a->scenes[k];
  s.req = a->req;
  scene_name(s.path, s.name, sizeof s.name);
  pc_scene scene = {0};
  int rc = pc_cli_load_scene("study", &s.req, s.path, &scene, e);
  if (!rc) rc = pc_cli_scene_bundle(&scene, &s.blob, &s.blob_n, s.hash, e);
  if (!rc) rc = pc_render_settings_check(&s.req.set, e);
  if (!rc) rc = pc_scene_check(&scene, e);
  if (!rc) rc = check_methods(a, &s.req, &scene, e);
  pc_scene_free(&scene);
  int n = snprintf(s.dir, sizeof s.dir, "%s/%s", a->out, s.name);
  if (!rc && (n < 0 || (size_t)n >= sizeof s.dir)) rc = pc_errf(e, PC_EINVAL, "--out: path too long");
  if (!rc) rc = make_dir(s.dir, e);
  if (!rc) rc = load_reference(a, farm, &s, k, a->workers[a->nsizes - 1], e);
  if (!rc && !(s.runs = calloc((size_t)a->nsizes * (size_t)a->runs * (size_t)a->nmethods, sizeof *s.runs)))
    rc = pc_errf(e, PC_ENOMEM, "out of memory");
  for (int size = 0; !rc && size < a->nsizes; size++)
    for (int r = 0; !rc && r < a->runs; r++) {
      char label[400];
      snprintf(label, sizeof label, "%s run %d/%lld, %d worker%s", s.name, r + 1, a->runs, a->workers[size],
               a->workers[size] > 1 ? "s" : "");
      dprintf(farm->log_fd, "%s: %d methods interleaved, %g s each (%g worker-seconds)\n", label, a->nmethods, a->seconds,
              a->seconds * a->workers[size]);
      pc_study_group g = {.scene_path = s.path, .blob = s.blob, .hash = s.hash, .blob_n = s.blob_n, .req = &s.req,
                          .methods = a->methods, .nmethods = a->nmethods, .seed = run_seed(a, r), .seconds = a->seconds,
                          .workers = a->workers[size], .snapshots = (int)a->snapshots - 1, .ref = &s.ref,
                          .keep_dir = size == a->nsizes - 1 && r == 0 ? s.dir : NULL, .work_dir = s.dir,
                          .label = label};
      rc = pc_study_farm_group(farm, &g, run_at(a, &s, size, r, 0), e);
      for (int m = 0; !rc && m < a->nmethods; m++) run_at(a, &s, size, r, m)->run = r;
    }
  char *text = NULL;
  size_t text_n = 0;
  FILE *mem = rc ? NULL : open_memstream(&text, &text_n);
  if (!rc && !mem) rc = pc_errf(e, PC_ENOMEM, "out of memory for the tables");
  if (!rc) rc = write_scene(a, &s, mem, e);
  if (mem) fclose(mem);
  if (!rc) {
    fputs("\n", stdout);
    fputs(text, stdout);
    fflush(stdout);
    pc_report_scene sc = {.name = s.name, .path = s.path, .dir = s.dir, .tables = text,
                          .reference = s.ref.estimated ? NULL : s.ref.rgb[PC_STUDY_BEAUTY], .w = s.ref.w, .h = s.ref.h,
                          .methods = a->methods, .nmethods = a->nmethods, .scaling = a->nsizes > 1,
                          .inner = s.ref.rgb[1 + PC_LAYER_INNER] != NULL, .shares = s.shares_chart,
                          .iterations = s.iterations_chart};
    rc = pc_report_add_scene(report, &sc, e);
  }
  free(text);
  scene_free(a, &s);
  return rc;
}

/* Every scene loads, its methods can render and its given reference fits, before any folder
 * is made or budget spent. */
static int precheck(const study_args *a, pc_err *e) {
  for (int k = 0; k < a->nscenes; k++) {
    pc_render_request req = a->req;
    pc_scene scene = {0};
    int rc = pc_cli_load_scene("study", &req, a->scenes[k], &scene, e);
    if (!rc) rc = pc_render_settings_check(&req.set, e);
    if (!rc) rc = pc_scene_check(&scene, e);
    if (!rc) rc = check_methods(a, &req, &scene, e);
    for (int m = 0; !rc && m < a->nmethods; m++) pc_cli_warn_method("study", a->scenes[k], a->methods[m].method, &req);
    if (!rc) pc_cli_warn_backs("study", &scene);
    pc_scene_free(&scene);
    if (!rc && a->nreferences) {
      pc_exr_file ref = {0};
      pc_study_ref slots;
      rc = pc_exr_read_layers(a->references[k], &ref, e);
      if (!rc) rc = reference_slots(&ref, a->references[k], &slots, e);
      if (!rc && !pc_study_ref_has(&slots, a->layer))
        rc = pc_errf(e, PC_EINVAL, "--layer: %s has no '%s' layer", a->references[k], pc_study_layer_name(a->layer));
      if (!rc && (req.set.width != ref.w || req.set.height != ref.h))
        rc = pc_errf(e, PC_EINVAL, "reference %s is %dx%d but the study renders %dx%d (set --width/--height to match)",
                     a->references[k], ref.w, ref.h, req.set.width, req.set.height);
      pc_exr_file_free(&ref);
    }
    if (rc) return rc;
  }
  return PC_OK;
}

static int run_study(study_args *a, pc_err *e) {
  pc_study_farm farm;
  pc_report report;
  int rc = precheck(a, e);
  if (!rc) rc = make_dir(a->out, e);
  if (rc) return rc;
  rc = pc_study_farm_open(&farm, a->host, a->token, (int)a->threads, e);
  if (rc) return rc;
  int nworkers = 0;
  rc = pc_study_farm_workers(&farm, &nworkers, e);
  if (!rc && !a->nsizes) {
    if (nworkers < 1) rc = pc_errf(e, PC_EINVAL, "--host: the farm has no worker connected");
    a->workers[a->nsizes++] = nworkers;
  }
  if (!rc && a->workers[a->nsizes - 1] > nworkers)
    rc = pc_errf(e, PC_EINVAL, "--workers: %d asked for, the farm has %d connected", a->workers[a->nsizes - 1], nworkers);
  char path[4096];
  if (!rc) rc = scene_path_join(path, sizeof path, a->out, "report.html", e);
  if (!rc) rc = pc_report_begin(&report, path, e);
  for (int k = 0; !rc && k < a->nscenes; k++) rc = study_scene(a, &farm, k, &report, e);
  if (!rc) rc = pc_report_end(&report, e);
  else pc_report_abandon(&report);
  if (!rc) printf("\nreport: %s\n", path);
  pc_study_farm_close(&farm);
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
