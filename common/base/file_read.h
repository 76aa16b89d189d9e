/* file_read.h: reading a whole untrusted input file into memory with a size bound, and writing
 * a buffer to a descriptor completely. */
#ifndef PC_FILE_READ_H
#define PC_FILE_READ_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"

/* What a repository cloned without Git LFS holds in place of each file it keeps in LFS: a short
 * text that begins so. No scene, mesh or image file begins that way. */
bool pc_is_lfs_pointer(const void *data, size_t len);
#define PC_LFS_POINTER_ERROR "a Git LFS pointer, not the file itself (its repository keeps the file in Git LFS: 'git lfs pull' there fetches it)"

/* Reads `path` into a malloc'd buffer with a terminating NUL (not counted in *len). Fails with
 * PC_ELIMIT if the file is larger than `max` bytes, and with PC_EINVAL if it is a Git LFS
 * pointer. */
int pc_file_read(const char *path, size_t max, char **data, size_t *len, pc_err *e);

/* Writes all n bytes (retrying short writes and EINTR); 0, or -1 with errno set. */
int pc_write_all(int fd, const void *data, size_t n);

#endif
