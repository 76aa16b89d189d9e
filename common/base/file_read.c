/* file_read.c: whole-file reads with a size bound (scene and mesh parsers) and complete writes. */
#include "file_read.h"

#include "big_alloc.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define LFS_PREFIX "version https://git-lfs.github.com/spec/"

bool pc_is_lfs_pointer(const void *data, size_t len) {
  return len >= sizeof LFS_PREFIX - 1 && memcmp(data, LFS_PREFIX, sizeof LFS_PREFIX - 1) == 0;
}

int pc_file_read(const char *path, size_t max, char **data, size_t *len, pc_err *e) {
  *data = NULL;
  *len = 0;
  /* O_NONBLOCK so a FIFO planted where a mesh should be cannot hang the open; non-regular
   * files are refused below. */
  int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return pc_errf(e, PC_EIO, "%s: cannot open: %s", path, strerror(errno));
  FILE *f = fdopen(fd, "rb");
  if (!f) {
    int err = errno;
    close(fd);
    return pc_errf(e, PC_EIO, "%s: cannot open: %s", path, strerror(err));
  }
  struct stat st;
  if (fstat(fileno(f), &st) != 0) {
    int err = errno;
    fclose(f);
    return pc_errf(e, PC_EIO, "%s: cannot stat: %s", path, strerror(err));
  }
  if (!S_ISREG(st.st_mode)) {
    fclose(f);
    return pc_errf(e, PC_EIO, "%s: not a regular file", path);
  }
  if (st.st_size < 0 || (unsigned long long)st.st_size > max) {
    fclose(f);
    return pc_errf(e, PC_ELIMIT, "%s: file is larger than the limit of %zu bytes", path, max);
  }
  size_t n = (size_t)st.st_size;
  char *buf = pc_big_alloc(n + 1);
  if (!buf) {
    fclose(f);
    return pc_errf(e, PC_ENOMEM, "%s: out of memory reading %zu bytes", path, n);
  }
  size_t got = fread(buf, 1, n, f);
  int rerr = ferror(f);
  fclose(f);
  if (got != n || rerr) {
    free(buf);
    return pc_errf(e, PC_EIO, "%s: read error", path);
  }
  buf[n] = 0;
  if (pc_is_lfs_pointer(buf, n)) {
    free(buf);
    return pc_errf(e, PC_EINVAL, "%s: " PC_LFS_POINTER_ERROR, path);
  }
  *data = buf;
  *len = n;
  return 0;
}

int pc_write_all(int fd, const void *data, size_t n) {
  const unsigned char *d = data;
  while (n) {
    ssize_t w = write(fd, d, n);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0) return -1;
    d += w;
    n -= (size_t)w;
  }
  return 0;
}
