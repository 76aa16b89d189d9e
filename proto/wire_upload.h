/* wire_upload.h: how often a worker uploads, agreed by both ends of the wire: the worker
 * spaces its uploads by these, the coordinator sizes ranges (each ends in an upload) and
 * progress deadlines by them. No dependencies, so the coordinator's pure range arithmetic
 * (range_size.c) can use them without the protocol. */
#ifndef PC_WIRE_UPLOAD_H
#define PC_WIRE_UPLOAD_H

/* The shortest spacing of a rendering worker's uploads (seconds; a range shorter than this
 * uploads at its end). Uploads further apart are covered by heartbeats showing progress. */
#define PC_WIRE_UPLOAD_INTERVAL 2.0
/* The longest: a lost worker loses at most this much of its work. */
#define PC_WIRE_UPLOAD_MAX_INTERVAL 30.0
/* An upload is the whole film, compressed while the worker's render pool waits: a farm
 * worker's uploads within a range, and the ranges that end in one, are spaced so that this
 * takes at most about this share of its time. Every 3 s (one iteration per range), a
 * 1280x720 film (132 MB, ~0.4 s to compress) made a one-thread worker's wall time 1.20x its
 * render time. Small films compress in milliseconds and keep PC_WIRE_UPLOAD_INTERVAL. */
#define PC_WIRE_UPLOAD_SHARE 0.05

/* What compressing an upload costs per byte of film before the worker has measured one: a
 * first upload pays for its buffers' first touch too (a 512x512 BDPT film of 37.5 MB took
 * 116 ms the first time on 2 threads, 50 ms the second; a 1280x720 one of 132 MB, ~0.4 s). */
#define PC_WIRE_ZIP_SECONDS_PER_BYTE 3e-9

/* The seconds of work over which an upload compressed in zip_seconds takes `share` of the
 * time, up to PC_WIRE_UPLOAD_MAX_INTERVAL (0 when either is unknown): how far apart the worker
 * spaces its uploads, and how long the coordinator makes the ranges that end in one. */
static inline double pc_wire_upload_spacing(double zip_seconds, double share) {
  double t = share > 0 && zip_seconds > 0 ? zip_seconds / share : 0;
  return t > PC_WIRE_UPLOAD_MAX_INTERVAL ? PC_WIRE_UPLOAD_MAX_INTERVAL : t;
}

#endif
