# kill_restart.sh: SIGKILL a worker mid-job, then SIGKILL the coordinator and restart it on
# the same port: the job completes and counts exactly the requested iterations, its merged
# sums and per-iteration squares (beauty_sq) are those of a single-process render of them and
# its per-pixel largest iterations (beauty_max, merged by max) the same bit for bit, so
# the relMSE the job reports (status) is the one that render estimates, and the checkpoint
# files a kill leaves behind (stand-ins here: a later generation never recorded, a temporary)
# are removed when the job resumes (issue 10).
. "$(dirname "$0")/lib.inc"
start_coord
start_worker w1; W1=$LAST
start_worker w2
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --spp 2000 --width 64 --height 64 $H | tail -1)
sleep 2
kill -9 "$W1"
sleep 1
[ "$(job_field "$J" state)" = running ] || fail "the job was $(job_field "$J" state) at the kill: nothing tested"
kill -9 "$COORD"
touch "$T/data/jobs/$J/ckpt.999999" "$T/data/jobs/$J/ckpt.7.tmp"
sleep 1
start_coord "$PORT"
start_worker w3
timeout 55 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait"
[ "$(job_field "$J" iterations)" = 2000 ] || fail "iterations $(job_field "$J" iterations) != 2000"
[ "$(ls "$T/data/jobs/$J" | grep -c '^ckpt\.')" = 1 ] || fail "stale checkpoints left: $(ls "$T/data/jobs/$J")"
CK=$(ls "$T/data/jobs/$J"/ckpt.*)
"$B/tests/farm_tool" exact "$CK" "$S/scenes/furnace/scene.xml" --spp 2000 --width 64 --height 64 >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "the merged sums, squares or maxima differ from a single-process render"; }
grep -E "beauty_sq|beauty_max|estimated" "$T/exact.out"
EST=$(sed -n 's/^estimated relMSE \([^/]*\)\/.*/\1/p' "$T/exact.out")
python3 -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(abs(a - b) > 1e-5 * b)" \
  "$(job_field "$J" relmse_estimate)" "$EST" || fail "status says relMSE $(job_field "$J" relmse_estimate), the film $EST"
echo PASS
