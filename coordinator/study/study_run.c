/* study_run.c: one method of an equal-time study: renders one iteration at a time until the
 * render-time budget is spent and, at the snapshot times, measures the film against the
 * reference (or, without one, takes the film's own estimate of its error). Only the time inside pc_render_iterations counts as render time, so taking
 * snapshots does not eat into a method's budget. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "study.h"

static const char *const slot_names[PC_STUDY_NLAYERS] = {"beauty", "pt", "nee", "lt", "inner"};

const char *pc_study_layer_name(int slot) {
  return slot >= 0 && slot < PC_STUDY_NLAYERS ? slot_names[slot] : "?";
}

int pc_study_layer_parse(const char *name) {
  for (int i = 0; i < PC_STUDY_NLAYERS; i++)
    if (strcmp(name, slot_names[i]) == 0) return i;
  return -1;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double snapshot_time(double seconds, int k, int max_snaps) {
  if (max_snaps <= 1) return seconds;
  return seconds * pow(PC_STUDY_FIRST_FRACTION, (double)(max_snaps - 1 - k) / (max_snaps - 1));
}

/* The beauty's relMSE and RMSE as the film estimates them (NAN when it cannot tell). */
static void estimate(const pc_film *film, float *img, pc_metrics *m) {
  memset(m, 0, sizeof *m);
  m->l1 = NAN;
  if (!pc_film_relmse_estimate(film, &m->relmse) || !pc_film_variance(film, img)) {
    m->rmse = NAN;
    return;
  }
  size_t n = (size_t)film->w * film->h * 3;
  double v = 0;
  for (size_t i = 0; i < n; i++) v += img[i];
  m->rmse = sqrt(v / (double)n);
}

static int measure(const pc_film *film, const pc_study_ref *ref, float *img, pc_study_snap *snap, pc_err *e) {
  if (ref->estimated) {
    estimate(film, img, &snap->m[PC_STUDY_BEAUTY]);
    return PC_OK;
  }
  for (int slot = 0; slot < PC_STUDY_NLAYERS; slot++) {
    if (!ref->rgb[slot]) continue;
    if (slot == PC_STUDY_BEAUTY) pc_film_beauty(film, img);
    else pc_film_layer_image(film, slot - 1, img);
    int rc = pc_metrics_rgb(img, ref->rgb[slot], film->w, film->h, &snap->m[slot], e);
    if (rc != PC_OK) return rc;
  }
  return PC_OK;
}

static bool layer_is_empty(const pc_film *film, int layer) {
  size_t n = (size_t)film->w * film->h * 3;
  for (size_t i = 0; i < n; i++)
    if (film->layers[layer].sum[i] != 0) return false;
  return true;
}

int pc_study_render(const pc_scene *scene, const pc_render_settings *set, int threads, double seconds,
                    int max_snaps, const pc_study_ref *ref, pc_film *film, pc_study_run *run, pc_err *e) {
  memset(run, 0, sizeof *run);
  run->method = set->method;
  if (max_snaps < 1 || max_snaps > PC_STUDY_MAX_SNAPSHOTS || !(seconds > 0))
    return pc_errf(e, PC_EINVAL, "study: bad budget %g s or snapshot count %d", seconds, max_snaps);
  if (film->w != ref->w || film->h != ref->h)
    return pc_errf(e, PC_EINVAL, "study: film %dx%d and reference %dx%d differ", film->w, film->h, ref->w, ref->h);
  pc_renderer *rend = NULL;
  float *img = malloc((size_t)film->w * film->h * 3 * sizeof *img);
  run->snaps = calloc((size_t)max_snaps, sizeof *run->snaps);
  if (!img || !run->snaps) {
    free(img);
    return pc_errf(e, PC_ENOMEM, "study: out of memory for the snapshots");
  }
  int rc = pc_renderer_create(scene, set, threads, &rend, e);
  if (rc == PC_OK) run->threads = pc_renderer_threads(rend);
  double render_time = 0;
  uint64_t it = 0;
  int next = 0; /* next snapshot time index */
  while (rc == PC_OK && next < max_snaps) {
    double t0 = now_s();
    rc = pc_render_iterations(rend, it, 1, film, &run->stats, NULL, NULL, NULL, e);
    render_time += now_s() - t0;
    if (rc != PC_OK) break;
    it++;
    if (render_time < snapshot_time(seconds, next, max_snaps) || (ref->estimated && it < 2)) continue;
    while (next < max_snaps && render_time >= snapshot_time(seconds, next, max_snaps)) next++;
    pc_study_snap *s = &run->snaps[run->nsnaps++];
    s->seconds = render_time;
    s->iterations = it;
    rc = measure(film, ref, img, s, e);
  }
  if (rc == PC_OK)
    for (int slot = 1; slot < PC_STUDY_NLAYERS; slot++) run->layer_empty[slot] = layer_is_empty(film, slot - 1);
  pc_renderer_destroy(rend);
  free(img);
  return rc;
}

void pc_study_run_free(pc_study_run *run) {
  if (!run) return;
  free(run->snaps);
  run->snaps = NULL;
  run->nsnaps = 0;
}
