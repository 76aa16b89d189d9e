/* render_flags.h: the command-line flags that describe a render (method, size, depth, seed,
 * halting, integrator parameters), shared by `render` and `submit` so both accept exactly the
 * same words and report bad values the same way. */
#ifndef PC_RENDER_FLAGS_H
#define PC_RENDER_FLAGS_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "parse.h"
#include "render.h"

typedef struct pc_render_request {
  pc_render_settings set;
  bool method_set, depth_set, width_set, height_set; /* overrides of the scene's own values */
  uint64_t spp;      /* iterations to render (0: not given) */
  double seconds;    /* wall-time budget (0: not given) */
  bool strict;       /* the loader's warnings are errors */
  const char *scene_root; /* folder confining the files the scene names (NULL: the scene's own) */
  double halt_noise; /* stop at this estimated relMSE (0: not given) */
  /* --method auto, or no --method on a scene whose integrator is pcbpt: a pilot chooses the
   * method and PCBPT parameters (pilot.h); set.method stays pcbpt until it has. */
  bool method_auto;
  /* The scene lets PT sample every path (pc_scene_pt_complete), so auto may choose it: set by
   * pc_render_request_apply_scene, false until then. */
  bool pt_complete;
  /* The scene lets LT sample every path (pc_scene_lt_complete): set as pt_complete. */
  bool lt_complete;
  /* The scene has caustics (pc_scene_has_caustics), so auto keeps every light-tracing path:
   * set by pc_render_request_apply_scene. */
  bool caustics;
} pc_render_request;

void pc_render_request_default(pc_render_request *r);

/* If argv[*i] is a render flag, consumes it (and its value), advancing *i, and returns 1;
 * returns 0 if it is not one; a negative code with "--flag: what is wrong" on a bad value. */
int pc_render_flag_parse(pc_render_request *r, int argc, char **argv, int *i, pc_err *e);

/* The loader options the flags give (-D, --strict, --scene-root); the caller adds its warning
 * sink. */
void pc_render_request_load_opts(const pc_render_request *r, pc_scene_load_opts *o);

/* Fills in what the flags left to the scene (method, maxDepth, film size, the sampler's
 * sampleCount as the iteration count when neither --spp nor --time is given) and gives the
 * scene's camera the final film size. Call between pc_scene_load and pc_scene_build. */
void pc_render_request_apply_scene(pc_render_request *r, pc_scene *s);

/* The PCBPT and CBDPT settings as the flags that give them ("--pcbpt-m 100 --pcbpt-k 1 ..."),
 * for the image header; "" for the other methods. Returns the length snprintf would write. */
int pc_render_settings_pcbpt_flags(const pc_render_settings *s, char *buf, size_t size);

/* Help text for the render flags (one flag per line). */
extern const char pc_render_flags_help[];

#endif
