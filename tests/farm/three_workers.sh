# three_workers.sh: three worker processes render a furnace job; the job completes with
# exactly the requested iterations and its image can be fetched.
. "$(dirname "$0")/lib.inc"
start_coord
for w in w1 w2 w3; do start_worker $w; done
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --spp 24 --width 64 --height 64 $H | tail -1)
timeout 50 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait"
[ "$(job_field "$J" iterations)" = 24 ] || fail "iterations $(job_field "$J" iterations) != 24"
"$B/pcbpt-coord" fetch "$J" --out "$T/out.exr" $H >/dev/null || fail "fetch"
[ -s "$T/out.exr" ] || fail "empty image"
echo PASS
