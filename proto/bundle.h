/* bundle.h: content-addressed scene bundles. A bundle is the scene XML and every file it
 * references (found by parsing the XML for `filename` parameters), serialized as a protobuf
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

/* Collects scene_path and its referenced files into a malloc'd blob with its hash. */
int pc_bundle_create(const char *scene_path, uint8_t **blob, size_t *n, uint8_t hash[PC_BUNDLE_HASH], pc_err *e);
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
