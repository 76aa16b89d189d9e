/* shape_cylinder.h: Mitsuba 0.6's `cylinder`, an exact open tube (no end caps) of a shape's
 * center (the start of its centreline), axes, radius and length: its placement from the XML
 * parameters and any later transform, its Embree user geometry, hit records and uniform area
 * sampling. Tessellating it would change the image (its silhouette, normals and emitted power);
 * Mitsuba intersects the quadric, and so does this. */
#ifndef PC_SHAPE_CYLINDER_H
#define PC_SHAPE_CYLINDER_H

#include <stdbool.h>

#include "scene.h"

/* Places an object-space cylinder from p0 to p1 of the given radius through xf, as Mitsuba
 * composes it (toWorld * translate(p0) * frame(p1 - p0) * scale(radius, radius, length)), into
 * sh's center, cyl_axes, radius and length. Returns NULL, or why it cannot: p0 == p1, a radius
 * that is not positive, or an xf that does not keep the tube circular (Mitsuba does not permit
 * non-uniform scales across the axis). */
const char *pc_cylinder_place(pc_shape *sh, vec3 p0, vec3 p1, float radius, const mat4 *xf);
/* Moves an already placed cylinder through xf (instances, motion); the same reasons to refuse. */
const char *pc_cylinder_transform(pc_shape *sh, const mat4 *xf);

/* Its axis-aligned bounds (the two end circles'). */
void pc_cylinder_bounds(const pc_shape *sh, vec3 *lo, vec3 *hi);
/* Its surface area, 2 pi r length. */
float pc_cylinder_area(const pc_shape *sh);
/* How far rays leave and reach a point p on it (PC_OFFSET_RELATIVE of its largest coordinate). */
float pc_cylinder_eps(const pc_shape *sh, vec3 p);
/* The hit record at p (found by a ray; re-projected onto the surface): Mitsuba's uv
 * (u = phi / 2 pi about the axis from cyl_axes.s, v = height / length), dpdu, dpdv, and the
 * normal cross(dpdu, dpdv): outward unless flipNormals or a mirroring toWorld turn it in. */
void pc_cylinder_hit(const pc_shape *sh, vec3 p, pc_hit *hit);
/* A point uniform by area from (u1, u2) in [0,1)^2, with that normal. */
void pc_cylinder_sample(const pc_shape *sh, float u1, float u2, vec3 *p, vec3 *n);
/* An Embree user geometry of it (one primitive; the callbacks read *sh, which must outlive the
 * geometry). NULL if Embree refused. `device` is an RTCDevice. */
void *pc_cylinder_geometry(void *device, const pc_shape *sh);

#endif
