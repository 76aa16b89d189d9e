/* fuzz_files.c: libFuzzer target for the binary files a scene names besides its XML and OBJ
 * (which fuzz_scene covers): textures and environment maps (PNG, JPEG, EXR, Radiance RGBE, PFM,
 * PPM, BMP, told apart by content, and TGA), the EXR reader of `compare` and references, and the PLY and Mitsuba
 * `serialized` meshes. Whatever the bytes: a clean return, no crash, no leak. The first byte
 * picks the reader, the second its option; the rest is the file:
 *   0  pc_image_read, sRGB decoding when the option is odd; pc_image_read_bytes (textures)
 *      when its bit 1 is set; the file named .tga when its bit 2 is set (TGA is told by name);
 *   1  pc_exr_read_layers (every RGB triplet and the header's attributes);
 *   2  pc_mesh_load_ply;
 *   3  pc_mesh_load_serialized, shape index = option % 4;
 *   4  pc_bundle_unpack of a scene bundle (as a worker unpacks what the coordinator took from a
 *      client), given its own hash so that the fuzzer gets past the check to the archive's
 *      parsing and the paths it writes; what it unpacks is removed after each input.
 * Seeds: tests/fuzz/seeds_files, small valid files of each kind with their two bytes. */
#include <ftw.h>
#include <sodium.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bundle.h"
#include "fuzz_dir.h"
#include "image.h"
#include "mesh.h"

enum { IMAGE, EXR_LAYERS, PLY, SERIALIZED, BUNDLE, NMODES };

/* The input's file, in a folder of its own (fuzz_dir.h). */
static char dir[4096], file[4200], tga[4200], cache[4200];

static int rm_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag;
  return ftw->level > 0 ? remove(path) : 0;
}

/* Empties the bundle cache (keeps the folder itself). */
static void empty_cache(void) { (void)nftw(cache, rm_entry, 16, FTW_DEPTH | FTW_PHYS); }

static void remove_dir(void) {
  empty_cache();
  rmdir(cache);
  unlink(file);
  unlink(tga);
  rmdir(dir);
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  fuzz_make_dir("fuzz-files", dir, sizeof dir, remove_dir);
  snprintf(file, sizeof file, "%s/input", dir);
  snprintf(tga, sizeof tga, "%s/input.tga", dir);
  snprintf(cache, sizeof cache, "%s/cache", dir);
  if (mkdir(cache, 0700) != 0 || sodium_init() < 0) {
    fprintf(stderr, "fuzz_files: cannot set up the bundle cache %s\n", cache);
    abort();
  }
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 2) return 0;
  const char *path = data[0] % NMODES == IMAGE && (data[1] & 4) ? tga : file;
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  size_t w = fwrite(data + 2, 1, size - 2, f);
  if (fclose(f) != 0 || w != size - 2) return 0;
  pc_err e;
  int option = data[1];
  switch (data[0] % NMODES) { /* the results are irrelevant; only crashes and leaks matter */
  case IMAGE: {
    pc_image img = {0};
    if (option & 2) (void)pc_image_read_bytes(path, option & 1, &img, &e);
    else (void)pc_image_read(path, option & 1, &img, &e);
    pc_image_free(&img);
    break;
  }
  case EXR_LAYERS: {
    pc_exr_file x = {0};
    (void)pc_exr_read_layers(file, &x, &e);
    pc_exr_file_free(&x);
    break;
  }
  case PLY: {
    pc_mesh m;
    (void)pc_mesh_load_ply(file, &m, &e);
    pc_mesh_free(&m);
    break;
  }
  case SERIALIZED: {
    pc_mesh m;
    bool face_normals;
    (void)pc_mesh_load_serialized(file, option % 4, &m, &face_normals, &e);
    pc_mesh_free(&m);
    break;
  }
  case BUNDLE: {
    uint8_t hash[PC_BUNDLE_HASH];
    char scene[4400];
    if (pc_bundle_hash(data + 2, size - 2, hash, &e) == 0)
      (void)pc_bundle_unpack(data + 2, size - 2, hash, cache, scene, sizeof scene, &e);
    empty_cache();
    break;
  }
  }
  return 0;
}
