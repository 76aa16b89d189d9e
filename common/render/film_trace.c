/* film_trace.c: a film's per-iteration trace (block means of each of its first iterations) and
 * the distribution of the per-iteration error it gives with the film's own image. */
#include "film_trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "film.h"

int pc_trace_blocks(int w, int h) {
  return (w < PC_TRACE_GRID ? w : PC_TRACE_GRID) * (h < PC_TRACE_GRID ? h : PC_TRACE_GRID);
}

void pc_trace_block_pixels(int w, int h, uint32_t *count) {
  memset(count, 0, (size_t)pc_trace_blocks(w, h) * sizeof *count);
  int gx = w < PC_TRACE_GRID ? w : PC_TRACE_GRID;
  for (int y = 0; y < h; y++) {
    int row = pc_trace_block_of(w, h, 0, y);
    for (int bx = 0; bx < gx; bx++)
      count[row + bx] += (uint32_t)(pc_trace_column_start(w, gx, bx + 1) - pc_trace_column_start(w, gx, bx));
  }
}

int pc_trace_reserve(pc_film_trace *t, uint32_t n, int blocks, pc_err *e) {
  if (n <= t->cap) return PC_OK;
  if (n > PC_TRACE_ITERATIONS) return pc_errf(e, PC_ELIMIT, "film trace: %u iterations, at most %u", n, PC_TRACE_ITERATIONS);
  uint32_t cap = t->cap ? t->cap : 16;
  while (cap < n) cap *= 2;
  if (cap > PC_TRACE_ITERATIONS) cap = PC_TRACE_ITERATIONS;
  uint32_t *it = realloc(t->iteration, cap * sizeof *it);
  if (!it) return pc_errf(e, PC_ENOMEM, "film trace: out of memory for %u iterations", cap);
  t->iteration = it;
  float *b = realloc(t->block, (size_t)cap * (size_t)blocks * sizeof *b);
  if (!b) return pc_errf(e, PC_ENOMEM, "film trace: out of memory for %u iterations", cap);
  t->block = b;
  t->cap = cap;
  return PC_OK;
}

void pc_trace_put(pc_film_trace *t, int blocks, uint32_t it, const float *block) {
  t->iteration[t->n] = it;
  memcpy(t->block + (size_t)t->n * (size_t)blocks, block, (size_t)blocks * sizeof *block);
  t->seen[it / 64] |= (uint64_t)1 << (it % 64);
  t->n++;
}

int pc_trace_append(pc_film_trace *dst, const pc_film_trace *src, int blocks, pc_err *e) {
  for (uint32_t k = 0; k < src->n; k++)
    if (pc_trace_has(dst, src->iteration[k]))
      return pc_errf(e, PC_EINVAL, "film trace: iteration %u is in both films", src->iteration[k]);
  int rc = pc_trace_reserve(dst, dst->n + src->n, blocks, e);
  for (uint32_t k = 0; k < src->n && rc == PC_OK; k++)
    pc_trace_put(dst, blocks, src->iteration[k], src->block + (size_t)k * (size_t)blocks);
  return rc;
}

void pc_trace_clear(pc_film_trace *t) {
  t->n = 0;
  memset(t->seen, 0, sizeof t->seen);
}

void pc_trace_free(pc_film_trace *t) {
  free(t->iteration);
  free(t->block);
  memset(t, 0, sizeof *t);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

bool pc_film_iteration_errors(const pc_film *f, pc_iteration_errors *out) {
  memset(out, 0, sizeof *out);
  const pc_film_trace *t = &f->trace;
  uint64_t nit = f->layers[PC_LAYER_PT].count;
  if (t->n < 2 || nit < 2 || f->nlayers < PC_LAYER_STD_COUNT) return false;
  int w = f->w, h = f->h, nb = pc_trace_blocks(w, h);
  double m[PC_TRACE_MAX_BLOCKS] = {0}, scale[PC_LAYER_STD_COUNT];
  uint32_t count[PC_TRACE_MAX_BLOCKS];
  pc_trace_block_pixels(w, h, count);
  for (int l = 0; l < PC_LAYER_STD_COUNT; l++) scale[l] = pc_film_layer_scale(f, &f->layers[l]);
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      size_t j = 3 * ((size_t)y * (size_t)w + (size_t)x);
      double b[3] = {0, 0, 0};
      for (int l = 0; l < PC_LAYER_STD_COUNT; l++)
        if (scale[l] != 0.0)
          for (int c = 0; c < 3; c++) b[c] += f->layers[l].sum[j + c] * scale[l];
      m[pc_trace_block_of(w, h, x, y)] += pc_luminance709(b[0], b[1], b[2]);
    }
  for (int k = 0; k < nb; k++) m[k] /= count[k];
  double *e = malloc(t->n * sizeof *e);
  if (!e) return false;
  double corr = (double)nit / (double)(nit - 1), sum = 0.0;
  out->max = -1.0;
  for (uint32_t i = 0; i < t->n; i++) {
    const float *b = t->block + (size_t)i * (size_t)nb;
    double s = 0.0;
    for (int k = 0; k < nb; k++) {
      double d = (double)b[k] - m[k];
      s += d * d * corr / (m[k] * m[k] + PC_RELMSE_EPS);
    }
    e[i] = s / nb;
    sum += e[i];
    if (e[i] > out->max) {
      out->max = e[i];
      out->worst = t->iteration[i];
    }
  }
  qsort(e, t->n, sizeof *e, cmp_double);
  uint32_t n = t->n, top = (n + 99) / 100;
  double topsum = 0.0;
  for (uint32_t i = n - top; i < n; i++) topsum += e[i];
  out->n = n;
  out->mean = sum / n;
  /* nearest rank */
#define RANK(q) e[(size_t)ceil((q) * n) > 0 ? (size_t)ceil((q) * n) - 1 : 0]
  out->p50 = RANK(0.5);
  out->p90 = RANK(0.9);
  out->p99 = RANK(0.99);
  for (int k = 0; k < PC_TRACE_TAIL_MAX && (1u << (k + 1)) <= n; k++) out->tail[out->ntail++] = RANK(1.0 - ldexp(1.0, -(k + 1)));
#undef RANK
  out->top1 = sum > 0.0 ? topsum / sum : 0.0;
  free(e);
  return true;
}
