/* job_prior.c: --method auto's pilot counted in the job's image (docs/auto.md). The pilot's
 * candidates that are rendered whatever the data says (BDPT, PCBPT K = 1 and K = 2) are jobs
 * of one pilot group: when one is done its film is folded into the group's, mixed by
 * iterations. The job the pilot chose names the group as its prior: at activation it takes
 * the group's film (and, with a lasting store, saves a copy for a restart), and every image it
 * shows is the mix of that film and its own. The pilot's weight is a / (a + x): a is its
 * amount in the unit of the job's budget (iterations, worker-seconds or seconds, fixed by the
 * client at submission: the counted candidates' sum over their number, since they share their
 * paths, pc_pilot_counted_share) and x the job's progress in that unit, at most the budget. So the
 * final image's weight is fixed before the pilot's values are seen: whichever method they
 * chose, the image is a fixed mix of two unbiased estimates, hence unbiased. (A weight from
 * the job's iterations or worker-seconds at its end would not be: a time budget buys as many
 * iterations as the chosen method's cost allows, and an iteration budget as many seconds.) */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "coord.h"
#include "file_read.h"
#include "wire_film.h"
#include "wire_log.h"

/* A saved prior: this line, then the film as a checkpoint stores it. */
#define PRIOR_MAGIC "pcbpt-prior-1\n"
#define PRIOR_MAGIC_LEN 14
#define PRIOR_LEAF "prior"

static uint64_t iterations(const pc_film *f) { return f->layers[PC_LAYER_PT].count; }

static void drop_group(pc_coord *c, pc_pilot_films *g) {
  for (pc_pilot_films **p = &c->pilot_films; *p; p = &(*p)->next)
    if (*p == g) {
      *p = g->next;
      break;
    }
  pc_film_free(&g->film);
  free(g);
}

static pc_pilot_films *find_group(const pc_coord *c, uint64_t group) {
  pc_pilot_films *g = c->pilot_films;
  while (g && g->group != group) g = g->next;
  return g;
}

void pc_prior_keep(pc_coord *c, pc_job *j) {
  if (!j->pilot_group || !j->film_ready || j->state != PC_JOB_DONE || iterations(&j->film) == 0) return;
  pc_pilot_films *g = find_group(c, j->pilot_group);
  if (!g) {
    int n = 0;
    for (pc_pilot_films *k = c->pilot_films; k; k = k->next) n++;
    if (n >= PC_COORD_MAX_PILOT_FILMS) { /* the oldest pilot's job never came */
      pc_pilot_films *old = c->pilot_films;
      for (pc_pilot_films *k = c->pilot_films; k; k = k->next)
        if (k->since < old->since) old = k;
      pc_wire_log("pilot group %016llx: no job took its films; dropped", (unsigned long long)old->group);
      drop_group(c, old);
    }
    if (!(g = calloc(1, sizeof *g))) {
      pc_wire_log("job %llu: out of memory to keep a pilot's film", (unsigned long long)j->id);
      return;
    }
    g->group = j->pilot_group;
    g->film = j->film; /* taken, not copied */
    g->worker_seconds = j->film_seconds;
    g->since = pc_coord_now();
    g->next = c->pilot_films;
    c->pilot_films = g;
    memset(&j->film, 0, sizeof j->film);
    j->film_ready = false;
    return;
  }
  pc_film mix;
  pc_err e = {0};
  double a = (double)iterations(&g->film), b = (double)iterations(&j->film);
  pc_film_part parts[] = {{&g->film, a / (a + b)}, {&j->film, b / (a + b)}};
  int rc = pc_film_init(&mix, j->film.w, j->film.h, j->set.strategy_layers, &e);
  if (!rc && (rc = pc_film_mix(&mix, parts, 2, &e)) != 0) pc_film_free(&mix);
  if (rc) {
    pc_wire_log("job %llu: its film stays out of pilot group %016llx: %s", (unsigned long long)j->id,
                (unsigned long long)j->pilot_group, e.msg);
    return;
  }
  pc_film_free(&g->film);
  g->film = mix;
  g->worker_seconds += j->film_seconds;
}

/* The prior to dir/prior through a synced temporary and a rename. */
static int save(const pc_coord *c, const pc_job *j, pc_err *e) {
  char path[600], tmp[640];
  pc_job_path(c, j, PRIOR_LEAF, path, sizeof path);
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  uint8_t *z = NULL;
  size_t zn = 0;
  int rc = pc_wire_film_zip(&j->prior, 1, &z, &zn, e);
  if (rc) return rc;
  int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) rc = pc_errf(e, PC_EIO, "%s: %s", tmp, strerror(errno));
  if (!rc && (pc_write_all(fd, PRIOR_MAGIC, PRIOR_MAGIC_LEN) != 0 || pc_write_all(fd, z, zn) != 0 || fsync(fd) != 0))
    rc = pc_errf(e, PC_EIO, "%s: %s", tmp, strerror(errno));
  if (fd >= 0 && close(fd) != 0 && !rc) rc = pc_errf(e, PC_EIO, "%s: %s", tmp, strerror(errno));
  if (!rc && rename(tmp, path) != 0) rc = pc_errf(e, PC_EIO, "%s: %s", path, strerror(errno));
  if (rc) unlink(tmp);
  free(z);
  return rc;
}

/* The copy save() made, into j->prior (*found false when there is none). */
static int load(const pc_coord *c, pc_job *j, bool *found, pc_err *e) {
  char path[600];
  pc_job_path(c, j, PRIOR_LEAF, path, sizeof path);
  *found = access(path, F_OK) == 0;
  if (!*found) return PC_OK;
  char *data = NULL;
  size_t n = 0;
  /* a film is at most 16384^2 pixels x 64 layers; its compressed form is bounded like an upload */
  int rc = pc_file_read(path, (size_t)1 << 40, &data, &n, e);
  if (rc) return rc;
  if (n < PRIOR_MAGIC_LEN || memcmp(data, PRIOR_MAGIC, PRIOR_MAGIC_LEN) != 0)
    rc = pc_errf(e, PC_EPARSE, "%s: not a saved pilot film", path);
  if (!rc) rc = pc_film_init(&j->prior, j->set.width, j->set.height, j->set.strategy_layers, e);
  if (!rc) {
    rc = pc_wire_film_load((const uint8_t *)data + PRIOR_MAGIC_LEN, n - PRIOR_MAGIC_LEN, &j->prior, e);
    if (rc) pc_film_free(&j->prior);
  }
  free(data);
  if (!rc) j->prior_ready = true;
  return rc;
}

void pc_prior_attach(pc_coord *c, pc_job *j) {
  if (!j->prior_group || j->prior_ready) return;
  pc_err e = {0};
  pc_pilot_films *g = find_group(c, j->prior_group);
  if (g) {
    if (g->film.w != j->set.width || g->film.h != j->set.height) {
      pc_wire_log("job %llu: pilot group %016llx's films are %dx%d: left out", (unsigned long long)j->id,
                  (unsigned long long)g->group, g->film.w, g->film.h);
      drop_group(c, g);
      return;
    }
    j->prior = g->film;
    j->prior_ready = true;
    memset(&g->film, 0, sizeof g->film);
    pc_wire_log("job %llu: its image includes its pilot's %llu iterations (%.2f worker-seconds)", (unsigned long long)j->id,
                (unsigned long long)iterations(&j->prior), g->worker_seconds);
    drop_group(c, g);
    /* a volatile store never restarts: the copy is for a coordinator that does */
    if (!c->volatile_store && save(c, j, &e) != 0)
      pc_wire_log("job %llu: the pilot's film is not saved (a restart will leave it out): %s", (unsigned long long)j->id, e.msg);
    return;
  }
  bool found;
  int rc = load(c, j, &found, &e);
  if (!rc && !found)
    pc_wire_log("job %llu: pilot group %016llx's films are gone (a restart, or too many pilots waiting): the image is "
                "the job's own", (unsigned long long)j->id, (unsigned long long)j->prior_group);
  else if (rc)
    pc_wire_log("job %llu: the pilot's saved film is left out: %s", (unsigned long long)j->id, e.msg);
}

double pc_prior_weight(const pc_job *j, double worker_seconds, double elapsed) {
  if (!j->prior_ready || !(j->prior_amount > 0)) return 0;
  if ((j->halt_iterations > 0) + (j->halt_worker_seconds > 0) + (j->halt_seconds > 0) != 1) return 0;
  double x, budget;
  if (j->halt_iterations > 0) {
    x = (double)j->film.layers[PC_LAYER_PT].count;
    budget = (double)j->halt_iterations;
  } else if (j->halt_worker_seconds > 0) {
    x = worker_seconds;
    budget = j->halt_worker_seconds;
  } else if (j->halt_seconds > 0) {
    x = elapsed;
    budget = j->halt_seconds;
  } else {
    return 0; /* --halt-noise alone: no budget to fix the weight by (the client sends no prior) */
  }
  x = fmin(fmax(x, 0.0), budget);
  return j->prior_amount / (j->prior_amount + x);
}

int pc_prior_shown(const pc_job *j, double weight, pc_film *tmp, const pc_film **shown, pc_err *e) {
  *shown = &j->film;
  if (!(weight > 0)) return PC_OK;
  pc_film_part parts[] = {{&j->prior, weight}, {&j->film, 1.0 - weight}};
  int rc = pc_film_init(tmp, j->film.w, j->film.h, j->set.strategy_layers, e);
  if (!rc && (rc = pc_film_mix(tmp, parts, 2, e)) != 0) pc_film_free(tmp);
  if (!rc) *shown = tmp;
  return rc;
}

bool pc_prior_relmse_estimate(const pc_job *j, double weight, double *out) {
  /* a part of weight 0 is never read: without a prior, this is the film's own estimate */
  pc_film_part parts[] = {{&j->prior, weight}, {&j->film, 1.0 - weight}};
  return pc_film_mix_relmse_estimate(parts, 2, out);
}

void pc_prior_free_all(pc_coord *c) {
  while (c->pilot_films) drop_group(c, c->pilot_films);
}
