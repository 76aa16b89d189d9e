/* metrics.c: RMSE, relMSE and L1 between a rendered image and a reference, per image and per
 * EXR layer (definitions in metrics.h). */
#include "metrics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int pc_metrics_rgb(const float *a, const float *ref, int w, int h, pc_metrics *out, pc_err *e) {
  if (!a || !ref || !out) return pc_errf(e, PC_EINVAL, "pc_metrics_rgb: NULL argument");
  if (w <= 0 || h <= 0) return pc_errf(e, PC_EINVAL, "pc_metrics_rgb: empty image %dx%d", w, h);
  size_t n = (size_t)w * h * 3;
  double se = 0, rel = 0, l1 = 0, sa = 0, sb = 0;
  uint64_t bad = 0;
  for (size_t i = 0; i < n; i++) {
    double x = a[i], y = ref[i];
    if (!isfinite(x) || !isfinite(y)) {
      bad++;
      continue;
    }
    double d = x - y;
    se += d * d;
    rel += d * d / (y * y + PC_RELMSE_EPS);
    l1 += fabs(d);
    sa += x;
    sb += y;
  }
  memset(out, 0, sizeof *out);
  out->nonfinite = bad;
  double cnt = (double)(n - bad);
  if (cnt > 0) {
    out->rmse = sqrt(se / cnt);
    out->relmse = rel / cnt;
    out->l1 = l1 / cnt;
    out->mean_a = sa / cnt;
    out->mean_b = sb / cnt;
  }
  return PC_OK;
}

int pc_metrics_image(const pc_image *a, const pc_image *ref, pc_metrics *out, pc_err *e) {
  if (!a || !ref) return pc_errf(e, PC_EINVAL, "pc_metrics_image: NULL argument");
  if (a->w != ref->w || a->h != ref->h)
    return pc_errf(e, PC_EINVAL, "image sizes differ: %dx%d vs reference %dx%d", a->w, a->h,
                   ref->w, ref->h);
  return pc_metrics_rgb(a->rgb, ref->rgb, a->w, a->h, out, e);
}

void pc_layer_metrics_free(pc_layer_metrics *m, int n) {
  if (!m) return;
  for (int i = 0; i < n; i++) free(m[i].name);
  free(m);
}

int pc_metrics_layers(const pc_exr_file *a, const pc_exr_file *ref, pc_layer_metrics **out,
                      int *n, pc_err *e) {
  if (!a || !ref || !out || !n) return pc_errf(e, PC_EINVAL, "pc_metrics_layers: NULL argument");
  *out = NULL;
  *n = 0;
  if (a->w != ref->w || a->h != ref->h)
    return pc_errf(e, PC_EINVAL, "image sizes differ: %dx%d vs reference %dx%d", a->w, a->h,
                   ref->w, ref->h);
  pc_layer_metrics *res = calloc((size_t)a->nlayers + 1, sizeof *res);
  if (!res) return pc_errf(e, PC_ENOMEM, "pc_metrics_layers: out of memory");
  int k = 0;
  for (int i = 0; i < a->nlayers; i++) {
    int j = 0;
    while (j < ref->nlayers && strcmp(a->names[i], ref->names[j]) != 0) j++;
    if (j == ref->nlayers) continue;
    int rc = pc_metrics_image(&a->layers[i], &ref->layers[j], &res[k].m, e);
    if (!rc && !(res[k].name = strdup(a->names[i])))
      rc = pc_errf(e, PC_ENOMEM, "pc_metrics_layers: out of memory");
    if (rc) {
      pc_layer_metrics_free(res, k + 1);
      return rc;
    }
    k++;
  }
  if (k == 0) {
    free(res);
    return pc_errf(e, PC_EINVAL, "the images have no layer in common");
  }
  *out = res;
  *n = k;
  return PC_OK;
}
