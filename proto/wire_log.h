/* wire_log.h: one-line, timestamped log records of the farm processes (stderr), so refused
 * connections and uploads leave a reason an operator can grep for. */
#ifndef PC_WIRE_LOG_H
#define PC_WIRE_LOG_H

#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
void pc_wire_log(const char *fmt, ...);

#endif
