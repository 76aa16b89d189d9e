/* scene_xml_ctx.h: state and helpers shared by the files of the Mitsuba scene loader
 * (scene_xml.c: scene, integrator, sensor, shapes, emitters; scene_materials_xml.c: BSDFs and
 * textures; scene_params.c: parameters, ids, $-substitution, paths). Private to them. */
#ifndef PC_SCENE_XML_CTX_H
#define PC_SCENE_XML_CTX_H

#include <limits.h>
#include <stdbool.h>

#include "scene.h"
#include "xml_tree.h"

typedef enum { PC_ID_BSDF, PC_ID_TEXTURE, PC_ID_OTHER, PC_ID_SHAPEGROUP } pc_id_kind;

typedef struct pc_sx_id {
  char *id;
  pc_id_kind kind;
  int index;
  int line;
} pc_sx_id;

typedef struct pc_sx {
  const char *file;  /* the file of the element being read (the scene path as given, or an
                        included file's), for messages */
  const char *main_file;
  char *dir;         /* realpath of the folder confining every file reference (the root) */
  const pc_scene_load_opts *opts; /* never NULL */
  char **warned;     /* warnings already given (without their location), so each is given once */
  int nwarned, cap_warned;
  char **names;      /* display names of included files (owned; nodes point at them) */
  int nnames, cap_names;
  const char *incl_stack[16]; /* real paths of the files being included, for loop detection */
  char *incl_names[16];       /* their names below the root (see pc_scene.file_names) */
  int incl_depth;
  pc_scene *s;
  pc_err *e;
  pc_sx_id *ids;
  int nids, cap_ids;
  int *id_table;     /* open addressing over ids, -1 empty */
  int id_table_size;
  char **pnames, **pvalues; /* <default> parameters */
  int nparams, cap_params;
  int ndefines;             /* the first ndefines parameters are the -D values */
  bool define_used[PC_SCENE_MAX_DEFINES]; /* whether a $name substituted that -D value */
  int default_material;     /* Mitsuba's diffuse 0.5 for shapes without a BSDF, -1 until needed */
  bool have_env;            /* an environment emitter was declared (Mitsuba allows one) */
  int cap_shapes, cap_materials, cap_textures, cap_lights, cap_motions;
  unsigned long long file_bytes; /* sizes of the files noted so far, against opts->max_file_bytes */
  /* shapegroups (scene_instance_xml.c): their shapes in object space, kept out of the scene,
   * group g being group_first[g] .. group_first[g + 1] - 1 (ngroups + 1 entries) */
  pc_shape *group_shapes;
  int ngroup_shapes, cap_group_shapes;
  int *group_first;
  int ngroups, cap_group_first;
  unsigned long long instanced_tris; /* triangles copied by instances, against PC_SX_MAX_INSTANCED_TRIS */
} pc_sx;

/* Parameter kinds a plugin declares. */
typedef enum {
  PC_P_INT,       /* <integer> */
  PC_P_FLOAT,     /* <float> (or <integer>) */
  PC_P_BOOL,      /* <boolean> */
  PC_P_STRING,    /* <string> */
  PC_P_COLOR,     /* <rgb>, <srgb>, <spectrum> -> vec3 */
  PC_P_COLOR_SIGNED, /* the same, negative <rgb> and <spectrum> values kept (pc_xv_color_signed) */
  PC_P_SLOT,      /* a colour or a texture (nested, or <ref name=.. id=..>) -> pc_tex_slot */
  PC_P_POINT,     /* <point> -> vec3 */
  PC_P_VECTOR,    /* <vector> -> vec3 (Mitsuba 0.6 keeps points and vectors apart) */
  PC_P_TRANSFORM, /* <transform>, or an <animation> that does not move -> mat4 */
  PC_P_MOTION,    /* <transform> or <animation> -> pc_sx_xf (the caller frees its anim) */
  PC_P_IOR,       /* <float> or <string> with a Mitsuba IOR name -> float */
  PC_P_IGNORED,   /* any value, accepted with a warning; out is the reason (const char *).
                     The name "*" matches every parameter the list does not name. */
} pc_param_kind;

typedef struct pc_param {
  const char *name;
  pc_param_kind kind;
  void *out;   /* int*, float*, bool*, const char**, vec3*, pc_tex_slot*, vec3* (point, vector), mat4*, pc_sx_xf*, float* */
  bool set;    /* filled by pc_sx_params */
  int line;
} pc_param;

/* A PC_P_MOTION value: a <transform> (anim.n == 0), or an <animation> that moves (xf the
 * identity); a static <animation> is the plain transform Mitsuba makes of it. */
typedef struct pc_sx_xf {
  mat4 xf;
  pc_anim anim;
} pc_sx_xf;

/* "what" strings for messages: e.g. "bsdf 'diffuse'". */
#define PC_SX_WHAT_MAX 96

/* Reads the parameter children of n into params; fails on unknown or repeated names, on the
 * wrong element for a parameter, and on malformed values. Non-parameter children (nested
 * objects other than named textures/refs in slots) are left to the caller. */
int pc_sx_params(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *params, int np);
/* True if pc_sx_params consumed this child. */
bool pc_sx_is_param(const pc_xml_node *ch, const pc_param *params, int np);
/* pc_sx_params, refusing any other child element. */
int pc_sx_params_only(pc_sx *c, const pc_xml_node *n, const char *what, pc_param *p, int np);
/* Error for a child element the caller does not accept. */
int pc_sx_unexpected(pc_sx *c, const pc_xml_node *ch, const char *what);

/* A warning "file:line: what: message" through opts->warn, once per distinct "what: message";
 * with --strict it is the error instead (returns its code; 0 otherwise). */
int pc_sx_warn(pc_sx *c, const pc_xml_node *n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* The name below the root of `rel` taken relative to the folder of the file named `base` (a
 * name below the root): "." and empty parts dropped, ".." taken lexically, as in the unpacked
 * bundle; NULL-terminated into out. Fails if it leaves the root. */
int pc_sx_name_below(pc_sx *c, const pc_xml_node *n, const char *base, const char *rel, char out[PATH_MAX]);
/* Records a file the scene read (for bundles): its real path and its name below the root. */
int pc_sx_note_file(pc_sx *c, const char *real, const char *name);

/* <include filename=...> at scene level (its attributes already substituted): parses the file
 * into *root (the caller splices root's children in the include's place and frees root) and
 * pushes it on the include stack; pc_sx_include_close pops it when its children are done. */
int pc_sx_include_open(pc_sx *c, const pc_xml_node *incl, pc_xml_node **root);
void pc_sx_include_close(pc_sx *c);

/* Registers an id (duplicates are errors). */
int pc_sx_id_add(pc_sx *c, const char *id, pc_id_kind kind, int index, int line);
/* Looks an id up; NULL if unknown. */
const pc_sx_id *pc_sx_id_find(const pc_sx *c, const char *id);

/* The $name substitution and <default> pass over the whole tree, in document order. */
int pc_sx_substitute(pc_sx *c, pc_xml_node *root);

/* Resolves a file name relative to the scene folder; refuses absolute paths, missing files and
 * paths that leave the folder. *out is malloc'd. */
int pc_sx_resolve(pc_sx *c, const pc_xml_node *n, const char *what, const char *rel, char **out);

/* Appends to the scene arrays (bounded by PC_SCENE_MAX_*). */
/* Grows *arr (capacity *cap elements of `elem` bytes) to hold `need` elements. */
int pc_sx_grow(pc_sx *c, void **arr, int *cap, int need, size_t elem);
int pc_sx_add_material(pc_sx *c, const pc_xml_node *n, const pc_material *m, int *index);
int pc_sx_add_texture(pc_sx *c, const pc_xml_node *n, const pc_texture *t, int *index);

/* Prefixes the message in c->e with "file:line: what: " (for errors from mesh and image
 * readers) and returns rc. */
int pc_sx_wrap(pc_sx *c, const pc_xml_node *n, const char *what, int rc);

/* BSDF and texture elements (scene_materials_xml.c). */
int pc_sx_bsdf(pc_sx *c, const pc_xml_node *n, int *index);
/* A <shape> appended to the scene (scene_xml.c), and a shape appended as is. */
int pc_sx_shape(pc_sx *c, const pc_xml_node *n);
int pc_sx_add_shape(pc_sx *c, const pc_xml_node *n, pc_shape *sh);
/* Keeps the scene's last shape, as it is now, as the object-space shape `anim` moves (Mitsuba
 * wraps a shape with a moving toWorld in an animated instance); a sphere's motion must scale
 * uniformly. */
int pc_sx_add_motion(pc_sx *c, const pc_xml_node *n, const char *what, const pc_anim *anim);
/* True if m is a rotation, uniform scale and translation; *s the scale. */
bool pc_sx_is_similarity(const mat4 *m, double *s);
/* Mitsuba's `shapegroup` (kept aside) and `instance` (its shapes copied into the scene through
 * the instance's toWorld); pc_sx_groups_free releases what the groups hold. */
int pc_sx_shapegroup(pc_sx *c, const pc_xml_node *n);
int pc_sx_instance(pc_sx *c, const pc_xml_node *n);
void pc_sx_groups_free(pc_sx *c);
int pc_sx_texture(pc_sx *c, const pc_xml_node *n, int *index);
/* The BSDFs of scene_bsdf_lambertian_xml.c (phong, roughdiffuse) into *m, or the one-line
 * refusal of a plugin pcbpt does not model. */
int pc_sx_bsdf_more(pc_sx *c, const pc_xml_node *n, const char *type, const char *what, pc_material *m);
int pc_sx_default_material(pc_sx *c, const pc_xml_node *n, int *index);
/* The wrappers bumpmap, coating and roughcoating into *m (whose slots hold their defaults), and
 * the `scale` texture into *t (scene_layers_xml.c). */
int pc_sx_bsdf_wrapper(pc_sx *c, const pc_xml_node *n, const char *type, const char *what, pc_material *m);
/* Mitsuba's `mask`, `blendbsdf` and `mixturebsdf` (scene_layers_xml.c). */
int pc_sx_bsdf_mix(pc_sx *c, const pc_xml_node *n, const char *type, const char *what, pc_material *m);
/* True if a parsed material (its components by index) transmits light, which Mitsuba's
 * twosided refuses to wrap. */
bool pc_sx_transmits(const pc_sx *c, const pc_material *m);
int pc_sx_scale_texture(pc_sx *c, const pc_xml_node *n, const char *what, pc_texture *t);
/* An OBJ's material library (scene_obj_xml.c), read as Mitsuba's obj plugin reads it: mtllib as
 * written in the OBJ obj_rel (relative to the scene's folder) at `line`. *out NULL, with a
 * warning, when Mitsuba would not find it either. */
typedef struct pc_sx_mtl pc_sx_mtl;
int pc_sx_mtl_load(pc_sx *c, const pc_xml_node *shape, const char *obj_rel, const char *mtllib, int line, pc_sx_mtl **out);
/* The scene material of the library's material `name` (made on first use), or -1 if the library
 * (which may be NULL) has none of that name. */
int pc_sx_mtl_material(pc_sx *c, pc_sx_mtl *lib, const char *name, int *index);
void pc_sx_mtl_free(pc_sx_mtl *lib);
/* Mitsuba's microfacet distribution names (beckmann, ggx, phong or its alias as); -1 if none. */
int pc_sx_distribution(const char *name, pc_mf_type *out);

#endif
