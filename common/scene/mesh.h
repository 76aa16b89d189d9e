/* mesh.h: an indexed triangle mesh in world space, as the loaders (OBJ, PLY, the built-in
 * shapes) produce it and the Embree scene consumes it. */
#ifndef PC_MESH_H
#define PC_MESH_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "vecmath.h"

/* Hard limits on untrusted mesh files; over them the loader fails with PC_ELIMIT. */
#define PC_MESH_MAX_VERTICES (1u << 26)
#define PC_MESH_MAX_TRIANGLES (1u << 26)

typedef struct pc_mesh {
  uint32_t nverts, ntris;
  vec3 *p;       /* nverts positions */
  vec3 *n;       /* nverts shading normals, or NULL (flat shading) */
  vec2 *uv;      /* nverts texture coordinates, or NULL */
  uint32_t *idx; /* 3*ntris vertex indices, counter-clockwise = front face */
} pc_mesh;

void pc_mesh_free(pc_mesh *m);
/* A deep copy into *dst; -1 (dst empty) when out of memory. */
int pc_mesh_copy(const pc_mesh *src, pc_mesh *dst);
/* Applies a transform (and its inverse transpose to normals) in place. */
void pc_mesh_transform(pc_mesh *m, const mat4 *xf);
/* Reverses every triangle's winding and negates shading normals (Mitsuba's flipNormals). */
void pc_mesh_flip(pc_mesh *m);

/* An OBJ file split into meshes as Mitsuba 0.6's obj plugin splits it (mesh_obj.c). */
#define PC_OBJ_MAX_MESHES 65536
typedef struct pc_obj_mesh {
  pc_mesh mesh;
  char *material; /* the `usemtl` name in force for its faces ("" if none) */
} pc_obj_mesh;
typedef struct pc_obj {
  int n;
  pc_obj_mesh *meshes;
  char *mtllib;    /* the last `mtllib` name as written (Mitsuba reads that one), or NULL */
  int mtllib_line;
} pc_obj;
/* collapse: Mitsuba's `collapse` (one mesh for the whole file); shape_index: its `shapeIndex`
 * (-1: every mesh). n may be 0 when shape_index selects no mesh. */
int pc_obj_load(const char *path, bool collapse, int shape_index, pc_obj *out, pc_err *e);
void pc_obj_free(pc_obj *o);

/* Loaders. `where` is the "file:line" of the referencing scene element, used in messages. */
/* The whole OBJ file as one mesh (pc_obj_load collapsed). */
int pc_mesh_load_obj(const char *path, pc_mesh *out, pc_err *e);
int pc_mesh_load_ply(const char *path, pc_mesh *out, pc_err *e);
/* Shape shape_index of a Mitsuba serialized file; *face_normals is the file's own flag. */
int pc_mesh_load_serialized(const char *path, int shape_index, pc_mesh *out, bool *face_normals, pc_err *e);
/* Built-in Mitsuba shapes in object space, before their toWorld transform. */
int pc_mesh_rectangle(pc_mesh *out);  /* [-1,1]^2 in z=0, normal +z */
int pc_mesh_cube(pc_mesh *out);       /* [-1,1]^3, outward normals */
int pc_mesh_disk(pc_mesh *out, int segments); /* unit disk in z=0, normal +z */

/* Mitsuba's smooth vertex normals (TriMesh::computeNormals: angle-weighted face normals);
 * replaces m->n. */
int pc_mesh_compute_normals(pc_mesh *m);
/* Mitsuba's maxSmoothAngle (TriMesh::rebuildTopology): rebuilds the vertices so that smooth
 * normals (replacing m->n) interpolate only across edges whose faces' normals lie within
 * max_angle_deg of each other. 0, or a negative code (PC_ENOMEM, PC_ELIMIT, PC_ENUMERIC for
 * non-finite data, PC_EINVAL for a bad index or angle). */
int pc_mesh_rebuild_topology(pc_mesh *m, float max_angle_deg);
/* Fails unless every index is in range, every value is finite and normals have unit length.
 * `where` prefixes the message ("scene.xml:12: shape obj"). */
int pc_mesh_validate(const pc_mesh *m, const char *where, pc_err *e);
/* Whether some triangle has nonzero area (a mesh without one is never hit). */
bool pc_mesh_has_area(const pc_mesh *m);

#endif
