/* big_alloc.c: see big_alloc.h. */
#define _DEFAULT_SOURCE
#include "big_alloc.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

#define HUGE_PAGE ((size_t)2 << 20)

void *pc_big_alloc(size_t n) {
  if (n > SIZE_MAX - HUGE_PAGE - PC_BIG_ALLOC_SLACK) return NULL;
  n += PC_BIG_ALLOC_SLACK;
  if (n < HUGE_PAGE) return malloc(n);
  size_t whole = (n + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE;
  void *p = aligned_alloc(HUGE_PAGE, whole);
  if (!p) return NULL;
#ifdef MADV_HUGEPAGE
  if (madvise(p, whole, MADV_HUGEPAGE) != 0) {
    /* Advice only: where the kernel has no huge pages to give (THP off, or another kernel), the
     * buffer is the same in small pages, so a refusal changes nothing here. */
  }
#endif
  return p;
}

size_t pc_big_memory_limit(void) {
  long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  size_t limit = pages > 0 && page > 0 && (unsigned long)pages <= SIZE_MAX / (unsigned long)page
                     ? (size_t)pages * (size_t)page
                     : 0;
  FILE *f = fopen("/sys/fs/cgroup/memory.max", "r"); /* "max" when unlimited */
  unsigned long long cg;
  if (f && fscanf(f, "%llu", &cg) == 1 && cg > 0 && cg <= SIZE_MAX && (limit == 0 || cg < limit)) limit = (size_t)cg;
  if (f) fclose(f);
  return limit;
}

void pc_big_spare_keep(pc_big_spare *s, void *buf, size_t cap) {
  if (!buf) return;
  if (cap > s->cap) {
    free(s->p);
    s->p = buf;
    s->cap = cap;
  } else {
    free(buf);
  }
}

void *pc_big_spare_take(pc_big_spare *s, size_t *cap) {
  void *p = s->p;
  *cap = p ? s->cap : 0;
  s->p = NULL;
  s->cap = 0;
  return p;
}

void pc_big_spare_free(pc_big_spare *s) {
  free(s->p);
  s->p = NULL;
  s->cap = 0;
}
