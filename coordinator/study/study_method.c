/* study_method.c: the names of a study's methods (study.h): an estimator, or pcbpt with a K and
 * a connection rate of its own, so they can be compared in one study on the same workers. */
#include <stdio.h>
#include <string.h>

#include "parse.h"
#include "study.h"

int pc_study_method_parse(const char *s, pc_study_method *out, pc_err *e) {
  memset(out, 0, sizeof *out);
  if (strlen(s) >= sizeof out->name) return pc_errf(e, PC_EINVAL, "method '%.40s': name too long", s);
  snprintf(out->name, sizeof out->name, "%s", s);
  if (strncmp(s, "pcbpt-k", 7) == 0) {
    const char *rate = strstr(s + 7, "-r");
    char digits[8] = "";
    size_t n = rate ? (size_t)(rate - (s + 7)) : strlen(s + 7);
    if (n < sizeof digits) memcpy(digits, s + 7, n); /* longer: stays empty, refused below */
    long long k;
    if (!pc_parse_i64(digits, 1, 64, &k))
      return pc_errf(e, PC_EINVAL, "method '%s': K must be a whole number from 1 to 64 (e.g. pcbpt-k2)", s);
    double r = 0.0;
    if (rate && (!pc_parse_f64(rate + 2, 0.0, 1.0, &r) || !((float)r > 0.f)))
      return pc_errf(e, PC_EINVAL, "method '%s': the rate must be in (0, 1] (e.g. pcbpt-k1-r0.25)", s);
    out->method = PC_METHOD_PCBPT;
    out->pcbpt_k = (int)k;
    out->pcbpt_rate = (float)r;
    return PC_OK;
  }
  if (pc_method_parse(s, &out->method) != PC_OK)
    return pc_errf(e, PC_EINVAL, "unknown method '%s' (pt, lt, bdpt, cbdpt, pcbpt, pcbpt-kN[-rR], auto)", s);
  return PC_OK;
}

void pc_study_method_apply(const pc_study_method *m, pc_render_settings *set) {
  set->method = m->method;
  if (m->pcbpt_k > 0) set->pcbpt_k = m->pcbpt_k;
  if (m->pcbpt_rate > 0.f) set->pcbpt_rate = m->pcbpt_rate;
}
