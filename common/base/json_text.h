/* json_text.h: text written into JSON output. Strings come from scene files, image headers and
 * the network, so every one is escaped, never printed raw. */
#ifndef PC_JSON_TEXT_H
#define PC_JSON_TEXT_H

#include <stdio.h>

/* s as a JSON string, quotes included: '"' and '\' escaped, control bytes as \u00XX. */
void pc_json_string(FILE *f, const char *s);
/* v with 9 significant digits, or null where it is not finite (JSON has no NaN or Inf). */
void pc_json_number(FILE *f, double v);

#endif
