/* study_shares.c: which strategies carry a method's image, from its final EXR alone: the share of
 * the beauty's mean luminance that each standard strategy layer holds (emitter hits, next-event
 * estimation, light tracing, inner connections). The layers sum to the beauty, so the shares
 * sum to 1 up to rounding. */
#include <string.h>

#include "study.h"

static double mean_luminance(const pc_image *im, size_t np) {
  double sum = 0;
  for (size_t p = 0; p < np; p++) sum += 0.2126 * im->rgb[3 * p] + 0.7152 * im->rgb[3 * p + 1] + 0.0722 * im->rgb[3 * p + 2];
  return np ? sum / (double)np : 0;
}

void pc_study_shares_exr(const pc_exr_file *x, pc_study_shares *s) {
  memset(s, 0, sizeof *s);
  const pc_image *beauty = NULL, *layer[PC_LAYER_STD_COUNT] = {0};
  for (int i = 0; i < x->nlayers; i++) {
    if (x->names[i][0] == '\0') beauty = &x->layers[i];
    int slot = pc_study_layer_parse(x->names[i]);
    if (slot > PC_STUDY_BEAUTY) layer[slot - 1] = &x->layers[i];
  }
  size_t np = (size_t)x->w * (size_t)x->h;
  double total = beauty ? mean_luminance(beauty, np) : 0;
  if (!(total > 0)) return; /* a black image (or none): no shares to tell */
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) {
    if (!layer[l]) return;
    s->share[l] = mean_luminance(layer[l], np) / total;
  }
  s->known = true;
}
