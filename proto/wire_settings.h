/* wire_settings.h: render settings to and from their wire form (proto Settings), so every
 * worker of a job renders with exactly the job's settings. */
#ifndef PC_WIRE_SETTINGS_H
#define PC_WIRE_SETTINGS_H

#include "error.h"
#include "pcbpt.pb-c.h"
#include "render.h"

/* Where the proto's lists of -D names and values point (into the settings' own buffer). */
typedef struct pc_wire_settings_buf {
  char *names[PC_SCENE_MAX_DEFINES], *values[PC_SCENE_MAX_DEFINES];
} pc_wire_settings_buf;

/* Fills out, whose strings point at a static method name and, through buf, into s: both must
 * outlive out. */
void pc_wire_settings_to_proto(const pc_render_settings *s, Pcbpt__Settings *out, pc_wire_settings_buf *buf);
/* Converts and validates (pc_render_settings_check); the message names the bad setting. */
int pc_wire_settings_from_proto(const Pcbpt__Settings *p, pc_render_settings *out, pc_err *e);

#endif
