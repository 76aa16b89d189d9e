/* parse.h: strict parsing of numbers from untrusted strings (flags, addresses). */
#ifndef PC_PARSE_H
#define PC_PARSE_H

#include <stdbool.h>
#include <stdint.h>

/* Strict number parsing: the whole string, in range; false otherwise. */
bool pc_parse_i64(const char *s, long long lo, long long hi, long long *out);
bool pc_parse_u64(const char *s, uint64_t lo, uint64_t hi, uint64_t *out);
bool pc_parse_f64(const char *s, double lo, double hi, double *out);

#endif
