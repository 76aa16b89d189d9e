/* file_replace.h: replacing a file atomically: writers fill "<path>.tmp.<pid>" and rename()
 * it over path, so a reader of path sees either the old file or the complete new one. */
#ifndef PC_FILE_REPLACE_H
#define PC_FILE_REPLACE_H

#include <stddef.h>

#include "error.h"

/* "<path>.tmp.<pid>" into buf. */
int pc_file_tmp_path(const char *path, char *buf, size_t size, pc_err *e);
/* rename(tmp, path), removing tmp when that fails. */
int pc_file_commit(const char *tmp, const char *path, pc_err *e);

#endif
