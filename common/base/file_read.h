/* file_read.h: reading a whole untrusted input file into memory with a size bound, and writing
 * a buffer to a descriptor completely. */
#ifndef PC_FILE_READ_H
#define PC_FILE_READ_H

#include <stddef.h>

#include "error.h"

/* Reads `path` into a malloc'd buffer with a terminating NUL (not counted in *len). Fails with
 * PC_ELIMIT if the file is larger than `max` bytes. */
int pc_file_read(const char *path, size_t max, char **data, size_t *len, pc_err *e);

/* Writes all n bytes (retrying short writes and EINTR); 0, or -1 with errno set. */
int pc_write_all(int fd, const void *data, size_t n);

#endif
