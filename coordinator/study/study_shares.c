/* study_shares.c: which strategies carry a method's image, from its final EXR alone: the share of
 * the beauty's mean luminance that each standard strategy layer holds (emitter hits, next-event
 * estimation, light tracing, inner connections). The layers sum to the beauty, so the shares
 * sum to 1 up to rounding. */
#include <string.h>

#include "study.h"

void pc_study_shares_exr(const pc_exr_file *x, pc_study_shares *s) {
  memset(s, 0, sizeof *s);
  const pc_image *beauty = NULL, *layer[PC_LAYER_STD_COUNT] = {0};
  for (int i = 0; i < x->nlayers; i++) {
    if (x->names[i][0] == '\0') beauty = &x->layers[i];
    int slot = pc_study_layer_parse(x->names[i]);
    if (slot > PC_STUDY_BEAUTY) layer[slot - 1] = &x->layers[i];
  }
  double total = beauty ? pc_study_mean_luminance(beauty) : 0;
  if (!(total > 0)) return; /* a black image (or none): no shares to tell */
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) {
    if (!layer[l]) return;
    s->share[l] = pc_study_mean_luminance(layer[l]) / total;
  }
  s->known = true;
}
