/* main.c: pcbpt-worker: parses the command line and runs one worker (worker.c) until a signal. */
#include <errno.h>
#include <sodium.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "auth.h"
#include "render_flags.h"
#include "wire_conn.h"
#include "wire_upload.h"
#include "worker.h"

static const char help[] =
    "usage: pcbpt-worker --connect HOST[:PORT] --token-file F [--threads N] [--name NAME] [--cache-dir DIR]\n"
    "                    [--max-film-mb N]\n"
    "Renders iteration ranges for a pcbpt coordinator (default port 7878). --threads 0 uses every core.\n"
    "--max-film-mb: the films it may make for one job (default: the machine's memory); a job that\n"
    "needs more fails its ranges on this worker with one line instead of being killed.\n";

int main(int argc, char **argv) {
  /* a peer that goes away mid-write must be an error return, not a fatal signal */
  if (signal(SIGPIPE, SIG_IGN) == SIG_ERR) perror("signal");
  const char *connect = NULL, *token = NULL, *cache = NULL, *name = NULL;
  long long threads = 0;
  double max_film_mb = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (strcmp(a, "--help") == 0) { fputs(help, stdout); return 0; }
    if (i + 1 >= argc) { fprintf(stderr, "pcbpt-worker: %s needs a value\n", a); return 2; }
    if (strcmp(a, "--connect") == 0) connect = argv[++i];
    else if (strcmp(a, "--token-file") == 0) token = argv[++i];
    else if (strcmp(a, "--cache-dir") == 0) cache = argv[++i];
    else if (strcmp(a, "--name") == 0) name = argv[++i];
    else if (strcmp(a, "--threads") == 0) {
      if (!pc_parse_i64(argv[++i], 0, 1024, &threads)) { fprintf(stderr, "pcbpt-worker: --threads: expected 0..1024\n"); return 2; }
    } else if (strcmp(a, "--max-film-mb") == 0) {
      if (!pc_parse_f64(argv[++i], 1, 1 << 30, &max_film_mb)) {
        fprintf(stderr, "pcbpt-worker: --max-film-mb: expected megabytes in [1, 2^30]\n");
        return 2;
      }
    } else { fprintf(stderr, "pcbpt-worker: unknown argument '%s'\n", a); return 2; }
  }
  if (!connect || !token) { fprintf(stderr, "pcbpt-worker: --connect and --token-file are required\n%s", help); return 2; }
  pc_err e = {0};
  char host[256], cache_dir[1024];
  int port;
  uint8_t key[PC_AUTH_KEY];
  if (pc_wire_parse_hostport(connect, host, sizeof host, &port, 7878) != 0) { fprintf(stderr, "pcbpt-worker: --connect: expected HOST[:PORT]\n"); return 2; }
  if (pc_auth_init(&e) != 0 || pc_auth_load_token(token, key, &e) != 0) { fprintf(stderr, "pcbpt-worker: %s\n", e.msg); return 1; }
  if (cache) snprintf(cache_dir, sizeof cache_dir, "%s", cache);
  else if (getenv("XDG_CACHE_HOME")) snprintf(cache_dir, sizeof cache_dir, "%s/pcbpt", getenv("XDG_CACHE_HOME"));
  else snprintf(cache_dir, sizeof cache_dir, "/tmp/pcbpt-cache-%ld", (long)getuid());
  pc_worker_opts o = {.host = host, .port = port, .key = key, .threads = (int)threads, .name = name,
                      .cache_dir = cache_dir, .handle_signals = true, .upload_share = PC_WIRE_UPLOAD_SHARE,
                      .max_film = (size_t)(max_film_mb * 1048576)};
  pc_worker *w = NULL;
  int rc = pc_worker_create(&o, &w, &e);
  sodium_memzero(key, sizeof key);
  if (rc) { fprintf(stderr, "pcbpt-worker: %s\n", e.msg); return 1; }
  rc = pc_worker_run(w, &e);
  pc_worker_destroy(w);
  if (rc) { fprintf(stderr, "pcbpt-worker: %s\n", e.msg); return 1; }
  return 0;
}
