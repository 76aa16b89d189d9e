/* render_flags.c: parsing of the render flags (see render_flags.h). */
#include "render_flags.h"

#include "irec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char pc_render_flags_help[] =
    "  --method M            pt, lt, bdpt, cbdpt, pcbpt or auto (default: the scene's integrator;\n"
    "                        auto for pcbpt): auto runs a short pilot of pt, bdpt and pcbpt\n"
    "                        K=1,2,4,8 (K=1 also with --mis 4; the best pcbpt also with a\n"
    "                        quarter and a sixteenth of the light paths, unless mirrors or glass\n"
    "                        make caustics) and renders with the most efficient (docs/auto.md)\n"
    "  --spp N               iterations to render, one sample per pixel each\n"
    "  --time SECONDS        render for this wall time (with --spp: whichever comes first)\n"
    "  --halt-noise E        stop once the image's estimated relMSE is at most E (--spp and\n"
    "                        --time stay upper bounds; docs/variance.md)\n"
    "  --seed N              job seed (default 1); iteration i is seeded from (seed, i)\n"
    "  --max-depth D         Mitsuba maxDepth: -1 infinite, 1 = emitters seen directly\n"
    "  --width W --height H  film size (default: the scene's hdrfilm)\n"
    "  --light-paths N       light-tracing paths per iteration (default W*H)\n"
    "  --mis-heuristic H     balance (default) or power\n"
    "  --strategy-layers D   also write one layer per (s,t) up to path length D\n"
    "  --pcbpt-m M           PCBPT stored light paths per iteration (default 100)\n"
    "  --pcbpt-k K           PCBPT connections per eye vertex (default 1)\n"
    "  --pcbpt-rate R        CBDPT and PCBPT share of eye vertices that connect to the stored\n"
    "                        paths, in (0, 1] (default 1): each connects with probability R\n"
    "                        and counts 1/R, for scenes whose inner paths carry little\n"
    "  --pcbpt-unseen-rate R PCBPT share of the eye vertices that connect to the stored paths in\n"
    "                        an iteration whose records see no light vertex, (0, 1] (default 0.25)\n"
    "  --pcbpt-candidates N  PCBPT candidates drawn from p_conn per eye vertex, K of them\n"
    "                        resampled by their contribution (default 1: no resampling but at\n"
    "                        dark eye vertices)\n"
    "  --pcbpt-dark-seen S   PCBPT: an eye vertex whose nearby records see less than this share\n"
    "                        of the light vertices is dark (default 0.1; 0: none is; 1: all are;\n"
    "                        none with K > 64)\n"
    "  --pcbpt-dark-candidates N  candidates per connection at a dark eye vertex: K N of them,\n"
    "                        at most 64 and at least --pcbpt-candidates (default 3)\n"
    "  --pcbpt-dark-mix F    uniform mix of p_conn at a dark eye vertex, (0, 1] (default 0.85)\n"
    "  --pcbpt-candidate-visibility V  what the resampling knows of a candidate's visibility:\n"
    "                        traced (default; its own shadow ray, reused by the selected one),\n"
    "                        uncertain (its shadow ray unless every nearby record sees it) or\n"
    "                        records (the records' estimate only, no extra rays)\n"
    "  --cache-fraction F    PCBPT importance-record paths as a fraction of W*H up to 128x128,\n"
    "                        of 128*sqrt(W*H) past it (default 0.004)\n"
    "  --knn N               PCBPT records interpolated per lookup (default 6)\n"
    "  --uniform-mix F       PCBPT weight of the uniform PMF in p_conn (default 0.5; at 1 no records\n"
    "                        are built unless the candidates read their visibility)\n"
    "  --mis MODE            PCBPT correlated MIS, the inner strategies' sample count in the\n"
    "                        weights: a count (default 2; at most M), upper-bound (1, Popov et\n"
    "                        al. eqs. 16-17) or standard (M)\n"
    "  --pmf MODE            PCBPT connection PMF: cached (default) or exact\n"
    "  -D NAME=VALUE         scene parameter: replaces $NAME in the scene (wins over <default>)\n"
    "  --strict              settings pcbpt ignores (sampler, rfilter, ...) are errors, not warnings\n"
    "  --scene-root DIR      folder the scene's includes and files may come from (default: its own)\n";

void pc_render_request_default(pc_render_request *r) {
  memset(r, 0, sizeof *r);
  pc_render_settings_default(&r->set);
}

int pc_render_flag_parse(pc_render_request *r, int argc, char **argv, int *i, pc_err *e) {
  static const char *const flags[] = {"--method", "--spp", "--time", "--seed", "--max-depth", "--width", "--height",
                                      "--light-paths", "--mis-heuristic", "--strategy-layers", "--pcbpt-m", "--pcbpt-k",
                                      "--cache-fraction", "--knn", "--uniform-mix", "--mis", "--pmf", "--halt-noise",
                                      "--pcbpt-candidates", "--pcbpt-candidate-visibility", "--pcbpt-rate", "--pcbpt-unseen-rate",
                                      "--pcbpt-dark-seen", "--pcbpt-dark-candidates", "--pcbpt-dark-mix", NULL};
  const char *flag = argv[*i];
  if (strcmp(flag, "--strict") == 0) {
    r->strict = true;
    return 1;
  }
  if (strcmp(flag, "-D") == 0 || strncmp(flag, "-D", 2) == 0) { /* -D a=b or -Da=b, as Mitsuba */
    const char *nv = flag[2] ? flag + 2 : NULL;
    if (!nv) {
      if (*i + 1 >= argc) return pc_errf(e, PC_EINVAL, "-D: missing name=value");
      nv = argv[++*i];
    }
    int rc = pc_scene_defines_add(&r->set.defines, nv, e);
    return rc ? rc : 1;
  }
  if (strcmp(flag, "--scene-root") == 0) {
    if (*i + 1 >= argc || !*argv[*i + 1]) return pc_errf(e, PC_EINVAL, "%s: missing folder", flag);
    r->scene_root = argv[++*i];
    return 1;
  }
  int which = -1;
  for (int k = 0; flags[k]; k++)
    if (strcmp(flag, flags[k]) == 0) which = k;
  if (which < 0) return 0;
  if (*i + 1 >= argc) return pc_errf(e, PC_EINVAL, "%s: missing value", flag);
  const char *v = argv[++*i];
  pc_render_settings *s = &r->set;
  long long ll;
  uint64_t u;
  double d;
  switch (which) {
  case 0:
    if (pc_method_parse(v, &s->method) != PC_OK)
      return pc_errf(e, PC_EINVAL, "%s: unknown method '%s' (pt, lt, bdpt, cbdpt, pcbpt, auto)", flag, v);
    r->method_set = true;
    r->method_auto = s->method == PC_METHOD_AUTO;
    if (r->method_auto) s->method = PC_METHOD_PCBPT; /* the pilot's base settings */
    break;
  case 1:
    if (!pc_parse_u64(v, 1, UINT64_C(1) << 40, &r->spp)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not a count >= 1", flag, v);
    break;
  case 2:
    if (!pc_parse_f64(v, 1e-3, 1e7, &r->seconds)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not a number of seconds > 0", flag, v);
    break;
  case 3:
    if (!pc_parse_u64(v, 0, UINT64_MAX, &s->seed)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not an unsigned integer", flag, v);
    break;
  case 4:
    if (!pc_parse_i64(v, -1, 1024, &ll) || ll == 0) return pc_errf(e, PC_EINVAL, "%s: '%s' is not -1 or 1..1024", flag, v);
    s->max_depth = (int)ll;
    r->depth_set = true;
    break;
  case 5:
  case 6:
    if (!pc_parse_i64(v, 1, PC_SCENE_MAX_FILM_DIM, &ll)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not 1..%d", flag, v, PC_SCENE_MAX_FILM_DIM);
    if (which == 5) { s->width = (int)ll; r->width_set = true; }
    else { s->height = (int)ll; r->height_set = true; }
    break;
  case 7:
    if (!pc_parse_u64(v, 1, UINT64_C(1) << 32, &u)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not 1..2^32", flag, v);
    s->light_paths = u;
    break;
  case 8:
    if (strcmp(v, "balance") == 0) s->mis_heuristic = PC_MIS_BALANCE;
    else if (strcmp(v, "power") == 0) s->mis_heuristic = PC_MIS_POWER;
    else return pc_errf(e, PC_EINVAL, "%s: '%s' is not balance or power", flag, v);
    break;
  case 9:
    if (!pc_parse_i64(v, 0, 8, &ll)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not 0..8", flag, v);
    s->strategy_layers = (int)ll;
    break;
  case 10:
    if (!pc_parse_i64(v, 1, 100000, &ll)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not 1..100000", flag, v);
    s->pcbpt_m = (int)ll;
    break;
  case 11:
    if (!pc_parse_i64(v, 1, 1000000, &ll)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not 1..1000000", flag, v);
    s->pcbpt_k = (int)ll;
    break;
  case 12:
    if (!pc_parse_f64(v, 1e-9, 1.0, &d)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not in (0, 1]", flag, v);
    s->cache_fraction = (float)d;
    break;
  case 13:
    if (!pc_parse_i64(v, 1, 64, &ll)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not 1..64", flag, v);
    s->knn = (int)ll;
    break;
  case 14:
  case 22:
    if (!pc_parse_f64(v, 0.0, 1.0, &d)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not in [0, 1]", flag, v);
    *(which == 14 ? &s->uniform_mix : &s->pcbpt_dark_seen) = (float)d;
    break;
  case 15:
    if (strcmp(v, "upper-bound") == 0) s->mis_mode = PC_MIS_UPPER_BOUND;
    else if (strcmp(v, "standard") == 0) s->mis_mode = PC_MIS_STANDARD;
    else if (pc_parse_f64(v, 1.0, 100000.0, &d)) {
      s->mis_mode = PC_MIS_COUNT;
      s->mis_count = (float)d;
    } else return pc_errf(e, PC_EINVAL, "%s: '%s' is not upper-bound, standard or a count >= 1", flag, v);
    break;
  case 16:
    if (strcmp(v, "cached") == 0) s->pmf_mode = PC_PMF_CACHED;
    else if (strcmp(v, "exact") == 0) s->pmf_mode = PC_PMF_EXACT;
    else return pc_errf(e, PC_EINVAL, "%s: '%s' is not cached or exact", flag, v);
    break;
  case 17:
    if (!pc_parse_f64(v, 1e-9, 1e6, &r->halt_noise)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not a relMSE > 0", flag, v);
    break;
  case 18:
  case 23:
    if (!pc_parse_i64(v, 1, PC_IREC_MAX_CANDIDATES, &ll)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not 1..%d", flag, v, PC_IREC_MAX_CANDIDATES);
    *(which == 18 ? &s->pcbpt_candidates : &s->pcbpt_dark_candidates) = (int)ll;
    break;
  case 19:
    if (strcmp(v, "records") == 0) s->candidate_visibility = PC_CANDVIS_RECORDS;
    else if (strcmp(v, "uncertain") == 0) s->candidate_visibility = PC_CANDVIS_UNCERTAIN;
    else if (strcmp(v, "traced") == 0) s->candidate_visibility = PC_CANDVIS_TRACED;
    else return pc_errf(e, PC_EINVAL, "%s: '%s' is not traced, uncertain or records", flag, v);
    break;
  case 20:
  case 21:
  case 24:
    /* (0, 1] as the settings hold it: a positive rate or mix that rounds to a float 0 is 0 */
    if (!pc_parse_f64(v, 0.0, 1.0, &d) || !((float)d > 0.f)) return pc_errf(e, PC_EINVAL, "%s: '%s' is not in (0, 1]", flag, v);
    *(which == 20 ? &s->pcbpt_rate : which == 21 ? &s->pcbpt_unseen_rate : &s->pcbpt_dark_mix) = (float)d;
    break;
  }
  return 1;
}

int pc_render_settings_pcbpt_flags(const pc_render_settings *s, char *buf, size_t size) {
  static const char *const visibility[] = {"records", "uncertain", "traced"};
  if (s->method != PC_METHOD_PCBPT && s->method != PC_METHOD_CBDPT) return snprintf(buf, size, "%s", "");
  char mis[32];
  if (s->mis_mode == PC_MIS_COUNT) snprintf(mis, sizeof mis, "%g", (double)s->mis_count);
  else snprintf(mis, sizeof mis, "%s", s->mis_mode == PC_MIS_STANDARD ? "standard" : "upper-bound");
  return snprintf(buf, size,
                  "--pcbpt-m %d --pcbpt-k %d --pcbpt-rate %g --pcbpt-unseen-rate %g --pcbpt-candidates %d --pcbpt-candidate-visibility %s"
                  " --pcbpt-dark-seen %g --pcbpt-dark-candidates %d --pcbpt-dark-mix %g --cache-fraction %g"
                  " --knn %d --uniform-mix %g --mis %s --pmf %s",
                  s->pcbpt_m, s->pcbpt_k, (double)s->pcbpt_rate, (double)s->pcbpt_unseen_rate, s->pcbpt_candidates, visibility[s->candidate_visibility],
                  (double)s->pcbpt_dark_seen, s->pcbpt_dark_candidates, (double)s->pcbpt_dark_mix,
                  (double)s->cache_fraction, s->knn, (double)s->uniform_mix, mis,
                  s->pmf_mode == PC_PMF_EXACT ? "exact" : "cached");
}

void pc_render_request_load_opts(const pc_render_request *r, pc_scene_load_opts *o) {
  memset(o, 0, sizeof *o);
  o->root = r->scene_root;
  o->defines = &r->set.defines;
  o->strict = r->strict;
}

void pc_render_request_apply_scene(pc_render_request *r, pc_scene *s) {
  if (r->spp == 0 && r->seconds == 0 && s->sample_count > 0) r->spp = (uint64_t)s->sample_count;
  if (!r->method_set) {
    r->set.method = s->method;
    r->method_auto = s->method == PC_METHOD_PCBPT;
  }
  r->pt_complete = pc_scene_pt_complete(s);
  r->lt_complete = pc_scene_lt_complete(s);
  r->caustics = pc_scene_has_caustics(s);
  if (!r->depth_set) r->set.max_depth = s->max_depth;
  if (!r->width_set) r->set.width = s->camera.width;
  if (!r->height_set) r->set.height = s->camera.height;
  s->camera.width = r->set.width;
  s->camera.height = r->set.height;
}
