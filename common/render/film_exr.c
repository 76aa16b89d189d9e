/* film_exr.c: writes a film as a multi-layer EXR: the beauty in R,G,B, every layer
 * normalized by its own count as <layer>.R/G/B (beauty_max as it is, the largest iteration), the per-pixel variance of the beauty's mean as
 * variance.R/G/B, and each layer's count (pcbpt.count.<layer>) and the estimated relMSE
 * (pcbpt.relmse_estimate) in the header, so a reader can recover the sums and knows the error;
 * and, when the film traced 2 or more iterations, the distribution of the per-iteration error
 * (pcbpt.iteration_error.*, film_trace.h). */
#include <stdio.h>
#include <string.h>
#include <stdlib.h>

#include "big_alloc.h"
#include "film.h"

int pc_film_write_exr(const pc_film *f, const char *path, const pc_exr_attr *extra, int nextra, pc_err *e) {
  size_t n = (size_t)f->w * f->h * 3;
  int nl = f->nlayers + 1; /* the beauty, every layer but beauty_sq, and the variance */
  float *pix = pc_big_alloc(sizeof(float) * n * (size_t)nl); /* a 512x512 film's layers: 14k faults in 4 KiB pages */
  pc_exr_layer *layers = calloc((size_t)nl, sizeof *layers);
  enum { ITER_ATTRS = 9 };
  pc_exr_attr *attrs = calloc((size_t)(f->nlayers + 2 + ITER_ATTRS + nextra), sizeof *attrs);
  char(*names)[40] = calloc((size_t)f->nlayers, sizeof *names);
  int rc;
  if (!pix || !layers || !attrs || !names) {
    rc = pc_errf(e, PC_ENOMEM, "%s: out of memory for the image", path);
    goto done;
  }
  pc_film_beauty(f, pix);
  layers[0].name = "";
  layers[0].rgb = pix;
  int na = 0, k = 1;
  for (int i = 0; i < f->nlayers; i++) {
    snprintf(names[i], sizeof names[i], "pcbpt.count.%s", f->layers[i].name);
    attrs[na++] = (pc_exr_attr){.name = names[i], .type = PC_ATTR_DOUBLE, .d = (double)f->layers[i].count};
    if (f->layers[i].norm == PC_NORM_SQUARE) continue; /* a means to the variance, not an image */
    if (f->layers[i].norm == PC_NORM_MAX && !pc_film_max_complete(f)) continue; /* cannot tell */
    float *dst = pix + n * (size_t)k;
    pc_film_layer_image(f, i, dst);
    layers[k].name = f->layers[i].name;
    layers[k++].rgb = dst;
  }
  double relmse;
  if (pc_film_variance(f, pix + n * (size_t)k)) {
    layers[k].name = "variance";
    layers[k].rgb = pix + n * (size_t)k;
    k++;
    pc_film_relmse_estimate(f, &relmse);
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
  rc = pc_exr_write(path, f->w, f->h, layers, k, attrs, na, e);
done:
  free(pix);
  free(layers);
  free(attrs);
  free(names);
  return rc;
}
