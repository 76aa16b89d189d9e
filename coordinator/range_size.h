/* range_size.h: how many fresh iterations a range holds (guided self-scheduling). Pure
 * arithmetic on what the scheduler knows, kept apart from the loop's state so it can be
 * tested on its own. */
#ifndef PC_RANGE_SIZE_H
#define PC_RANGE_SIZE_H

#include <stdbool.h>
#include <stdint.h>

/* A range shorter than this much of its worker's time costs more in its upload (a whole
 * film, whatever the iteration count) than it saves in balance at the end of a job. */
#define PC_RANGE_MIN_SECONDS 0.5

typedef struct pc_range_size_in {
  double rate;            /* the asking worker's iterations/s on this job; <= 0: not measured */
  double others_rate;     /* summed rates of the other workers on this job or idle */
  bool bounded;           /* the job ends at an iteration count */
  uint64_t unassigned;    /* bounded: fresh iterations nobody holds yet */
  double outstanding;     /* bounded: iterations held by the others (or orphaned) not yet rendered */
  double range_seconds;   /* target length of a range in the asking worker's time */
  bool alone;             /* no other worker will share the job: nothing to keep back */
  double upload_seconds;  /* what the worker's last upload took to compress (0: unknown) */
  uint64_t interleaved;   /* bounded, > 0: the job's iteration count, shared out in ranges of at
                             most 1 / PC_RANGE_INTERLEAVE of it (see there) */
} pc_range_size_in;

/* An iteration-bounded job of a study group (the candidates of --method auto's pilot,
 * docs/auto.md) is measured against the other jobs of its group: its cost per iteration is
 * compared with theirs, so a change of the machine's load must fall on all of them alike.
 * The group's work requests alternate between its jobs, but a range sized by time alone holds
 * all a small job has left after its probe: one candidate's iterations in one stretch, then
 * the next's (at 128x128 a pilot's second batch was three stretches of 27 iterations, 0.3-0.4 s
 * each), and a slow moment of the machine fell on one candidate only (one pilot of outdoor
 * measured K = 1 at 0.995x BDPT's CPU time per iteration, against 1.28-1.34x in the two others).
 * In ranges of at most an eighth of the job the candidates take turns (the price: up to 8
 * uploads of a film per candidate instead of 1). */
#define PC_RANGE_INTERLEAVE 8

/* The size of the next fresh range, >= 1 and (bounded) <= unassigned; the caller checks
 * that something is left. An unmeasured worker gets a 1-iteration probe, which measures
 * it; alone on a bounded job (not interleaved), all of it instead: the probe's upload of a
 * whole film (first-touch memory and all: 0.1-0.25 s of a 512x512 BDPT render's 5 s) would
 * measure nothing the one worker's trusted claim does not, and the worker spaces the uploads
 * within the range by their cost. Otherwise a range is range_seconds of the worker's rate,
 * and near the end of a bounded job half of the worker's fair share of the work left
 * (unassigned + outstanding, in proportion to its rate, so all would finish together): the
 * ranges shrink as the job ends, and the half kept back evens out wrong rate estimates on
 * later requests; alone, the whole share (every range ends in an upload of a whole film).
 * Not under PC_RANGE_MIN_SECONDS of work, nor under what pays for the range's upload (its
 * cost over PC_WIRE_UPLOAD_SHARE, up to PC_WIRE_UPLOAD_MAX_INTERVAL), unless the whole share
 * is less. */
uint64_t pc_range_size(const pc_range_size_in *in);

#endif
