/* big_alloc.h: buffers of megabytes (film layers, upload bodies, scene files read whole, mesh
 * arrays, scene bundles) in transparent huge pages where the kernel offers them. A fresh 4 KiB
 * page costs a fault on first touch; on the VMs the farm runs on, a render's ~60k such faults
 * (films of 512x512, uploads' buffers) were 5-7% of a 16-spp cornell-box BDPT render's CPU,
 * and a 5M-triangle scene's 340k (its 125 MB PLY read, parsed, bundled, sent and unpacked)
 * half of its start's wall time. A 2 MiB page takes one fault for 512 of them. */
#ifndef PC_BIG_ALLOC_H
#define PC_BIG_ALLOC_H

#include <stddef.h>

/* Bytes past the n asked that a buffer from pc_big_alloc may be read through (not written):
 * Embree reads a shared buffer's last element with a 16-byte load, so a mesh's 12-byte
 * vertices and index triples can be handed to it without a copy (scene_build.c). */
#define PC_BIG_ALLOC_SLACK 16

/* n bytes (uninitialized, PC_BIG_ALLOC_SLACK more readable), 2 MiB-aligned and advised as
 * huge pages when that is at least 2 MiB; otherwise plain malloc (n == 0 included: a pointer
 * to free like any other). NULL only when out of memory. Free with free(). */
void *pc_big_alloc(size_t n);

/* The memory this process can ever have: the machine's RAM, or its cgroup's limit (v2's
 * memory.max) where that is lower; 0 when neither can be read. What a render's films need is
 * known before they are made, and films larger than this cannot be filled: where the kernel
 * overcommits, allocating them succeeds and the process is killed while they are zeroed. */
size_t pc_big_memory_limit(void);
/* Megabytes (MiB), rounded up: sizes in messages. */
static inline size_t pc_big_mb(size_t bytes) { return bytes / 1048576 + (bytes % 1048576 != 0); }

/* A buffer kept from one use to the next (an upload's: a fresh one's pages are each cleared by
 * the kernel at their first write). */
typedef struct pc_big_spare {
  void *p;
  size_t cap;
} pc_big_spare;
/* Keeps buf (cap bytes; NULL: nothing) as the spare when it is the larger, freeing the other. */
void pc_big_spare_keep(pc_big_spare *s, void *buf, size_t cap);
/* The spare, which the caller now owns (NULL when there is none), and its size in *cap. */
void *pc_big_spare_take(pc_big_spare *s, size_t *cap);
/* Frees the spare, if any. */
void pc_big_spare_free(pc_big_spare *s);

#endif
