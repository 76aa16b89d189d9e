/* film_exr.c: writes a film as a multi-layer EXR: the beauty in R,G,B, every layer
 * normalized by its own count as <layer>.R/G/B (beauty_max as it is, the largest iteration), the per-pixel variance of the beauty's mean as
 * variance.R/G/B, and each layer's count (pcbpt.count.<layer>) and the estimated relMSE
 * (pcbpt.relmse_estimate) in the header, so a reader can recover the sums and knows the error;
 * and, when the film traced 2 or more iterations, the distribution of the per-iteration error
 * (pcbpt.iteration_error.*, film_trace.h). */
#include <stdio.h>
#include <string.h>
#include <stdlib.h>

#include "film.h"

/* What each layer of the file is made from, a band of rows at a time (pc_exr_write_rows): at
 * 3840x2160 the images in floats would be ~0.8 GB beside the film, their pages cleared by
 * the kernel at every checkpoint. */
enum { FROM_BEAUTY = -1, FROM_VARIANCE = -2 };
typedef struct film_bands {
  const pc_film *f;
  int n;
  int from[PC_FILM_MAX_LAYERS + 2]; /* a film layer, or FROM_* */
} film_bands;

static int fill_bands(void *user, int y0, int ny, float *const *rows, pc_err *e) {
  (void)e;
  const film_bands *b = user;
  for (int k = 0; k < b->n; k++) {
    if (b->from[k] == FROM_BEAUTY) pc_film_beauty_rows(b->f, y0, ny, rows[k]);
    else if (b->from[k] == FROM_VARIANCE) pc_film_variance_rows(b->f, y0, ny, rows[k]);
    else pc_film_layer_rows(b->f, b->from[k], y0, ny, rows[k]);
  }
  return PC_OK;
}

int pc_film_write_exr(const pc_film *f, const char *path, const pc_exr_attr *extra, int nextra, pc_err *e) {
  enum { ITER_ATTRS = 9 };
  pc_exr_attr *attrs = calloc((size_t)(f->nlayers + 2 + ITER_ATTRS + nextra), sizeof *attrs);
  char(*names)[40] = calloc((size_t)f->nlayers, sizeof *names);
  const char *layer_names[PC_FILM_MAX_LAYERS + 2];
  film_bands b = {.f = f};
  int rc;
  if (!attrs || !names) {
    rc = pc_errf(e, PC_ENOMEM, "%s: out of memory for the image", path);
    goto done;
  }
  layer_names[b.n] = "";
  b.from[b.n++] = FROM_BEAUTY;
  int na = 0;
  for (int i = 0; i < f->nlayers; i++) {
    snprintf(names[i], sizeof names[i], "pcbpt.count.%s", f->layers[i].name);
    attrs[na++] = (pc_exr_attr){.name = names[i], .type = PC_ATTR_DOUBLE, .d = (double)f->layers[i].count};
    if (f->layers[i].norm == PC_NORM_SQUARE) continue; /* a means to the variance, not an image */
    if (f->layers[i].norm == PC_NORM_MAX && !pc_film_max_complete(f)) continue; /* cannot tell */
    layer_names[b.n] = f->layers[i].name;
    b.from[b.n++] = i;
  }
  double relmse;
  if (pc_film_relmse_estimate(f, &relmse)) { /* known exactly when the variance is */
    layer_names[b.n] = "variance";
    b.from[b.n++] = FROM_VARIANCE;
    attrs[na++] = (pc_exr_attr){.name = "pcbpt.relmse_estimate", .type = PC_ATTR_DOUBLE, .d = relmse};
  }
  attrs[na++] = (pc_exr_attr){.name = "pcbpt.dropped_nonfinite", .type = PC_ATTR_DOUBLE, .d = (double)f->dropped_nonfinite};
  pc_iteration_errors ie;
  char tail[PC_TRACE_TAIL_MAX * 16 + 1] = "";
  if (pc_film_iteration_errors(f, &ie)) {
    static const char *names_ie[] = {"pcbpt.iteration_error.n",   "pcbpt.iteration_error.mean", "pcbpt.iteration_error.p50",
                                     "pcbpt.iteration_error.p90", "pcbpt.iteration_error.p99",  "pcbpt.iteration_error.max",
                                     "pcbpt.iteration_error.worst", "pcbpt.iteration_error.top1"};
    double v[] = {ie.n, ie.mean, ie.p50, ie.p90, ie.p99, ie.max, ie.worst, ie.top1};
    for (int i = 0; i < 8; i++) attrs[na++] = (pc_exr_attr){.name = names_ie[i], .type = PC_ATTR_DOUBLE, .d = v[i]};
    for (int i = 0; i < ie.ntail; i++) snprintf(tail + strlen(tail), sizeof tail - strlen(tail), i ? " %.6g" : "%.6g", ie.tail[i]);
    attrs[na++] = (pc_exr_attr){.name = "pcbpt.iteration_error.tail", .type = PC_ATTR_STRING, .s = tail};
  }
  for (int i = 0; i < nextra; i++) attrs[na++] = extra[i];
  rc = pc_exr_write_rows(path, f->w, f->h, layer_names, b.n, fill_bands, &b, attrs, na, e);
done:
  free(attrs);
  free(names);
  return rc;
}
