/* wire_film.h: a film's sums and counts as bytes (uploads and checkpoints) and the zstd
 * compression that wraps them. Decoding is into a film the receiver already shaped from the
 * job's settings, so a wrong resolution, a different layer set or a non-finite sum is refused
 * before anything is added. */
#ifndef PC_WIRE_FILM_H
#define PC_WIRE_FILM_H

#include <stddef.h>
#include <stdint.h>

#include "error.h"
#include "film.h"

/* Upper bound on a serialized film (and so on what a decompressor may produce). */
#define PC_WIRE_FILM_MAX ((size_t)1 << 34)

size_t pc_wire_film_size(const pc_film *f);
/* The size of a serialized film of like's shape and layers with ntrace trace records. */
size_t pc_wire_film_size_traced(const pc_film *like, uint32_t ntrace);
/* Serializes f (little-endian, layer by layer, sums as byte planes) into out, which holds
 * pc_wire_film_size(f) bytes; pc_wire_film_pack into a malloc'd buffer. */
void pc_wire_film_pack_to(const pc_film *f, uint8_t *out);
int pc_wire_film_pack(const pc_film *f, uint8_t **out, size_t *n, pc_err *e);
/* Fills `into` (already initialised with the expected shape and layers) from buf; checks the
 * shape, layer names and norms, and that every sum is finite. `into` is unchanged on error.
 * A film serialized before beauty_sq or beauty_max existed (one or two layers short) loads
 * with them empty. */
int pc_wire_film_unpack(const uint8_t *buf, size_t n, pc_film *into, pc_err *e);
/* A delta's sum per sample of its layer stays under 2^PC_WIRE_SAMPLE_LOG2 (1.8e19; no real
 * radiance comes near): larger finite sums would add to infinity or overflow the image's
 * floats, so pc_wire_film_add refuses them. */
#define PC_WIRE_SAMPLE_LOG2 64
/* What a serialized film holds, for a judge to see before anything is added: its per-layer
 * counts (counts[into->nlayers]) and the iterations its trace holds. */
typedef struct pc_wire_film_counts {
  const uint64_t *counts;
  const uint32_t *traced;
  uint32_t ntraced;
} pc_wire_film_counts;
/* 0 accepts, an error code (with e set) refuses. */
typedef int (*pc_wire_counts_judge)(void *user, const pc_wire_film_counts *c, pc_err *e);
/* The same checks (a non-finite or unbounded sum, or a trace record of an iteration `into` traces
 * already, is refused before the counts are judged), then judge (NULL: any counts), then adds buf's
 * sums (beauty_max: their max), counts, dropped samples and trace into `into` (unchanged on error):
 * a merge without an intermediate film. */
int pc_wire_film_add(const uint8_t *buf, size_t n, pc_film *into, pc_wire_counts_judge judge, void *user, pc_err *e);

/* pc_wire_film_add of a zstd frame of a serialized film (an upload), decompressed twice through
 * a small window (once to check, once to add) instead of into a copy of the film. */
int pc_wire_film_add_z(const uint8_t *z, size_t zn, pc_film *into, pc_wire_counts_judge judge, void *user, pc_err *e);
/* A checkpoint: a zstd frame of a serialized film (whole, or of an older coordinator without
 * beauty_sq and/or beauty_max) checked and unpacked into `into` as pc_wire_film_unpack does, the same way. */
int pc_wire_film_load(const uint8_t *z, size_t zn, pc_film *into, pc_err *e);

/* Where pc_wire_film_compress puts the compressed bytes as they come: 0, or an error code. */
typedef int (*pc_wire_sink)(void *user, const uint8_t *p, size_t n, pc_err *e);
/* Serializes and compresses f as one zstd frame (what pc_wire_compress of pc_wire_film_pack
 * gives, and the loaders read) through a 1 MiB staging buffer, so no serialized copy of the
 * film is ever whole in memory; *zn (may be NULL) gets the compressed size. threads > 1: zstd
 * compresses on that many threads of its own while this one stages (a worker's render pool
 * waits for its uploads); the frame is another but decodes to the same film. A libzstd built
 * without threads compresses on this one. */
int pc_wire_film_compress(const pc_film *f, int threads, pc_wire_sink sink, void *user, size_t *zn, pc_err *e);
/* The same into a malloc'd buffer (an upload). */
int pc_wire_film_zip(const pc_film *f, int threads, uint8_t **out, size_t *outn, pc_err *e);
/* The same into *buf, a buffer of *cap bytes the caller keeps from one upload to the next
 * (NULL, 0 at first), replaced by a new one when it cannot hold the worst case: a fresh
 * buffer's pages are each cleared by the kernel at their first write. *outn: bytes written. */
int pc_wire_film_zip_reuse(const pc_film *f, int threads, uint8_t **buf, size_t *cap, size_t *outn, pc_err *e);

/* zstd one-shot compression (a fast level) into a malloc'd buffer. */
int pc_wire_compress(const uint8_t *in, size_t n, uint8_t **out, size_t *outn, pc_err *e);
/* Decompresses a zstd frame whose content size must be exactly `expect` (<= limit). */
int pc_wire_decompress(const uint8_t *in, size_t n, size_t expect, size_t limit, uint8_t **out, pc_err *e);

#endif
