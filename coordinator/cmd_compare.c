/* cmd_compare.c: `pcbpt-coord compare A.exr REF.exr`: RMSE, relMSE and L1 of A against the
 * reference REF, for the beauty and every layer present in both files, and the relMSE each
 * image estimated for itself (docs/variance.md) when its header has it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image.h"
#include "metrics.h"
#include "verbs.h"

static const char compare_help[] =
    "usage: pcbpt-coord compare A.exr REF.exr [--json]\n"
    "Error of A against the reference REF for the beauty and every layer present in both:\n"
    "RMSE, relMSE = mean (a-b)^2/(b^2+0.01), L1 = mean |a-b|, and both means; then each image's own\n"
    "estimate of its beauty relMSE when its header has one (pcbpt.relmse_estimate): for independent\n"
    "renders the measured relMSE is about the sum of the two.\n";

/* The image's own relMSE estimate from its header, or -1. */
static double own_estimate(const pc_exr_file *x) {
  for (int i = 0; i < x->nattrs; i++)
    if (strcmp(x->attr_names[i], "pcbpt.relmse_estimate") == 0) return strtod(x->attr_values[i], NULL);
  return -1;
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
  if (json) printf("{\"a\": \"%s\", \"reference\": \"%s\", \"layers\": [", paths[0], paths[1]);
  else printf("%-10s %14s %14s %14s %12s %12s\n", "layer", "RMSE", "relMSE", "L1", "mean", "mean(ref)");
  for (int i = 0; i < n; i++) {
    const pc_metrics *m = &lm[i].m;
    const char *name = lm[i].name[0] ? lm[i].name : "beauty";
    if (json)
      printf("%s{\"layer\": \"%s\", \"rmse\": %.9g, \"relmse\": %.9g, \"l1\": %.9g, \"mean\": %.9g, \"mean_ref\": %.9g, "
             "\"nonfinite\": %llu}",
             i ? ", " : "", name, m->rmse, m->relmse, m->l1, m->mean_a, m->mean_b, (unsigned long long)m->nonfinite);
    else
      printf("%-10s %14.6e %14.6e %14.6e %12.6g %12.6g%s\n", name, m->rmse, m->relmse, m->l1, m->mean_a, m->mean_b,
             m->nonfinite ? "  (non-finite samples skipped)" : "");
  }
  double ea = own_estimate(&a), eb = own_estimate(&b);
  if (json) {
    printf("], \"relmse_estimate\": ");
    if (ea >= 0) printf("%.9g", ea);
    else printf("null");
    printf(", \"relmse_estimate_ref\": ");
    if (eb >= 0) printf("%.9g", eb);
    else printf("null");
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
