/* scene_embree.h: the Embree steps that building a scene (scene_build.c) and moving a view of
 * it (scene_motion.c) share. Private to common/scene. */
#ifndef PC_SCENE_EMBREE_H
#define PC_SCENE_EMBREE_H

#include "scene.h"

/* Makes Embree geometry of s->shapes[shape] as it is now, on s's device, and attaches it to
 * rtc_scene (an RTCScene) with geomID == shape. */
int pc_scene_attach_shape(const pc_scene *s, void *rtc_scene, int shape, pc_err *e);
/* Commits rtc_scene and reports the first error Embree gave s's device. */
int pc_scene_commit(const pc_scene *s, void *rtc_scene, pc_err *e);
/* Grows [lo, hi] to hold every animated shape at every time. */
void pc_scene_motion_bounds(const pc_scene *s, vec3 *lo, vec3 *hi);

#endif
