/* wire_settings.c: pc_render_settings <-> proto Settings. */
#include "wire_settings.h"

#include <stdio.h>

void pc_wire_settings_to_proto(const pc_render_settings *s, Pcbpt__Settings *out, pc_wire_settings_buf *buf) {
  pcbpt__settings__init(out);
  out->method = (char *)pc_method_name(s->method);
  out->width = (uint32_t)s->width;
  out->height = (uint32_t)s->height;
  out->max_depth = s->max_depth;
  out->seed = s->seed;
  out->light_paths = s->light_paths;
  out->mis_heuristic = (uint32_t)s->mis_heuristic;
  out->strategy_layers = (uint32_t)s->strategy_layers;
  out->pcbpt_m = (uint32_t)s->pcbpt_m;
  out->pcbpt_k = (uint32_t)s->pcbpt_k;
  out->pcbpt_rate = s->pcbpt_rate;
  out->pcbpt_unseen_rate = s->pcbpt_unseen_rate;
  out->pcbpt_candidates = (uint32_t)s->pcbpt_candidates;
  out->pcbpt_candidate_visibility = (uint32_t)s->candidate_visibility;
  out->pcbpt_dark_seen = s->pcbpt_dark_seen;
  out->pcbpt_dark_candidates = (uint32_t)s->pcbpt_dark_candidates;
  out->pcbpt_dark_mix = s->pcbpt_dark_mix;
  out->cache_fraction = s->cache_fraction;
  out->knn = (uint32_t)s->knn;
  out->uniform_mix = s->uniform_mix;
  out->mis_mode = (uint32_t)s->mis_mode;
  out->mis_count = s->mis_count;
  out->pmf_mode = (uint32_t)s->pmf_mode;
  for (int i = 0; i < s->defines.n; i++) {
    const char *n, *v;
    pc_scene_defines_get(&s->defines, i, &n, &v);
    buf->names[i] = (char *)n;
    buf->values[i] = (char *)v;
  }
  out->n_define_names = out->n_define_values = (size_t)s->defines.n;
  out->define_names = buf->names;
  out->define_values = buf->values;
}

int pc_wire_settings_from_proto(const Pcbpt__Settings *p, pc_render_settings *out, pc_err *e) {
  pc_render_settings s;
  pc_render_settings_default(&s);
  if (!p) return pc_errf(e, PC_EINVAL, "settings: missing");
  if (pc_method_parse(p->method, &s.method) != 0) return pc_errf(e, PC_EINVAL, "settings: unknown method '%.32s'", p->method);
  if (s.method == PC_METHOD_AUTO) return pc_errf(e, PC_EINVAL, "settings: method auto is chosen by the client's pilot, not sent");
  if (p->width > PC_SCENE_MAX_FILM_DIM || p->height > PC_SCENE_MAX_FILM_DIM || p->strategy_layers > 64 ||
      p->pcbpt_m > (1u << 24) || p->pcbpt_k > (1u << 24) || p->pcbpt_candidates > 1024 || p->pcbpt_dark_candidates > 1024 || p->knn > 1024 || p->mis_heuristic > PC_MIS_POWER ||
      p->mis_mode > PC_MIS_COUNT || p->pmf_mode > PC_PMF_EXACT ||
      p->pcbpt_candidate_visibility > PC_CANDVIS_TRACED)
    return pc_errf(e, PC_EINVAL, "settings: a value is out of range (size %ux%u)", p->width, p->height);
  s.width = (int)p->width;
  s.height = (int)p->height;
  s.max_depth = p->max_depth;
  s.seed = p->seed;
  s.light_paths = p->light_paths;
  s.mis_heuristic = (pc_mis_heuristic)p->mis_heuristic;
  s.strategy_layers = (int)p->strategy_layers;
  s.pcbpt_m = (int)p->pcbpt_m;
  s.pcbpt_k = (int)p->pcbpt_k;
  s.pcbpt_rate = p->pcbpt_rate == 0.f ? 1.f : p->pcbpt_rate; /* range: pc_render_settings_check */
  s.pcbpt_unseen_rate = p->pcbpt_unseen_rate == 0.f ? 1.f : p->pcbpt_unseen_rate;
  s.pcbpt_candidates = (int)p->pcbpt_candidates;
  s.candidate_visibility = (pc_candidate_visibility)p->pcbpt_candidate_visibility;
  s.pcbpt_dark_seen = p->pcbpt_dark_seen; /* ranges: pc_render_settings_check */
  if (p->pcbpt_dark_candidates != 0) s.pcbpt_dark_candidates = (int)p->pcbpt_dark_candidates;
  if (p->pcbpt_dark_mix != 0.f) s.pcbpt_dark_mix = p->pcbpt_dark_mix;
  s.cache_fraction = p->cache_fraction;
  s.knn = (int)p->knn;
  s.uniform_mix = p->uniform_mix;
  s.mis_mode = (pc_mis_mode)p->mis_mode;
  if (s.mis_mode == PC_MIS_COUNT) s.mis_count = p->mis_count; /* range: pc_render_settings_check */
  s.pmf_mode = (pc_pmf_mode)p->pmf_mode;
  if (p->n_define_names != p->n_define_values || p->n_define_names > PC_SCENE_MAX_DEFINES)
    return pc_errf(e, PC_EINVAL, "settings: malformed -D parameters");
  for (size_t i = 0; i < p->n_define_names; i++) {
    char nv[PC_SCENE_DEFINES_BYTES];
    if ((size_t)snprintf(nv, sizeof nv, "%s=%s", p->define_names[i], p->define_values[i]) >= sizeof nv)
      return pc_errf(e, PC_ELIMIT, "settings: -D parameters too long");
    int rc = pc_scene_defines_add(&s.defines, nv, e);
    if (rc) return rc;
  }
  int rc = pc_render_settings_check(&s, e);
  if (rc) return rc;
  *out = s;
  return 0;
}
