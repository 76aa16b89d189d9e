# pause_coord.sh: the coordinator stopped (SIGSTOP) for 6 s, longer than --heartbeat-timeout 5,
# while two workers render: on SIGCONT it reads their waiting heartbeats instead of dropping
# them (issue 10, failure 8), and the job ends with its exact count and image.
. "$(dirname "$0")/lib.inc"
start_coord
start_worker w1
start_worker w2
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --method pt --spp 300 --width 32 --height 32 $H | tail -1)
for _ in $(seq 50); do [ "$(job_field "$J" iterations)" -gt 0 ] && break; sleep 0.1; done
kill -STOP "$COORD"
sleep 6
kill -CONT "$COORD"
timeout 30 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait"
[ "$(job_field "$J" iterations)" = 300 ] || fail "iterations $(job_field "$J" iterations) != 300"
grep -E "no heartbeat|worker '.*' left" "$T/coord.log" && fail "a live worker was dropped after the pause"
grep "the loop did not run" "$T/coord.log"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$S/scenes/furnace/scene.xml" --method pt --spp 300 --width 32 --height 32 >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "image not exact"; }
echo PASS
