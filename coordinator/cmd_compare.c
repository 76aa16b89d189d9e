/* cmd_compare.c: `pcbpt-coord compare A.exr REF.exr`: RMSE, relMSE and L1 of A against the
 * reference REF, for the beauty and every layer present in both files, and the relMSE each
 * image estimated for itself (docs/variance.md) when its header has it. Strategy layers whose
 * MIS weights differ between the two (their headers' pcbpt.weights) are flagged: they share
 * the image out differently, so their difference is not an error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image.h"
#include "text_out.h"
#include "metrics.h"
#include "study.h"
#include "render.h"
#include "verbs.h"

static const char compare_help[] =
    "usage: pcbpt-coord compare A.exr REF.exr [--json]\n"
    "Error of A against the reference REF for the beauty and every layer present in both:\n"
    "RMSE, relMSE = mean (a-b)^2/(b^2+0.01), L1 = mean |a-b|, and both means; then each image's own\n"
    "estimate of its beauty relMSE when its header has one (pcbpt.relmse_estimate): for independent\n"
    "renders the measured relMSE is about the sum of the two.\n"
    "The strategy layers (pt, nee, lt, inner, sNtM) are the shares of the image each kind of strategy\n"
    "carries under the method's MIS weights: where the two headers' weights differ (pcbpt.weights,\n"
    "e.g. PT against BDPT, or PCBPT's inner strategies counting 2 against BDPT's 1) those rows are\n"
    "marked as not comparable (\"comparable\": false in JSON); the beauty always compares.\n";

/* The image's own relMSE estimate from its header, or -1. */
static double own_estimate(const pc_exr_file *x) {
  const char *v = pc_exr_attr_get(x, "pcbpt.relmse_estimate");
  return v ? strtod(v, NULL) : -1;
}

int pc_cmd_compare(int argc, char **argv) {
  const char *paths[2] = {NULL, NULL};
  int npaths = 0;
  int json = 0;
  for (int i = 0; i < argc; i++) {
    if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
      fputs(compare_help, stdout);
      return 0;
    } else if (strcmp(argv[i], "--json") == 0) {
      json = 1;
    } else if (argv[i][0] == '-') {
      fprintf(stderr, "pcbpt-coord compare: unknown flag '%s' (see --help)\n", argv[i]);
      return 2;
    } else if (npaths < 2) {
      paths[npaths++] = argv[i];
    } else {
      fprintf(stderr, "pcbpt-coord compare: unexpected argument '%s' (two images only)\n", argv[i]);
      return 2;
    }
  }
  if (npaths != 2) {
    fprintf(stderr, "pcbpt-coord compare: need two EXR files (see --help)\n");
    return 2;
  }
  pc_err err = {0};
  pc_exr_file a = {0}, b = {0};
  pc_layer_metrics *lm = NULL;
  int n = 0, status = 1;
  if (pc_exr_read_layers(paths[0], &a, &err) != PC_OK || pc_exr_read_layers(paths[1], &b, &err) != PC_OK ||
      pc_metrics_layers(&a, &b, &lm, &n, &err) != PC_OK) {
    fprintf(stderr, "pcbpt-coord compare: %s\n", err.msg);
    goto done;
  }
  const char *wa = pc_exr_attr_get(&a, PC_WEIGHTS_ATTR), *wb = pc_exr_attr_get(&b, PC_WEIGHTS_ATTR);
  bool unlike = pc_weights_unlike(wa, wb);
  char t1[256], t2[256]; /* a header's text as printed: bounded, no control bytes */
  if (json) {
    printf("{\"a\": ");
    pc_json_string(stdout, paths[0]);
    printf(", \"reference\": ");
    pc_json_string(stdout, paths[1]);
    printf(", \"layers\": [");
  }
  else printf("%-10s %14s %14s %14s %12s %12s\n", "layer", "RMSE", "relMSE", "L1", "mean", "mean(ref)");
  for (int i = 0; i < n; i++) {
    const pc_metrics *m = &lm[i].m;
    const char *name = lm[i].name[0] ? lm[i].name : "beauty";
    bool comparable = !(unlike && pc_weights_layer(lm[i].name));
    if (json) {
      printf("%s{\"layer\": ", i ? ", " : "");
      pc_json_string(stdout, name);
      const char *keys[] = {"rmse", "relmse", "l1", "mean", "mean_ref"};
      double vals[] = {m->rmse, m->relmse, m->l1, m->mean_a, m->mean_b};
      for (int k = 0; k < 5; k++) {
        printf(", \"%s\": ", keys[k]);
        pc_json_number(stdout, vals[k]);
      }
      printf(", \"nonfinite\": %llu, \"comparable\": %s}", (unsigned long long)m->nonfinite, comparable ? "true" : "false");
    } else
      printf("%-10s %14.6e %14.6e %14.6e %12.6g %12.6g%s%s\n", name, m->rmse, m->relmse, m->l1, m->mean_a, m->mean_b,
             m->nonfinite ? "  (non-finite samples skipped)" : "", comparable ? "" : "  (not comparable: weighted unlike)");
  }
  char why[1024];
  pc_image_kind ka = pc_image_kind_exr(&a), kb = pc_image_kind_exr(&b);
  pc_image_kind_differs(&kb, &ka, why, sizeof why);
  if (why[0])
    fprintf(stderr, "pcbpt-coord compare: warning: the images are of different things (%s), so their difference is not an "
            "error\n", why);
  if (unlike && !json)
    printf("strategy layers weighted unlike: %s against the reference's %s; each shares the image out among its "
           "strategies otherwise, so their differences are not errors (the beauty compares)\n",
           pc_text_printable(wa, t1, sizeof t1), pc_text_printable(wb, t2, sizeof t2));
  double ea = own_estimate(&a), eb = own_estimate(&b);
  if (json) {
    printf("], \"weights\": ");
    if (wa) pc_json_string(stdout, wa);
    else printf("null");
    printf(", \"weights_ref\": ");
    if (wb) pc_json_string(stdout, wb);
    else printf("null");
    printf(", \"relmse_estimate\": ");
    pc_json_number(stdout, ea >= 0 ? ea : NAN);
    printf(", \"relmse_estimate_ref\": ");
    pc_json_number(stdout, eb >= 0 ? eb : NAN);
    printf("}\n");
  } else if (ea >= 0 || eb >= 0) {
    char sa[32] = "-", sb[32] = "-";
    if (ea >= 0) snprintf(sa, sizeof sa, "%.6e", ea);
    if (eb >= 0) snprintf(sb, sizeof sb, "%.6e", eb);
    printf("estimated beauty relMSE (own iterations): %s, reference %s\n", sa, sb);
  }
  status = 0;
done:
  pc_layer_metrics_free(lm, n);
  pc_exr_file_free(&a);
  pc_exr_file_free(&b);
  return status;
}
