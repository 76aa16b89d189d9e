/* study_method.c: the names of a study's methods (study.h): an estimator, or pcbpt with a K of
 * its own, so K values can be compared in one study on the same workers. */
#include <stdio.h>
#include <string.h>

#include "parse.h"
#include "study.h"

int pc_study_method_parse(const char *s, pc_study_method *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  if (strlen(s) >= sizeof out->name) return pc_errf(e, PC_EINVAL, "method '%.40s': name too long", s);
  snprintf(out->name, sizeof out->name, "%s", s);
  if (strncmp(s, "pcbpt-k", 7) == 0) {
    long long k;
    if (!pc_parse_i64(s + 7, 1, 64, &k))
      return pc_errf(e, PC_EINVAL, "method '%s': K must be a whole number from 1 to 64 (e.g. pcbpt-k2)", s);
    out->method = PC_METHOD_PCBPT;
    out->pcbpt_k = (int)k;
    return PC_OK;
  }
  if (pc_method_parse(s, &out->method) != PC_OK)
    return pc_errf(e, PC_EINVAL, "unknown method '%s' (pt, lt, bdpt, cbdpt, pcbpt, pcbpt-kN, auto)", s);
  return PC_OK;
}
