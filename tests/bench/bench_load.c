/* bench_load.c: benchmark (not a test) of scene loading: writes a grid of just over a million
 * triangles (with normals and texture coordinates) as an OBJ, a binary PLY and an ASCII PLY,
 * and prints the wall time of loading each through the scene loader (parse, transform,
 * validate), best of three. Usage: bench_load [DIR] (default: a temporary folder). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "scene.h"

#define N 709 /* vertices per side: 2 * 708^2 = 1,002,528 triangles */

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int write_obj(const char *path) {
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  for (int j = 0; j < N; j++)
    for (int i = 0; i < N; i++) fprintf(f, "v %.6f %.6f %.6f\n", i / (double)(N - 1), j / (double)(N - 1), 0.01 * ((i * 7 + j * 13) % 17));
  for (int j = 0; j < N; j++)
    for (int i = 0; i < N; i++) fprintf(f, "vt %.6f %.6f\n", i / (double)(N - 1), j / (double)(N - 1));
  fprintf(f, "vn 0 0 1\n");
  for (int j = 0; j + 1 < N; j++)
    for (int i = 0; i + 1 < N; i++) {
      int a = j * N + i + 1, b = a + 1, c = a + N + 1, d = a + N;
      fprintf(f, "f %d/%d/1 %d/%d/1 %d/%d/1\nf %d/%d/1 %d/%d/1 %d/%d/1\n", a, a, b, b, c, c, a, a, c, c, d, d);
    }
  return fclose(f);
}

static int write_ply(const char *path, int binary) {
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  fprintf(f, "ply\nformat %s 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
             "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
             "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
          binary ? "binary_little_endian" : "ascii", N * N, 2 * (N - 1) * (N - 1));
  for (int j = 0; j < N; j++)
    for (int i = 0; i < N; i++) {
      float v[8] = {i / (float)(N - 1), j / (float)(N - 1), 0.01f * (float)((i * 7 + j * 13) % 17), 0, 0, 1,
                    i / (float)(N - 1), j / (float)(N - 1)};
      if (binary) fwrite(v, sizeof v, 1, f);
      else fprintf(f, "%g %g %g %g %g %g %g %g\n", v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
    }
  for (int j = 0; j + 1 < N; j++)
    for (int i = 0; i + 1 < N; i++) {
      int a = j * N + i, t[2][3] = {{a, a + 1, a + N + 1}, {a, a + N + 1, a + N}};
      for (int k = 0; k < 2; k++) {
        if (binary) {
          unsigned char three = 3;
          fwrite(&three, 1, 1, f);
          fwrite(t[k], sizeof t[k], 1, f);
        } else {
          fprintf(f, "3 %d %d %d\n", t[k][0], t[k][1], t[k][2]);
        }
      }
    }
  return fclose(f);
}

static int bench(const char *dir, const char *type, const char *mesh) {
  char scene[4096];
  snprintf(scene, sizeof scene, "%s/%s.xml", dir, mesh);
  FILE *f = fopen(scene, "w");
  if (!f) return -1;
  fprintf(f, "<scene version=\"0.6.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>"
             "<shape type=\"%s\"><string name=\"filename\" value=\"%s\"/></shape></scene>\n", type, mesh);
  if (fclose(f)) return -1;
  double best = 1e30;
  uint32_t tris = 0;
  for (int rep = 0; rep < 3; rep++) {
    pc_scene s;
    pc_err e = {0};
    double t0 = now_s();
    if (pc_scene_load(scene, &s, &e)) {
      fprintf(stderr, "bench_load: %s\n", e.msg);
      return -1;
    }
    double t = now_s() - t0;
    tris = s.shapes[0].mesh.ntris;
    pc_scene_free(&s);
    if (t < best) best = t;
  }
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, mesh);
  FILE *g = fopen(path, "rb");
  long size = 0;
  if (g && fseek(g, 0, SEEK_END) == 0) size = ftell(g);
  if (g) fclose(g);
  printf("%-14s %9u triangles %7.1f MB  load %.3f s (best of 3)  %s\n", mesh, tris, size / 1e6, best,
         best < 2.0 ? "under 2 s" : "OVER 2 s");
  return 0;
}

int main(int argc, char **argv) {
  char tmpl[] = "/tmp/pcbpt_bench_load_XXXXXX";
  const char *dir = argc > 1 ? argv[1] : mkdtemp(tmpl);
  if (!dir) return 1;
  char p[4096];
  double t0 = now_s();
  snprintf(p, sizeof p, "%s/grid.obj", dir);
  if (write_obj(p)) return 1;
  snprintf(p, sizeof p, "%s/grid.ply", dir);
  if (write_ply(p, 1)) return 1;
  snprintf(p, sizeof p, "%s/grid_ascii.ply", dir);
  if (write_ply(p, 0)) return 1;
  printf("wrote the meshes in %.1f s; loading (wall time, machine shared: figures vary)\n", now_s() - t0);
  int rc = bench(dir, "obj", "grid.obj") | bench(dir, "ply", "grid.ply") | bench(dir, "ply", "grid_ascii.ply");
  if (argc <= 1) {
    const char *names[] = {"grid.obj", "grid.ply", "grid_ascii.ply", "grid.obj.xml", "grid.ply.xml", "grid_ascii.ply.xml"};
    for (int i = 0; i < 6; i++) {
      snprintf(p, sizeof p, "%s/%s", dir, names[i]);
      unlink(p);
    }
    rmdir(dir);
  }
  return rc ? 1 : 0;
}
