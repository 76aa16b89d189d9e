/* test_scene_parser.c: the Mitsuba scene loader: good scenes give the right values, every
 * refused construct fails with "scene.xml:line:" and a key word, and mutated files never
 * crash. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <embree3/rtcore.h>
#include <sys/stat.h>

#include "fresnel.h"
#include "render.h"
#include "scene.h"
#include "test_helpers_fs.h"

static void good_path(char *out, size_t cap, const char *name) {
  snprintf(out, cap, "%s/tests/data/good/%s", th_source_dir(), name);
}

static void near3(vec3 a, vec3 b, float tol) {
  if (fabsf(a.x - b.x) > tol || fabsf(a.y - b.y) > tol || fabsf(a.z - b.z) > tol) {
    print_error("(%g %g %g) != (%g %g %g)\n", a.x, a.y, a.z, b.x, b.y, b.z);
    fail();
  }
}

static vec3 tri_normal(const pc_mesh *m, uint32_t t) {
  vec3 a = m->p[m->idx[3 * t]], b = m->p[m->idx[3 * t + 1]], c = m->p[m->idx[3 * t + 2]];
  return v3_norm(v3_cross(v3_sub(b, a), v3_sub(c, a)));
}

static void test_full_scene(void **state) {
  (void)state;
  char path[4096];
  good_path(path, sizeof path, "full.xml");
  pc_scene s;
  pc_err e = {0};
  int rc = pc_scene_load(path, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_string_equal(s.path, path);
  assert_int_equal(s.method, PC_METHOD_PCBPT);
  assert_int_equal(s.max_depth, 5); /* the first <default> wins */

  /* camera: lookat from +z toward the origin: left = -x, up = +y, dir = -z */
  const pc_camera *c = &s.camera;
  assert_int_equal(c->width, 320);
  assert_int_equal(c->height, 240);
  assert_true(c->fov_deg == 40.f);
  assert_int_equal(c->fov_axis, 'y');
  double want[3][4] = {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, -1, 5}};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 4; j++) assert_true(fabs(c->to_world.m[i][j] - want[i][j]) < 1e-9);

  /* textures: the scene-level checkerboard and the one nested in the roughplastic */
  assert_int_equal(s.ntextures, 2);
  assert_int_equal(s.textures[0].type, PC_TEX_CHECKER);
  near3(s.textures[0].color0, v3(0.1f, 0.2f, 0.3f), 1e-6f);
  near3(s.textures[0].color1, v3s(0.2f), 1e-6f);
  assert_true(s.textures[0].uscale == 4.f && s.textures[0].vscale == 1.f && s.textures[0].uoffset == 0.f);
  near3(s.textures[1].color0, v3s(0.4f), 1e-6f);

  /* materials in declaration order; shapes without a BSDF share Mitsuba's diffuse 0.5 */
  assert_int_equal(s.nmaterials, 8);
  const pc_material *m = s.materials;
  assert_int_equal(m[0].type, PC_MAT_DIFFUSE);
  assert_false(m[0].twosided);
  assert_int_equal(m[0].reflectance.tex, 0);
  assert_int_equal(m[1].type, PC_MAT_DIFFUSE);
  assert_true(m[1].twosided);
  assert_int_equal(m[1].reflectance.tex, 0);
  assert_int_equal(m[2].type, PC_MAT_ROUGHCONDUCTOR);
  assert_true(fabsf(m[2].alpha - 0.25f) < 1e-7f);
  assert_int_equal(m[2].distribution, PC_MF_GGX);
  vec3 eta, k;
  assert_true(pc_conductor_ior("Au", &eta, &k));
  near3(m[2].eta, eta, 1e-6f);
  near3(m[2].k, k, 1e-6f);
  near3(m[2].specular.value, v3s(1), 0);
  assert_int_equal(m[3].type, PC_MAT_DIELECTRIC);
  assert_true(fabsf(m[3].int_ior - 1.333f) < 1e-6f && m[3].ext_ior == 1.f);
  assert_int_equal(m[4].type, PC_MAT_PLASTIC);
  assert_true(fabsf(m[4].int_ior - 1.49f) < 1e-6f && fabsf(m[4].ext_ior - 1.000277f) < 1e-6f);
  assert_true(m[4].nonlinear);
  near3(m[4].reflectance.value, v3s(0.21586f), 1e-4f); /* sRGB #808080 in linear */
  assert_int_equal(m[4].reflectance.tex, -1);
  assert_int_equal(m[5].type, PC_MAT_DIFFUSE);
  near3(m[5].reflectance.value, v3s(0.5f), 0);
  assert_int_equal(m[6].type, PC_MAT_ROUGHPLASTIC);
  assert_true(fabsf(m[6].alpha - 0.3f) < 1e-7f);
  assert_int_equal(m[6].distribution, PC_MF_BECKMANN); /* Mitsuba's default */
  assert_int_equal(m[6].reflectance.tex, 1);
  assert_int_equal(m[7].type, PC_MAT_CONDUCTOR);
  assert_true(pc_conductor_ior("Cu", &eta, &k));
  near3(m[7].eta, eta, 1e-6f);

  assert_int_equal(s.nshapes, 7);
  const pc_shape *sh = s.shapes;
  /* obj and ply describe the same quad; both rotated 90 degrees about z then translated */
  const pc_mesh *a = &sh[0].mesh, *b = &sh[1].mesh;
  assert_int_equal(sh[0].material, 1);
  assert_int_equal(sh[1].material, 4);
  assert_int_equal(a->nverts, 4);
  assert_int_equal(a->ntris, 2);
  assert_int_equal(b->nverts, 4);
  assert_int_equal(b->ntris, 2);
  assert_non_null(a->n);
  assert_non_null(a->uv);
  for (uint32_t i = 0; i < 4; i++) {
    near3(a->p[i], b->p[i], 1e-6f);
    near3(a->n[i], b->n[i], 1e-6f);
    near3(a->n[i], v3(0, 0, 1), 1e-6f);
    assert_true(a->uv[i].x == b->uv[i].x && a->uv[i].y == b->uv[i].y);
  }
  for (int i = 0; i < 6; i++) assert_int_equal(a->idx[i], b->idx[i]);
  near3(a->p[1], v3(1, 3, 3), 1e-6f); /* (1,0,0) rotated to (0,1,0), then translated */
  near3(a->p[3], v3(0, 2, 3), 1e-6f); /* (0,1,0) rotated to (-1,0,0) */
  assert_true(a->uv[0].y == 1.f);     /* flipTexCoords defaults to true */

  /* rectangle: scaled, rotated to face -y, flipped to face +y; an area light */
  const pc_mesh *r = &sh[2].mesh;
  assert_int_equal(sh[2].kind, PC_SHAPE_MESH);
  assert_null(r->n);
  for (uint32_t t = 0; t < r->ntris; t++) near3(tri_normal(r, t), v3(0, 1, 0), 1e-6f);
  for (uint32_t i = 0; i < r->nverts; i++) {
    assert_true(fabsf(r->p[i].y - 3.f) < 1e-6f);
    assert_true(fabsf(fabsf(r->p[i].x) - 0.5f) < 1e-6f && fabsf(fabsf(r->p[i].z) - 0.5f) < 1e-6f);
  }
  assert_int_equal(sh[2].light, 0);
  assert_int_equal(sh[2].material, 5);
  assert_int_equal(s.nlights, 2);
  assert_int_equal(s.lights[0].type, PC_LIGHT_AREA);
  assert_int_equal(s.lights[0].shape, 2);
  near3(s.lights[0].radiance, v3(10, 8, 6), 0);
  assert_int_equal(s.lights[1].type, PC_LIGHT_POINT);
  near3(s.lights[1].position, v3(0, 4, 0), 0);
  near3(s.lights[1].intensity, v3s(3), 0);

  /* sphere: center (1,0,0) radius 0.5, scaled by 2 then moved down z */
  assert_int_equal(sh[3].kind, PC_SHAPE_SPHERE);
  near3(sh[3].center, v3(2, 0, -1), 1e-6f);
  assert_true(fabsf(sh[3].radius - 1.f) < 1e-6f);
  assert_false(sh[3].flip_normals);
  assert_int_equal(sh[3].material, 3);

  /* cube: 12 outward-facing triangles */
  const pc_mesh *cu = &sh[4].mesh;
  assert_int_equal(cu->ntris, 12);
  for (uint32_t t = 0; t < 12; t++) {
    vec3 cen = v3_scale(v3_add(v3_add(cu->p[cu->idx[3 * t]], cu->p[cu->idx[3 * t + 1]]), cu->p[cu->idx[3 * t + 2]]), 1.f / 3);
    assert_true(v3_dot(tri_normal(cu, t), cen) > 0.3f);
  }
  /* disk: facing +z, area close to pi */
  const pc_mesh *d = &sh[5].mesh;
  double area = 0;
  for (uint32_t t = 0; t < d->ntris; t++) {
    near3(tri_normal(d, t), v3(0, 0, 1), 1e-5f);
    vec3 p0 = d->p[d->idx[3 * t]], p1 = d->p[d->idx[3 * t + 1]], p2 = d->p[d->idx[3 * t + 2]];
    area += 0.5 * v3_len(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
  }
  assert_true(fabs(area - M_PI) < 1e-3);
  /* faceNormals drops the file's normals */
  assert_null(sh[6].mesh.n);
  assert_int_equal(sh[6].material, 5);
  for (int i = 0; i < s.nshapes; i++)
    if (i != 2) assert_int_equal(sh[i].light, -1);
  pc_scene_free(&s);
}

static void test_cornell_box(void **state) {
  (void)state;
  const char *src = getenv("PCBPT_SOURCE_DIR");
  assert_non_null(src);
  char path[4096];
  snprintf(path, sizeof path, "%s/scenes/cornell-box/scene.xml", src);
  pc_scene s;
  pc_err e = {0};
  int rc = pc_scene_load(path, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 8);
  assert_int_equal(s.nlights, 1);
  assert_int_equal(s.lights[0].shape, 7);
  assert_int_equal(s.shapes[7].light, 0);
  near3(s.lights[0].radiance, v3(17, 12, 4), 0);
  const pc_material *left = &s.materials[s.shapes[4].material];
  assert_int_equal(left->type, PC_MAT_DIFFUSE);
  assert_true(left->twosided);
  near3(left->reflectance.value, v3(0.63f, 0.065f, 0.05f), 1e-7f);
  assert_false(s.materials[s.shapes[7].material].twosided);
  assert_int_equal(s.method, PC_METHOD_PCBPT);
  assert_int_equal(s.max_depth, 11);
  assert_int_equal(s.camera.width, 256);
  assert_true(s.camera.fov_deg == 19.5f);
  assert_int_equal(s.camera.fov_axis, 'x');
  assert_true(fabs(s.camera.to_world.m[2][3] - 6.8) < 1e-9 && s.camera.to_world.m[1][3] == 1.0);
  /* the left wall at x = -1 has normals computed from its winding, which faces -x (the
   * walls are twosided, so the file never needed to care) */
  const pc_mesh *w = &s.shapes[4].mesh;
  assert_non_null(w->n);
  near3(w->n[0], v3(-1, 0, 0), 1e-6f);
  pc_scene_free(&s);
}

/* ---- scenes written to a temporary folder ---- */

typedef struct tmp {
  char root[256];  /* holds outside.obj */
  char dir[300];   /* the scene folder */
  char scene[400];
} tmp;

static const char *QUAD_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

static void tmp_make(tmp *t) {
  strcpy(t->root, "/tmp/pcbpt_scene_XXXXXX");
  assert_non_null(mkdtemp(t->root));
  snprintf(t->dir, sizeof t->dir, "%s/scene", t->root);
  assert_int_equal(mkdir(t->dir, 0700), 0);
  snprintf(t->scene, sizeof t->scene, "%s/scene.xml", t->dir);
  assert_int_equal(th_write_str(t->root, "outside.obj", QUAD_OBJ), 0);
  assert_int_equal(th_write_str(t->dir, "quad.obj", QUAD_OBJ), 0);
  assert_int_equal(th_write_str(t->dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"), 0);
  assert_int_equal(th_write_str(t->dir, "badidx.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 1 2 9\n"), 0);
  assert_int_equal(th_write_str(t->dir, "tex.png", "not really a png"), 0);
  char link[400], target[400];
  snprintf(link, sizeof link, "%s/escape.obj", t->dir);
  snprintf(target, sizeof target, "%s/outside.obj", t->root);
  assert_int_equal(symlink(target, link), 0);
}

/* Loads `body` wrapped in <scene version="0.6.0"> (which is line 1, so body line k is file
 * line k+1). */
static int load_body(tmp *t, const char *body, pc_scene *s, pc_err *e) {
  char *xml = malloc(strlen(body) + 64);
  sprintf(xml, "<scene version=\"0.6.0\">\n%s\n</scene>\n", body);
  int w = th_write_str(t->dir, "scene.xml", xml);
  free(xml);
  assert_int_equal(w, 0);
  return pc_scene_load(t->scene, s, e);
}

/* load_body that must succeed: prints the loader's message (with `what`) before failing. */
static void load_ok(tmp *t, const char *body, const char *what, pc_scene *s) {
  pc_err e = {0};
  int rc = load_body(t, body, s, &e);
  if (rc) print_error("%s: %s\n", what, e.msg);
  assert_int_equal(rc, 0);
}

#define SENSOR "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>"
#define KEY(t, body) "<transform time=\"" #t "\">" body "</transform>"

typedef struct bad_case {
  const char *body;
  int line;
  const char *word;
} bad_case;

static const bad_case bad_cases[] = {
    /* integrator */
    {"<integrator type=\"path\">\n<integer name=\"maxDepth\" value=\"0\"/>\n</integrator>", 3, "maxDepth"},
    {"<integrator type=\"path\"><integer name=\"maxDepth\" value=\"-2\"/></integrator>", 2, "maxDepth"},
    {"\n<integrator type=\"volpath\"/><medium type=\"homogeneous\" id=\"m\"/>", 3, "participating media"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><film type=\"hdrfilm\">\n<integer name=\"cropWidth\" value=\"8\"/></film></sensor>", 3, "crop"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n<sampler type=\"independent\"><integer name=\"sampleCount\" value=\"0\"/></sampler></sensor>", 3, "sampleCount"},
    {"<integrator type=\"path\"/>\n<integrator type=\"path\"/>", 3, "integrator"},
    {"<integrator type=\"path\">\n<boolean name=\"hideEmitters\" value=\"true\"/></integrator>", 3, "hideEmitters"},
    {"<integrator type=\"bdpt\">\n<boolean name=\"lightImage\" value=\"false\"/></integrator>", 3, "lightImage"},
    {"<integrator type=\"path\"><integer name=\"maxDepth\" value=\"5x\"/></integrator>", 2, "integer"},
    {"<integrator type=\"path\"><integer name=\"maxDepth\" value=\"99999999999\"/></integrator>", 2, "integer"},
    {"\n<integrator type=\"ao\"/>", 3, "ambient occlusion, not light"},
    {"\n<integrator type=\"field\"><string name=\"field\" value=\"position\"/></integrator>", 3, "geometric fields"},
    {"\n<integrator type=\"multichannel\"><integrator type=\"path\"/></integrator>", 3, "several images"},
    {"\n<integrator type=\"adaptive\"/>", 3, "needs a nested <integrator>"},
    {"<integrator type=\"irrcache\"><integrator type=\"path\"/>\n<integrator type=\"path\"/></integrator>", 3, "more than one nested"},
    {"<integrator type=\"adaptive\"><integrator type=\"path\">\n<integer name=\"maxDepth\" value=\"0\"/></integrator></integrator>", 3, "maxDepth"},
    /* sensor */
    {"<sensor type=\"orthographic\"/>", 2, "orthographic"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\n<string name=\"focalLength\" value=\"35mm\"/></sensor>", 3, "not both"},
    {"<sensor type=\"perspective\">\n<string name=\"focalLength\" value=\"35cm\"/></sensor>", 3, "focalLength '35cm'"},
    {"<sensor type=\"thinlens\"><float name=\"apertureRadius\" value=\"0.1\"/>\n<string name=\"focalLength\" value=\"-5mm\"/></sensor>", 3, "positive length"},
    {"<sensor type=\"perspective\">\n<float name=\"focalLength\" value=\"35\"/></sensor>", 3, "cannot be given as <float>"},
    {"<sensor type=\"perspective\">\n<float name=\"focalLength\" value=\"50\"/></sensor>", 3, "focalLength"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n<string name=\"fovAxis\" value=\"z\"/></sensor>", 3, "fovAxis"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"180\"/></sensor>", 2, "fov"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n<transform name=\"toWorld\"><scale value=\"2\"/></transform></sensor>", 3, "rigid"},
    /* a 1-degree shear (a published bedroom's camera): Mitsuba refuses it too; a shear of 5e-4,
       which Mitsuba accepts, a still sensor takes (test_near_rigid_camera) */
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n<transform name=\"toWorld\"><matrix value=\"1 0.0175 0 0 0 1 0 0 0 0 1 0 0 0 0 1\"/></transform></sensor>", 3, "Mitsuba 0.6 refuses it too"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n<film type=\"hdrfilm\"><integer name=\"width\" value=\"0\"/></film></sensor>", 3, "width"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n<film type=\"hdrfilm\"><integer name=\"height\" value=\"20000\"/></film></sensor>", 3, "height"},
    {SENSOR "\n" SENSOR, 3, "sensor"},
    /* transforms */
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><transform name=\"toWorld\">\n<translate x=\"nan\"/></transform></sensor>", 3, "non-finite"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><transform name=\"toWorld\">\n<lookat origin=\"0,0,0\" target=\"0,1,0\" up=\"0,1,0\"/></transform></sensor>", 3, "parallel"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><transform name=\"toWorld\">\n<lookat origin=\"1,1,1\" target=\"1,1,1\" up=\"0,1,0\"/></transform></sensor>", 3, "origin equals target"},
    {"<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><transform name=\"toWorld\">\n<lookat origin=\"1,1\" target=\"0,0,0\" up=\"0,1,0\"/></transform></sensor>", 3, "origin"},
    {"<shape type=\"cube\">\n<transform name=\"toWorld\"><scale x=\"0\"/></transform></shape>", 3, "singular"},
    {"<shape type=\"cube\"><transform name=\"toWorld\">\n<matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1\"/></transform></shape>", 3, "affine"},
    {"<shape type=\"cube\"><transform name=\"toWorld\">\n<matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 1\"/></transform></shape>", 3, "16 numbers"},
    {"<shape type=\"cube\"><transform name=\"toWorld\">\n<skew value=\"1\"/></transform></shape>", 3, "skew"},
    {"<shape type=\"cube\"><transform name=\"toWorld\">\n<rotate angle=\"30\"/></transform></shape>", 3, "zero axis"},
    {"<shape type=\"cube\"><transform name=\"toWorld\">\n<translate x=\"1e300\"/><scale value=\"1e300\"/></transform></shape>", 3, "non-finite"},
    /* shapes and files */
    {"\n<shape type=\"hair\"/>", 3, "hair"},
    {"<shape type=\"obj\"/>", 2, "filename"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"missing.obj\"/></shape>", 2, "cannot find"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"/etc/passwd\"/></shape>", 2, "absolute"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"../outside.obj\"/></shape>", 2, "outside"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"escape.obj\"/></shape>", 2, "outside"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"flat.obj\"/><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>", 2, "an emitter whose every triangle is degenerate"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"badidx.obj\"/></shape>", 2, "badidx.obj:5:"},
    {"<shape type=\"ply\"><string name=\"filename\" value=\"quad.obj\"/></shape>", 2, "not a PLY"},
    {"<shape type=\"sphere\">\n<transform name=\"toWorld\"><scale x=\"2\"/></transform></shape>", 2, "sphere"},
    {"<shape type=\"sphere\"><float name=\"radius\" value=\"-1\"/></shape>", 2, "radius"},
    {"<shape type=\"cube\"><boolean name=\"flipNormals\" value=\"yes\"/></shape>", 2, "true or false"},
    {"<shape type=\"cube\"><bsdf type=\"diffuse\"/>\n<bsdf type=\"diffuse\"/></shape>", 3, "more than one BSDF"},
    {"<shape type=\"cube\">\n<medium type=\"homogeneous\" name=\"interior\"/></shape>", 3, "medium"},
    /* emitters */
    {"<emitter type=\"envmap\"/>", 2, "filename"},
    {"<emitter type=\"envmap\"><string name=\"filename\" value=\"nothere.exr\"/></emitter>", 2, "cannot find"},
    {"<emitter type=\"envmap\"><string name=\"filename\" value=\"tex.png\"/>\n<float name=\"gamma\" value=\"2.2\"/></emitter>", 3, "gamma"},
    {"<emitter type=\"envmap\"><string name=\"filename\" value=\"tex.png\"/>\n<float name=\"scale\" value=\"-1\"/></emitter>", 3, "scale"},
    {"<emitter type=\"envmap\"><string name=\"filename\" value=\"tex.png\"/>\n<transform name=\"toWorld\"><scale x=\"2\"/></transform></emitter>", 3, "rotation"},
    {"<emitter type=\"constant\">\n<rgb name=\"radiance\" value=\"0\"/></emitter>", 3, "radiance"},
    {"<emitter type=\"constant\"/>\n<emitter type=\"constant\"/>", 3, "only one environment"},
    {"<emitter type=\"collimated\"/>", 2, "emitter 'collimated': not modelled by pcbpt"},
    {"<bsdf type=\"roughconductor\">\n<texture type=\"checkerboard\" name=\"alpha\"/></bsdf>", 3,
     "bsdf 'roughconductor': a texture for 'alpha' (Mitsuba's plugin reads one): not modelled by pcbpt"},
    {"<bsdf type=\"phong\">\n<texture type=\"checkerboard\" name=\"exponent\"/></bsdf>", 3, "a texture for 'exponent'"},
    {"<bsdf type=\"roughconductor\">\n<texture type=\"checkerboard\" name=\"wobble\"/></bsdf>", 3, "unexpected <texture"},
    {"<bsdf type=\"diffuse\" id=\"a\"/>\n<alias id=\"b\" as=\"c\"/>", 3, "no object has the id 'b'"},
    {"<bsdf type=\"diffuse\" id=\"a\"/><bsdf type=\"diffuse\" id=\"c\"/>\n<alias id=\"a\" as=\"c\"/>", 3, "duplicate id 'c'"},
    {"<bsdf type=\"diffuse\" id=\"a\"/>\n<alias id=\"a\"/>", 3, "needs both"},
    {"<emitter type=\"directional\">\n<vector name=\"direction\" x=\"0\" y=\"0\" z=\"0\"/></emitter>", 3, "non-zero vector"},
    {"<emitter type=\"directional\"><vector name=\"direction\" x=\"1\"/>\n<transform name=\"toWorld\"/></emitter>", 2, "not both"},
    {"<emitter type=\"directional\">\n<transform name=\"toWorld\"><scale x=\"2\"/></transform></emitter>", 3, "scales or shears"},
    {"<emitter type=\"directional\">\n<rgb name=\"irradiance\" value=\"0\"/></emitter>", 3, "'irradiance' must be positive"},
    {"<emitter type=\"directional\">\n<point name=\"direction\" x=\"1\" y=\"0\" z=\"0\"/></emitter>", 3, "cannot be given as <point>"},
    {"<emitter type=\"sunsky\"/>", 2, "sunsky"},
    {"<emitter type=\"sunsky\"/>", 2, "emitter 'sunsky': not modelled by pcbpt"},
    {"<emitter type=\"constant\">\n<float name=\"samplingWeight\" value=\"0\"/></emitter>", 3, "samplingWeight"},
    {"<emitter type=\"envmap\"><string name=\"filename\" value=\"tex.png\"/>\n<float name=\"samplingWeight\" value=\"2e6\"/></emitter>", 3, "samplingWeight"},
    {"<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>", 2, "nested"},
    {"<shape type=\"cube\">\n<emitter type=\"point\"/></shape>", 3, "point"},
    {"<shape type=\"cube\"><emitter type=\"area\">\n<rgb name=\"radiance\" value=\"0\"/></emitter></shape>", 3, "radiance"},
    {"<emitter type=\"point\">\n<float name=\"samplingWeight\" value=\"0\"/></emitter>", 3, "samplingWeight"},
    {"<shape type=\"cube\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/>\n<float name=\"samplingWeight\" value=\"-1\"/></emitter></shape>", 3, "samplingWeight"},
    {"\n<shape type=\"hair\"/>", 3, "shape 'hair': not modelled by pcbpt"},
    {"<bsdf type=\"hk\"/>", 2, "bsdf 'hk': not modelled by pcbpt (participating media in a layer)"},
    {"<bsdf type=\"normalmap\"><bsdf type=\"diffuse\"/></bsdf>", 2, "needs a normal texture"},
    {"<bsdf type=\"normalmap\"><bsdf type=\"diffuse\"/>\n<texture type=\"bitmap\"><string name=\"filename\" value=\"n.png\"/></texture></bsdf>", 3,
     "a bitmap normal map needs an explicit 'gamma'"},
    /* BSDFs */
    {"<bsdf type=\"hk\"/>", 2, "hk"},
    {"<shape type=\"disk\">\n<sensor type=\"irradiancemeter\"/></shape>", 3, "irradiancemeter': not modelled"},
    {"<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"1.5, 0.5, 0.5\"/></bsdf>", 3, "above 1"},
    {"<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"-0.5\"/></bsdf>", 3, "negative"},
    {"<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"0.1, 0.2\"/></bsdf>", 3, "1 or 3"},
    {"<bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"500:0.5, 400:0.5\"/></bsdf>", 3, "increasing"},
    {"<bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"500:0.5\"/></bsdf>", 3, "at least 2"},
    {"<bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"500:0.5, 600\"/></bsdf>", 3, "wavelength:value"},
    {"<bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"500:0.5, 600:-1\"/></bsdf>", 3, "negative"},
    {"<bsdf type=\"diffuse\">\n<spectrum name=\"reflectance\" value=\"0.1 0.2\"/></bsdf>", 3, "1 or 3"},
    {"<shape type=\"cube\"><emitter type=\"area\">\n<blackbody name=\"radiance\" temperature=\"hot\"/></emitter></shape>", 3, "temperature"},
    {"<shape type=\"cube\"><emitter type=\"area\">\n<blackbody name=\"radiance\" temperature=\"5\"/></emitter></shape>", 3, "100..1e6"},
    {"<bsdf type=\"diffuse\">\n<float name=\"reflectance\" value=\"0.5\"/></bsdf>", 3, "cannot be given"},
    {"<bsdf type=\"diffuse\">\n<rgb value=\"0.5\"/></bsdf>", 3, "name"},
    {"<bsdf type=\"diffuse\">\n<bsdf type=\"diffuse\"/></bsdf>", 3, "unexpected"},
    {"<bsdf type=\"roughconductor\">\n<string name=\"distribution\" value=\"walter\"/></bsdf>", 2, "distribution 'walter' unknown"},
    {"<bsdf type=\"roughplastic\"><string name=\"distribution\" value=\"ggx\"/><float name=\"alphaU\" value=\"0.1\"/><float name=\"alphaV\" value=\"0.2\"/></bsdf>", 2, "anisotropic"},
    {"<bsdf type=\"roughconductor\"><float name=\"alphaU\" value=\"0.1\"/><float name=\"alphaV\" value=\"1.2\"/></bsdf>", 2, "alphaV"},
    {"<bsdf type=\"bumpmap\">\n<bsdf type=\"diffuse\"/></bsdf>", 2, "displacement texture"},
    {"<bsdf type=\"bumpmap\"><bsdf type=\"diffuse\"/>\n<texture type=\"bitmap\"><string name=\"filename\" value=\"tex.png\"/></texture></bsdf>", 3, "gamma"},
    {"<bsdf type=\"bumpmap\">\n<texture type=\"checkerboard\"/></bsdf>", 2, "wraps no BSDF"},
    {"<bsdf type=\"bumpmap\"><texture type=\"checkerboard\"/>\n<texture type=\"checkerboard\"/><bsdf type=\"diffuse\"/></bsdf>", 3, "more than one"},
    {"<bsdf type=\"coating\">\n<bsdf type=\"bumpmap\"><texture type=\"checkerboard\"/><bsdf type=\"diffuse\"/></bsdf></bsdf>", 2, "bumpmap inside another BSDF: not modelled"},
    {"<bsdf type=\"mask\">\n<bsdf type=\"bumpmap\"><texture type=\"checkerboard\"/><bsdf type=\"diffuse\"/></bsdf></bsdf>", 3, "bumpmap inside another BSDF: not modelled"},
    {"<bsdf type=\"mask\"><rgb name=\"opacity\" value=\"1.5\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 2, "'opacity' must lie in [0, 1]"},
    {"<bsdf type=\"mask\">\n<bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>", 3, "more than 1 nested"},
    {"<bsdf type=\"mask\"/>", 2, "needs one nested BSDF"},
    {"<bsdf type=\"blendbsdf\"><bsdf type=\"diffuse\"/></bsdf>", 2, "needs two nested BSDFs"},
    {"<bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"-0.5\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>", 2, "'weight' must lie in [0, 1]"},
    {"<bsdf type=\"mixturebsdf\"><string name=\"weights\" value=\"0.5\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>", 2, "2 nested BSDFs but 1 weights"},
    {"<bsdf type=\"mixturebsdf\"><string name=\"weights\" value=\"0.5 x\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>", 2, "could not parse the BSDF weights"},
    {"<bsdf type=\"mixturebsdf\"><string name=\"weights\" value=\"0 0\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>", 2, "sum to more than zero"},
    {"<bsdf type=\"mixturebsdf\"><string name=\"weights\" value=\"-1 2\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>", 2, "invalid BSDF weight"},
    {"<bsdf type=\"mixturebsdf\"><bsdf type=\"diffuse\"/></bsdf>", 2, "'weights' is required"},
    {"<bsdf type=\"twosided\">\n<bsdf type=\"mask\"><bsdf type=\"diffuse\"/></bsdf></bsdf>", 3, "transmits"},
    {"<bsdf type=\"twosided\">\n<bsdf type=\"difftrans\"/></bsdf>", 3, "transmits"},
    {"<bsdf type=\"difftrans\"><rgb name=\"transmittance\" value=\"2\"/></bsdf>", 2, "above 1"},
    {"<bsdf type=\"coating\"><float name=\"intIOR\" value=\"1.2\"/><float name=\"extIOR\" value=\"1.2\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 2, "differ"},
    {"<bsdf type=\"coating\"><float name=\"thickness\" value=\"-1\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 2, "thickness"},
    {"<bsdf type=\"coating\"><rgb name=\"specularReflectance\" value=\"1.5\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 2, "above 1"},
    {"<bsdf type=\"coating\"/>", 2, "wraps no BSDF"},
    {"<bsdf type=\"roughcoating\"><string name=\"distribution\" value=\"blinn\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 2, "'blinn' unknown"},
    {"<bsdf type=\"roughcoating\"><float name=\"alphaU\" value=\"0.1\"/><float name=\"alphaV\" value=\"0.2\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 2, "anisotropic"},
    {"<bsdf type=\"roughcoating\"><float name=\"alpha\" value=\"0\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 2, "alpha"},
    {"<texture type=\"scale\" id=\"t\">\n<float name=\"scale\" value=\"-1\"/><texture type=\"checkerboard\"/></texture>", 2, "positive"},
    {"<texture type=\"scale\" id=\"t\"><texture type=\"checkerboard\"/>\n<texture type=\"checkerboard\"/></texture>", 3, "unexpected"},
    {"<bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0\"/></bsdf>", 2, "alpha"},
    {"<bsdf type=\"conductor\"><string name=\"material\" value=\"Xx\"/></bsdf>", 2, "Xx"},
    {"<bsdf type=\"conductor\"><rgb name=\"eta\" value=\"1\"/></bsdf>", 2, "eta and k"},
    {"<bsdf type=\"dielectric\">\n<string name=\"intIOR\" value=\"unobtainium\"/></bsdf>", 3, "unobtainium"},
    {"<bsdf type=\"dielectric\">\n<float name=\"intIOR\" value=\"-1\"/></bsdf>", 2, "intIOR"},
    {"<bsdf type=\"roughdielectric\"><float name=\"alpha\" value=\"2\"/></bsdf>", 2, "alpha"},
    {"<bsdf type=\"ward\">\n<string name=\"variant\" value=\"walter\"/></bsdf>", 3, "variant 'walter'"},
    {"<bsdf type=\"ward\"><float name=\"alphaU\" value=\"0.1\"/><float name=\"alphaV\" value=\"0.2\"/></bsdf>", 2, "anisotropic"},
    {"<bsdf type=\"ward\"><rgb name=\"specularReflectance\" value=\"0.6\"/><rgb name=\"diffuseReflectance\" value=\"0.5\"/></bsdf>", 2, "energy"},
    {"<bsdf type=\"ward\"><float name=\"alpha\" value=\"0\"/></bsdf>", 2, "alpha"},
    {"<bsdf type=\"twosided\">\n<bsdf type=\"roughdielectric\"/></bsdf>", 3, "dielectric"},
    {"<bsdf type=\"twosided\">\n<bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></bsdf>", 3, "twosided"},
    {"<bsdf type=\"twosided\">\n<bsdf type=\"dielectric\"/></bsdf>", 3, "dielectric"},
    {"<bsdf type=\"twosided\"><bsdf type=\"diffuse\"/>\n<bsdf type=\"diffuse\"/></bsdf>", 3, "more than one"},
    {"<bsdf type=\"twosided\"/>", 2, "wraps no"},
    {"<bsdf type=\"diffuse\" id=\"a\"/><bsdf type=\"twosided\" id=\"b\"><ref id=\"a\"/></bsdf>\n<bsdf type=\"twosided\"><ref id=\"b\"/></bsdf>", 3, "twosided"},
    {"<bsdf type=\"diffuse\"/>\n<bsdf/>", 3, "type"},
    /* textures */
    {"<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"tex.png\"/>\n<string name=\"wrapMode\" value=\"clamp\"/></texture>", 2, "repeat"},
    {"<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"tex.png\"/>\n<float name=\"gamma\" value=\"-2\"/></texture>", 3, "gamma"},
    {"<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"tex.png\"/>\n<string name=\"filterType\" value=\"cubic\"/></texture>", 2, "filterType"},
    {"<texture type=\"bitmap\" id=\"t\"/>", 2, "filename"},
    {"<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"nothere.png\"/></texture>", 2, "cannot find"},
    {"<texture type=\"scale\" id=\"t\"/>", 2, "scale"},
    {"<texture type=\"checkerboard\"/>", 2, "id"},
    {"<texture type=\"checkerboard\" id=\"t\"><float name=\"uscale\" value=\"0\"/></texture>", 2, "uscale"},
    {"<bsdf type=\"diffuse\">\n<texture type=\"checkerboard\"/></bsdf>", 3, "unexpected"},
    /* ids and references */
    {"<shape type=\"cube\">\n<ref id=\"nope\"/></shape>", 3, "unknown id"},
    {"<texture type=\"checkerboard\" id=\"t\"/><shape type=\"cube\">\n<ref id=\"t\"/></shape>", 3, "not a BSDF"},
    {"<bsdf type=\"diffuse\" id=\"b\"/><bsdf type=\"diffuse\">\n<ref name=\"reflectance\" id=\"b\"/></bsdf>", 3, "not a texture"},
    {"<bsdf type=\"diffuse\" id=\"x\"/>\n<texture type=\"checkerboard\" id=\"x\"/>", 3, "duplicate id"},
    /* defaults and substitution */
    {"<shape type=\"cube\">\n<float name=\"x\" value=\"$undefined\"/></shape>", 3, "undefined parameter"},
    {"<shape type=\"cube\">\n<default name=\"a\" value=\"1\"/></shape>", 3, "<default>"},
    {"<default name=\"a\"/>", 2, "<default>"},
    /* structure */
    {"\n<include filename=\"other.xml\"/>", 3, "include"},
    {"\n<include filename=\"scene.xml\"/>", 3, "include loop"},
    {"\n<include filename=\"../outside.xml\"/>", 3, "outside"},
    {"<shape type=\"cube\">\n<include filename=\"inc.xml\"/></shape>", 3, "child of <scene>"},
    {"\n<default name=\"x\" value=\"$x\"/>", 3, "expands to itself"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"quad.obj\"/><boolean name=\"faceNormals\" value=\"true\"/>\n<float name=\"maxSmoothAngle\" value=\"30\"/></shape>", 3, "cannot be given together"},
    {"<shape type=\"obj\"><string name=\"filename\" value=\"quad.obj\"/>\n<float name=\"maxSmoothAngle\" value=\"1e9\"/></shape>", 3, "maxSmoothAngle"},
    {"<medium type=\"homogeneous\"/>", 2, "medium 'homogeneous': not modelled by pcbpt (participating media"},
    {"\n<phase type=\"isotropic\"/>", 3, "phase 'isotropic': not modelled by pcbpt (participating media"},
    /* a parameter Mitsuba's plugin reads (vertex colours) that pcbpt does not honour */
    {"<shape type=\"ply\">\n<boolean name=\"srgb\" value=\"true\"/></shape>", 3, "parameter 'srgb'"},
    {"<shape type=\"cube\" color=\"red\"/>", 2, "unknown attribute"},
    {"<shape type=\"cube\">\n<bsdf type=\"diffuse\">", 4, "syntax"},
    {"<shape type=\"cube\">hello</shape>", 2, "text"},
};

static void test_bad_scenes(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  int failures = 0;
  for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
    const bad_case *bc = &bad_cases[i];
    pc_scene s;
    pc_err e = {0};
    int rc = load_body(&t, bc->body, &s, &e);
    char where[64];
    snprintf(where, sizeof where, "scene.xml:%d:", bc->line);
    if (rc == 0) {
      print_error("case %zu loaded but should fail: %s\n", i, bc->body);
      pc_scene_free(&s);
      failures++;
    } else if (!strstr(e.msg, where) || !strstr(e.msg, bc->word) || e.code != rc) {
      print_error("case %zu: message '%s' lacks '%s' or '%s'\n", i, e.msg, where, bc->word);
      failures++;
    }
  }
  th_rm_rf(t.root);
  assert_int_equal(failures, 0);
}

static void test_bad_documents(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  static const struct { const char *xml; const char *word; } docs[] = {
      {"<scene version=\"2.0.0\"/>", "version"},
      {"<scene/>", "version"},
      {"<notascene version=\"0.6.0\"/>", "root element"},
      {"<!DOCTYPE scene [<!ENTITY a \"aaaa\">]>\n<scene version=\"0.6.0\"/>", "DOCTYPE"},
      {"", "syntax"},
  };
  for (size_t i = 0; i < sizeof docs / sizeof docs[0]; i++) {
    assert_int_equal(th_write_str(t.dir, "scene.xml", docs[i].xml), 0);
    pc_scene s;
    pc_err e = {0};
    assert_true(pc_scene_load(t.scene, &s, &e) < 0);
    if (!strstr(e.msg, docs[i].word)) print_error("doc %zu: '%s'\n", i, e.msg);
    assert_non_null(strstr(e.msg, docs[i].word));
  }
  /* nesting deeper than the bound */
  char deep[64 * 20 + 64] = "<scene version=\"0.6.0\">";
  for (int i = 0; i < 70; i++) strcat(deep, "<a>");
  assert_int_equal(th_write_str(t.dir, "scene.xml", deep), 0);
  pc_scene s;
  pc_err e = {0};
  assert_int_equal(pc_scene_load(t.scene, &s, &e), PC_ELIMIT);
  assert_non_null(strstr(e.msg, "deeply"));
  /* a missing scene file */
  char missing[512];
  snprintf(missing, sizeof missing, "%s/none.xml", t.dir);
  assert_true(pc_scene_load(missing, &s, &e) < 0);
  th_rm_rf(t.root);
}


/* ---- warnings, --strict, includes, -D, spectra ---- */

typedef struct warn_log {
  int n;
  char lines[16][700];
} warn_log;

static void collect(void *ud, const char *line) {
  warn_log *w = ud;
  if (w->n < 16) snprintf(w->lines[w->n], sizeof w->lines[0], "%s", line);
  w->n++;
}

static int load_body_opts(tmp *t, const char *body, const pc_scene_load_opts *o, pc_scene *s, pc_err *e) {
  char *xml = malloc(strlen(body) + 64);
  sprintf(xml, "<scene version=\"0.6.0\">\n%s\n</scene>\n", body);
  int w = th_write_str(t->dir, "scene.xml", xml);
  free(xml);
  assert_int_equal(w, 0);
  return pc_scene_load_with(t->scene, o, s, e);
}

#define FOV "<float name=\"fov\" value=\"45\"/>"
static const bad_case warn_cases[] = {
    /* a mesh of degenerate triangles only: Mitsuba loads it and never hits it */
    {SENSOR "\n<shape type=\"obj\"><string name=\"filename\" value=\"flat.obj\"/></shape>", 3, "every triangle is degenerate"},
    {"<integrator type=\"bdpt\">\n<integer name=\"rrDepth\" value=\"5\"/></integrator>" SENSOR, 3, "rrDepth"},
    {"<integrator type=\"bdpt\">\n<boolean name=\"strictNormals\" value=\"true\"/></integrator>" SENSOR, 3, "strictNormals"},
    {"\n<integrator type=\"volpath\"/>" SENSOR, 3, "integrator 'volpath': not a pcbpt method"},
    {"<integrator type=\"path\">\n<sampler type=\"independent\"/></integrator>" SENSOR, 3, "nested <sampler>"},
    {"<integrator type=\"path\" id=\"i\"/>" SENSOR, 2, "id ignored"},
    {"<sensor type=\"perspective\">" FOV "<film type=\"hdrfilm\">\n<rfilter type=\"mitchell\"/></film></sensor>", 3, "negative lobes is not modelled"},
    {"<sensor type=\"perspective\">" FOV "<film type=\"hdrfilm\">\n<rfilter type=\"gaussian\"><float name=\"radius\" value=\"3\"/></rfilter></film></sensor>", 3, "radius 4 stddev"},
    {"<sensor type=\"perspective\">" FOV "<film type=\"hdrfilm\"><rfilter type=\"tent\"/>\n<boolean name=\"highQualityEdges\" value=\"true\"/></film></sensor>", 2, "highQualityEdges"},
    {"<sensor type=\"perspective\">" FOV "<film type=\"hdrfilm\">\n<rfilter type=\"tent\"><float name=\"radius\" value=\"2\"/></rfilter></film></sensor>", 3, "radius"},
    {"<sensor type=\"perspective\">" FOV "\n<film type=\"ldrfilm\"/></sensor>", 3, "ldrfilm"},
    {"<sensor type=\"perspective\">" FOV "<film type=\"hdrfilm\">\n<string name=\"pixelFormat\" value=\"rgb\"/></film></sensor>", 3, "pixelFormat"},
    {"<sensor type=\"perspective\">" FOV "<film type=\"hdrfilm\">\n<boolean name=\"banner\" value=\"false\"/></film></sensor>", 3, "banner"},
    {"<sensor type=\"perspective\">" FOV "\n<sampler type=\"ldsampler\"><integer name=\"sampleCount\" value=\"16\"/></sampler></sensor>", 3, "sampleCount 16"},
    {"<sensor type=\"perspective\">" FOV "\n<float name=\"focusDistance\" value=\"3\"/></sensor>", 3, "focusDistance"},
    {"\n<integer name=\"maxDepth\" value=\"5\"/>" SENSOR, 3, "scene: parameter 'maxDepth'"},
    {"<bsdf type=\"conductor\">\n<string name=\"distribution\" value=\"ggx\"/></bsdf>" SENSOR, 3, "parameter 'distribution' ignored"},
    {"<bsdf type=\"plastic\">\n<float name=\"alpha\" value=\"0.1\"/></bsdf>" SENSOR, 3, "does not read it either"},
    {"<bsdf type=\"thindielectric\">\n<float name=\"alpha\" value=\"0.1\"/></bsdf>" SENSOR, 3, "does not read it either"},
    {"<emitter type=\"constant\">\n<float name=\"scale\" value=\"2\"/></emitter>" SENSOR, 3, "emitter 'constant': parameter 'scale' ignored"},
    {"<bsdf type=\"diffuse\">\n<rgb name=\"foo\" value=\"0.5\"/></bsdf>" SENSOR, 3, "'foo'"},
    {"<shape type=\"cube\">\n<string name=\"filename\" value=\"quad.obj\"/></shape>" SENSOR, 3, "shape 'cube': parameter 'filename' ignored"},
    {"<bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"ggx\"/>\n<boolean name=\"sampleVisible\" value=\"false\"/></bsdf>" SENSOR, 3, "steers"},
    /* parameters of other renderers' forks (Mitsuba warns and goes on), on every plugin */
    {"<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/>\n<rgb name=\"reflectance\" value=\"0.5\"/></bsdf>" SENSOR, 3, "the last value counts"},
    {"<bsdf type=\"phong\">\n<string name=\"sdmmFilename\" value=\"x.sdmm\"/></bsdf>" SENSOR, 3, "bsdf 'phong': parameter 'sdmmFilename' ignored"},
    {"<bsdf type=\"coating\"><bsdf type=\"diffuse\"/>\n<float name=\"foo\" value=\"1\"/></bsdf>" SENSOR, 3, "bsdf 'coating': parameter 'foo' ignored"},
    {"<shape type=\"sphere\">\n<integer name=\"foo\" value=\"1\"/></shape>" SENSOR, 3, "shape 'sphere': parameter 'foo' ignored"},
    {"<bsdf type=\"bumpmap\"><texture type=\"checkerboard\"/><bsdf type=\"diffuse\"/>\n<float name=\"x\" value=\"1\"/></bsdf>" SENSOR, 3, "bsdf 'bumpmap': parameter 'x' ignored"},
};

static void test_warnings(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  int failures = 0;
  for (size_t i = 0; i < sizeof warn_cases / sizeof warn_cases[0]; i++) {
    const bad_case *wc = &warn_cases[i];
    warn_log log = {0};
    pc_scene_load_opts o = {.warn = collect, .warn_ud = &log};
    pc_scene s;
    pc_err e = {0};
    char where[64];
    snprintf(where, sizeof where, "scene.xml:%d: warning:", wc->line);
    int rc = load_body_opts(&t, wc->body, &o, &s, &e);
    if (rc) {
      print_error("warn case %zu failed: %s\n", i, e.msg);
      failures++;
      continue;
    }
    pc_scene_free(&s);
    bool found = false;
    for (int k = 0; k < log.n && k < 16; k++) found |= strstr(log.lines[k], where) && strstr(log.lines[k], wc->word);
    if (!found) {
      print_error("warn case %zu: no warning with '%s' and '%s' among %d (first: %s)\n", i, where, wc->word, log.n,
                  log.n ? log.lines[0] : "");
      failures++;
    }
    /* --strict: the same line is the error */
    o.strict = true;
    rc = load_body_opts(&t, wc->body, &o, &s, &e);
    snprintf(where, sizeof where, "scene.xml:%d:", wc->line);
    if (rc == 0) {
      pc_scene_free(&s);
      print_error("warn case %zu loads under --strict\n", i);
      failures++;
    } else if (!strstr(e.msg, where) || !strstr(e.msg, "--strict")) {
      print_error("warn case %zu under --strict: '%s'\n", i, e.msg);
      failures++;
    }
  }
  /* the same warning once per scene, however often it applies; the sampler gives the count */
  warn_log log = {0};
  pc_scene_load_opts o = {.warn = collect, .warn_ud = &log};
  pc_scene s;
  pc_err e = {0};
  int rc = load_body_opts(&t,
                          "<sensor type=\"perspective\">" FOV "<sampler type=\"independent\"><integer name=\"sampleCount\" value=\"7\"/>"
                          "</sampler><film type=\"hdrfilm\"><boolean name=\"banner\" value=\"false\"/><rfilter type=\"lanczos\"/>"
                          "</film></sensor>\n<shape type=\"cube\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/>"
                          "<float name=\"samplingWeight\" value=\"3\"/></emitter></shape>"
                          "<emitter type=\"constant\"><float name=\"samplingWeight\" value=\"0.5\"/></emitter>",
                          &o, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(log.n, 3); /* sampler, banner, rfilter */
  assert_int_equal(s.sample_count, 7);
  assert_true(s.lights[0].sampling_weight == 3.f);
  assert_int_equal(s.nlights, 2);
  assert_int_equal(s.lights[1].type, PC_LIGHT_ENV);
  assert_true(s.lights[1].sampling_weight == 0.5f);
  pc_scene_free(&s);
  /* an unknown parameter: one line per (plugin, parameter), whatever its values and lines */
  log.n = 0;
  rc = load_body_opts(&t,
                      SENSOR "\n<bsdf type=\"phong\"><string name=\"sdmmFilename\" value=\"a.sdmm\"/></bsdf>\n"
                      "<bsdf type=\"phong\"><string name=\"sdmmFilename\" value=\"b.sdmm\"/></bsdf>\n"
                      "<bsdf type=\"diffuse\"><string name=\"sdmmFilename\" value=\"c.sdmm\"/></bsdf>",
                      &o, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  pc_scene_free(&s);
  assert_int_equal(log.n, 2);
  assert_non_null(strstr(log.lines[0], "scene.xml:3: warning: bsdf 'phong': parameter 'sdmmFilename' ignored"));
  assert_non_null(strstr(log.lines[1], "scene.xml:5: warning: bsdf 'diffuse': parameter 'sdmmFilename' ignored"));
  /* a repeated parameter: the last value counts */
  rc = load_body_opts(&t, SENSOR "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.2\"/><rgb name=\"reflectance\" value=\"0.7\"/></bsdf>",
                      &o, &s, &e);
  assert_int_equal(rc, 0);
  assert_true(s.materials[0].reflectance.value.x == 0.7f);
  pc_scene_free(&s);
  th_rm_rf(t.root);
  assert_int_equal(failures, 0);
}

/* A still pinhole whose matrix Mitsuba accepts though it is not rigid to 1e-4 (printed with few
 * digits): loaded with its axes as they are, and its raster positions invert its rays. */
static void test_near_rigid_camera(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  int rc = load_body(&t, "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><transform name=\"toWorld\">"
                         "<matrix value=\"-1 0.0005 0 0 0 1 0 1 0.0003 0 -1 5 0 0 0 1\"/></transform></sensor>", &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  pc_camera_prepare(&s.camera);
  assert_true(s.camera.inv_det != 1.f);
  for (float py = 0.5f; py < s.camera.height; py += 37.f)
    for (float px = 0.5f; px < s.camera.width; px += 41.f) {
      float rx, ry;
      assert_true(pc_camera_raster(&s.camera, pc_camera_ray_dir(&s.camera, px, py), &rx, &ry));
      assert_true(fabsf(rx - px) < 2e-3f && fabsf(ry - py) < 2e-3f);
    }
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* PT cannot sample a path from a point or spot light through a delta lobe: with such a light,
 * any shape with a delta lobe (also wrapped or mixed in) makes the scene incomplete for it; an
 * area light, or only rough and diffuse materials, leave it complete. And caustics
 * (pc_scene_has_caustics): a shape of mirror or glass, smooth, thin or rough, also wrapped or
 * mixed in; not a plastic's or a coating's coat over a diffuse base. LT (pc_scene_lt_complete)
 * misses any delta lobe, whatever the light. */
static void test_pt_complete(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
#define POINT "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"2\" z=\"0\"/></emitter>"
#define SPOT "<emitter type=\"spot\"/>"
#define DIRECTIONAL "<emitter type=\"directional\"/>"
#define AREA "<shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>"
  static const struct {
    const char *light, *bsdf;
    bool complete, caustics;
  } cases[] = {
      {POINT, "<bsdf type=\"diffuse\"/>", true, false},
      {POINT, "<bsdf type=\"roughconductor\"/>", true, false},
      {POINT, "<bsdf type=\"roughdielectric\"/>", true, true},
      {POINT, "<bsdf type=\"dielectric\"/>", false, true},
      {POINT, "<bsdf type=\"thindielectric\"/>", false, true},
      {SPOT, "<bsdf type=\"conductor\"/>", false, true},
      {DIRECTIONAL, "<bsdf type=\"dielectric\"/>", false, true},
      {DIRECTIONAL, "<bsdf type=\"roughplastic\"/>", true, false},
      {POINT, "<bsdf type=\"plastic\"/>", false, false},
      {POINT, "<bsdf type=\"roughplastic\"/>", true, false},
      {POINT, "<bsdf type=\"bumpmap\"><bsdf type=\"conductor\"/><texture type=\"checkerboard\"/></bsdf>", false, true},
      {POINT, "<bsdf type=\"roughcoating\"><bsdf type=\"diffuse\"/></bsdf>", true, false},
      {POINT, "<bsdf type=\"roughcoating\"><bsdf type=\"conductor\"/></bsdf>", false, true},
      {POINT, "<bsdf type=\"coating\"><bsdf type=\"diffuse\"/></bsdf>", false, false},
      {POINT, "<bsdf type=\"coating\"><bsdf type=\"conductor\"/></bsdf>", false, true},
      {POINT, "<bsdf type=\"mask\"><bsdf type=\"dielectric\"/><float name=\"opacity\" value=\"0.5\"/></bsdf>", false, true},
      {POINT, "<bsdf type=\"mask\"><bsdf type=\"diffuse\"/><float name=\"opacity\" value=\"0.5\"/></bsdf>", false, false},
      {POINT, "<bsdf type=\"mixturebsdf\"><string name=\"weights\" value=\"0.5, 0.5\"/><bsdf type=\"diffuse\"/>"
              "<bsdf type=\"roughconductor\"/></bsdf>", true, false},
      {POINT, "<bsdf type=\"mixturebsdf\"><string name=\"weights\" value=\"0.5, 0.5\"/><bsdf type=\"diffuse\"/>"
              "<bsdf type=\"conductor\"/></bsdf>", false, true},
      {AREA, "<bsdf type=\"dielectric\"/>", true, true},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char body[1024];
    snprintf(body, sizeof body, SENSOR "%s<shape type=\"sphere\">%s</shape>", cases[i].light, cases[i].bsdf);
    pc_scene s;
    pc_err e = {0};
    int rc = load_body(&t, body, &s, &e);
    if (rc) print_error("case %zu: %s\n", i, e.msg);
    assert_int_equal(rc, 0);
    if (pc_scene_pt_complete(&s) != cases[i].complete) print_error("case %zu: %s\n", i, cases[i].bsdf);
    assert_true(pc_scene_pt_complete(&s) == cases[i].complete);
    if (pc_scene_has_caustics(&s) != cases[i].caustics) print_error("case %zu: caustics %s\n", i, cases[i].bsdf);
    assert_true(pc_scene_has_caustics(&s) == cases[i].caustics);
    /* light tracing misses a delta lobe whatever the light: with a point or spot, exactly where
       pt does; the area-lit case is glass */
    assert_true(pc_scene_lt_complete(&s) == (strcmp(cases[i].light, AREA) == 0 ? false : cases[i].complete));
    pc_scene_free(&s);
  }
  /* a delta material no shape uses does not count */
  pc_scene s;
  pc_err e = {0};
  char body[1024];
  snprintf(body, sizeof body, SENSOR "%s<bsdf type=\"conductor\" id=\"unused\"/><shape type=\"sphere\"/>", POINT);
  assert_int_equal(load_body(&t, body, &s, &e), 0);
  assert_true(pc_scene_pt_complete(&s));
  assert_false(pc_scene_has_caustics(&s));
  pc_scene_free(&s);
  th_rm_rf(t.root);
#undef POINT
#undef SPOT
#undef DIRECTIONAL
#undef AREA
}

/* Mitsuba's `directional`: irradiance 1 along +z by default; `direction` normalized, or toWorld's
 * +z axis; its power is what crosses the disk its light paths start on. */
static void test_directional_params(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  static const struct {
    const char *emitter;
    vec3 dir, irradiance;
  } cases[] = {
      {"<emitter type=\"directional\"/>", {0, 0, 1}, {1, 1, 1}},
      {"<emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"-2\" z=\"0\"/>"
       "<rgb name=\"irradiance\" value=\"3, 2, 1\"/></emitter>", {0, -1, 0}, {3, 2, 1}},
      {"<emitter type=\"directional\"><transform name=\"toWorld\"><lookat origin=\"1, 1, 1\" target=\"2, 0, 1\" up=\"0, 0, 1\"/></transform>"
       "<spectrum name=\"irradiance\" value=\"5\"/></emitter>", {0.70710678f, -0.70710678f, 0}, {5, 5, 5}},
      {"<emitter type=\"directional\"><transform name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/></transform></emitter>",
       {0, -1, 0}, {1, 1, 1}},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char body[1024];
    snprintf(body, sizeof body, SENSOR "<shape type=\"sphere\"/>%s", cases[i].emitter);
    pc_scene s;
    load_ok(&t, body, cases[i].emitter, &s);
    assert_int_equal(s.nlights, 1);
    const pc_light *l = &s.lights[0];
    assert_int_equal(l->type, PC_LIGHT_DIRECTIONAL);
    for (int k = 0; k < 3; k++) {
      assert_float_equal(((const float *)&l->direction)[k], ((const float *)&cases[i].dir)[k], 1e-6);
      assert_float_equal(((const float *)&l->irradiance)[k], ((const float *)&cases[i].irradiance)[k], 1e-6);
    }
    pc_err e = {0};
    assert_int_equal(pc_scene_build(&s, &e), 0);
    assert_float_equal(l->power, M_PI * s.env_radius * s.env_radius * v3_luminance(cases[i].irradiance), 1e-4 * l->power);
    assert_int_equal(s.env_light, -1); /* not the environment an escaping eye ray sees */
    pc_scene_free(&s);
  }
  th_rm_rf(t.root);
}

/* maxSmoothAngle reaches the mesh: a cube's 90-degree edges split its 8 corners into 24 vertices */
static void test_smooth_angle_param(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  assert_int_equal(th_write_str(t.dir, "cube.obj",
                                "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                                "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                                "f 3 4 8\nf 3 8 7\nf 2 3 7\nf 2 7 6\nf 1 5 8\nf 1 8 4\n"),
                   0);
  pc_scene s;
  pc_err e = {0};
  int rc = load_body(&t, SENSOR "<shape type=\"obj\"><string name=\"filename\" value=\"cube.obj\"/>"
                                "<float name=\"maxSmoothAngle\" value=\"30\"/></shape>"
                                "<shape type=\"obj\"><string name=\"filename\" value=\"cube.obj\"/></shape>",
                     &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.shapes[0].mesh.nverts, 24);
  assert_non_null(s.shapes[0].mesh.n);
  assert_int_equal(s.shapes[1].mesh.nverts, 8);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* Negative conductor eta and k (exported scenes have them) give the Fresnel term of their
 * magnitudes, which is what Mitsuba's formula computes with them; elsewhere a negative colour,
 * and one through sRGB, stays an error. Also Mitsuba's #rrggbb colours. */
static void test_negative_conductor(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  int rc = load_body(&t, SENSOR "<bsdf type=\"roughconductor\" id=\"c\"><float name=\"extEta\" value=\"1\"/>"
                                "<rgb name=\"eta\" value=\"-0.0485226, 4.14275, 4.66977\"/>"
                                "<spectrum name=\"k\" value=\"-0.0363742, 0.0937665, 1.30074\"/></bsdf>",
                     &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  vec3 eta = v3(-0.0485226f, 4.14275f, 4.66977f), k = v3(-0.0363742f, 0.0937665f, 1.30074f);
  const pc_material *m = &s.materials[0];
  assert_true(m->eta.x == -eta.x && m->eta.y == eta.y && m->k.x == -k.x && m->k.z == k.z);
  for (float c = 0.05f; c <= 1.f; c += 0.05f) {
    vec3 a = pc_fresnel_conductor(c, eta, k), b = pc_fresnel_conductor(c, m->eta, m->k);
    assert_true(a.x == b.x && a.y == b.y && a.z == b.z);
  }
  pc_scene_free(&s);
  /* #rrggbb: bytes over 255, taken as linear in <rgb> (Mitsuba's scenehandler), decoded in <srgb> */
  rc = load_body(&t, SENSOR "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"#ff8000\"/></bsdf>"
                            "<bsdf type=\"diffuse\"><srgb name=\"reflectance\" value=\"#ff8000\"/></bsdf>",
                 &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  vec3 lin = s.materials[0].reflectance.value, dec = s.materials[1].reflectance.value;
  assert_true(lin.x == 1.f && fabsf(lin.y - 128.f / 255.f) < 1e-6f && lin.z == 0.f);
  assert_true(dec.x == 1.f && fabsf(dec.y - 0.21586f) < 1e-4f && dec.z == 0.f);
  pc_scene_free(&s);
  assert_true(load_body(&t, SENSOR "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"#ff80g0\"/></bsdf>", &s, &e) < 0);
  assert_non_null(strstr(e.msg, "#rrggbb"));
  static const char *const refused[] = {
      SENSOR "<bsdf type=\"conductor\"><srgb name=\"eta\" value=\"-0.1, 1, 1\"/><rgb name=\"k\" value=\"1\"/></bsdf>",
      SENSOR "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"-0.1, 0.5, 0.5\"/></bsdf>",
  };
  for (int i = 0; i < 2; i++) {
    assert_true(load_body(&t, refused[i], &s, &e) < 0);
    assert_non_null(strstr(e.msg, "negative value"));
  }
  th_rm_rf(t.root);
}

/* No <sensor>: Mitsuba's default camera (fov 45 along x, 768x576, unrotated), centred on the
 * shapes' bounds in x and y, at their nearest z minus the distance at which their x-y extent
 * fills the fov; a warning, an error under --strict. */
static void test_default_sensor(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  warn_log log = {0};
  pc_scene_load_opts o = {.warn = collect, .warn_ud = &log};
  pc_scene s;
  pc_err e = {0};
  /* the cube spans [1,3] x [-1,1] x [-1,1], the sphere reaches x = 5 and z = 4 */
  const char *body = "<shape type=\"cube\"><transform name=\"toWorld\"><translate x=\"2\"/></transform></shape>"
                     "<shape type=\"sphere\"><point name=\"center\" x=\"4\" y=\"0\" z=\"3\"/></shape>";
  int rc = load_body_opts(&t, body, &o, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(log.n, 1);
  assert_non_null(strstr(log.lines[0], "scene.xml:1: warning: the scene has no <sensor>"));
  const pc_camera *cam = &s.camera;
  assert_int_equal(cam->width, 768);
  assert_int_equal(cam->height, 576);
  assert_true(cam->fov_deg == 45.f && cam->fov_axis == 'x');
  double dist = 4.0 / (2.0 * tan(22.5 * M_PI / 180.0)); /* x extent 1..5 */
  assert_true(fabs(cam->to_world.m[0][3] - 3.0) < 1e-6 && fabs(cam->to_world.m[1][3]) < 1e-6);
  assert_true(fabs(cam->to_world.m[2][3] - (-1.0 - dist)) < 1e-5);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) assert_true(cam->to_world.m[i][j] == (i == j));
  pc_scene_free(&s);
  o.strict = true;
  assert_true(load_body_opts(&t, body, &o, &s, &e) < 0);
  assert_non_null(strstr(e.msg, "no <sensor>"));
  th_rm_rf(t.root);
}

/* -D and <default>, <include> with $names in its path, messages naming the included file, the
 * root folder option, and the list of files the scene read. */
static void test_include_and_defines(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  char sub[400], other[400];
  snprintf(sub, sizeof sub, "%s/parts", t.dir);
  assert_int_equal(mkdir(sub, 0700), 0);
  snprintf(other, sizeof other, "%s/shared", t.root);
  assert_int_equal(mkdir(other, 0700), 0);
  assert_int_equal(th_write_str(sub, "a.xml",
                                "<scene version=\"0.6.0\">\n<default name=\"depth\" value=\"9\"/>\n"
                                "<integrator type=\"path\"><integer name=\"maxDepth\" value=\"$depth\"/></integrator>\n"
                                "<include filename=\"b.xml\"/></scene>"),
                   0);
  assert_int_equal(th_write_str(sub, "b.xml",
                                "<scene version=\"0.6.0\"><shape type=\"obj\"><string name=\"filename\" value=\"$mesh\"/></shape></scene>"),
                   0);
  assert_int_equal(th_write_str(sub, "bad.xml", "<scene version=\"0.6.0\">\n\n<shape type=\"hair\"/></scene>"), 0);
  assert_int_equal(th_write_str(sub, "loop.xml", "<scene version=\"0.6.0\"><include filename=\"loop2.xml\"/></scene>"), 0);
  assert_int_equal(th_write_str(sub, "loop2.xml", "<scene version=\"0.6.0\">\n<include filename=\"loop.xml\"/></scene>"), 0);
  assert_int_equal(th_write_str(other, "i.xml", "<scene version=\"0.6.0\"><integrator type=\"bdpt\"/></scene>"), 0);
  const char *body = "<default name=\"part\" value=\"a\"/><default name=\"mesh\" value=\"flat.obj\"/>\n"
                     "<include filename=\"parts/$part.xml\"/>\n" SENSOR;
  pc_scene_defines d = {0};
  pc_err e = {0};
  assert_int_equal(pc_scene_defines_add(&d, "mesh=quad.obj", &e), 0);
  assert_int_equal(pc_scene_defines_add(&d, "depth=4", &e), 0);
  assert_int_equal(pc_scene_defines_add(&d, "depth=3", &e), 0); /* a later -D replaces */
  assert_int_equal(d.n, 2);
  assert_int_equal(pc_scene_defines_add(&d, "x=$x", &e), PC_EINVAL);
  assert_non_null(strstr(e.msg, "expands to itself"));
  assert_int_equal(pc_scene_defines_add(&d, "=1", &e), PC_EINVAL);
  assert_int_equal(pc_scene_defines_add(&d, "a-b=1", &e), PC_EINVAL);
  assert_int_equal(pc_scene_defines_add(&d, "zeta=1", &e), 0); /* no $zeta in the scene */
  pc_scene_load_opts o = {.defines = &d};
  pc_scene s;
  int rc = load_body_opts(&t, body, &o, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.max_depth, 3);
  /* the scene keeps the -D values a $name used, in an included file too, and not zeta */
  char used[PC_SCENE_DEFINES_TEXT];
  pc_scene_defines_text(&s.defines_used, used, sizeof used);
  assert_string_equal(used, "depth=3 mesh=quad.obj");
  assert_int_equal(s.nshapes, 1);
  assert_int_equal(s.nfiles, 4); /* scene.xml, a.xml, b.xml, quad.obj */
  assert_non_null(strstr(s.files[0], "/scene.xml"));
  assert_non_null(strstr(s.files[1], "/parts/a.xml"));
  assert_non_null(strstr(s.files[2], "/parts/b.xml"));
  assert_non_null(strstr(s.files[3], "/quad.obj"));
  pc_scene_free(&s);
  /* without -D the <default>s hold: flat.obj is degenerate (never hit: a warning, here made an
     error by --strict), named in the included file */
  pc_scene_load_opts strict = {.strict = true};
  rc = load_body_opts(&t, body, &strict, &s, &e);
  assert_int_not_equal(rc, 0);
  assert_non_null(strstr(e.msg, "parts/b.xml:1:"));
  assert_non_null(strstr(e.msg, "degenerate"));
  /* an unused -D is a warning, which --strict makes the error, naming the main file */
  pc_scene_load_opts strict_d = {.defines = &d, .strict = true};
  rc = load_body_opts(&t, body, &strict_d, &s, &e);
  assert_int_equal(rc, PC_EUNSUPPORTED);
  assert_non_null(strstr(e.msg, "scene.xml:"));
  assert_non_null(strstr(e.msg, "-D zeta=1: the scene names no $zeta, so the value changes nothing"));
  /* an error inside an included file names it and its line */
  rc = load_body_opts(&t, "<include filename=\"parts/bad.xml\"/>" SENSOR, NULL, &s, &e);
  assert_int_equal(rc, PC_EUNSUPPORTED);
  assert_non_null(strstr(e.msg, "parts/bad.xml:3: shape 'hair': not modelled by pcbpt"));
  /* a loop through two files is one line */
  rc = load_body_opts(&t, "<include filename=\"parts/loop.xml\"/>" SENSOR, NULL, &s, &e);
  assert_int_equal(rc, PC_EINVAL);
  assert_non_null(strstr(e.msg, "parts/loop2.xml:2: <include>: 'loop.xml' includes itself"));
  /* outside the scene's folder unless the root allows it */
  rc = load_body_opts(&t, "<include filename=\"../shared/i.xml\"/>" SENSOR, NULL, &s, &e);
  assert_int_equal(rc, PC_EINVAL);
  assert_non_null(strstr(e.msg, "outside"));
  pc_scene_load_opts wide = {.root = t.root};
  rc = load_body_opts(&t, "<include filename=\"../shared/i.xml\"/>" SENSOR, &wide, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.method, PC_METHOD_BDPT);
  pc_scene_free(&s);
  pc_scene_load_opts narrow = {.root = sub};
  rc = load_body_opts(&t, SENSOR, &narrow, &s, &e);
  assert_int_equal(rc, PC_EINVAL);
  assert_non_null(strstr(e.msg, "outside its root"));
  th_rm_rf(t.root);
}

static void test_defaults_and_values(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  /* no integrator, no film: Mitsuba's defaults; mirror flips allowed on the camera; matrix,
   * rotate and order of transform children; extEta divides; srgb; near/far clip accepted */
  const char *body =
      "<default name=\"w\" value=\"0.25\"/>\n"
      "<sensor type=\"perspective\"><float name=\"fov\" value=\"30\"/><float name=\"nearClip\" value=\"0.1\"/>"
      "<float name=\"farClip\" value=\"100\"/>"
      "<transform name=\"toWorld\"><scale x=\"-1\"/><translate x=\"2\"/></transform></sensor>\n"
      "<shape type=\"rectangle\"><transform name=\"toWorld\"><translate x=\"1\"/><scale value=\"2\"/></transform>"
      "<bsdf type=\"conductor\"><rgb name=\"eta\" value=\"2, 2, 2\"/><rgb name=\"k\" value=\"4\"/>"
      "<float name=\"extEta\" value=\"2\"/></bsdf></shape>\n"
      "<shape type=\"rectangle\"><transform name=\"toWorld\">"
      "<matrix value=\"1 0 0 5, 0 1 0 0, 0 0 1 0, 0 0 0 1\"/><rotate y=\"1\" angle=\"90\"/></transform>"
      "<bsdf type=\"diffuse\"><srgb name=\"reflectance\" value=\"$w\"/></bsdf></shape>\n"
      "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"-1\"/></transform></shape>\n";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.method, PC_METHOD_PT);
  assert_int_equal(s.max_depth, -1);
  assert_int_equal(s.camera.width, 768);
  assert_int_equal(s.camera.height, 576);
  assert_int_equal(s.camera.fov_axis, 'x');
  assert_true(s.camera.to_world.m[0][0] == -1 && s.camera.to_world.m[0][3] == 2);
  /* translate then scale: (1,1,0) -> (2,1,0) -> (4,2,0) */
  near3(s.shapes[0].mesh.p[2], v3(4, 2, 0), 1e-6f);
  near3(s.materials[0].eta, v3s(1), 0);
  near3(s.materials[0].k, v3s(2), 0);
  /* the matrix moves +5 in x, then rotate +90 about y (right-handed) maps +x to -z:
   * (1,1,0) -> (6,1,0) -> (0,1,-6) */
  near3(s.shapes[1].mesh.p[2], v3(0, 1, -6), 1e-5f);
  near3(s.materials[1].reflectance.value, v3s(0.050876f), 1e-5f);
  assert_int_equal(s.shapes[2].material, s.shapes[0].material + 2);
  /* a mirrored rectangle still faces +z: the winding follows the transformed normal */
  near3(tri_normal(&s.shapes[2].mesh, 0), v3(0, 0, 1), 1e-6f);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* Mitsuba's ward: its defaults (balanced, alpha 0.1, specular 0.2, diffuse 0.5) and the
 * parameters as dp-veach-lamp writes them. */
static void test_ward(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  const char *body = SENSOR "\n<shape type=\"rectangle\"><bsdf type=\"ward\"/></shape>\n"
                            "<shape type=\"rectangle\"><bsdf type=\"ward\"><spectrum name=\"diffuseReflectance\" value=\"0\"/>"
                            "<rgb name=\"specularReflectance\" value=\"0.61600 0.47520 0.35200\"/><float name=\"alphaU\" value=\"0.4\"/>"
                            "<float name=\"alphaV\" value=\"0.4\"/><string name=\"variant\" value=\"ward-duer\"/></bsdf></shape>\n";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  const pc_material *m = s.materials;
  assert_int_equal(m[0].type, PC_MAT_WARD);
  assert_int_equal(m[0].ward, PC_WARD_BALANCED);
  assert_true(m[0].alpha == 0.1f);
  near3(m[0].specular.value, v3s(0.2f), 0);
  near3(m[0].reflectance.value, v3s(0.5f), 0);
  assert_int_equal(m[1].type, PC_MAT_WARD);
  assert_int_equal(m[1].ward, PC_WARD_DUER);
  assert_true(m[1].alpha == 0.4f);
  near3(m[1].specular.value, v3(0.616f, 0.4752f, 0.352f), 1e-6f);
  near3(m[1].reflectance.value, v3s(0), 0);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* Mitsuba's phong (defaults: exponent 30, specular 0.2, diffuse 0.5; a sum above 1 scaled by
 * 0.99/max unless ensureEnergyConservation is false) and roughdiffuse (alpha 0.2, either
 * reflectance name). */
static void test_phong_roughdiffuse(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  const char *body = SENSOR "\n<shape type=\"rectangle\"><bsdf type=\"phong\"/></shape>\n"
                            "<shape type=\"rectangle\"><bsdf type=\"phong\"><float name=\"exponent\" value=\"50\"/>"
                            "<rgb name=\"specularReflectance\" value=\"0.5 0.5 0.5\"/>"
                            "<rgb name=\"diffuseReflectance\" value=\"0.9 0.1 0.1\"/></bsdf></shape>\n"
                            "<shape type=\"rectangle\"><bsdf type=\"phong\"><boolean name=\"ensureEnergyConservation\" value=\"false\"/>"
                            "<rgb name=\"diffuseReflectance\" value=\"0.9 0.1 0.1\"/></bsdf></shape>\n"
                            "<shape type=\"rectangle\"><bsdf type=\"roughdiffuse\"/></shape>\n"
                            "<shape type=\"rectangle\"><bsdf type=\"roughdiffuse\"><float name=\"alpha\" value=\"0.7\"/>"
                            "<boolean name=\"useFastApprox\" value=\"true\"/>"
                            "<rgb name=\"diffuseReflectance\" value=\"0.3 0.2 0.1\"/></bsdf></shape>\n";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  const pc_material *m = s.materials;
  assert_int_equal(m[0].type, PC_MAT_PHONG);
  assert_true(m[0].exponent == 30.f && m[0].lobe_scale == 1.f);
  near3(m[0].specular.value, v3s(0.2f), 0);
  near3(m[0].reflectance.value, v3s(0.5f), 0);
  assert_true(m[1].exponent == 50.f);
  assert_true(fabsf(m[1].lobe_scale - 0.99f / 1.4f) < 1e-6f);
  assert_true(m[2].lobe_scale == 1.f);
  assert_int_equal(m[3].type, PC_MAT_ROUGHDIFFUSE);
  assert_true(m[3].alpha == 0.2f && !m[3].fast_approx);
  near3(m[3].reflectance.value, v3s(0.5f), 0);
  assert_true(m[4].alpha == 0.7f && m[4].fast_approx);
  near3(m[4].reflectance.value, v3(0.3f, 0.2f, 0.1f), 1e-6f);
  pc_scene_free(&s);
  /* the scaling is a warning, an error under --strict; both names at once are refused */
  pc_scene_load_opts strict = {.strict = true};
  body = SENSOR "\n<shape type=\"rectangle\"><bsdf type=\"phong\"><spectrum name=\"diffuseReflectance\" value=\"0.95\"/>"
                "</bsdf></shape>\n";
  assert_int_not_equal(load_body_opts(&t, body, &strict, &s, &e), 0);
  assert_non_null(strstr(e.msg, "ensureEnergyConservation"));
  body = SENSOR "\n<shape type=\"rectangle\"><bsdf type=\"roughdiffuse\"><spectrum name=\"reflectance\" value=\"0.5\"/>"
                "<spectrum name=\"diffuseReflectance\" value=\"0.5\"/></bsdf></shape>\n";
  assert_int_not_equal(load_body(&t, body, &s, &e), 0);
  assert_non_null(strstr(e.msg, "not both"));
  /* diffuse takes diffuseReflectance too (Mitsuba 0.6's diffuse.cpp reads either name), a
     value or a texture; above 1 is refused by that name; not both */
  body = SENSOR "\n<shape type=\"rectangle\"><bsdf type=\"diffuse\"><rgb name=\"diffuseReflectance\" value=\"0.3 0.2 0.1\"/>"
                "</bsdf></shape>\n<shape type=\"rectangle\"><bsdf type=\"diffuse\"><texture name=\"diffuseReflectance\" "
                "type=\"checkerboard\"/></bsdf></shape>\n";
  rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.materials[0].type, PC_MAT_DIFFUSE);
  near3(s.materials[0].reflectance.value, v3(0.3f, 0.2f, 0.1f), 1e-6f);
  assert_true(s.materials[0].reflectance.tex < 0);
  assert_true(s.materials[1].reflectance.tex >= 0);
  pc_scene_free(&s);
  body = SENSOR "\n<shape type=\"rectangle\"><bsdf type=\"diffuse\"><spectrum name=\"diffuseReflectance\" value=\"1.5\"/>"
                "</bsdf></shape>\n";
  assert_int_not_equal(load_body(&t, body, &s, &e), 0);
  assert_non_null(strstr(e.msg, "'diffuseReflectance' above 1"));
  body = SENSOR "\n<shape type=\"rectangle\"><bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"0.5\"/>"
                "<spectrum name=\"diffuseReflectance\" value=\"0.5\"/></bsdf></shape>\n";
  assert_int_not_equal(load_body(&t, body, &s, &e), 0);
  assert_non_null(strstr(e.msg, "not both"));
  th_rm_rf(t.root);
}

/* Mitsuba 0.6's obj plugin: a mesh per `g` and per `usemtl` after faces, each with its own
 * vertices; the material of a mesh is the last unnamed or same-named BSDF child, else the .mtl
 * material (sRGB Kd, illum models, d as a mask), else the default; collapse, loadMaterials and
 * shapeIndex (with Mitsuba's numbering of the last mesh). */
static const char *GROUPS_OBJ = "mtllib sub/m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
                                "usemtl red\nf 1 2 3 4\nusemtl glass\nf 2 5 6 3\ng other\nusemtl shiny\nf 1 2 3\n";
static const char *GROUPS_MTL = "# comment\nnewmtl red\nKd 0.5 0.25 1\nKa 1 1 1\nnewmtl glass\nillum 7\n"
                                "newmtl shiny\nKd 0.2 0.2 0.2\nKs 0.5 0.5 0.5\nNs 20\nillum 2\n"
                                "newmtl masked\nKd 1 1 1\nd 0.25\nmap_Ks missing.png\nNs 10\nillum 2\nnewmtl metal\nillum 5\n";

static int obj_scene(tmp *t, const char *inner, pc_scene *s, pc_err *e) {
  char body[2048];
  snprintf(body, sizeof body, SENSOR "\n<shape type=\"obj\"><string name=\"filename\" value=\"sub/g.obj\"/>%s</shape>", inner);
  return load_body(t, body, s, e);
}

static float srgb_to_linear(float v) { return v <= 0.04045f ? v / 12.92f : powf((v + 0.055f) / 1.055f, 2.4f); }

static void test_obj_materials(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  char sub[400];
  snprintf(sub, sizeof sub, "%s/sub", t.dir);
  assert_int_equal(mkdir(sub, 0700), 0);
  assert_int_equal(th_write_str(sub, "g.obj", GROUPS_OBJ), 0);
  assert_int_equal(th_write_str(sub, "m.mtl", GROUPS_MTL), 0);
  pc_scene s;
  pc_err e = {0};
  int rc = obj_scene(&t, "", &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 3);
  /* each mesh has its own vertices (the shared edge is not merged across meshes) */
  assert_int_equal(s.shapes[0].mesh.nverts, 4);
  assert_int_equal(s.shapes[1].mesh.nverts, 4);
  assert_int_equal(s.shapes[2].mesh.ntris, 1);
  const pc_material *red = &s.materials[s.shapes[0].material];
  assert_int_equal(red->type, PC_MAT_DIFFUSE);
  near3(red->reflectance.value, v3(srgb_to_linear(0.5f), srgb_to_linear(0.25f), 1.f), 1e-5f);
  assert_int_equal(s.materials[s.shapes[1].material].type, PC_MAT_DIELECTRIC);
  const pc_material *shiny = &s.materials[s.shapes[2].material];
  assert_int_equal(shiny->type, PC_MAT_PHONG);
  assert_true(shiny->exponent == 20.f);
  pc_scene_free(&s);
  /* an unnamed BSDF replaces every mesh's; a named one after it the meshes of its name */
  rc = obj_scene(&t, "<bsdf type=\"roughconductor\"/><bsdf type=\"conductor\" name=\"glass\"/>", &s, &e);
  assert_int_equal(rc, 0);
  assert_int_equal(s.materials[s.shapes[0].material].type, PC_MAT_ROUGHCONDUCTOR);
  assert_int_equal(s.materials[s.shapes[1].material].type, PC_MAT_CONDUCTOR);
  assert_int_equal(s.materials[s.shapes[2].material].type, PC_MAT_ROUGHCONDUCTOR);
  pc_scene_free(&s);
  /* Mitsuba's null BSDF: everything passes through, a mask of opacity 0 */
  rc = obj_scene(&t, "<bsdf type=\"null\" name=\"glass\"/>", &s, &e);
  assert_int_equal(rc, 0);
  assert_int_equal(s.materials[s.shapes[1].material].type, PC_MAT_MASK);
  near3(s.materials[s.shapes[1].material].weight.value, v3s(0.f), 0);
  pc_scene_free(&s);
  /* ... and an unnamed one after the named one replaces it too (document order) */
  rc = obj_scene(&t, "<bsdf type=\"conductor\" name=\"glass\"/><bsdf type=\"roughconductor\"/>", &s, &e);
  assert_int_equal(rc, 0);
  assert_int_equal(s.materials[s.shapes[1].material].type, PC_MAT_ROUGHCONDUCTOR);
  pc_scene_free(&s);
  /* collapse: one mesh with the last usemtl's material */
  rc = obj_scene(&t, "<boolean name=\"collapse\" value=\"true\"/>", &s, &e);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 1);
  assert_int_equal(s.shapes[0].mesh.ntris, 5);
  assert_int_equal(s.materials[s.shapes[0].material].type, PC_MAT_PHONG);
  pc_scene_free(&s);
  /* loadMaterials false: Mitsuba's default diffuse 0.5 */
  rc = obj_scene(&t, "<boolean name=\"loadMaterials\" value=\"false\"/>", &s, &e);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 3);
  near3(s.materials[s.shapes[1].material].reflectance.value, v3s(0.5f), 0);
  pc_scene_free(&s);
  /* shapeIndex counts meshes in file order, and Mitsuba tests the last mesh against the
   * count before it, so index 1 selects the second mesh and the last */
  rc = obj_scene(&t, "<integer name=\"shapeIndex\" value=\"0\"/>", &s, &e);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 1);
  assert_int_equal(s.shapes[0].mesh.ntris, 2);
  pc_scene_free(&s);
  rc = obj_scene(&t, "<integer name=\"shapeIndex\" value=\"1\"/>", &s, &e);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 2);
  pc_scene_free(&s);
  /* an emitter cannot go on several meshes (Mitsuba refuses it too) */
  rc = obj_scene(&t, "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1 1 1\"/></emitter>", &s, &e);
  assert_int_not_equal(rc, 0);
  assert_non_null(strstr(e.msg, "emitter on an OBJ file of 3 meshes"));
  /* a mask from d, a missing map as black (a warning; an error under --strict), illum 5 */
  assert_int_equal(th_write_str(sub, "g.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl masked\nf 1 2 3\n"
                                              "usemtl metal\nf 1 3 2\nusemtl nosuch\nf 3 2 1\n"), 0);
  rc = obj_scene(&t, "", &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  const pc_material *mask = &s.materials[s.shapes[0].material];
  assert_int_equal(mask->type, PC_MAT_MASK);
  near3(mask->weight.value, v3s(0.25f), 0);
  assert_int_equal(s.materials[mask->nested].type, PC_MAT_PHONG); /* map_Ks counts as non-zero */
  assert_int_equal(s.materials[s.shapes[1].material].type, PC_MAT_CONDUCTOR);
  near3(s.materials[s.shapes[2].material].reflectance.value, v3s(0.5f), 0);
  pc_scene_free(&s);
  pc_scene_load_opts strict = {.strict = true};
  char body[512];
  snprintf(body, sizeof body, SENSOR "\n<shape type=\"obj\"><string name=\"filename\" value=\"sub/g.obj\"/></shape>");
  assert_int_not_equal(load_body_opts(&t, body, &strict, &s, &e), 0);
  assert_non_null(strstr(e.msg, "missing.png"));
  /* a malformed library names its file and line */
  assert_int_equal(th_write_str(sub, "m.mtl", "newmtl masked\nKd 0.5\n"), 0);
  assert_int_not_equal(obj_scene(&t, "", &s, &e), 0);
  assert_non_null(strstr(e.msg, "m.mtl:2: 'Kd' needs 3 finite numbers"));
  assert_int_equal(th_write_str(sub, "m.mtl", "newmtl masked\nd 2\n"), 0);
  assert_int_not_equal(obj_scene(&t, "", &s, &e), 0);
  assert_non_null(strstr(e.msg, "m.mtl:2: 'd' must lie in [0, 1]"));
  /* a missing library: the meshes keep the default (a warning) */
  assert_int_equal(th_write_str(sub, "g.obj", "mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl a\nf 1 2 3\n"), 0);
  assert_int_equal(obj_scene(&t, "", &s, &e), 0);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* Embree traces the meshes' own arrays (rtcSetSharedGeometryBuffer) where they have the
 * slack its 16-byte loads need (pc_big_alloc's): a rectangle, a cube and an instance's copy
 * are not copied again. */
static void test_embree_shares_meshes(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  const char *body = SENSOR "\n<shape type=\"rectangle\"/>\n<shape type=\"cube\"/>\n"
                            "<shape type=\"shapeGroup\" id=\"g\"><shape type=\"rectangle\"/></shape>\n"
                            "<shape type=\"instance\"><ref id=\"g\"/></shape>\n<emitter type=\"constant\"/>\n";
  int rc = load_body(&t, body, &s, &e);
  if (!rc) rc = pc_scene_build(&s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 3);
  for (int i = 0; i < s.nshapes; i++) {
    RTCGeometry g = rtcGetGeometry((RTCScene)s.rtc_scene, (unsigned)i);
    assert_non_null(g);
    assert_ptr_equal(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_VERTEX, 0), s.shapes[i].mesh.p);
    assert_ptr_equal(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_INDEX, 0), s.shapes[i].mesh.idx);
  }
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* pc_tri_consts: a hit on a still mesh takes its triangle's precomputed normal, tangents,
 * offset and (without shading normals) frame. Every field of every hit, and the shading point
 * made from it, is bit for bit what the hit computes without the table: on a mesh with shading
 * normals (one triangle whose normals face against its winding, so that ng turns over, and one
 * with degenerate texture coordinates, whose tangents then follow the turned ng), the same
 * mesh with face normals, a rectangle and a sphere. (test_motion_params: a moving mesh has no
 * table.) */
static void test_tri_consts(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  assert_int_equal(th_write_str(t.dir, "uvn.obj",
                                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\n"
                                "vt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\n"
                                "vn 0 0 1\nvn 0.3 0 1\nvn 0 0.3 1\nvn 0.1 0 -1\n"
                                "f 1/1/1 2/2/2 3/3/3\nf 2/4/4 4/4/4 3/4/4\nf 1/1/1 5/2/2 2/3/3\n"),
                   0);
  const char *body = SENSOR "\n<shape type=\"obj\"><string name=\"filename\" value=\"uvn.obj\"/></shape>\n"
                            "<shape type=\"obj\"><string name=\"filename\" value=\"uvn.obj\"/>"
                            "<boolean name=\"faceNormals\" value=\"true\"/><transform name=\"toWorld\">"
                            "<translate x=\"3\"/></transform></shape>\n"
                            "<shape type=\"rectangle\"><transform name=\"toWorld\"><translate x=\"-3\"/></transform></shape>\n"
                            "<shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"3\" z=\"0\"/></shape>\n"
                            "<emitter type=\"constant\"/>\n";
  pc_scene s;
  pc_err e = {0};
  int rc = load_body(&t, body, &s, &e);
  if (!rc) rc = pc_scene_build(&s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 4);
  assert_non_null(s.shapes[0].mesh.n);
  assert_null(s.shapes[1].mesh.n);
  for (int i = 0; i < 3; i++) assert_non_null(s.shapes[i].tri);
  assert_null(s.shapes[3].tri);
  pc_tri_consts *tables[3];
  int hits = 0, framed = 0, turned = 0;
  for (int k = 0; k < 4000; k++) {
    /* rays from both sides at every shape, through a grid around it */
    int shape = k % 4, side = (k / 4) % 2;
    float u = (float)((k / 8) % 25) / 24.f * 1.4f - 0.2f, v = (float)((k / 200) % 20) / 19.f * 1.4f - 0.2f;
    vec3 base = shape == 1 ? v3(3, 0, 0) : shape == 2 ? v3(-3.5f, -0.5f, 0) : shape == 3 ? v3(-0.5f, 2.5f, 0) : v3s(0);
    vec3 target = v3_add(base, v3(u, v, (k / 4000.f) * (shape == 0 ? 1.f : 0.f)));
    vec3 o = v3_add(target, v3(0.37f, -0.21f, side ? 3.f : -3.f)), d = v3_sub(target, o);
    if (k % 16 == 5) { o = v3_add(base, v3(0.4f, -3, 0.3f)); d = v3_sub(target, o); } /* at the y = 0 triangle */
    pc_hit a, b;
    bool ha = pc_scene_intersect(&s, o, d, INFINITY, &a);
    for (int i = 0; i < 3; i++) tables[i] = s.shapes[i].tri, s.shapes[i].tri = NULL;
    bool hb = pc_scene_intersect(&s, o, d, INFINITY, &b);
    for (int i = 0; i < 3; i++) s.shapes[i].tri = tables[i];
    assert_true(ha == hb);
    if (!ha) continue;
    hits++;
    assert_memory_equal(&a.p, &b.p, sizeof a.p);
    assert_memory_equal(&a.ng, &b.ng, sizeof a.ng);
    assert_memory_equal(&a.ns, &b.ns, sizeof a.ns);
    assert_memory_equal(&a.uv, &b.uv, sizeof a.uv);
    assert_memory_equal(&a.dpdu, &b.dpdu, sizeof a.dpdu);
    assert_memory_equal(&a.dpdv, &b.dpdv, sizeof a.dpdv);
    assert_true(a.t == b.t && a.eps == b.eps && a.shape == b.shape && a.prim == b.prim);
    const frame *f = pc_hit_frame(&s, &a);
    assert_true((f != NULL) == (a.shape == 1 || a.shape == 2));
    const pc_material *m = &s.materials[s.shapes[a.shape].material];
    pc_shading sa, sb;
    if (f) pc_shading_make_framed(&sa, m, s.textures, a.ng, f, a.dpdu, a.dpdv, a.uv, v3_neg(d));
    else pc_shading_make(&sa, m, s.textures, a.ng, a.ns, a.dpdu, a.dpdv, a.uv, v3_neg(d));
    pc_shading_make(&sb, m, s.textures, b.ng, b.ns, b.dpdu, b.dpdv, b.uv, v3_neg(d));
    assert_memory_equal(&sa, &sb, sizeof sa);
    framed += f != NULL;
    turned += a.shape == 0 && a.prim == 1 && v3_dot(a.ng, tables[0][1].f.n) < 0.f;
  }
  assert_true(hits > 2000 && framed > 500 && turned > 20);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* pc_scene_check, the clients' check without a BVH: the scene errors the loader leaves to the
 * build (no emitter, no shapes) as pc_scene_build reports them, word for word; on good scenes
 * (a still one with a sphere and an environment, a moving one) the same light tables and
 * bounding sphere as the build, bit for bit, no Embree scene, and a renderer check that passes
 * for every method. */
static void test_check_without_bvh(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  static const char *const bad[] = {
      SENSOR "\n<shape type=\"cube\"/>\n",                                                   /* no emitter */
      SENSOR "\n<emitter type=\"constant\"/>\n",                                              /* no shapes */
  };
  for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
    pc_scene a, b;
    pc_err ea = {0}, eb = {0};
    assert_int_equal(load_body(&t, bad[i], &a, &ea), 0);
    assert_int_equal(load_body(&t, bad[i], &b, &eb), 0);
    int ra = pc_scene_check(&a, &ea), rb = pc_scene_build(&b, &eb);
    if (ra != rb || !ra || strcmp(ea.msg, eb.msg) != 0) print_error("case %zu: '%s' against '%s'\n", i, ea.msg, eb.msg);
    assert_int_not_equal(ra, 0);
    assert_int_equal(ra, rb);
    assert_string_equal(ea.msg, eb.msg);
    pc_scene_free(&a);
    pc_scene_free(&b);
  }
  static const char *const good[] = {
      SENSOR "\n<shape type=\"cube\"/>\n<shape type=\"sphere\"><point name=\"center\" x=\"3\" y=\"0\" z=\"0\"/></shape>\n"
             "<shape type=\"rectangle\"><transform name=\"toWorld\"><translate y=\"4\"/></transform>"
             "<emitter type=\"area\"><rgb name=\"radiance\" value=\"2\"/></emitter></shape>\n"
             "<emitter type=\"constant\"/>\n",
      "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><float name=\"shutterOpen\" value=\"0\"/><float name=\"shutterClose\" value=\"1\"/>"
      "</sensor>\n<shape type=\"sphere\"><animation name=\"toWorld\">" KEY(0, "<translate x=\"-1\"/>")
          KEY(1, "<translate x=\"1\"/>") "</animation></shape>\n"
      "<shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n",
  };
  for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
    pc_scene a, b;
    pc_err e = {0};
    assert_int_equal(load_body(&t, good[i], &a, &e), 0);
    assert_int_equal(load_body(&t, good[i], &b, &e), 0);
    int rc = pc_scene_check(&a, &e);
    if (!rc) rc = pc_scene_build(&b, &e);
    if (rc) print_error("%s\n", e.msg);
    assert_int_equal(rc, 0);
    assert_null(a.rtc_scene);
    assert_non_null(b.rtc_scene);
    assert_int_equal(a.nlights, b.nlights);
    assert_memory_equal(a.light_cdf, b.light_cdf, sizeof(float) * (size_t)(a.nlights + 1));
    assert_int_equal(a.env_light, b.env_light);
    assert_true(a.scene_radius == b.scene_radius);
    assert_memory_equal(&a.scene_center, &b.scene_center, sizeof(vec3));
    assert_int_equal(pc_scene_moves(&a), i == 1);
    for (int m = PC_METHOD_PT; m <= PC_METHOD_PCBPT; m++) {
      pc_render_settings set;
      pc_render_settings_default(&set);
      set.method = (pc_method)m;
      set.width = set.height = 8;
      rc = pc_renderer_check(&a, &set, &e);
      if (rc) print_error("method %d: %s\n", m, e.msg);
      assert_int_equal(rc, 0);
    }
    pc_scene_free(&a);
    pc_scene_free(&b);
  }
  th_rm_rf(t.root);
}

/* The probe also counts what the camera sees outside the sensor's clip range (Mitsuba's path
 * tracer clips it away): a wall 5 ahead (depth 5 along the view, 49% of the image) and a cube
 * whose front face is at depth 2 (51%); the clip range is validated as Mitsuba validates it. */
static void test_probe_clip(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  static const struct {
    const char *clip;
    int nearer_pct, farther_pct;
  } c[] = {
      {"", 0, 0},
      {"<float name=\"nearClip\" value=\"4\"/>", 51, 0},
      {"<float name=\"nearClip\" value=\"2.5\"/><float name=\"farClip\" value=\"4\"/>", 51, 49},
      {"<float name=\"nearClip\" value=\"1\"/><float name=\"farClip\" value=\"4.9\"/>", 0, 49},
      {"<float name=\"farClip\" value=\"1\"/>", 0, 100},
  };
  for (size_t i = 0; i < sizeof c / sizeof *c; i++) {
    char body[2048];
    snprintf(body, sizeof body,
             "<emitter type=\"constant\"/><sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>%s</sensor>"
             "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate z=\"5\"/></transform></shape>"
             "<shape type=\"cube\"><transform name=\"toWorld\"><scale value=\"0.5\"/><translate z=\"2.5\"/></transform></shape>",
             c[i].clip);
    pc_scene s;
    load_ok(&t, body, c[i].clip, &s);
    pc_err e = {0};
    pc_scene_backs b;
    assert_int_equal(pc_scene_check(&s, &e), 0);
    assert_int_equal(pc_scene_probe_backs(&s, 32, &b, &e), 0);
    int np = (int)lround(100.0 * b.nearer / b.rays), fp = (int)lround(100.0 * b.farther / b.rays);
    if (abs(np - c[i].nearer_pct) > 2 || abs(fp - c[i].farther_pct) > 2) print_error("case %zu: %d%% nearer, %d%% farther\n", i, np, fp);
    assert_true(abs(np - c[i].nearer_pct) <= 2 && abs(fp - c[i].farther_pct) <= 2);
    pc_scene_free(&s);
  }
  static const char *const bad[] = {"<float name=\"nearClip\" value=\"0\"/>",
                                    "<float name=\"nearClip\" value=\"5\"/><float name=\"farClip\" value=\"5\"/>"};
  for (size_t i = 0; i < 2; i++) {
    char body[512];
    snprintf(body, sizeof body, "<sensor type=\"perspective\">\n%s</sensor><shape type=\"cube\"/>", bad[i]);
    pc_scene s;
    pc_err e = {0};
    assert_int_not_equal(load_body(&t, body, &s, &e), 0);
    assert_non_null(strstr(e.msg, ":3: sensor 'perspective': the clip range must satisfy 0 < nearClip < farClip"));
  }
  th_rm_rf(t.root);
}

/* pc_scene_probe_backs: the camera (at the origin, looking along +z) sees a wall 5 ahead. A
 * rectangle's normal is +z, so unflipped the wall shows its back; what counts as black there is
 * the one-sided materials, not twosided ones, glass or flipped normals; the shapes come most seen
 * first with the line of their element, and a shape of an included file names that file. */
static void test_probe_backs(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  const char *lit = "<emitter type=\"constant\"/>\n" SENSOR "\n";
  struct {
    const char *shapes;
    int backs_pct, nshapes, line0;
  } c[] = {
      /* one wall over the whole view, its back to the camera */
      {"<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate z=\"5\"/></transform></shape>", 100, 1, 4},
      /* the same facing the camera */
      {"<shape type=\"rectangle\"><boolean name=\"flipNormals\" value=\"true\"/><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate z=\"5\"/></transform></shape>", 0, 0, 0},
      /* twosided, glass, and a mix with a twosided part: nothing black behind */
      {"<shape type=\"rectangle\"><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate z=\"5\"/></transform></shape>", 0, 0, 0},
      {"<shape type=\"rectangle\"><bsdf type=\"dielectric\"/><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate z=\"5\"/></transform></shape>", 0, 0, 0},
      {"<shape type=\"rectangle\"><bsdf type=\"roughconductor\"/><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate z=\"5\"/></transform></shape>", 100, 1, 4},
      /* two halves, the left one (+x is the image's left) turned away; a closed cube in front
         of them shows no back, and hides 31% of the (768x576) image, half of it on the left */
      {"<shape type=\"rectangle\"><boolean name=\"flipNormals\" value=\"true\"/><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate x=\"-9\" z=\"5\"/></transform></shape>\n"
       "<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/><translate x=\"9\" z=\"5\"/></transform></shape>\n"
       "<shape type=\"cube\"><transform name=\"toWorld\"><scale value=\"0.5\"/><translate z=\"3\"/></transform></shape>", 34, 1, 5},
      /* the back wall in an included file */
      {"<include filename=\"wall.xml\"/>", 100, 1, 3},
  };
  assert_int_equal(th_write_str(t.dir, "wall.xml",
                                "<scene version=\"0.6.0\">\n\n<shape type=\"rectangle\"><transform name=\"toWorld\"><scale x=\"9\" y=\"9\"/>"
                                "<translate z=\"5\"/></transform></shape></scene>"),
                   0);
  for (size_t i = 0; i < sizeof c / sizeof *c; i++) {
    char body[2048];
    snprintf(body, sizeof body, "%s%s", lit, c[i].shapes);
    pc_scene s;
    pc_err e = {0};
    int rc = load_body(&t, body, &s, &e);
    if (!rc) rc = pc_scene_check(&s, &e);
    pc_scene_backs b;
    if (!rc) rc = pc_scene_probe_backs(&s, 32, &b, &e);
    if (rc) print_error("case %zu: %s\n", i, e.msg);
    assert_int_equal(rc, 0);
    assert_null(s.rtc_scene); /* the probe's structure is gone */
    assert_int_equal(b.rays, 32 * 32);
    int pct = (int)lround(100.0 * b.backs / b.rays);
    if (abs(pct - c[i].backs_pct) > 3 || b.nshapes != c[i].nshapes) print_error("case %zu: %d%% in %d shapes\n", i, pct, b.nshapes);
    assert_true(abs(pct - c[i].backs_pct) <= 3);
    assert_int_equal(b.nshapes, c[i].nshapes);
    if (b.nshapes) {
      const pc_shape *sh = &s.shapes[b.shape[0]];
      assert_int_equal(sh->xml_line, c[i].line0);
      assert_int_equal(b.count[0], b.backs);
      if (strstr(c[i].shapes, "include")) {
        assert_int_equal(sh->xml_file, 1);
        assert_int_equal(s.nxml_includes, 1);
        assert_non_null(strstr(s.xml_includes[0], "wall.xml"));
      } else {
        assert_int_equal(sh->xml_file, 0);
      }
    }
    pc_scene_free(&s);
  }
  th_rm_rf(t.root);
}

/* <lookat> with an up 4e-7 off the view direction (a published scene generator's camera):
 * Mitsuba refuses only an exactly parallel up, and the camera is then a rigid frame. */
static void test_lookat_near_parallel(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  int rc = load_body(&t,
                     "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><transform name=\"toWorld\">"
                     "<lookat origin=\"-0.005318722046727225,0.9891165271306032,6.845925144295989\" "
                     "target=\"-0.005318579310501861,0.9891165818924574,5.914105333595855\" "
                     "up=\"-1.365978749359233e-07,3.874228812786048e-07,0.9999999999999155\"/></transform></sensor>\n"
                     "<shape type=\"cube\"/>",
                     &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  pc_camera_prepare(&s.camera);
  near3(s.camera.dir, v3(0, 0, -1), 1e-5f);
  assert_true(fabsf(v3_dot(s.camera.right, s.camera.up)) < 1e-5f);
  assert_true(fabsf(v3_len(s.camera.right) - 1.f) < 1e-5f && fabsf(v3_len(s.camera.up) - 1.f) < 1e-5f);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* Mitsuba's integrators that pcbpt renders another way: a wrapper (adaptive, irrcache) renders
 * what its nested integrator does, maxDepth included; `direct` is the paths of at most two
 * segments; `vpl` defaults to maxDepth 5, every other one to -1. */
static void test_integrator_kinds(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  static const struct {
    const char *integrator;
    int max_depth;
    pc_method method;
  } cases[] = {
      {"<integrator type=\"adaptive\"><float name=\"maxError\" value=\"0.05\"/>"
       "<integrator type=\"path\"><integer name=\"maxDepth\" value=\"3\"/></integrator></integrator>", 3, PC_METHOD_PT},
      {"<integrator type=\"irrcache\"><integrator type=\"adaptive\"><integrator type=\"bdpt\">"
       "<integer name=\"maxDepth\" value=\"7\"/></integrator></integrator></integrator>", 7, PC_METHOD_BDPT},
      {"<integrator type=\"direct\"><integer name=\"shadingSamples\" value=\"4\"/><integer name=\"maxDepth\" value=\"7\"/>"
       "</integrator>", 2, PC_METHOD_PT},
      {"<integrator type=\"photonmapper\"><integer name=\"maxDepth\" value=\"4\"/></integrator>", 4, PC_METHOD_PT},
      {"<integrator type=\"vpl\"/>", 5, PC_METHOD_PT},
      {"<integrator type=\"vpl\"><integer name=\"maxDepth\" value=\"-1\"/></integrator>", -1, PC_METHOD_PT},
      {"<integrator type=\"sppm\"/>", -1, PC_METHOD_PT},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char body[1024];
    snprintf(body, sizeof body, "%s" SENSOR "<shape type=\"sphere\"/>", cases[i].integrator);
    pc_scene s;
    load_ok(&t, body, cases[i].integrator, &s);
    assert_int_equal(s.max_depth, cases[i].max_depth);
    assert_int_equal(s.method, cases[i].method);
    pc_scene_free(&s);
  }
  th_rm_rf(t.root);
}

/* Mitsuba's focalLength ("<x>mm" on 35 mm film, 50mm when neither it nor fov is given): the
 * diagonal field of view 2 atan(43.27 mm / 2x). */
static void test_focal_length(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  static const struct {
    const char *sensor;
    double fov;
  } cases[] = {
      {"<sensor type=\"perspective\"/>", 46.7930},
      {"<sensor type=\"perspective\"><string name=\"focalLength\" value=\"35mm\"/></sensor>", 63.4404},
      {"<sensor type=\"thinlens\"><float name=\"apertureRadius\" value=\"0.1\"/><string name=\"focalLength\" value=\"200\"/></sensor>",
       12.3470},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char body[1024];
    snprintf(body, sizeof body, "%s<shape type=\"sphere\"/>", cases[i].sensor);
    pc_scene s;
    load_ok(&t, body, cases[i].sensor, &s);
    assert_float_equal(s.camera.fov_deg, cases[i].fov, 1e-3);
    assert_int_equal(s.camera.fov_axis, 'd');
    pc_scene_free(&s);
  }
  th_rm_rf(t.root);
}

/* <spectrum filename=...>: read as Mitsuba's InterpolatedSpectrum reads a file (comments and
 * blank lines skipped, the first line without two numbers ends it), the same RGB as the same
 * samples written as a wavelength:value list; bad files are refused with the file named. */
static void test_spectrum_file(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  assert_int_equal(th_write_str(t.dir, "r.spd", "# measured\n\n  400 0.2\n450\t0.4\n\r\n550 0.9 extra\n700 0.5\nend of data\n800 9\n"), 0);
  assert_int_equal(th_write_str(t.dir, "one.spd", "500 1\n"), 0);
  assert_int_equal(th_write_str(t.dir, "down.spd", "500 1\n400 1\n"), 0);
  pc_scene a, b;
  load_ok(&t, SENSOR "<shape type=\"sphere\"><bsdf type=\"diffuse\"><spectrum name=\"reflectance\" filename=\"r.spd\"/></bsdf>"
                     "<emitter type=\"area\"><spectrum name=\"radiance\" filename=\"r.spd\"/></emitter></shape>",
          "file", &a);
  load_ok(&t, SENSOR "<shape type=\"sphere\"><bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"400:0.2, 450:0.4, 550:0.9, 700:0.5\"/></bsdf>"
                     "<emitter type=\"area\"><spectrum name=\"radiance\" value=\"400:0.2, 450:0.4, 550:0.9, 700:0.5\"/></emitter></shape>",
          "list", &b);
  vec3 ra = a.materials[a.shapes[0].material].reflectance.value, rb = b.materials[b.shapes[0].material].reflectance.value;
  assert_true(ra.x == rb.x && ra.y == rb.y && ra.z == rb.z && ra.y > 0.3f);
  assert_true(a.lights[0].radiance.x == rb.x && a.lights[0].radiance.y == rb.y && a.lights[0].radiance.z == rb.z);
  pc_scene_free(&a);
  pc_scene_free(&b);
  static const struct { const char *spectrum, *want; } bad[] = {
      {"filename=\"missing.spd\"", "cannot find 'missing.spd'"},
      {"filename=\"one.spd\"", "'one.spd': needs at least 2 entries"},
      {"filename=\"down.spd\"", "'down.spd': needs at least 2 entries at increasing wavelengths"},
      {"filename=\"r.spd\" value=\"0.5\"", "unknown attribute 'value'"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char body[512];
    snprintf(body, sizeof body, SENSOR "<shape type=\"sphere\"><bsdf type=\"diffuse\"><spectrum name=\"reflectance\" %s/></bsdf></shape>",
             bad[i].spectrum);
    pc_err e = {0};
    assert_int_not_equal(load_body(&t, body, &a, &e), 0);
    if (!strstr(e.msg, bad[i].want)) print_error("case %zu: %s\n", i, e.msg);
    assert_non_null(strstr(e.msg, bad[i].want));
  }
  th_rm_rf(t.root);
}

/* Mitsuba's emitters default to its D65 spectrum, white (1, 1, 1) in RGB mode. */
static void test_emitter_defaults(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  load_ok(&t, SENSOR "<shape type=\"cube\"><emitter type=\"area\"/></shape><emitter type=\"point\"/><emitter type=\"constant\"/>",
          "defaults", &s);
  assert_int_equal(s.nlights, 3);
  vec3 area = s.lights[0].radiance, point = s.lights[1].intensity, env = s.lights[2].radiance;
  assert_true(area.x == 1.f && area.y == 1.f && area.z == 1.f);
  assert_true(point.x == 1.f && point.y == 1.f && point.z == 1.f);
  assert_true(env.x == 1.f && env.y == 1.f && env.z == 1.f);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* <alias id="a" as="b"/>: b refers to what a does. */
static void test_alias(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  load_ok(&t,
          SENSOR "<bsdf type=\"diffuse\"/><bsdf type=\"roughplastic\" id=\"a\"/><alias id=\"a\" as=\"b\"/>"
                 "<shape type=\"cube\"><ref id=\"b\"/></shape><shape type=\"sphere\"><ref id=\"a\"/></shape>",
          "alias", &s);
  assert_int_equal(s.nshapes, 2);
  assert_int_equal(s.shapes[0].material, s.shapes[1].material);
  assert_int_equal(s.materials[s.shapes[0].material].type, PC_MAT_ROUGHPLASTIC);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* <lookat> without an up, or with a zero one: Mitsuba takes the first axis of its
 * coordinateSystem about the view direction (so a camera's roll is Mitsuba's). */
static void test_lookat_without_up(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  static const struct {
    const char *lookat;
    vec3 dir, up;
  } cases[] = {
      {"<lookat origin=\"0, 0, 3\" target=\"0, 0, 0\"/>", {0, 0, -1}, {1, 0, 0}},
      {"<lookat origin=\"0, 0, 3\" target=\"0, 0, 0\" up=\"0, 0, 0\"/>", {0, 0, -1}, {1, 0, 0}},
      {"<lookat origin=\"0, 0, 0\" target=\"2, 1, 0.5\"/>", {0.872872f, 0.436436f, 0.218218f}, {0.423405f, -0.899735f, 0.105851f}},
      {"<lookAt origin=\"1, 1, 1\" target=\"1, 3, 1\" up=\"\"/>", {0, 1, 0}, {1, 0, 0}},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char body[1024];
    snprintf(body, sizeof body,
             "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><transform name=\"toWorld\">%s</transform></sensor>"
             "<shape type=\"cube\"/>",
             cases[i].lookat);
    pc_scene s;
    load_ok(&t, body, cases[i].lookat, &s);
    pc_camera_prepare(&s.camera);
    near3(s.camera.dir, cases[i].dir, 1e-5f);
    near3(v3_norm(s.camera.up), cases[i].up, 1e-5f);
    pc_scene_free(&s);
  }
  th_rm_rf(t.root);
}

/* Mitsuba's shapegroup and instance: the group's shapes appear once per instance, through the
 * instance's toWorld after their own; the group itself is not rendered. */
static void test_instances(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  const char *body = SENSOR "\n<shape type=\"shapeGroup\" id=\"g\"><shape type=\"rectangle\">"
                            "<transform name=\"toWorld\"><translate x=\"1\"/></transform>"
                            "<bsdf type=\"diffuse\"/></shape><shape type=\"sphere\"><float name=\"radius\" value=\"0.5\"/></shape></shape>\n"
                            "<shape type=\"instance\"><ref id=\"g\"/></shape>\n"
                            "<shape type=\"instance\"><ref id=\"g\"/><transform name=\"toWorld\"><scale value=\"2\"/>"
                            "<translate z=\"5\"/></transform></shape>\n";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.nshapes, 4);
  assert_int_equal(s.shapes[0].kind, PC_SHAPE_MESH);
  assert_int_equal(s.shapes[1].kind, PC_SHAPE_SPHERE);
  assert_int_equal(s.shapes[0].material, s.shapes[2].material);
  /* rectangle corner (-1,-1,0) -> (0,-1,0) -> scaled (0,-2,0) -> (0,-2,5) */
  bool found = false;
  for (uint32_t i = 0; i < s.shapes[2].mesh.nverts; i++) {
    vec3 p = s.shapes[2].mesh.p[i];
    found |= fabsf(p.x) < 1e-6f && fabsf(p.y + 2) < 1e-6f && fabsf(p.z - 5) < 1e-6f;
  }
  assert_true(found);
  near3(s.shapes[3].center, v3(0, 0, 5), 1e-6f);
  assert_true(fabsf(s.shapes[3].radius - 1.f) < 1e-6f);
  pc_scene_free(&s);
  const struct { const char *body, *want; } bad[] = {
      {"<shape type=\"instance\"><ref id=\"nope\"/></shape>", "not a shapegroup"},
      {"<shape type=\"shapegroup\" id=\"g\"><shape type=\"rectangle\"><emitter type=\"area\">"
       "<rgb name=\"radiance\" value=\"1 1 1\"/></emitter></shape></shape>", "emitter in a group: not modelled"},
      {"<shape type=\"shapegroup\" id=\"g\"><shape type=\"sphere\"/></shape><shape type=\"instance\"><ref id=\"g\"/>"
       "<transform name=\"toWorld\"><scale x=\"2\"/></transform></shape>", "holds a sphere"},
      {"<shape type=\"shapegroup\"><shape type=\"sphere\"/></shape>", "needs an id"},
  };
  char buf[1024];
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    snprintf(buf, sizeof buf, SENSOR "%s", bad[i].body);
    assert_int_not_equal(load_body(&t, buf, &s, &e), 0);
    if (!strstr(e.msg, bad[i].want)) print_error("%s\n", e.msg);
    assert_non_null(strstr(e.msg, bad[i].want));
  }
  th_rm_rf(t.root);
}

/* Mitsuba's AnimatedTransform: a keyframe T * R * S comes back at its own time; rotation is
 * slerped, translation and scale lerped, and times outside the keys clamp. */
static void test_animation(void **state) {
  (void)state;
  pc_err e = {0};
  pc_anim a = {0};
  double c = cos(M_PI / 4), sn = sin(M_PI / 4);
  /* time 2: rotate 90 degrees about y, scale (1, 2, 3), translate (4, 5, 6) */
  mat4 k1 = {{{0, 0, 3, 4}, {0, 2, 0, 5}, {-1, 0, 0, 6}, {0, 0, 0, 1}}};
  mat4 k0 = mat4_identity();
  assert_int_equal(pc_anim_append(&a, 2.0, &k1, &e), 0);
  assert_int_equal(pc_anim_append(&a, 0.0, &k0, &e), 0);
  assert_int_equal(pc_anim_finish(&a, &e), 0);
  assert_false(pc_anim_is_static(&a));
  for (int t = 0; t < 2; t++) {
    mat4 m = pc_anim_eval(&a, t ? 2.0 : 0.0), want = t ? k1 : k0;
    for (int r = 0; r < 3; r++)
      for (int k = 0; k < 4; k++) assert_true(fabs(m.m[r][k] - want.m[r][k]) < 1e-9);
  }
  /* halfway: 45 degrees about y, scale (1, 1.5, 2), translation (2, 2.5, 3) */
  mat4 m = pc_anim_eval(&a, 1.0);
  mat4 want = {{{c * 1, 0, sn * 2, 2}, {0, 1.5, 0, 2.5}, {-sn * 1, 0, c * 2, 3}, {0, 0, 0, 1}}};
  for (int r = 0; r < 3; r++)
    for (int k = 0; k < 4; k++) assert_true(fabs(m.m[r][k] - want.m[r][k]) < 1e-9);
  m = pc_anim_eval(&a, 7.0);
  assert_true(fabs(m.m[0][3] - 4) < 1e-12 && fabs(m.m[2][0] + 1) < 1e-9);
  m = pc_anim_eval(&a, -3.0);
  assert_true(fabs(m.m[0][0] - 1) < 1e-12 && m.m[0][3] == 0);
  assert_true(fabs(pc_anim_max_scale(&a) - 3) < 1e-9);
  /* a mirror is a proper rotation with a negative stretch, as Mitsuba flips both factors */
  mat4 mirror = {{{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
  assert_int_equal(pc_anim_append(&a, 5.0, &mirror, &e), 0);
  assert_int_equal(pc_anim_finish(&a, &e), 0);
  m = pc_anim_eval(&a, 5.0);
  for (int r = 0; r < 3; r++)
    for (int k = 0; k < 3; k++) assert_true(fabs(m.m[r][k] - mirror.m[r][k]) < 1e-9);
  mat4 singular = {{{0, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
  assert_int_not_equal(pc_anim_append(&a, 9.0, &singular, &e), 0);
  assert_int_equal(pc_anim_append(&a, 2.0, &k0, &e), 0);
  assert_int_not_equal(pc_anim_finish(&a, &e), 0);
  assert_non_null(strstr(e.msg, "two keyframes at time 2"));
  pc_anim_free(&a);
}

static void test_motion_params(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  const char *body =
      "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><float name=\"shutterOpen\" value=\"0.5\"/>"
      "<float name=\"shutterClose\" value=\"1.5\"/><animation name=\"toWorld\">" KEY(0, "<translate z=\"-5\"/>")
          KEY(2, "<translate x=\"1\" z=\"-5\"/>") "</animation></sensor>\n"
      "<shape type=\"sphere\"><float name=\"radius\" value=\"0.5\"/><animation name=\"toWorld\">"
      KEY(0, "<translate x=\"-1\"/>") KEY(1, "<scale value=\"2\"/><translate x=\"1\"/>") "</animation></shape>\n"
      /* one key, or equal keys: the plain transform Mitsuba makes of it */
      "<shape type=\"rectangle\"><animation name=\"toWorld\">" KEY(3, "<translate y=\"7\"/>") "</animation>"
      "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n"
      "<shape type=\"shapegroup\" id=\"g\"><shape type=\"cube\"/><shape type=\"sphere\"/></shape>\n"
      "<shape type=\"instance\"><ref id=\"g\"/><animation name=\"toWorld\">" KEY(0, "") KEY(1, "<translate y=\"1\"/>")
      "</animation></shape>\n";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_true(s.shutter_open == 0.5f && s.shutter_close == 1.5f);
  assert_int_equal(s.camera_anim.n, 2);
  assert_int_equal(s.nshapes, 4);
  assert_int_equal(s.nmotions, 3);
  assert_int_equal(s.motions[0].shape, 0);
  assert_int_equal(s.motions[1].shape, 2);
  assert_int_equal(s.motions[2].shape, 3);
  float mean_y = 0;
  for (uint32_t i = 0; i < s.shapes[1].mesh.nverts; i++) mean_y += s.shapes[1].mesh.p[i].y / (float)s.shapes[1].mesh.nverts;
  assert_true(fabsf(mean_y - 7) < 1e-5f);
  assert_true(pc_scene_moves(&s));
  float t0 = pc_scene_time(&s, 1, 0), t1 = pc_scene_time(&s, 1, 1);
  assert_true(t0 >= 0.5f && t0 < 1.5f && t1 >= 0.5f && t1 < 1.5f && t0 != t1);
  assert_true(pc_scene_time(&s, 1, 0) == t0);
  /* built: placed at shutterOpen; a view moves to its own time, the scene stays */
  assert_int_equal(pc_scene_build(&s, &e), 0);
  assert_null(s.shapes[2].tri); /* a moving mesh computes its hits' constants at each hit */
  assert_non_null(s.shapes[1].tri);
  near3(s.shapes[0].center, v3(0, 0, 0), 1e-6f);
  assert_true(fabsf(s.shapes[0].radius - 0.75f) < 1e-6f);
  near3(s.camera.pos, v3(0.25f, 0, -5), 1e-6f);
  pc_scene *v;
  assert_int_equal(pc_scene_view_create(&s, &v, &e), 0);
  assert_int_equal(pc_scene_view_set_time(v, 1.0f, &e), 0);
  near3(v->shapes[0].center, v3(1, 0, 0), 1e-6f);
  assert_true(fabsf(v->shapes[0].radius - 1.f) < 1e-6f);
  near3(v->camera.pos, v3(0.5f, 0, -5), 1e-6f);
  near3(v->shapes[3].center, v3(0, 1, 0), 1e-6f);
  near3(s.shapes[0].center, v3(0, 0, 0), 1e-6f);
  pc_hit h;
  assert_true(pc_scene_intersect(v, v3(1, 0, -5), v3(0, 0, 1), 100.f, &h) && h.shape == 0);
  assert_false(pc_scene_intersect(&s, v3(1.8f, 0, -5), v3(0, 0, 1), 100.f, &h) && h.shape == 0);
  pc_scene_view_destroy(v);
  /* the bounding sphere holds the sphere at every time */
  assert_true(v3_len(v3_sub(v3(2, 0, 0), s.scene_center)) <= s.scene_radius);
  pc_scene_free(&s);
  const struct { const char *body, *want; } bad[] = {
      {"<shape type=\"rectangle\"><animation name=\"toWorld\">" KEY(0, "") KEY(1, "<translate x=\"1\"/>") "</animation>"
       "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>", "an emitter on a moving shape"},
      {"<emitter type=\"point\"><animation name=\"toWorld\">" KEY(0, "") KEY(1, "<translate x=\"1\"/>") "</animation></emitter>",
       "a moving 'toWorld' (motion blur): not modelled"},
      {"<emitter type=\"directional\"><animation name=\"toWorld\">" KEY(0, "") KEY(1, "<rotate x=\"1\" angle=\"10\"/>")
       "</animation></emitter>", "a moving 'toWorld' (motion blur): not modelled"},
      {"<shape type=\"shapegroup\" id=\"g\"><shape type=\"cube\"><animation name=\"toWorld\">" KEY(0, "")
       KEY(1, "<translate x=\"1\"/>") "</animation></shape></shape>", "nested instancing"},
      {"<shape type=\"sphere\"><animation name=\"toWorld\">" KEY(0, "") KEY(1, "<scale x=\"2\"/>") "</animation></shape>",
       "does not scale uniformly"},
      {"<shape type=\"cube\"><animation name=\"toWorld\">" KEY(1, "") KEY(1, "<translate x=\"1\"/>") "</animation></shape>",
       "two keyframes at time 1"},
      {"<shape type=\"cube\"><animation name=\"toWorld\"><transform/></animation></shape>", "lacks its time"},
      {"<shape type=\"cube\"><animation name=\"toWorld\"><rotate x=\"1\" angle=\"3\"/></animation></shape>", "holds <transform"},
      {"<shape type=\"cube\"><animation name=\"toWorld\">" KEY(0, "<scale x=\"0\"/>") "</animation></shape>", "singular"},
      {"<shape type=\"cube\"><animation name=\"toWorld\">" KEY(nan, "") "</animation></shape>", "time"},
      {"<shape type=\"cube\"><animation name=\"toWorld\"></animation></shape>", "without keyframes"},
  };
  char buf[2048];
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    snprintf(buf, sizeof buf, SENSOR "%s", bad[i].body);
    assert_int_not_equal(load_body(&t, buf, &s, &e), 0);
    if (!strstr(e.msg, bad[i].want)) print_error("case %zu: %s\n", i, e.msg);
    assert_non_null(strstr(e.msg, bad[i].want));
    assert_non_null(strstr(e.msg, "scene.xml:"));
  }
  const char *shutter = "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/><float name=\"shutterOpen\" value=\"2\"/>"
                        "<float name=\"shutterClose\" value=\"1\"/></sensor>";
  assert_int_not_equal(load_body(&t, shutter, &s, &e), 0);
  assert_non_null(strstr(e.msg, "shutterClose 1 is before shutterOpen 2"));
  th_rm_rf(t.root);
}

static void test_thinlens_params(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_scene s;
  pc_err e = {0};
  const struct { const char *params; float aperture, focus; } good[] = {
      {"<float name=\"apertureRadius\" value=\"0.1\"/><float name=\"focusDistance\" value=\"3\"/>", 0.1f, 3.f},
      {"<float name=\"apertureRadius\" value=\"0.2\"/>", 0.2f, 1e4f},
      {"<float name=\"apertureRadius\" value=\"0.2\"/><float name=\"farClip\" value=\"50\"/>", 0.2f, 50.f},
      {"<float name=\"apertureRadius\" value=\"0\"/>", 0.f, 1e4f},
  };
  char buf[1024];
  for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
    snprintf(buf, sizeof buf, "<sensor type=\"thinlens\"><float name=\"fov\" value=\"45\"/>%s</sensor>", good[i].params);
    int rc = load_body(&t, buf, &s, &e);
    if (rc) print_error("%s\n", e.msg);
    assert_int_equal(rc, 0);
    assert_true(s.camera.aperture_radius == good[i].aperture && s.camera.focus_distance == good[i].focus);
    pc_scene_free(&s);
  }
  const struct { const char *params, *want; } bad[] = {
      {"", "'apertureRadius' is required"},
      {"<float name=\"apertureRadius\" value=\"-1\"/>", "apertureRadius must be finite and not negative"},
      {"<float name=\"apertureRadius\" value=\"1\"/><float name=\"focusDistance\" value=\"0\"/>", "focusDistance must be positive"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    snprintf(buf, sizeof buf, "<sensor type=\"thinlens\"><float name=\"fov\" value=\"45\"/>%s</sensor>", bad[i].params);
    assert_int_not_equal(load_body(&t, buf, &s, &e), 0);
    if (!strstr(e.msg, bad[i].want)) print_error("case %zu: %s\n", i, e.msg);
    assert_non_null(strstr(e.msg, bad[i].want));
  }
  /* a pinhole has no lens, whatever it is given */
  assert_int_equal(load_body(&t, "<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>"
                                 "<float name=\"focusDistance\" value=\"3\"/></sensor>", &s, &e), 0);
  assert_true(s.camera.aperture_radius == 0.f);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

static void test_bitmap_texture(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  char png[512];
  snprintf(png, sizeof png, "%s/tex/checker.png", t.dir);
  char sub[512];
  snprintf(sub, sizeof sub, "%s/tex", t.dir);
  assert_int_equal(mkdir(sub, 0700), 0);
  const float rgb[6] = {1, 1, 1, 0, 0, 0};
  pc_err e = {0};
  assert_int_equal(pc_png_write_preview(png, 2, 1, rgb, 0.f, &e), 0);
  pc_scene s;
  const char *body =
      SENSOR "\n<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"tex/checker.png\"/>"
      "<float name=\"uscale\" value=\"2\"/><float name=\"voffset\" value=\"0.5\"/>"
      "<string name=\"filterType\" value=\"nearest\"/><string name=\"wrapMode\" value=\"repeat\"/></texture>\n"
      "<shape type=\"rectangle\"><bsdf type=\"diffuse\"><ref name=\"reflectance\" id=\"t\"/></bsdf></shape>";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_int_equal(s.ntextures, 1);
  assert_int_equal(s.textures[0].type, PC_TEX_BITMAP);
  assert_int_equal(s.textures[0].img.w, 2);
  assert_int_equal(s.textures[0].img.h, 1);
  assert_true(s.textures[0].uscale == 2.f && s.textures[0].vscale == 1.f && s.textures[0].voffset == 0.5f);
  /* an 8-bit PNG stays in its bytes */
  assert_true(s.textures[0].img.rgb == NULL && s.textures[0].img.rgb8 != NULL);
  assert_true(fabsf(pc_image_sample(&s.textures[0].img, 0) - 1.f) < 1e-3f && pc_image_sample(&s.textures[0].img, 3) < 1e-3f);
  assert_int_equal(s.materials[0].reflectance.tex, 0);
  pc_scene_free(&s);
  /* Mitsuba's gamma: the 8-bit values are v^(1/gamma)-encoded instead of sRGB */
  const float grey[3] = {0.5f, 0.5f, 0.5f};
  assert_int_equal(pc_png_write_preview(png, 1, 1, grey, 0.f, &e), 0); /* written sRGB-encoded: byte 188 */
  for (int g = 0; g < 3; g++) {
    static const char *const gam[] = {"", "<float name=\"gamma\" value=\"1\"/>", "<float name=\"gamma\" value=\"2.2\"/>"};
    char b[1024];
    snprintf(b, sizeof b, SENSOR "<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"tex/checker.png\"/>%s</texture>",
             gam[g]);
    assert_int_equal(load_body(&t, b, &s, &e), 0);
    float v = pc_image_sample(&s.textures[0].img, 0), byte = roundf(255.f * (1.055f * powf(0.5f, 1 / 2.4f) - 0.055f)) / 255.f;
    float want = g == 0 ? 0.5f : g == 1 ? byte : powf(byte, 2.2f);
    if (fabsf(v - want) > 3e-3f) print_error("gamma case %d: %g, expected %g\n", g, v, want);
    assert_true(fabsf(v - want) < 3e-3f);
    pc_scene_free(&s);
  }
  th_rm_rf(t.root);
}

/* Mitsuba's wrappers: a bump map through a scaled bitmap (uvscale), coatings, anisotropic
 * roughness; an id inside a wrapper names the wrapped BSDF alone (as in Mitsuba). */
static void test_layers(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_err e = {0};
  pc_scene s;
  char png[512];
  snprintf(png, sizeof png, "%s/bump.png", t.dir);
  const float rgb[6] = {1, 1, 1, 0, 0, 0};
  assert_int_equal(pc_png_write_preview(png, 2, 1, rgb, 0.f, &e), 0);
  const char *body =
      SENSOR "\n<bsdf type=\"bumpmap\" id=\"bumped\"><texture type=\"scale\"><float name=\"scale\" value=\"0.5\"/>"
      "<texture type=\"bitmap\"><string name=\"filename\" value=\"bump.png\"/><float name=\"uvscale\" value=\"3\"/>"
      "<float name=\"vscale\" value=\"2\"/></texture></texture>"
      "<bsdf type=\"twosided\" id=\"inner\"><bsdf type=\"roughconductor\"><float name=\"alphaU\" value=\"0.1\"/>"
      "<float name=\"alphaV\" value=\"0.3\"/></bsdf></bsdf></bsdf>\n"
      "<bsdf type=\"coating\" id=\"coat\"><float name=\"intIOR\" value=\"1.075\"/><rgb name=\"sigmaA\" value=\"0.1 0.2 0.3\"/>"
      "<float name=\"thickness\" value=\"2\"/><ref id=\"inner\"/></bsdf>\n"
      "<bsdf type=\"roughcoating\" id=\"rc\"><string name=\"distribution\" value=\"ggx\"/><float name=\"alphaU\" value=\"0.3\"/><float name=\"alphaV\" value=\"0.3\"/>"
      "<bsdf type=\"diffuse\"/></bsdf>\n"
      "<shape type=\"rectangle\"><ref id=\"bumped\"/></shape><shape type=\"rectangle\"><ref id=\"inner\"/></shape>"
      "<shape type=\"rectangle\"><ref id=\"coat\"/></shape><shape type=\"sphere\"><ref id=\"rc\"/></shape>"
      "<emitter type=\"constant\"/>";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  const pc_material *bm = &s.materials[s.shapes[0].material], *in = &s.materials[s.shapes[1].material];
  assert_int_equal(bm->type, PC_MAT_BUMPMAP);
  assert_int_equal(in->type, PC_MAT_ROUGHCONDUCTOR);
  assert_true(in->twosided && in->alpha == 0.1f && in->alpha_v == 0.3f);
  assert_int_equal(bm->nested, s.shapes[1].material);
  /* the nested bitmap is taken over by the scale texture: one texture */
  assert_int_equal(s.ntextures, 1);
  const pc_texture *tx = &s.textures[bm->bump_tex];
  assert_true(tx->type == PC_TEX_BITMAP && tx->scaled && tx->scale.x == 0.5f && tx->uscale == 3.f && tx->vscale == 2.f);
  const pc_material *coat = &s.materials[s.shapes[2].material];
  assert_int_equal(coat->type, PC_MAT_COATING);
  assert_true(coat->int_ior == 1.075f && coat->thickness == 2.f && coat->nested == s.shapes[1].material);
  near3(coat->sigma_a.value, v3(0.1f, 0.2f, 0.3f), 1e-6f);
  const pc_material *rcm = &s.materials[s.shapes[3].material];
  assert_true(rcm->type == PC_MAT_ROUGHCOATING && rcm->distribution == PC_MF_GGX && rcm->alpha == 0.3f);
  rc = pc_scene_build(&s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_ptr_equal(bm->inner, in);
  assert_true(coat->spec_sampling_weight > 0.5f && coat->spec_sampling_weight < 1.f);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* Mitsuba's combining BSDFs: mask (opacity texture, nested twosided), blendbsdf (a float
 * weight), mixturebsdf (weights rescaled by ensureEnergyConservation, or not), difftrans. */
static void test_mixes(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  pc_err e = {0};
  pc_scene s;
  const char *body =
      SENSOR "\n<bsdf type=\"mask\" id=\"m\"><texture type=\"checkerboard\" name=\"opacity\"/>"
      "<bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></bsdf>\n"
      "<bsdf type=\"blendbsdf\" id=\"b\"><float name=\"weight\" value=\"0.25\"/><bsdf type=\"diffuse\"/>"
      "<bsdf type=\"conductor\"/></bsdf>\n"
      "<bsdf type=\"mixturebsdf\" id=\"x\"><string name=\"weights\" value=\"0.6, 0.6;0.3\"/><bsdf type=\"diffuse\"/>"
      "<bsdf type=\"difftrans\"><rgb name=\"transmittance\" value=\"0 0.5 0\"/></bsdf><ref id=\"b\"/></bsdf>\n"
      "<bsdf type=\"mixturebsdf\" id=\"y\"><boolean name=\"ensureEnergyConservation\" value=\"false\"/>"
      "<string name=\"weights\" value=\"1 1\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>\n"
      "<shape type=\"rectangle\"><ref id=\"m\"/></shape><shape type=\"rectangle\"><ref id=\"b\"/></shape>"
      "<shape type=\"rectangle\"><ref id=\"x\"/></shape><shape type=\"sphere\"><ref id=\"y\"/></shape>"
      "<emitter type=\"constant\"/>";
  int rc = load_body(&t, body, &s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  const pc_material *m = &s.materials[s.shapes[0].material], *b = &s.materials[s.shapes[1].material];
  const pc_material *x = &s.materials[s.shapes[2].material], *y = &s.materials[s.shapes[3].material];
  assert_int_equal(m->type, PC_MAT_MASK);
  assert_true(m->weight.tex == 0 && s.materials[m->nested].twosided && s.materials[m->nested].type == PC_MAT_DIFFUSE);
  assert_int_equal(b->type, PC_MAT_BLEND);
  assert_true(b->nmix == 2 && b->weight.tex < 0 && b->weight.value.x == 0.25f);
  assert_int_equal(s.materials[b->mix_nested[1]].type, PC_MAT_CONDUCTOR);
  assert_true(x->type == PC_MAT_MIXTURE && x->nmix == 3 && x->mix_nested[2] == s.shapes[1].material);
  assert_int_equal(s.materials[x->mix_nested[1]].type, PC_MAT_DIFFTRANS);
  near3(s.materials[x->mix_nested[1]].transmittance.value, v3(0, 0.5f, 0), 1e-6f);
  assert_true(fabsf(x->mix_w[0] - 0.4f) < 1e-6f && fabsf(x->mix_w[2] - 0.2f) < 1e-6f && fabsf(x->mix_p[1] - 0.4f) < 1e-6f);
  assert_true(y->mix_w[0] == 1.f && y->mix_w[1] == 1.f && y->mix_p[0] == 0.5f);
  rc = pc_scene_build(&s, &e);
  if (rc) print_error("%s\n", e.msg);
  assert_int_equal(rc, 0);
  assert_ptr_equal(m->inner, &s.materials[m->nested]);
  assert_ptr_equal(x->mix[2], b);
  pc_scene_free(&s);
  th_rm_rf(t.root);
}

/* Mutated copies of the full scene never crash (run under -DPCBPT_SANITIZE=ON as well). */
static void test_mutations(void **state) {
  (void)state;
  tmp t;
  tmp_make(&t);
  char src[4096], p[512];
  good_path(src, sizeof src, "full.xml");
  size_t len = 0;
  char *orig = th_read(src, &len);
  assert_non_null(orig);
  snprintf(p, sizeof p, "%s/meshes", t.dir);
  assert_int_equal(mkdir(p, 0700), 0);
  const char *meshes[] = {"quad.obj", "quad.ply", "tri_normals.obj"};
  for (int i = 0; i < 3; i++) {
    char name[512];
    snprintf(name, sizeof name, "meshes/%s", meshes[i]);
    good_path(src, sizeof src, name);
    char *m = th_read(src, NULL);
    assert_non_null(m);
    assert_int_equal(th_write_str(t.dir, name, m), 0);
    free(m);
  }
  static const char alphabet[] = "<>/=\"$ -0123456789.,#xyz\n";
  uint64_t seed = 12345;
  char *buf = malloc(len + 64);
  int loaded = 0;
  for (int it = 0; it < 400; it++) {
    memcpy(buf, orig, len);
    size_t n = len;
    int edits = 1 + it % 4;
    for (int k = 0; k < edits; k++) {
      seed = seed * 6364136223846793005ull + 1442695040888963407ull;
      size_t pos = (size_t)(seed >> 33) % n;
      int op = (int)((seed >> 20) % 4);
      char ch = alphabet[(seed >> 8) % (sizeof alphabet - 1)];
      if (op == 0) buf[pos] = ch;
      else if (op == 1) n = pos + 1; /* truncate */
      else if (op == 2 && n + 1 < len + 64) {
        memmove(buf + pos + 1, buf + pos, n - pos);
        buf[pos] = ch;
        n++;
      } else if (n > 1) {
        memmove(buf + pos, buf + pos + 1, n - pos - 1);
        n--;
      }
    }
    snprintf(p, sizeof p, "%s/scene.xml", t.dir);
    assert_int_equal(th_write(p, buf, n), 0);
    pc_scene s;
    pc_err e = {0};
    int rc = pc_scene_load(p, &s, &e);
    if (rc == 0) {
      loaded++;
      pc_scene_free(&s);
    } else {
      assert_true(strlen(e.msg) > 0);
    }
  }
  free(buf);
  free(orig);
  th_rm_rf(t.root);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_full_scene),       cmocka_unit_test(test_cornell_box),
      cmocka_unit_test(test_bad_scenes),       cmocka_unit_test(test_bad_documents),
      cmocka_unit_test(test_defaults_and_values), cmocka_unit_test(test_bitmap_texture),
      cmocka_unit_test(test_mutations),        cmocka_unit_test(test_warnings),
      cmocka_unit_test(test_smooth_angle_param), cmocka_unit_test(test_negative_conductor),
      cmocka_unit_test(test_default_sensor),   cmocka_unit_test(test_include_and_defines),
      cmocka_unit_test(test_ward),             cmocka_unit_test(test_phong_roughdiffuse),
      cmocka_unit_test(test_embree_shares_meshes), cmocka_unit_test(test_tri_consts),
      cmocka_unit_test(test_check_without_bvh), cmocka_unit_test(test_probe_backs),
      cmocka_unit_test(test_lookat_near_parallel),
      cmocka_unit_test(test_lookat_without_up),
      cmocka_unit_test(test_alias),
      cmocka_unit_test(test_emitter_defaults),
      cmocka_unit_test(test_probe_clip),
      cmocka_unit_test(test_spectrum_file),
      cmocka_unit_test(test_focal_length),
      cmocka_unit_test(test_integrator_kinds),
    cmocka_unit_test(test_instances),        cmocka_unit_test(test_layers),
      cmocka_unit_test(test_mixes),            cmocka_unit_test(test_obj_materials),
      cmocka_unit_test(test_animation),        cmocka_unit_test(test_motion_params),
      cmocka_unit_test(test_thinlens_params),  cmocka_unit_test(test_pt_complete), cmocka_unit_test(test_near_rigid_camera),
      cmocka_unit_test(test_directional_params),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
