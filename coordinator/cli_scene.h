/* cli_scene.h: loading a request's scene for the verbs that render (see cli_scene.c). */
#ifndef PC_CLI_SCENE_H
#define PC_CLI_SCENE_H

#include <stddef.h>
#include <stdint.h>

#include "bundle.h"
#include "render_flags.h"

/* Loads path with req's loader options (warnings to stderr as "pcbpt-coord VERB: ..."), then
 * lets the scene fill what the flags left open (64 iterations if neither it nor they say). */
int pc_cli_load_scene(const char *verb, pc_render_request *req, const char *path, pc_scene *s, pc_err *e);
/* Warns on stderr ("pcbpt-coord VERB: warning: PATH: ...") when method m is PT and the scene
 * has light PT never samples (pc_render_request.pt_complete): the image would lack it. */
void pc_cli_warn_method(const char *verb, const char *path, pc_method m, const pc_render_request *req);
/* Warns on stderr when a checked scene (pc_scene_check) shows the camera the back of one-sided
 * materials over 1% of its image or more (pc_scene_probe_backs): they render black, as in Mitsuba
 * 0.6, and the warning names the shapes and the way out. */
void pc_cli_warn_backs(const char *verb, pc_scene *s);
/* The bundle of a loaded scene: every file it read, below its root folder. */
int pc_cli_scene_bundle(const pc_scene *s, uint8_t **blob, size_t *n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e);

#endif
