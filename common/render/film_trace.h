/* film_trace.h: what a film keeps of its single iterations beside their sums, so that the
 * distribution of the per-iteration error can be told (docs/variance.md "Heavy tails: the
 * error of each iteration"): for each of a job's first PC_TRACE_ITERATIONS iterations, its
 * beauty's mean luminance over each block of a grid of at most PC_TRACE_GRID x PC_TRACE_GRID
 * blocks. The iterations of a job are independent and identically distributed, so the first
 * ones are as good a sample as any; the bound keeps a film's trace at most ~1 MiB however long
 * the job runs. A trace merges by concatenation: an iteration traced twice is refused, as the
 * sums would count it twice. */
#ifndef PC_FILM_TRACE_H
#define PC_FILM_TRACE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"

#define PC_TRACE_GRID 8
#define PC_TRACE_ITERATIONS 4096u
#define PC_TRACE_MAX_BLOCKS (PC_TRACE_GRID * PC_TRACE_GRID)

typedef struct pc_film_trace {
  uint32_t n, cap;
  uint32_t *iteration; /* [n], in the order they were added */
  float *block;        /* [n * blocks]: record k's block means */
  uint64_t seen[PC_TRACE_ITERATIONS / 64];
} pc_film_trace;

/* The grid of a w x h image: min(w, 8) x min(h, 8) blocks; pixel (x, y) is in block
 * (y * gy / h) * gx + x * gx / w. */
int pc_trace_blocks(int w, int h);
static inline int pc_trace_block_of(int w, int h, int x, int y) {
  int gx = w < PC_TRACE_GRID ? w : PC_TRACE_GRID, gy = h < PC_TRACE_GRID ? h : PC_TRACE_GRID;
  return (int)((int64_t)y * gy / h) * gx + (int)((int64_t)x * gx / w);
}
/* The first column of block column bx (of gx) of a w-pixel row: the x with x * gx / w == bx
 * are [pc_trace_column_start(w, gx, bx), pc_trace_column_start(w, gx, bx + 1)). */
static inline int pc_trace_column_start(int w, int gx, int bx) { return (int)(((int64_t)bx * w + gx - 1) / gx); }
/* Pixels in each block (count[pc_trace_blocks(w, h)]). */
void pc_trace_block_pixels(int w, int h, uint32_t *count);

static inline bool pc_trace_has(const pc_film_trace *t, uint32_t it) {
  return it < PC_TRACE_ITERATIONS && (t->seen[it / 64] >> (it % 64) & 1u);
}
/* Room for n records of `blocks` values in all (ENOMEM, t unchanged, when there is none). */
int pc_trace_reserve(pc_film_trace *t, uint32_t n, int blocks, pc_err *e);
/* Adds iteration it's block means; the caller reserved room and checked it is new and below
 * PC_TRACE_ITERATIONS. */
void pc_trace_put(pc_film_trace *t, int blocks, uint32_t it, const float *block);
/* Appends src's records (refused, dst unchanged, when one is in dst already or no memory). */
int pc_trace_append(pc_film_trace *dst, const pc_film_trace *src, int blocks, pc_err *e);
void pc_trace_clear(pc_film_trace *t);
void pc_trace_free(pc_film_trace *t);

/* The distribution of the per-iteration error: iteration i's block means b_ik against the
 * film's own block means m_k over its N iterations,
 *   e_i = mean_k  (b_ik - m_k)^2 N / (N - 1)  /  (m_k^2 + PC_RELMSE_EPS),
 * the relMSE of one iteration's image at block resolution (N / (N - 1) undoes m_k's own share
 * of b_ik, so e_i's mean estimates it without bias in the numerator). A light-tailed estimator
 * has e_i near their mean; a heavy-tailed one mostly small ones and a few that carry the error
 * (a firefly landing), which `top1` shows. */
#define PC_TRACE_TAIL_MAX 13 /* tail points: e at P(E > e) = 2^-1 .. 2^-13 (4096 = 2^12 records) */
typedef struct pc_iteration_errors {
  uint32_t n;          /* traced iterations the figures are over */
  double mean, p50, p90, p99, max;
  uint32_t worst;      /* the iteration of the largest */
  double top1;         /* share of sum e_i carried by the largest ceil(n / 100) */
  int ntail;           /* tail[k]: the e exceeded by a fraction 2^-(k+1) of the iterations */
  double tail[PC_TRACE_TAIL_MAX];
} pc_iteration_errors;

#endif
