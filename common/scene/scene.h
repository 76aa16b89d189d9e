/* scene.h: a loaded scene: shapes (world-space meshes, exact spheres and cylinders), materials, textures,
 * lights, camera and the integrator element's defaults; plus its Embree acceleration structure
 * and ray queries. Loading (scene_xml.c) fills the plain data; pc_scene_build makes it
 * renderable. */
#ifndef PC_SCENE_H
#define PC_SCENE_H

#include <stdbool.h>
#include <stdint.h>

#include "anim.h"
#include "bsdf.h"
#include "camera.h"
#include "error.h"
#include "light.h"
#include "mesh.h"
#include "texture.h"
#include "vecmath.h"

typedef enum { PC_SHAPE_MESH, PC_SHAPE_SPHERE, PC_SHAPE_CYLINDER } pc_shape_kind;

/* What a hit on one triangle of a still mesh needs that depends on the triangle alone, taken
 * once by pc_scene_build instead of at every hit: the unit geometric normal and the texture
 * tangents (a cross product, a square root and two divisions per hit), the vertices' largest
 * coordinate for the ray offset, and on a mesh without shading normals the shading frame too
 * (its normal is the triangle's). 64 bytes, one cache line. */
typedef struct pc_tri_consts {
  frame f;          /* f.n: the unit geometric normal (counter-clockwise side); f.s, f.t: the
                       shading frame from f.n and dpdu where the mesh has no shading normals
                       (elsewhere f.s.x = 1 marks degenerate texture coordinates) */
  vec3 dpdu, dpdv;  /* as pc_hit's */
  float vmax;       /* largest coordinate magnitude of the three vertices (pc_triangle_eps) */
} pc_tri_consts;

/* The most memory the pc_tri_consts of a scene's still meshes take together (256k triangles;
 * the meshes that do not fit compute theirs at each hit). A table of a large mesh costs more
 * memory than it saves time: its rows, read at random, are as far as the vertices are, and on
 * a 1M-triangle ball it sped BDPT by ~0.5% for 64 MB (ajar-door's boxes and planes: -2.3%). */
#define PC_TRI_CONSTS_MAX_BYTES ((size_t)16 << 20)

typedef struct pc_shape {
  pc_shape_kind kind;
  pc_mesh mesh;          /* PC_SHAPE_MESH, world space, flipNormals already applied */
  pc_tri_consts *tri;    /* per triangle of a still mesh, or NULL (scene_build.c, build_tri_consts) */
  vec3 center;           /* PC_SHAPE_SPHERE: its centre; PC_SHAPE_CYLINDER: the start of its
                            centreline (world space) */
  float radius;
  frame cyl_axes;        /* PC_SHAPE_CYLINDER: unit axes, n along the centreline (shape_cylinder.h) */
  float length;          /* PC_SHAPE_CYLINDER: of the centreline */
  bool flip_normals;     /* PC_SHAPE_SPHERE, PC_SHAPE_CYLINDER: normals point inward */
  int material;          /* index into materials */
  int light;             /* index into lights if this shape is an area emitter, else -1 */
  int xml_file, xml_line; /* the <shape> element it comes from: the scene file (0) or included
                             file xml_includes[xml_file - 1], and its line (for messages) */
} pc_shape;

/* A shape whose toWorld is an <animation>: its shape in object space (the scene's shapes[shape]
 * holds it moved to one time of the shutter). */
typedef struct pc_motion {
  int shape;
  pc_anim anim;
  pc_shape object;
} pc_motion;

/* PC_METHOD_AUTO is a choice, not an estimator: a pilot resolves it to pt, bdpt or pcbpt with
 * parameters (common/render/pilot.h) before anything renders; the renderer refuses it. */
typedef enum { PC_METHOD_PT, PC_METHOD_LT, PC_METHOD_BDPT, PC_METHOD_CBDPT, PC_METHOD_PCBPT, PC_METHOD_AUTO } pc_method;

/* Limits on what one scene may contain (untrusted input). */
#define PC_SCENE_MAX_SHAPES 65536
#define PC_SCENE_MAX_MATERIALS 65536
#define PC_SCENE_MAX_TEXTURES 4096
#define PC_SCENE_MAX_LIGHTS 65536
#define PC_SCENE_MAX_FILM_DIM 16384

/* Command-line $name parameters (Mitsuba's -D name=value), kept in one flat buffer so render
 * settings that carry them stay plain data: "name\0value\0name\0value\0...". */
#define PC_SCENE_MAX_DEFINES 64
#define PC_SCENE_DEFINES_BYTES 4096
typedef struct pc_scene_defines {
  int n;
  int used;                    /* bytes of buf in use */
  char buf[PC_SCENE_DEFINES_BYTES];
} pc_scene_defines;

typedef struct pc_scene {
  char *path;                 /* scene file as given */
  pc_shape *shapes; int nshapes;
  pc_material *materials; int nmaterials;
  pc_texture *textures; int ntextures;
  pc_light *lights; int nlights;
  pc_camera camera;
  pc_method method;           /* from <integrator type=...>: path, bdpt or pcbpt */
  int max_depth;              /* Mitsuba maxDepth: -1 infinite, 1 = emitters seen directly */
  int sample_count;           /* the <sampler>'s sampleCount (0: none): default iteration count */
  /* Motion blur: each iteration renders the scene at one time drawn uniformly in the sensor's
   * [shutter_open, shutter_close] (Mitsuba samples a time per path the same way); a renderer
   * moves the animated shapes and sensor of its own view (pc_scene_view). */
  float shutter_open, shutter_close;
  pc_motion *motions; int nmotions;
  pc_anim camera_anim;        /* n == 0: the sensor does not move */
  /* every file the scene read (itself first), for bundles: its real path, and its name below
   * root as the scene reaches it (a link inside the folder keeps its own name, so the unpacked
   * bundle holds every name the scene uses) */
  char **files, **file_names; int nfiles;
  char *root;                 /* real path of the folder that confines those files */
  char **xml_includes; int nxml_includes; /* included XML files as messages name them */
  /* built by pc_scene_build */
  void *rtc_device, *rtc_scene; /* RTCDevice, RTCScene (kept opaque to users of this header) */
  void *rtc_error;            /* where Embree's error callback records the first error */
  float *light_cdf;           /* nlights+1, power-proportional selection */
  float scene_radius;         /* bounding sphere radius, for ray offsets */
  vec3 scene_center;
  int env_light;              /* index of the environment emitter, -1 if none */
  float env_radius;           /* light paths from the environment start on a disk of this radius
                                 perpendicular to their direction, outside the bounding sphere */
  /* Every ray traced through this scene is handed to ray_hook first (NULL but in the Embree
   * ceiling benchmark, tests/bench/bench_rays.c, which records a render's rays to replay them
   * through Embree alone): shadow rays test t in [0, tfar) of o + t d. */
  void (*ray_hook)(void *user, bool shadow, vec3 o, vec3 d, float tfar);
  void *ray_hook_user;
  pc_scene_defines defines_used; /* the load's -D values that a $name of the scene substituted */
} pc_scene;


/* Adds "name=value" (name: letters, digits, _; a later -D of the same name replaces it). */
int pc_scene_defines_add(pc_scene_defines *d, const char *name_eq_value, pc_err *e);
/* The i-th definition. */
void pc_scene_defines_get(const pc_scene_defines *d, int i, const char **name, const char **value);
/* The definitions as one line, "a=1 b=x y", in the order of their names (so two sets of the same
 * values print alike whatever order they were given in); "" for none. Returns the length
 * snprintf would write; PC_SCENE_DEFINES_TEXT bytes always suffice. */
#define PC_SCENE_DEFINES_TEXT (PC_SCENE_DEFINES_BYTES + 2 * PC_SCENE_MAX_DEFINES)
int pc_scene_defines_text(const pc_scene_defines *d, char *buf, size_t size);

/* Receives one warning line ("file:line: what"), already without repeats. */
typedef void (*pc_scene_warn_fn)(void *ud, const char *line);

typedef struct pc_scene_load_opts {
  const char *root;                 /* folder confining every file the scene names (NULL: the scene's own) */
  const pc_scene_defines *defines;  /* -D values; they win over <default> */
  pc_scene_warn_fn warn;            /* NULL: warnings are not reported */
  void *warn_ud;
  bool strict;                      /* what would be a warning is an error */
  size_t max_file_bytes;            /* the scene's files together, checked before any is read (0: no bound) */
} pc_scene_load_opts;

/* Parses a Mitsuba 0.6 XML scene (the subset in DESIGN.md §5). Errors are "file:line: what".
 * opts may be NULL (no -D, warnings dropped, the scene's folder as root). */
int pc_scene_load_with(const char *path, const pc_scene_load_opts *opts, pc_scene *out, pc_err *e);
int pc_scene_load(const char *path, pc_scene *out, pc_err *e);
/* Builds Embree geometry, light sampling tables and derived material data. */
int pc_scene_build(pc_scene *s, pc_err *e);
/* Instead of pc_scene_build, for a client that only checks a scene before sending it: the same
 * checks and derived data without the ray-tracing structure (the bounding sphere from the
 * shapes' vertices), so a scene of millions of triangles is checked in a pass over its arrays
 * instead of a BVH build. What only the build can meet (Embree out of memory, an Embree without
 * spheres) is the worker's to report. The scene can then be bundled, given to
 * pc_renderer_check and freed; it cannot be rendered. */
int pc_scene_check(pc_scene *s, pc_err *e);
/* Where the camera sees the back of a one-sided material (pc_material_shows_behind), which
 * renders black as in Mitsuba 0.6: a scene whose walls face away from the room it encloses
 * (published conversions from renderers whose materials are two-sided) renders nearly black,
 * and a user is owed the reason. Also where it sees a surface outside the sensor's clip range,
 * which Mitsuba's path tracer would see past and pcbpt does not. pc_scene_probe_backs traces
 * grid x grid primary rays through the image of a checked scene (pc_scene_check, not built) on
 * an Embree structure of its own, released before it returns. */
#define PC_SCENE_BACKS_NAMED 3
typedef struct pc_scene_backs {
  int rays, backs;                  /* rays traced; of them, the first hits on such a back */
  int nearer, farther;              /* first hits nearer than nearClip, beyond farClip (along the view) */
  int nshapes;                      /* shapes whose backs were hit, the most hit first (at most 3) */
  int shape[PC_SCENE_BACKS_NAMED], count[PC_SCENE_BACKS_NAMED];
} pc_scene_backs;
int pc_scene_probe_backs(pc_scene *s, int grid, pc_scene_backs *out, pc_err *e);
/* Grows [lo, hi] to hold the shape as it is now. */
void pc_shape_grow_bounds(const pc_shape *sh, vec3 *lo, vec3 *hi);
/* Frees everything (safe on a zeroed or partially loaded scene). */
void pc_scene_free(pc_scene *s);

const char *pc_method_name(pc_method m);
int pc_method_parse(const char *name, pc_method *out); /* "pt" or "path", "lt", "bdpt", ... */
/* Whether path tracing (eye paths with next-event estimation) can sample every path of the
 * scene. It cannot when a point or spot light shines on a surface through a delta lobe (a
 * caustic of a glass or mirror, light through a thin pane or a mask's holes): such a path
 * reaches the light only by a connection from its last surface vertex, which a delta lobe does
 * not make, and an eye path never hits a light that sits at one point. Its image then lacks that
 * light, however long it runs, while the bidirectional methods' light sub-paths find it. Judged
 * from the shapes' materials and the lights, before or after pc_scene_build. */
bool pc_scene_pt_complete(const pc_scene *s);
/* Whether light tracing can sample every path of the scene. It cannot where the camera sees a
 * delta lobe (a mirror or glass, a smooth plastic coat, a mask's holes): its paths reach the
 * camera only by a connection from their last surface vertex, which a delta lobe does not make,
 * so its image lacks what is seen in or through such a surface. Judged from the materials of
 * every shape (seen or not), before or after pc_scene_build. */
bool pc_scene_lt_complete(const pc_scene *s);
/* A shape is a mirror or a glass (pc_material_casts_caustics): light that reaches a diffuse
 * surface by way of it and is seen from there (a caustic) is sampled well by light tracing
 * alone, so the light-tracing paths are not to be cut (--method auto's stage 5, pilot.h). */
bool pc_scene_has_caustics(const pc_scene *s);

/* Motion blur (scene_motion.c). True if the scene changes during the shutter. */
bool pc_scene_moves(const pc_scene *s);
/* The time iteration `iteration` of job `seed` renders at (shutter_open for a still scene). */
float pc_scene_time(const pc_scene *s, uint64_t seed, uint64_t iteration);
/* Places the animated shapes and sensor of a loaded scene at `time` (pc_scene_build places them
 * at shutter_open); without Embree data yet, only the plain data. */
int pc_scene_place(pc_scene *s, float time, pc_err *e);
/* A view of a built scene that a renderer moves to its iteration's time: the static shapes and
 * everything else are shared with `s`, which must outlive it. */
int pc_scene_view_create(const pc_scene *s, pc_scene **out, pc_err *e);
/* Moves the view's animated shapes and sensor to `time`. */
int pc_scene_view_set_time(pc_scene *view, float time, pc_err *e);
void pc_scene_view_destroy(pc_scene *view);

/* A ray hit with everything shading needs. */
typedef struct pc_hit {
  vec3 p;
  vec3 ng;          /* geometric normal, front side */
  vec3 ns;          /* interpolated shading normal (== ng when the mesh has none) */
  vec2 uv;
  vec3 dpdu, dpdv;  /* position derivatives along uv, as Mitsuba's: a triangle's from its texture
                       coordinates (its edges p1-p0, p2-p0 without them), a sphere's analytic */
  float t;
  float eps;        /* rays leave and reach the point that far off (PC_OFFSET_RELATIVE) */
  int shape, prim;
} pc_hit;

/* The shading frame of a hit whose triangle keeps it (a still mesh without shading normals:
 * what pc_shading_frame gives for its ng, ns and dpdu), else NULL. */
static inline const frame *pc_hit_frame(const pc_scene *s, const pc_hit *h) {
  const pc_shape *sh = &s->shapes[h->shape];
  return sh->tri && !sh->mesh.n ? &sh->tri[h->prim].f : NULL;
}

/* Closest hit along (o, d) within (0, tmax); d need not be normalised. */
bool pc_scene_intersect(const pc_scene *s, vec3 o, vec3 d, float tmax, pc_hit *hit);
/* How far rays leave and reach a point off its surface: 2^-20 (8 ulps) of the largest
 * coordinate of the point and of the primitive it lies on. Floating point is relative, so is
 * the offset: a hit point rebuilt from barycentrics is off its triangle's plane by a few ulps
 * of its own or its vertices' coordinates (through the barycentrics' error). The offset was
 * 1e-4 x max(1, |p|, scene radius / 100), whose share of the geometry grew as the scene shrank,
 * moved off the origin or gained a large far-away part: the Cornell box at 1/1000 scale came
 * out 0.4-0.9% off, moved 10^4 units away (an offset of 1, half the box) 13-28%, and beside a
 * plane 10^5 wide 0.8-1.4% with the radius as the only floor (tests/cli/test_scale.sh). */
#define PC_OFFSET_RELATIVE 0x1p-20f
/* A point on no surface (point and spot lights). */
static inline float pc_point_eps(vec3 p) { return PC_OFFSET_RELATIVE * v3_maxabs(p); }
static inline float pc_sphere_eps(vec3 center, float radius, vec3 p) {
  return PC_OFFSET_RELATIVE * pc_maxf(v3_maxabs(p), v3_maxabs(center) + radius);
}
static inline float pc_triangle_vmax(vec3 p0, vec3 p1, vec3 p2) {
  return pc_maxf(v3_maxabs(p0), pc_maxf(v3_maxabs(p1), v3_maxabs(p2)));
}
static inline float pc_triangle_eps_vmax(vec3 p, float vmax) { return PC_OFFSET_RELATIVE * pc_maxf(v3_maxabs(p), vmax); }
static inline float pc_triangle_eps(vec3 p, vec3 p0, vec3 p1, vec3 p2) {
  return pc_triangle_eps_vmax(p, pc_triangle_vmax(p0, p1, p2));
}
/* p moved eps off a surface with geometric normal ng, on the side of direction d. */
static inline vec3 pc_offset_by(vec3 p, vec3 ng, vec3 d, float eps) {
  return v3_madd(p, ng, v3_dot(d, ng) >= 0.f ? eps : -eps);
}
/* True if the ray from p (offset ea off a surface with geometric normal ng, zero for none)
 * along direction d leaves the scene: the environment is visible that way. */
bool pc_scene_escapes(const pc_scene *s, vec3 p, vec3 ng, float eps, vec3 d);
/* True if the open segment from a to b is unoccluded; each end is offset off its surface along
 * its geometric normal by its offset ea, eb (na or nb zero: a point on no surface). */
bool pc_scene_visible(const pc_scene *s, vec3 a, vec3 na, float ea, vec3 b, vec3 nb, float eb);

#endif
