/* file_read.h: reading a whole untrusted input file into memory with a size bound. */
#ifndef PC_FILE_READ_H
#define PC_FILE_READ_H

#include <stddef.h>

#include "error.h"

/* Reads `path` into a malloc'd buffer with a terminating NUL (not counted in *len). Fails with
 * PC_ELIMIT if the file is larger than `max` bytes. */
int pc_file_read(const char *path, size_t max, char **data, size_t *len, pc_err *e);

#endif
