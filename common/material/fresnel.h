/* fresnel.h: Fresnel reflectance of dielectric and conductor interfaces and the diffuse
 * (cosine-averaged) Fresnel reflectance, following Mitsuba 0.6's definitions. */
#ifndef PC_FRESNEL_H
#define PC_FRESNEL_H

#include "vecmath.h"

/* Unpolarized reflectance of a dielectric boundary with relative index eta = n_int / n_ext.
 * cos_i is signed with respect to the normal (> 0: arriving from the exterior side). Writes the
 * signed cosine of the refracted direction (opposite sign to cos_i, 0 on total internal
 * reflection) to *cos_t when non-NULL. */
float pc_fresnel_dielectric(float cos_i, float eta, float *cos_t);

/* Reflectance of a conductor with complex relative index eta + i k, per RGB channel. */
vec3 pc_fresnel_conductor(float cos_i, vec3 eta, vec3 k);

/* Mitsuba's fresnelDiffuseReflectance(eta): the cosine-weighted hemispherical average of
 * pc_fresnel_dielectric(cos, eta) for light arriving from the exterior side. */
float pc_fresnel_diffuse_reflectance(float eta);

#endif
