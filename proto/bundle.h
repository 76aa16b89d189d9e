/* bundle.h: content-addressed scene bundles. A bundle is the scene XML and every file the
 * scene loader read for it (included XML, meshes, images), serialized as a protobuf
 * Bundle and zstd-compressed; its address is the BLAKE2b-256 hash of those bytes. Unpacking
 * verifies the hash and writes only under the cache directory (no absolute paths, no "..",
 * no symlink following), so a hostile bundle cannot escape it. */
#ifndef PC_BUNDLE_H
#define PC_BUNDLE_H

#include <stddef.h>
#include <stdint.h>

#include "error.h"

#define PC_BUNDLE_HASH 32
#define PC_BUNDLE_MAX ((size_t)1 << 30)     /* compressed and uncompressed limit */
#define PC_BUNDLE_MAX_FILES 4096
#define PC_BUNDLE_MAX_PATH 1024

/* Packs files (real paths, read) under names (relative paths; files[0] is the scene), as
 * pc_scene's files and file_names list them, into a malloc'd blob with its hash. Unpacked, the
 * scene's root folder becomes the bundle's folder (pc_bundle_dir). */
int pc_bundle_create(const char *const *files, const char *const *names, int nfiles, uint8_t **blob, size_t *n,
                     uint8_t hash[PC_BUNDLE_HASH], pc_err *e);
/* The folder a bundle unpacks into (the scene's root folder there). */
int pc_bundle_dir(const char *cache_dir, const uint8_t hash[PC_BUNDLE_HASH], char *out, size_t out_size);
int pc_bundle_hash(const uint8_t *blob, size_t n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e);
void pc_bundle_hex(const uint8_t hash[PC_BUNDLE_HASH], char out[2 * PC_BUNDLE_HASH + 1]);
/* Parses 64 hex digits; returns PC_EINVAL otherwise. */
int pc_bundle_unhex(const char *hex, uint8_t hash[PC_BUNDLE_HASH]);
/* True if rel is a safe relative path: no leading '/', no "." or ".." or empty component, no
 * backslash or control characters, shorter than PC_BUNDLE_MAX_PATH. */
int pc_bundle_path_ok(const char *rel);
/* Verifies blob against hash and unpacks it into cache_dir/<hex>/ (atomically: a partial
 * unpack is never visible). Writes the unpacked scene file's path into scene_out. */
int pc_bundle_unpack(const uint8_t *blob, size_t n, const uint8_t hash[PC_BUNDLE_HASH], const char *cache_dir,
                     char *scene_out, size_t scene_out_size, pc_err *e);
/* If the bundle is already unpacked in cache_dir, writes its scene path and returns 1; 0 if not. */
int pc_bundle_lookup(const char *cache_dir, const uint8_t hash[PC_BUNDLE_HASH], char *scene_out, size_t scene_out_size);

#endif
