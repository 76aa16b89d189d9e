/* kdtree.c: see kdtree.h. Build: split every subrange at its median along its widest axis
 * (quickselect, so O(n) per level and O(n log n) overall). Points are ordered by the key
 * (coordinate, original index); the key is unique, so the tree is the same on every machine
 * and duplicate positions cannot stall the selection. */
#include "kdtree.h"

#include <stdlib.h>

static inline float coord(vec3 p, int ax) { return ax == 0 ? p.x : (ax == 1 ? p.y : p.z); }

static inline int key_less(const pc_kdtree *t, int a, int b, int ax) {
  float ca = coord(t->pts[a], ax), cb = coord(t->pts[b], ax);
  return ca < cb || (ca == cb && t->idx[a] < t->idx[b]);
}

static inline void swap_pt(pc_kdtree *t, int a, int b) {
  vec3 p = t->pts[a];
  t->pts[a] = t->pts[b];
  t->pts[b] = p;
  int i = t->idx[a];
  t->idx[a] = t->idx[b];
  t->idx[b] = i;
}

/* Rearranges [lo, hi) so position nth holds the element of rank nth - lo by key, with smaller
 * keys before it and larger after. */
static void select_nth(pc_kdtree *t, int lo, int hi, int nth, int ax) {
  while (hi - lo > 1) {
    int m = lo + (hi - lo) / 2, last = hi - 1;
    /* Median of three moved to `last` as the pivot: avoids the quadratic case on sorted
     * input, which record positions along a scanline often are. */
    if (key_less(t, m, lo, ax)) swap_pt(t, m, lo);
    if (key_less(t, last, lo, ax)) swap_pt(t, last, lo);
    if (key_less(t, m, last, ax)) swap_pt(t, m, last);
    int store = lo;
    for (int i = lo; i < last; i++)
      if (key_less(t, i, last, ax)) swap_pt(t, i, store++);
    swap_pt(t, store, last);
    if (store == nth) return;
    if (nth < store) hi = store;
    else lo = store + 1;
  }
}

/* Splits [lo, hi) at its middle position along its widest axis until a range holds at most
 * PC_KDTREE_LEAF points: [lo, mid) keys <= key(mid) <= [mid, hi) keys. */
static void build_range(pc_kdtree *t, int lo, int hi) {
  while (hi - lo > PC_KDTREE_LEAF) {
    vec3 mn = t->pts[lo], mx = t->pts[lo];
    for (int i = lo + 1; i < hi; i++) {
      vec3 p = t->pts[i];
      mn = v3(fminf(mn.x, p.x), fminf(mn.y, p.y), fminf(mn.z, p.z));
      mx = v3(fmaxf(mx.x, p.x), fmaxf(mx.y, p.y), fmaxf(mx.z, p.z));
    }
    vec3 ext = v3_sub(mx, mn);
    int ax = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    int mid = lo + (hi - lo) / 2;
    select_nth(t, lo, hi, mid, ax);
    t->axis[mid] = (unsigned char)ax;
    t->split[mid] = coord(t->pts[mid], ax); /* building [mid, hi) moves that point */
    build_range(t, lo, mid);
    lo = mid; /* the right half iteratively: recursion depth stays log2(n) */
  }
}

int pc_kdtree_build(pc_kdtree *t, const vec3 *pts, int n, pc_err *e) {
  if (n < 0) return pc_errf(e, PC_EINVAL, "kd-tree: negative point count %d", n);
  for (int i = 0; i < n; i++)
    if (!v3_is_finite(pts[i])) return pc_errf(e, PC_EINVAL, "kd-tree: point %d is not finite", i);
  t->n = 0;
  if (n > t->cap) {
    vec3 *p = realloc(t->pts, (size_t)n * sizeof *p);
    if (p) t->pts = p;
    int *ix = realloc(t->idx, (size_t)n * sizeof *ix);
    if (ix) t->idx = ix;
    unsigned char *a = realloc(t->axis, (size_t)n);
    if (a) t->axis = a;
    float *sp = realloc(t->split, (size_t)n * sizeof *sp);
    if (sp) t->split = sp;
    if (!p || !ix || !a || !sp) return pc_errf(e, PC_ENOMEM, "kd-tree: out of memory for %d points", n);
    t->cap = n;
  }
  for (int i = 0; i < n; i++) {
    t->pts[i] = pts[i];
    t->idx[i] = i;
  }
  build_range(t, 0, n);
  t->n = n;
  return PC_OK;
}

void pc_kdtree_free(pc_kdtree *t) {
  free(t->pts);
  free(t->idx);
  free(t->axis);
  free(t->split);
  *t = (pc_kdtree){0};
}

size_t pc_kdtree_bytes(const pc_kdtree *t) {
  return (size_t)t->cap * PC_KDTREE_POINT_BYTES;
}

/* Inserts candidate (d, i) into the list idx/d2 of m entries sorted by (d2, index), dropping
 * the last entry when the list already holds k. The caller has checked that it beats that one. */
static inline int insert_sorted(int *idx, float *d2, int m, int k, float d, int i) {
  int pos = m < k ? m++ : k - 1;
  while (pos > 0 && (d2[pos - 1] > d || (d2[pos - 1] == d && idx[pos - 1] > i))) {
    d2[pos] = d2[pos - 1];
    idx[pos] = idx[pos - 1];
    pos--;
  }
  d2[pos] = d;
  idx[pos] = i;
  return m;
}

/* Squared length, the one expression for point distances and cell bounds alike: it is monotone
 * in each |component| (float rounding is), so a bound from offsets no larger than a point's
 * coordinate differences never exceeds that point's computed distance. */
static inline float len2(float dx, float dy, float dz) { return dx * dx + dy * dy + dz * dz; }

/* A subtree still to visit: the query's offset from its cell per axis (0 inside the slab) and
 * the squared distance they give, a lower bound for every point in it (Arya and Mount 1993). */
typedef struct knn_frame {
  int lo, hi;
  float off[3], bound;
} knn_frame;

int pc_kdtree_knn(const pc_kdtree *t, vec3 q, int k, int *idx, float *d2) {
  if (k < 1 || k > PC_KDTREE_MAX_K) return 0;
  if (k > t->n) k = t->n;
  if (k == 0) return 0;
  /* k is small, so a sorted array beats a heap. Depth-first, nearer child first: every descent
   * pushes one far sibling per level, so the stack never holds more than the depth (< 32). */
  knn_frame stack[64];
  int sp = 0, m = 0;
  float worst = INFINITY; /* d2 of the k-th candidate once there are k */
  float qc[3] = {q.x, q.y, q.z};
  stack[sp++] = (knn_frame){0, t->n, {0.f, 0.f, 0.f}, 0.f};
  while (sp > 0) {
    knn_frame f = stack[--sp];
    /* A point exactly at the bound may still win its tie by a smaller index: prune only when
     * strictly beyond it. */
    if (f.bound > worst) continue;
    int lo = f.lo, hi = f.hi;
    while (hi - lo > PC_KDTREE_LEAF) {
      int mid = lo + (hi - lo) / 2, ax = t->axis[mid];
      /* Every point across the plane is at least |diff| away along ax, and no nearer along the
       * other axes than the cell. */
      float diff = qc[ax] - t->split[mid];
      knn_frame far = f;
      far.off[ax] = diff;
      far.bound = len2(far.off[0], far.off[1], far.off[2]);
      if (diff < 0.f) {
        far.lo = mid;
        far.hi = hi;
        hi = mid;
      } else {
        far.lo = lo;
        far.hi = mid;
        lo = mid;
      }
      if (far.bound <= worst) stack[sp++] = far;
    }
    for (int i = lo; i < hi; i++) {
      vec3 p = t->pts[i];
      float d = len2(q.x - p.x, q.y - p.y, q.z - p.z);
      if (d > worst) continue;
      int id = t->idx[i];
      if (m == k && d == worst && id > idx[k - 1]) continue;
      m = insert_sorted(idx, d2, m, k, d, id);
      if (m == k) worst = d2[k - 1];
    }
  }
  return m;
}
