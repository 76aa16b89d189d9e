/* serve.h: running a coordinator on a loop (the `serve` verb and the embedded farm). */
#ifndef PC_SERVE_H
#define PC_SERVE_H

#include "coord.h"

/* Opens the store in data_dir, resumes unfinished jobs and listens on host:port (0 = any). */
int pc_coord_start(pc_coord *c, uv_loop_t *loop, const char *host, int port, const char *data_dir,
                   const uint8_t key[PC_AUTH_KEY], pc_err *e);
/* Thread-safe: closes the listener, the timers and every connection, so the loop's uv_run
 * returns once background work has drained; then pc_coord_free. */
void pc_coord_stop(pc_coord *c);
void pc_coord_free(pc_coord *c);

#endif
