/* error.c: message texts for PC_E* codes and the pc_err formatter. */
#include "error.h"

#include <stdarg.h>
#include <stdio.h>

const char *pc_strerror(int code) {
  switch (code) {
  case PC_OK: return "success";
  case PC_EINVAL: return "invalid value";
  case PC_EIO: return "input/output error";
  case PC_ENOMEM: return "out of memory";
  case PC_EPARSE: return "parse error";
  case PC_EUNSUPPORTED: return "unsupported feature";
  case PC_EEMBREE: return "Embree error";
  case PC_ELIMIT: return "size limit exceeded";
  case PC_EEXR: return "OpenEXR error";
  case PC_EIMAGE: return "image codec error";
  case PC_ECANCELED: return "cancelled";
  case PC_ENUMERIC: return "non-finite number";
  default: return "unknown error";
  }
}

int pc_errf(pc_err *e, int code, const char *fmt, ...) {
  if (e) {
    e->code = code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
  }
  return code;
}
