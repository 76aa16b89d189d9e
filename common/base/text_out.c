/* text_out.c: see text_out.h. */
#include "text_out.h"

#include <math.h>

void pc_json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
    else if (*p < 0x20) fprintf(f, "\\u%04x", *p);
    else fputc(*p, f);
  }
  fputc('"', f);
}

void pc_json_number(FILE *f, double v) {
  if (isfinite(v)) fprintf(f, "%.9g", v);
  else fputs("null", f);
}

const char *pc_text_printable(const char *s, char *out, size_t size) {
  size_t k = 0;
  for (const unsigned char *p = (const unsigned char *)s; *p && k + 1 < size; p++)
    out[k++] = *p < 0x20 || *p == 0x7f ? '?' : (char)*p;
  if (size) out[k] = 0;
  return out;
}
