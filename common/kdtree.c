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

static void build_range(pc_kdtree *t, int lo, int hi) {
  while (hi - lo > 1) {
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
    build_range(t, lo, mid);
    lo = mid + 1; /* the right half iteratively: recursion depth stays log2(n) */
  }
  if (hi - lo == 1) t->axis[lo] = 0;
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
    if (!p || !ix || !a) return pc_errf(e, PC_ENOMEM, "kd-tree: out of memory for %d points", n);
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
  *t = (pc_kdtree){0};
}

size_t pc_kdtree_bytes(const pc_kdtree *t) {
  return (size_t)t->cap * (sizeof(vec3) + sizeof(int) + 1);
}

/* A bounded max-heap of the best candidates so far, ordered by (d2, index): the root is the
 * worst kept candidate, the one a closer point replaces. */
typedef struct knn_heap {
  int k, n;
  int *idx;
  float *d2;
} knn_heap;

static inline int cand_worse(float da, int ia, float db, int ib) { return da > db || (da == db && ia > ib); }

static void heap_sift_down(knn_heap *h, int i) {
  for (;;) {
    int l = 2 * i + 1, r = l + 1, w = i;
    if (l < h->n && cand_worse(h->d2[l], h->idx[l], h->d2[w], h->idx[w])) w = l;
    if (r < h->n && cand_worse(h->d2[r], h->idx[r], h->d2[w], h->idx[w])) w = r;
    if (w == i) return;
    float td = h->d2[i];
    int ti = h->idx[i];
    h->d2[i] = h->d2[w];
    h->idx[i] = h->idx[w];
    h->d2[w] = td;
    h->idx[w] = ti;
    i = w;
  }
}

static void heap_offer(knn_heap *h, float d2, int idx) {
  if (h->n < h->k) {
    int i = h->n++;
    h->d2[i] = d2;
    h->idx[i] = idx;
    while (i > 0) {
      int p = (i - 1) / 2;
      if (!cand_worse(h->d2[i], h->idx[i], h->d2[p], h->idx[p])) break;
      float td = h->d2[i];
      int ti = h->idx[i];
      h->d2[i] = h->d2[p];
      h->idx[i] = h->idx[p];
      h->d2[p] = td;
      h->idx[p] = ti;
      i = p;
    }
  } else if (cand_worse(h->d2[0], h->idx[0], d2, idx)) {
    h->d2[0] = d2;
    h->idx[0] = idx;
    heap_sift_down(h, 0);
  }
}

static void search(const pc_kdtree *t, vec3 q, int lo, int hi, knn_heap *h) {
  while (lo < hi) {
    int mid = lo + (hi - lo) / 2;
    vec3 p = t->pts[mid];
    float dx = q.x - p.x, dy = q.y - p.y, dz = q.z - p.z;
    heap_offer(h, dx * dx + dy * dy + dz * dz, t->idx[mid]);
    if (hi - lo == 1) return;
    int ax = t->axis[mid];
    float diff = coord(q, ax) - coord(p, ax);
    int near_lo = diff < 0.f ? lo : mid + 1, near_hi = diff < 0.f ? mid : hi;
    int far_lo = diff < 0.f ? mid + 1 : lo, far_hi = diff < 0.f ? hi : mid;
    search(t, q, near_lo, near_hi, h);
    /* Every point across the plane is at least |diff| away (float rounding is monotone, so
     * this holds for the computed distances too). Equal distance must still be visited: a
     * point there with a smaller index wins the tie. */
    if (h->n == h->k && diff * diff > h->d2[0]) return;
    lo = far_lo;
    hi = far_hi;
  }
}

int pc_kdtree_knn(const pc_kdtree *t, vec3 q, int k, int *idx, float *d2) {
  if (k < 1 || k > PC_KDTREE_MAX_K) return 0;
  knn_heap h = {k < t->n ? k : t->n, 0, idx, d2};
  if (h.k == 0) return 0;
  search(t, q, 0, t->n, &h);
  /* Heap sort in place: repeatedly move the worst to the end. */
  int n = h.n;
  while (h.n > 1) {
    int last = --h.n;
    float td = h.d2[0];
    int ti = h.idx[0];
    h.d2[0] = h.d2[last];
    h.idx[0] = h.idx[last];
    h.d2[last] = td;
    h.idx[last] = ti;
    heap_sift_down(&h, 0);
  }
  return n;
}
