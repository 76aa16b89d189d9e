/* study_farm.h: the renders of an equal-time study as farm jobs (docs/farm-study.md). A study
 * farm is a coordinator reached as a client: a remote one (--host) or the embedded one-machine
 * farm `render` uses, so one code path serves both. A group is one run of the study: every
 * method submitted at once as jobs of one study group, which the coordinator interleaves in
 * short slices on the same workers, each job halting at the same budget of worker-seconds and
 * keeping its merged film at log-spaced worker-seconds; the client fetches those snapshots
 * and the final images and measures them. */
#ifndef PC_STUDY_FARM_H
#define PC_STUDY_FARM_H

#include <stdbool.h>
#include <stdint.h>

#include "embedded.h"
#include "render_flags.h"
#include "study.h"

typedef struct pc_study_farm {
  char hostport[300];
  const char *token;
  bool embedded;
  pc_embedded emb;
  int threads;        /* embedded: the worker's render threads */
  bool worker_started;
  int log_fd;         /* progress lines (the embedded farm sends stderr to its log) */
} pc_study_farm;

/* host NULL: starts the embedded farm (one worker with `threads` threads). */
int pc_study_farm_open(pc_study_farm *f, const char *host, const char *token_file, int threads, pc_err *e);
void pc_study_farm_close(pc_study_farm *f);
/* Workers connected now (the embedded farm: 1). */
int pc_study_farm_workers(pc_study_farm *f, int *n, pc_err *e);

typedef struct pc_study_group {
  const char *scene_path;                 /* the job name */
  const uint8_t *blob, *hash;             /* the scene's bundle */
  size_t blob_n;
  const pc_render_request *req;           /* settings shared by every method */
  const pc_study_method *methods;
  int nmethods;
  uint64_t seed;
  double seconds;                         /* per method, on a farm of `workers` */
  int workers;                            /* farm size: the budget is seconds * workers
                                             worker-seconds, at most this many at once */
  int snapshots;                          /* kept per job before its final image (0: none) */
  const pc_study_ref *ref;                /* NULL: measure nothing (a reference render) */
  const char *keep_dir;                   /* final images kept as <keep_dir>/<method>.exr+.png */
  const char *keep_path;                  /* one method: its final image kept here */
  const char *work_dir;                   /* snapshots are fetched through a file here (NULL:
                                             keep_dir, else the current directory) */
  const char *label;                      /* progress lines: "ajar-door run 2/3, 2 workers" */
} pc_study_group;

/* Runs one group; runs[m] (freed with pc_study_run_free) gets method m's curve: each snapshot
 * then the final image, measured against g->ref. */
int pc_study_farm_group(pc_study_farm *f, const pc_study_group *g, pc_study_run *runs, pc_err *e);

#endif
