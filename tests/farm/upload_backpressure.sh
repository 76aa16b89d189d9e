# upload_backpressure.sh: uploads larger than the coordinator's upload budget divided by the
# workers sending them (a 128x128 film's are ~1 MB; --max-buffered-mb 0.25, three workers). Over
# the budget the coordinator pauses senders, but one upload always proceeds while no merge is
# pending; pausing every sender at once deadlocked the farm (a 4K job with four workers never
# merged an upload). The job must end with its exact count and image.
. "$(dirname "$0")/lib.inc"
COORD_ARGS="--max-buffered-mb 0.25"
start_coord
for w in w1 w2 w3; do start_worker $w; done
SC="$S/scenes/cornell-box/scene.xml"
J=$("$B/pcbpt-coord" submit "$SC" --method pt --spp 150 --width 128 --height 128 $H | tail -1)
timeout 90 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "the job stalled: $(job_field "$J" iterations) of 150 iterations"
[ "$(job_field "$J" iterations)" = 150 ] || fail "iterations $(job_field "$J" iterations) != 150"
UPS=$(sed -n "s/.*job $J: done, .*(\([0-9]*\) uploads merged.*/\1/p" "$T/coord.log")
[ "${UPS:-0}" -ge 6 ] || fail "only ${UPS:-0} uploads: too few to overlap"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$SC" --method pt --spp 150 --width 128 --height 128 >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "image not exact"; }
echo "PASS ($UPS uploads over a 0.25 MB budget)"
