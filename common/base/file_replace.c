/* file_replace.c: writing a file under a temporary name and renaming it over the target. */
#include "file_replace.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

int pc_file_tmp_path(const char *path, char *buf, size_t size, pc_err *e) {
  int n = snprintf(buf, size, "%s.tmp.%ld", path, (long)getpid());
  if (n < 0 || (size_t)n >= size) return pc_errf(e, PC_EINVAL, "%s: path too long", path);
  return PC_OK;
}

int pc_file_commit(const char *tmp, const char *path, pc_err *e) {
  if (rename(tmp, path) != 0) {
    int err = errno;
    unlink(tmp);
    return pc_errf(e, PC_EIO, "%s: cannot rename %s into place: %s", path, tmp, strerror(err));
  }
  return PC_OK;
}
