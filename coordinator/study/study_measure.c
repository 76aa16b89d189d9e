/* study_measure.c: one point of a farm study's curve from an image the farm wrote (a job's
 * snapshot or its final image): its errors against the reference per layer, or without one
 * the beauty's own estimate from its header and variance layer, and the times in its header. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study.h"
#include "text_out.h"

double pc_study_exr_number(const pc_exr_file *x, const char *name) {
  const char *v = pc_exr_attr_get(x, name);
  if (!v) return NAN;
  char *end;
  double d = strtod(v, &end);
  return end != v ? d : NAN;
}

static const pc_image *layer(const pc_exr_file *x, const char *name) {
  for (int i = 0; i < x->nlayers; i++)
    if (strcmp(x->names[i], name) == 0) return &x->layers[i];
  return NULL;
}

pc_image_kind pc_image_kind_exr(const pc_exr_file *x) {
  return (pc_image_kind){pc_study_exr_number(x, "pcbpt.max_depth"), pc_exr_attr_get(x, PC_SCENE_BUNDLE_ATTR),
                         pc_exr_attr_get(x, PC_SCENE_DEFINES_ATTR)};
}

void pc_image_kind_differs(const pc_image_kind *ref, const pc_image_kind *mine, char *why, size_t n) {
  size_t k = 0;
  why[0] = 0;
  if (isfinite(ref->max_depth) && isfinite(mine->max_depth) && ref->max_depth != mine->max_depth)
    k += (size_t)snprintf(why, n, "max depth %g in the reference, %g here", ref->max_depth, mine->max_depth);
  if (k < n && ref->bundle && mine->bundle && strcmp(ref->bundle, mine->bundle) != 0)
    k += (size_t)snprintf(why + k, n - k, "%sother scene files in the reference (the scene, a mesh or a texture changed, or "
                          "another scene)", k ? "; " : "");
  char a[256], b[256];
  if (k < n && ref->defines && mine->defines && strcmp(ref->defines, mine->defines) != 0)
    snprintf(why + k, n - k, "%s-D '%s' in the reference, '%s' here", k ? "; " : "", pc_text_printable(ref->defines, a, sizeof a),
             pc_text_printable(mine->defines, b, sizeof b));
}

void pc_study_weights_exr(const pc_exr_file *x, const pc_study_ref *ref, pc_study_run *run) {
  const char *w = pc_exr_attr_get(x, PC_WEIGHTS_ATTR);
  snprintf(run->weights, sizeof run->weights, "%s", w ? w : "");
  run->unlike = !ref->estimated && pc_weights_unlike(w, ref->weights);
}

int pc_study_measure_exr(const pc_exr_file *x, const char *path, const pc_study_ref *ref, int workers,
                         pc_study_snap *s, bool layer_empty[PC_STUDY_NLAYERS], pc_err *e) {
  memset(s, 0, sizeof *s);
  if (x->w != ref->w || x->h != ref->h)
    return pc_errf(e, PC_EINVAL, "%s: %dx%d, the reference is %dx%d", path, x->w, x->h, ref->w, ref->h);
  s->worker_seconds = pc_study_exr_number(x, "pcbpt.worker_seconds");
  s->wall = pc_study_exr_number(x, "pcbpt.render_seconds");
  double it = pc_study_exr_number(x, "pcbpt.iterations");
  if (!(s->worker_seconds >= 0) || !(it >= 0))
    return pc_errf(e, PC_EPARSE, "%s: no pcbpt.worker_seconds or pcbpt.iterations in the header", path);
  s->iterations = (uint64_t)it;
  s->seconds = s->worker_seconds / (workers > 0 ? workers : 1);
  size_t n = (size_t)x->w * x->h * 3;
  for (int slot = 0; slot < PC_STUDY_NLAYERS; slot++) {
    const pc_image *img = layer(x, slot == PC_STUDY_BEAUTY ? "" : pc_study_layer_name(slot));
    if (layer_empty && slot > 0) {
      bool empty = true;
      for (size_t i = 0; img && i < n && empty; i++) empty = img->rgb[i] == 0;
      layer_empty[slot] = empty;
    }
    if (ref->estimated || !ref->rgb[slot]) continue;
    if (!img) {
      s->m[slot].relmse = s->m[slot].rmse = s->m[slot].l1 = NAN;
      continue;
    }
    int rc = pc_metrics_rgb(img->rgb, ref->rgb[slot], x->w, x->h, &s->m[slot], e);
    if (rc != PC_OK) return rc;
  }
  if (ref->estimated) {
    pc_metrics *m = &s->m[PC_STUDY_BEAUTY];
    double est = pc_study_exr_number(x, "pcbpt.relmse_estimate");
    const pc_image *var = layer(x, "variance");
    m->relmse = est >= 0 ? est : NAN;
    m->l1 = NAN;
    m->rmse = NAN;
    if (var) {
      double v = 0;
      for (size_t i = 0; i < n; i++) v += var->rgb[i];
      m->rmse = sqrt(v / (double)n);
    }
  }
  return PC_OK;
}
