# cancel_acks.sh: an upload merged just before its job is cancelled is still answered (its
# acknowledgement waited for a checkpoint a cancelled job never writes, and a worker uploads
# nothing more until its last upload is answered: issue 10, failure 1); then a real worker
# renders the next job to its exact count.
. "$(dirname "$0")/lib.inc"
start_coord
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --method pt --spp 100000 --width 32 --height 32 $H | tail -1)
"$B/tests/farm_tool" cancelack 127.0.0.1:$PORT "$T/tok" >"$T/ca.out" 2>&1 || { cat "$T/ca.out"; fail "the upload of a cancelled job was never answered"; }
cat "$T/ca.out"
[ "$(job_field "$J" state)" = cancelled ] || fail "job $J $(job_field "$J" state)"
start_worker w1
J2=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --method pt --spp 40 --width 32 --height 32 $H | tail -1)
timeout 20 "$B/pcbpt-coord" wait "$J2" $H >/dev/null || fail "the next job did not complete"
[ "$(job_field "$J2" iterations)" = 40 ] || fail "iterations $(job_field "$J2" iterations) != 40"
echo PASS
