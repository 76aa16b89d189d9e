/* client.h: a blocking, authenticated connection from a client verb to a coordinator. */
#ifndef PC_CLIENT_H
#define PC_CLIENT_H

#include "error.h"
#include "render_flags.h"
#include "wire_frame.h"

typedef struct pc_client {
  int fd;
  pc_wire_decoder dec;  /* holds the receiving direction's seal */
  pc_seal_dir seal_tx;
} pc_client;

/* Connects to "HOST[:PORT]", says hello as a client and completes the challenge/response,
 * checking the coordinator's proof too; every later frame is sealed (wire_seal.h). */
int pc_client_connect(const char *hostport, const char *token_file, pc_client *cl, pc_err *e);
/* The same with another role (the farm tests speak as a worker). */
int pc_client_connect_as(const char *hostport, const char *token_file, Pcbpt__Role role, pc_client *cl, pc_err *e);
int pc_client_send(pc_client *cl, const Pcbpt__Envelope *env, pc_err *e);
/* Waits up to timeout_s for the next frame; an Error frame becomes PC_EINVAL with its reason. */
int pc_client_recv(pc_client *cl, double timeout_s, Pcbpt__Envelope **out, pc_err *e);
void pc_client_close(pc_client *cl);
/* Sends a scene bundle (pc_bundle_create) in bounded chunks. */
int pc_client_send_bundle(pc_client *cl, const uint8_t *blob, size_t n, const uint8_t *hash, pc_err *e);
/* Downloads a job's image to `out` (through a temporary file renamed into place); *bytes is
 * its size. */
/* Sends a Submit of an uploaded bundle (the caller fills name, bundle hash, settings, halts and
 * priority) and waits for its reply: *job is the new job's id. */
int pc_client_submit(pc_client *cl, const Pcbpt__Submit *sub, uint64_t *job, pc_err *e);
/* A render job of an uploaded bundle: req's settings, --spp, --time and --halt-noise, with
 * --method auto's report (may be "") and its pilot's films to mix in (prior_group 0: none;
 * coordinator/job_prior.c). */
int pc_client_submit_request(pc_client *cl, const char *name, const uint8_t *hash, const pc_render_request *req,
                             const char *auto_report, uint64_t prior_group, double prior_amount, int priority,
                             uint64_t *job, pc_err *e);
/* Asks for the status of `job` (0: every job); *out is a STATUS_REPLY envelope the caller frees
 * with pcbpt__envelope__free_unpacked. */
int pc_client_status(pc_client *cl, uint64_t job, Pcbpt__Envelope **out, pc_err *e);
int pc_client_fetch(pc_client *cl, uint64_t job, const char *out, uint64_t *bytes, pc_err *e);
/* The same for a study job's snapshot k >= 1 (0: the image). */
int pc_client_fetch_snapshot(pc_client *cl, uint64_t job, uint32_t snapshot, const char *out, uint64_t *bytes, pc_err *e);

#endif
