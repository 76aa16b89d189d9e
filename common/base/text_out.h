/* text_out.h: text from untrusted places (scene files, image headers, the network) written out:
 * into JSON escaped, never raw, and for a terminal without its control bytes. */
#ifndef PC_TEXT_OUT_H
#define PC_TEXT_OUT_H

#include <stdio.h>

/* s as a JSON string, quotes included: '"' and '\' escaped, control bytes as \u00XX. */
void pc_json_string(FILE *f, const char *s);
/* v with 9 significant digits, or null where it is not finite (JSON has no NaN or Inf). */
void pc_json_number(FILE *f, double v);
/* At most size - 1 bytes of s into out, each control byte (a terminal's escape sequences among
 * them) as '?'; returns out. */
const char *pc_text_printable(const char *s, char *out, size_t size);

#endif
