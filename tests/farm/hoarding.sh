# hoarding.sh: a worker that claims 1e8 iterations/s, takes a range and then only sends
# heartbeats (issue 10, failure 7). Ranges are sized by what a worker's uploads measured, so
# it gets a one-iteration probe, not the job; the probe's progress deadline passes
# (--progress-timeout 2), the worker ignores the request to upload and stop, and the range is
# taken back and rendered by a real worker; the hoarder's late upload is refused. The job ends
# with its exact count and image.
. "$(dirname "$0")/lib.inc"
COORD_ARGS="--progress-timeout 2"
start_coord
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --method pt --spp 200 --width 32 --height 32 $H | tail -1)
"$B/tests/farm_tool" hoard 127.0.0.1:$PORT "$T/tok" "$J" 15 >"$T/hoard.out" 2>&1 &
HOARD=$!; PIDS+=("$HOARD")
sleep 0.5
start_worker w1
timeout 12 "$B/pcbpt-coord" wait "$J" $H >/dev/null || { cat "$T/hoard.out"; fail "the job stalled behind the hoarder"; }
wait "$HOARD" || { cat "$T/hoard.out"; fail "the hoarder's range was not taken back, or its late upload was counted"; }
cat "$T/hoard.out"
[ "$(job_field "$J" iterations)" = 200 ] || fail "iterations $(job_field "$J" iterations) != 200"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$S/scenes/furnace/scene.xml" --method pt --spp 200 --width 32 --height 32 >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "image not exact"; }
grep -E "overdue|taken back" "$T/coord.log"
echo PASS
