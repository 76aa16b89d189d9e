/* wire_settings.h: render settings to and from their wire form (proto Settings), so every
 * worker of a job renders with exactly the job's settings. */
#ifndef PC_WIRE_SETTINGS_H
#define PC_WIRE_SETTINGS_H

#include "error.h"
#include "pcbpt.pb-c.h"
#include "render.h"

/* Fills out (whose string field points at a static method name). */
void pc_wire_settings_to_proto(const pc_render_settings *s, Pcbpt__Settings *out);
/* Converts and validates (pc_render_settings_check); the message names the bad setting. */
int pc_wire_settings_from_proto(const Pcbpt__Settings *p, pc_render_settings *out, pc_err *e);

#endif
