/* kdtree.h: a static 3-d kd-tree over a point set (PCBPT importance-record positions), built
 * once per iteration and queried for the k nearest neighbours. The tree is implicit: the
 * points are permuted so that every subrange [lo, hi) larger than a leaf splits at its middle
 * position (the split plane through that point), which keeps it in four flat arrays and lets
 * a query run without allocating; leaves of up to PC_KDTREE_LEAF points are scanned. Results are
 * deterministic: neighbours are ordered by (squared distance, point index), so equal distances
 * are broken by the smaller index, exactly as a brute-force scan would. */
#ifndef PC_KDTREE_H
#define PC_KDTREE_H

#include <stddef.h>

#include "error.h"
#include "vecmath.h"

/* Largest k a query accepts (callers keep k-sized arrays on the stack). */
#define PC_KDTREE_MAX_K 64
/* Points per leaf: a short linear scan is cheaper than descending further. */
#define PC_KDTREE_LEAF 8

typedef struct pc_kdtree {
  int n;
  int cap;              /* allocated entries; reused by the next build when large enough */
  vec3 *pts;            /* points in tree order */
  int *idx;             /* original index of each tree-order point */
  unsigned char *axis;  /* split axis and coordinate of the inner node whose middle position */
  float *split;         /* this is */
} pc_kdtree;

/* Builds (or rebuilds, reusing memory) the tree over pts[0..n). O(n log n) expected.
 * A zeroed pc_kdtree is a valid empty tree. Fails with PC_EINVAL on n < 0 or non-finite
 * points and PC_ENOMEM when allocation fails (the old tree is then empty). */
int pc_kdtree_build(pc_kdtree *t, const vec3 *pts, int n, pc_err *e);
void pc_kdtree_free(pc_kdtree *t);

/* The min(k, n) nearest points to q (1 <= k <= PC_KDTREE_MAX_K), ascending by (squared
 * distance, index), written to idx[] and d2[]; returns their number (0 if k is out of range). */
int pc_kdtree_knn(const pc_kdtree *t, vec3 q, int k, int *idx, float *d2);

/* Bytes the tree holds per point of capacity. */
#define PC_KDTREE_POINT_BYTES (sizeof(vec3) + sizeof(int) + 1 + sizeof(float))

/* Bytes held by the tree. */
size_t pc_kdtree_bytes(const pc_kdtree *t);

#endif
