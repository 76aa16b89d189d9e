/* fuzz_dir.h: the folder a file-reading fuzz target writes its inputs into: made once under
 * TMPDIR (mkdtemp) and emptied and removed at exit by `cleanup` (libFuzzer exits through exit()
 * at -max_total_time), so runs leave nothing behind. Aborts when it cannot be made. */
#ifndef PC_FUZZ_DIR_H
#define PC_FUZZ_DIR_H

#include <stdio.h>
#include <stdlib.h>

static void fuzz_make_dir(const char *target, char *dir, size_t n, void (*cleanup)(void)) {
  const char *tmp = getenv("TMPDIR");
  int k = snprintf(dir, n, "%s/pcbpt-%s-XXXXXX", tmp && *tmp ? tmp : "/tmp", target);
  if (k < 0 || (size_t)k >= n || !mkdtemp(dir)) {
    fprintf(stderr, "%s: cannot make a folder for the inputs under %s\n", target, tmp && *tmp ? tmp : "/tmp");
    abort();
  }
  if (atexit(cleanup) != 0) {
    cleanup();
    fprintf(stderr, "%s: cannot register the folder's removal\n", target);
    abort();
  }
}

#endif
