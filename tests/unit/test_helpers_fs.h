/* test_helpers_fs.h: temporary folders and files for the loader tests (header-only so each
 * test executable stays one .c file). */
#ifndef PC_TEST_HELPERS_FS_H
#define PC_TEST_HELPERS_FS_H

#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int th_rm_one(const char *p, const struct stat *st, int flag, struct FTW *f) {
  (void)st, (void)flag, (void)f;
  return remove(p);
}

static inline void th_rm_rf(const char *dir) { nftw(dir, th_rm_one, 16, FTW_DEPTH | FTW_PHYS); }

static inline int th_write(const char *path, const void *data, size_t len) {
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  size_t n = fwrite(data, 1, len, f);
  return (fclose(f) == 0 && n == len) ? 0 : -1;
}

static inline int th_write_str(const char *dir, const char *name, const char *text) {
  char p[4096];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  return th_write(p, text, strlen(text));
}

/* Reads a whole file (malloc'd, NUL-terminated). */
static inline char *th_read(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = malloc((size_t)n + 1);
  if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
    free(b);
    b = NULL;
  }
  fclose(f);
  if (b) b[n] = 0;
  if (len) *len = (size_t)n;
  return b;
}

static inline const char *th_source_dir(void) {
  const char *s = getenv("PCBPT_SOURCE_DIR");
  return s ? s : ".";
}

#endif
