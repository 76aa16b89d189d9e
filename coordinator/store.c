/* store.c: the job store (SQLite in the data dir): jobs with their settings, state and
 * progress, and every iteration range handed out with how much of it is acknowledged. Range
 * ids come from AUTOINCREMENT so they are never reused; iteration indices come from
 * jobs.next_iter, which is advanced in the same transaction that records a new range.
 * Columns added later come by migrations numbered in PRAGMA user_version, so a data dir of
 * an older coordinator opens and keeps its jobs. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "coord.h"

static const char schema[] =
    "PRAGMA journal_mode=WAL;"
    "PRAGMA synchronous=FULL;"
    "CREATE TABLE IF NOT EXISTS jobs(id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL,"
    " bundle BLOB NOT NULL, settings BLOB NOT NULL, halt_iterations INTEGER NOT NULL,"
    " halt_seconds REAL NOT NULL, priority INTEGER NOT NULL, state TEXT NOT NULL,"
    " next_iter INTEGER NOT NULL DEFAULT 0, done INTEGER NOT NULL DEFAULT 0,"
    " elapsed REAL NOT NULL DEFAULT 0, ckpt_gen INTEGER NOT NULL DEFAULT 0,"
    " light_per_iter INTEGER NOT NULL DEFAULT -1, error TEXT NOT NULL DEFAULT '',"
    " rays INTEGER NOT NULL DEFAULT 0, t_paths REAL NOT NULL DEFAULT 0, t_lt REAL NOT NULL DEFAULT 0,"
    " t_pmf REAL NOT NULL DEFAULT 0, t_connect REAL NOT NULL DEFAULT 0, pmf_bytes INTEGER NOT NULL DEFAULT 0);"
    "CREATE TABLE IF NOT EXISTS ranges(id INTEGER PRIMARY KEY AUTOINCREMENT, job INTEGER NOT NULL,"
    " first INTEGER NOT NULL, count INTEGER NOT NULL, acked INTEGER NOT NULL DEFAULT 0,"
    " open INTEGER NOT NULL DEFAULT 1);"
    "CREATE INDEX IF NOT EXISTS ranges_open ON ranges(job, open);";

/* migrations[i] takes a store from user_version i to i + 1 */
static const char *const migrations[] = {
    "ALTER TABLE jobs ADD COLUMN failures INTEGER NOT NULL DEFAULT 0;", /* ranges workers could not render */
    /* study jobs (docs/farm-study.md): worker-seconds behind the committed iterations, and
     * the snapshots kept and ranges re-run, so a restart keeps the budget and the numbering */
    "ALTER TABLE jobs ADD COLUMN t_total REAL NOT NULL DEFAULT 0;"
    "ALTER TABLE jobs ADD COLUMN snapshots INTEGER NOT NULL DEFAULT 0;"
    "ALTER TABLE jobs ADD COLUMN ranges_rerun INTEGER NOT NULL DEFAULT 0;",
    /* CPU seconds of the render threads (the auto pilot's cost); unknown for older jobs */
    "ALTER TABLE jobs ADD COLUMN t_cpu REAL NOT NULL DEFAULT -1;",
};

static int db_err(pc_coord *c, pc_err *e, const char *what) {
  return pc_errf(e, PC_EIO, "store %s/jobs.db: %s: %s", c->data_dir, what, sqlite3_errmsg(c->db));
}

static int migrate(pc_coord *c, const char *path, pc_err *e);

int pc_store_open(pc_coord *c, pc_err *e) {
  char path[512];
  snprintf(path, sizeof path, "%s/jobs.db", c->data_dir);
  if (sqlite3_open_v2(path, &c->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, NULL) != SQLITE_OK) {
    int rc = db_err(c, e, "open");
    sqlite3_close(c->db);
    c->db = NULL;
    return rc;
  }
  char *msg = NULL;
  /* a throw-away store needs no durability; the rest of the schema is the same */
  const char *sync = c->volatile_store ? "PRAGMA synchronous=OFF;" : "";
  if (sqlite3_busy_timeout(c->db, 5000) != SQLITE_OK || sqlite3_exec(c->db, schema, NULL, NULL, &msg) != SQLITE_OK ||
      sqlite3_exec(c->db, sync, NULL, NULL, &msg) != SQLITE_OK) {
    int rc = pc_errf(e, PC_EIO, "store %s: schema: %s", path, msg ? msg : sqlite3_errmsg(c->db));
    sqlite3_free(msg);
    sqlite3_close(c->db);
    c->db = NULL;
    return rc;
  }
  return migrate(c, path, e);
}

/* Brings an older store's tables up to this coordinator's (see migrations). */
static int migrate(pc_coord *c, const char *path, pc_err *e) {
  sqlite3_stmt *st = NULL;
  int version = -1;
  if (sqlite3_prepare_v2(c->db, "PRAGMA user_version", -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
    version = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  int nmig = (int)(sizeof migrations / sizeof migrations[0]), rc = 0;
  if (version < 0) rc = db_err(c, e, "user_version");
  else if (version > nmig) rc = pc_errf(e, PC_EINVAL, "store %s: schema version %d is newer than this coordinator's %d", path, version, nmig);
  for (char *msg = NULL; !rc && version < nmig; version++) {
    char bump[64];
    snprintf(bump, sizeof bump, "PRAGMA user_version=%d;", version + 1);
    if (sqlite3_exec(c->db, "BEGIN IMMEDIATE", NULL, NULL, &msg) != SQLITE_OK ||
        sqlite3_exec(c->db, migrations[version], NULL, NULL, &msg) != SQLITE_OK ||
        sqlite3_exec(c->db, bump, NULL, NULL, &msg) != SQLITE_OK || sqlite3_exec(c->db, "COMMIT", NULL, NULL, &msg) != SQLITE_OK) {
      rc = pc_errf(e, PC_EIO, "store %s: migration to version %d: %s", path, version + 1, msg ? msg : sqlite3_errmsg(c->db));
      sqlite3_free(msg);
      sqlite3_exec(c->db, "ROLLBACK", NULL, NULL, NULL);
    }
  }
  if (rc) {
    sqlite3_close(c->db);
    c->db = NULL;
  }
  return rc;
}

void pc_store_close(pc_coord *c) {
  if (c->db) sqlite3_close(c->db);
  c->db = NULL;
}

static int exec(pc_coord *c, const char *sql, pc_err *e) {
  if (sqlite3_exec(c->db, sql, NULL, NULL, NULL) != SQLITE_OK) return db_err(c, e, sql);
  return 0;
}
int pc_store_begin(pc_coord *c, pc_err *e) { return exec(c, "BEGIN IMMEDIATE", e); }
int pc_store_commit(pc_coord *c, pc_err *e) { return exec(c, "COMMIT", e); }
void pc_store_rollback(pc_coord *c) { sqlite3_exec(c->db, "ROLLBACK", NULL, NULL, NULL); }

/* Steps a statement to completion; `bound` is the OR of its sqlite3_bind_* results (SQLITE_OK
 * is 0), so a failed bind is reported instead of running with a NULL parameter. */
static int step_done(pc_coord *c, sqlite3_stmt *st, int bound, pc_err *e, const char *what) {
  if (bound != SQLITE_OK) {
    int rc = db_err(c, e, what);
    sqlite3_finalize(st);
    return rc;
  }
  int r = sqlite3_step(st);
  int rc = r == SQLITE_DONE ? 0 : db_err(c, e, what);
  sqlite3_finalize(st);
  return rc;
}

int pc_store_insert_job(pc_coord *c, pc_job *j, pc_err *e) {
  sqlite3_stmt *st;
  int b = SQLITE_OK;
  if (sqlite3_prepare_v2(c->db, "INSERT INTO jobs(name,bundle,settings,halt_iterations,halt_seconds,priority,state,t_cpu)"
                                " VALUES(?,?,?,?,?,?,?,0)", -1, &st, NULL) != SQLITE_OK)
    return db_err(c, e, "prepare insert job");
  b |= sqlite3_bind_text(st, 1, j->name, -1, SQLITE_TRANSIENT);
  b |= sqlite3_bind_blob(st, 2, j->bundle, PC_BUNDLE_HASH, SQLITE_TRANSIENT);
  b |= sqlite3_bind_blob(st, 3, j->settings_blob, (int)j->settings_len, SQLITE_TRANSIENT);
  b |= sqlite3_bind_int64(st, 4, (sqlite3_int64)j->halt_iterations);
  b |= sqlite3_bind_double(st, 5, j->halt_seconds);
  b |= sqlite3_bind_int(st, 6, j->priority);
  b |= sqlite3_bind_text(st, 7, pc_job_state_name(j->state), -1, SQLITE_STATIC);
  int rc = step_done(c, st, b, e, "insert job");
  if (!rc) j->id = (uint64_t)sqlite3_last_insert_rowid(c->db);
  return rc;
}

int pc_store_update_job(pc_coord *c, const pc_job *j, pc_err *e) {
  sqlite3_stmt *st;
  int b = SQLITE_OK;
  if (sqlite3_prepare_v2(c->db, "UPDATE jobs SET state=?,next_iter=?,done=?,elapsed=?,ckpt_gen=?,light_per_iter=?,error=?,"
                                "rays=?,t_paths=?,t_lt=?,t_pmf=?,t_connect=?,pmf_bytes=?,failures=?,t_total=?,snapshots=?,"
                                "ranges_rerun=?,t_cpu=? WHERE id=?", -1, &st, NULL) != SQLITE_OK)
    return db_err(c, e, "prepare update job");
  b |= sqlite3_bind_text(st, 1, pc_job_state_name(j->state), -1, SQLITE_STATIC);
  b |= sqlite3_bind_int64(st, 2, (sqlite3_int64)j->next_iter);
  b |= sqlite3_bind_int64(st, 3, (sqlite3_int64)j->done);
  b |= sqlite3_bind_double(st, 4, j->elapsed);
  b |= sqlite3_bind_int64(st, 5, (sqlite3_int64)j->ckpt_gen);
  b |= sqlite3_bind_int64(st, 6, j->light_per_iter);
  b |= sqlite3_bind_text(st, 7, j->error, -1, SQLITE_TRANSIENT);
  b |= sqlite3_bind_int64(st, 8, (sqlite3_int64)j->stats.rays);
  b |= sqlite3_bind_double(st, 9, j->stats.t_paths);
  b |= sqlite3_bind_double(st, 10, j->stats.t_lt);
  b |= sqlite3_bind_double(st, 11, j->stats.t_pmf);
  b |= sqlite3_bind_double(st, 12, j->stats.t_connect);
  b |= sqlite3_bind_int64(st, 13, (sqlite3_int64)j->stats.pmf_bytes);
  b |= sqlite3_bind_int(st, 14, j->failures);
  b |= sqlite3_bind_double(st, 15, j->stats.t_total);
  b |= sqlite3_bind_int64(st, 16, (sqlite3_int64)j->snaps_taken);
  b |= sqlite3_bind_int64(st, 17, (sqlite3_int64)j->ranges_rerun);
  b |= sqlite3_bind_double(st, 18, j->stats.t_cpu);
  b |= sqlite3_bind_int64(st, 19, (sqlite3_int64)j->id);
  return step_done(c, st, b, e, "update job");
}

int pc_store_insert_range(pc_coord *c, uint64_t job, uint64_t first, uint64_t count, uint64_t *id, pc_err *e) {
  sqlite3_stmt *st;
  int b = SQLITE_OK;
  if (sqlite3_prepare_v2(c->db, "INSERT INTO ranges(job,first,count) VALUES(?,?,?)", -1, &st, NULL) != SQLITE_OK)
    return db_err(c, e, "prepare insert range");
  b |= sqlite3_bind_int64(st, 1, (sqlite3_int64)job);
  b |= sqlite3_bind_int64(st, 2, (sqlite3_int64)first);
  b |= sqlite3_bind_int64(st, 3, (sqlite3_int64)count);
  int rc = step_done(c, st, b, e, "insert range");
  if (!rc) *id = (uint64_t)sqlite3_last_insert_rowid(c->db);
  return rc;
}

int pc_store_update_range(pc_coord *c, const pc_range *r, bool open, pc_err *e) {
  sqlite3_stmt *st;
  int b = SQLITE_OK;
  if (sqlite3_prepare_v2(c->db, "UPDATE ranges SET count=?,acked=?,open=? WHERE id=?", -1, &st, NULL) != SQLITE_OK)
    return db_err(c, e, "prepare update range");
  b |= sqlite3_bind_int64(st, 1, (sqlite3_int64)r->count);
  b |= sqlite3_bind_int64(st, 2, (sqlite3_int64)r->acked);
  b |= sqlite3_bind_int(st, 3, open ? 1 : 0);
  b |= sqlite3_bind_int64(st, 4, (sqlite3_int64)r->id);
  return step_done(c, st, b, e, "update range");
}

static int load_ranges(pc_coord *c, pc_job *j, pc_err *e) {
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(c->db, "SELECT id,first,count,acked FROM ranges WHERE job=? AND open=1 ORDER BY id", -1, &st,
                         NULL) != SQLITE_OK)
    return db_err(c, e, "prepare load ranges");
  if (sqlite3_bind_int64(st, 1, (sqlite3_int64)j->id) != SQLITE_OK) {
    int rc = db_err(c, e, "bind load ranges");
    sqlite3_finalize(st);
    return rc;
  }
  pc_range **tail = &j->ranges;
  int r, rc = 0;
  double now = pc_coord_now();
  while ((r = sqlite3_step(st)) == SQLITE_ROW) {
    pc_range *g = calloc(1, sizeof *g);
    if (!g) { rc = pc_errf(e, PC_ENOMEM, "store: out of memory"); break; }
    g->id = (uint64_t)sqlite3_column_int64(st, 0);
    g->first = (uint64_t)sqlite3_column_int64(st, 1);
    g->count = (uint64_t)sqlite3_column_int64(st, 2);
    g->acked = g->merged = (uint64_t)sqlite3_column_int64(st, 3);
    /* its worker may come back and claim it within the grace period */
    g->orphan_since = now;
    *tail = g;
    tail = &g->next;
  }
  if (!rc && r != SQLITE_DONE) rc = db_err(c, e, "load ranges");
  sqlite3_finalize(st);
  return rc;
}

int pc_store_load(pc_coord *c, pc_err *e) {
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(c->db, "SELECT id,name,bundle,settings,halt_iterations,halt_seconds,priority,state,next_iter,"
                                "done,elapsed,ckpt_gen,light_per_iter,error,rays,t_paths,t_lt,t_pmf,t_connect,pmf_bytes,failures,t_total,snapshots,ranges_rerun,t_cpu FROM jobs ORDER BY id", -1, &st, NULL) != SQLITE_OK)
    return db_err(c, e, "prepare load jobs");
  pc_job **tail = &c->jobs;
  int r, rc = 0;
  while ((r = sqlite3_step(st)) == SQLITE_ROW) {
    pc_job *j = calloc(1, sizeof *j);
    if (!j) { rc = pc_errf(e, PC_ENOMEM, "store: out of memory"); break; }
    j->id = (uint64_t)sqlite3_column_int64(st, 0);
    snprintf(j->name, sizeof j->name, "%s", (const char *)sqlite3_column_text(st, 1));
    if (sqlite3_column_bytes(st, 2) == PC_BUNDLE_HASH) memcpy(j->bundle, sqlite3_column_blob(st, 2), PC_BUNDLE_HASH);
    j->settings_len = (size_t)sqlite3_column_bytes(st, 3);
    j->settings_blob = malloc(j->settings_len + 1);
    if (!j->settings_blob) { free(j); rc = pc_errf(e, PC_ENOMEM, "store: out of memory"); break; }
    if (j->settings_len) memcpy(j->settings_blob, sqlite3_column_blob(st, 3), j->settings_len);
    j->halt_iterations = (uint64_t)sqlite3_column_int64(st, 4);
    j->halt_seconds = sqlite3_column_double(st, 5);
    j->priority = sqlite3_column_int(st, 6);
    if (pc_job_state_parse((const char *)sqlite3_column_text(st, 7), &j->state) != 0) j->state = PC_JOB_FAILED;
    j->next_iter = (uint64_t)sqlite3_column_int64(st, 8);
    j->done = (uint64_t)sqlite3_column_int64(st, 9);
    j->elapsed = sqlite3_column_double(st, 10);
    j->ckpt_gen = (uint64_t)sqlite3_column_int64(st, 11);
    j->light_per_iter = sqlite3_column_int64(st, 12);
    snprintf(j->error, sizeof j->error, "%s", (const char *)sqlite3_column_text(st, 13));
    j->stats.rays = (uint64_t)sqlite3_column_int64(st, 14);
    j->stats.t_paths = sqlite3_column_double(st, 15);
    j->stats.t_lt = sqlite3_column_double(st, 16);
    j->stats.t_pmf = sqlite3_column_double(st, 17);
    j->stats.t_connect = sqlite3_column_double(st, 18);
    j->stats.pmf_bytes = (uint64_t)sqlite3_column_int64(st, 19);
    j->failures = sqlite3_column_int(st, 20);
    j->stats.t_total = sqlite3_column_double(st, 21);
    j->snaps_taken = j->snaps_queued_n = (uint32_t)sqlite3_column_int64(st, 22);
    j->ranges_rerun = (uint32_t)sqlite3_column_int64(st, 23);
    j->stats.t_cpu = sqlite3_column_double(st, 24);
    j->stats_merged = j->stats;
    j->relmse_est = -1; /* until its film is loaded */
    *tail = j;
    tail = &j->next;
    if (j->state == PC_JOB_RUNNING || j->state == PC_JOB_STOPPING || j->state == PC_JOB_QUEUED)
      if ((rc = load_ranges(c, j, e)) != 0) break;
  }
  if (!rc && r != SQLITE_DONE) rc = db_err(c, e, "load jobs");
  sqlite3_finalize(st);
  return rc;
}
