/* error.h: the error convention of the whole project. Every fallible function returns 0 or a
 * negative PC_E* code and, when given a pc_err, fills a one-line human message naming what is
 * wrong and where ("scene.xml:12: unknown BSDF plugin 'foo'"). Library code never exits. */
#ifndef PC_ERROR_H
#define PC_ERROR_H

enum {
  PC_OK = 0,
  PC_EINVAL = -1,       /* a value out of range or malformed */
  PC_EIO = -2,          /* file or OS error */
  PC_ENOMEM = -3,       /* allocation failed */
  PC_EPARSE = -4,       /* syntax error in an input file */
  PC_EUNSUPPORTED = -5, /* valid input using a feature pcbpt does not model */
  PC_EEMBREE = -6,      /* Embree reported an error */
  PC_ELIMIT = -7,       /* an input exceeds a hard size limit */
  PC_EEXR = -8,         /* OpenEXR reported an error */
  PC_EIMAGE = -9,       /* PNG/JPEG codec error */
  PC_ECANCELED = -10,   /* the operation was cancelled */
  PC_ENUMERIC = -11,    /* NaN or Inf where a finite value is required */
};

typedef struct pc_err {
  int code;
  char msg[512];
} pc_err;

const char *pc_strerror(int code);

/* Sets e (if non-NULL) to code and a printf-formatted message; returns code, so callers can
 * write `return pc_errf(e, PC_EINVAL, "%s:%d: ...", file, line);`. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
int pc_errf(pc_err *e, int code, const char *fmt, ...);

#endif
