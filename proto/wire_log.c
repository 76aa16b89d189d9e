/* wire_log.c: timestamped log lines on stderr. */
#include "wire_log.h"

#include <stdarg.h>
#include <stdio.h>
#include <time.h>

void pc_wire_log(const char *fmt, ...) {
  char line[1024];
  struct timespec ts;
  struct tm tm;
  clock_gettime(CLOCK_REALTIME, &ts);
  localtime_r(&ts.tv_sec, &tm);
  int n = (int)strftime(line, sizeof line, "%H:%M:%S", &tm);
  n += snprintf(line + n, sizeof line - (size_t)n, ".%03ld ", ts.tv_nsec / 1000000);
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(line + n, sizeof line - (size_t)n, fmt, ap);
  va_end(ap);
  /* one write per line keeps lines of concurrent processes from interleaving */
  fprintf(stderr, "%s\n", line);
}
