# range_failures.sh: a job fails after three ranges its workers could not render, counted
# across a coordinator restart (the count is in the store); and a data dir written before
# that count existed (schema version 0) still opens with its jobs.
. "$(dirname "$0")/lib.inc"
# an old store: the jobs table without the failures column, one finished job
mkdir -p "$T/data"
python3 - "$T/data/jobs.db" <<'PY'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.executescript("""
CREATE TABLE jobs(id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL, bundle BLOB NOT NULL,
 settings BLOB NOT NULL, halt_iterations INTEGER NOT NULL, halt_seconds REAL NOT NULL, priority INTEGER NOT NULL,
 state TEXT NOT NULL, next_iter INTEGER NOT NULL DEFAULT 0, done INTEGER NOT NULL DEFAULT 0,
 elapsed REAL NOT NULL DEFAULT 0, ckpt_gen INTEGER NOT NULL DEFAULT 0, light_per_iter INTEGER NOT NULL DEFAULT -1,
 error TEXT NOT NULL DEFAULT '', rays INTEGER NOT NULL DEFAULT 0, t_paths REAL NOT NULL DEFAULT 0,
 t_lt REAL NOT NULL DEFAULT 0, t_pmf REAL NOT NULL DEFAULT 0, t_connect REAL NOT NULL DEFAULT 0,
 pmf_bytes INTEGER NOT NULL DEFAULT 0);
CREATE TABLE ranges(id INTEGER PRIMARY KEY AUTOINCREMENT, job INTEGER NOT NULL, first INTEGER NOT NULL,
 count INTEGER NOT NULL, acked INTEGER NOT NULL DEFAULT 0, open INTEGER NOT NULL DEFAULT 1);
INSERT INTO jobs(name, bundle, settings, halt_iterations, halt_seconds, priority, state, done)
 VALUES('old-job', x'00', x'', 16, 0, 0, 'done', 16);
""")
db.commit()
PY
start_coord
"$B/pcbpt-coord" list $H | grep -q "old-job" || fail "the old store's job is not listed"
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --spp 100000 --width 16 --height 16 $H | tail -1)
refuse() { # the n-th refusal, as logged
  "$B/tests/farm_tool" fail 127.0.0.1:$PORT "$T/tok" >>"$T/w-fail.log" 2>&1 || fail "farm_tool fail"
  for _ in $(seq 50); do [ "$(grep -c "job $J: range .* failed on" "$T/coord.log")" -ge "$1" ] && return; sleep 0.1; done
  fail "refusal $1 not logged"
}
refuse 1
refuse 2
[ "$(job_field "$J" state)" = running ] || fail "job $(job_field "$J" state) after two refusals"
kill -9 "$COORD"
sleep 0.5
start_coord "$PORT"
refuse 3
for _ in $(seq 50); do [ "$(job_field "$J" state)" = failed ] && break; sleep 0.1; done
[ "$(job_field "$J" state)" = failed ] || fail "job $(job_field "$J" state) after three refusals across a restart"
echo PASS
