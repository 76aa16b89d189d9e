/* anim.h: Mitsuba 0.6's AnimatedTransform (an <animation> of timed <transform>s): each keyframe
 * is split by a polar decomposition into a translation, a rotation and the diagonal of the
 * stretch (Mitsuba keeps only that), which are interpolated separately (lerp, slerp, lerp),
 * clamped outside the first and last time, and composed as translate * rotate * scale. */
#ifndef PC_ANIM_H
#define PC_ANIM_H

#include <stdbool.h>

#include "error.h"
#include "vecmath.h"

#define PC_ANIM_MAX_KEYS 1024

typedef struct pc_keyframe {
  double time;
  double t[3];   /* translation */
  double q[4];   /* rotation quaternion x, y, z, w */
  double s[3];   /* the stretch's diagonal */
} pc_keyframe;

typedef struct pc_anim {
  pc_keyframe *k; /* sorted by time once pc_anim_finish has run */
  int n;          /* 0: not animated */
  int cap;
} pc_anim;

/* Appends the keyframe of matrix m at `time`: PC_EINVAL if its linear part is singular,
 * PC_ELIMIT past PC_ANIM_MAX_KEYS, PC_ENOMEM. */
int pc_anim_append(pc_anim *a, double time, const mat4 *m, pc_err *e);
/* Sorts the keyframes by time; PC_EINVAL (naming the time) if two share a time. */
int pc_anim_finish(pc_anim *a, pc_err *e);
/* True if every time gives the same transform (Mitsuba then uses a plain transform). */
bool pc_anim_is_static(const pc_anim *a);
/* The transform at `time`. */
mat4 pc_anim_eval(const pc_anim *a, double time);
/* The largest |scale| of any keyframe, which bounds the stretch at every time. */
double pc_anim_max_scale(const pc_anim *a);
/* True if every keyframe's stretch is the same (a rigid motion stays rigid in between). */
bool pc_anim_same_scale(const pc_anim *a);
void pc_anim_free(pc_anim *a);

#endif
