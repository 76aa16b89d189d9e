# cancel_mid_upload.sh: a job cancelled while a worker's upload is half sent. The worker hands
# an upload to its connection a few chunks at a time; the coordinator takes an upload's chunks
# in order on a connection, so the dropped upload must still be sent to its end (and refused)
# rather than cut off, or the worker's next upload would start mid-stream and its connection be
# dropped. The worker reaches the coordinator through relay.py holding back each upload chunk
# 25 ms (a 1024x1024 film's upload: over a hundred chunks, several times what the sockets
# buffer), and the job is
# cancelled once 1 MB of an upload is through. The next job then renders to its exact count and
# image on the same connection.
. "$(dirname "$0")/lib.inc"
start_coord
start_relay 0.025
start_worker w1 "$RPORT"
J=$("$B/pcbpt-coord" submit "$S/scenes/cornell-box/scene.xml" --method pt --spp 100000 --width 1024 --height 1024 $H | tail -1)
up() { find "$T/cap" -name '*.c2s' -size +1024k | head -1; }
for _ in $(seq 300); do [ -n "$(up)" ] && break; sleep 0.1; done
[ -n "$(up)" ] || fail "no upload began"
"$B/pcbpt-coord" cancel "$J" $H >/dev/null || fail "cancel"
for _ in $(seq 300); do grep -q "upload was dropped with" "$T/w1.log" && grep -q "refused upload.*job is not running" "$T/coord.log" && break; sleep 0.1; done
grep "upload was dropped with" "$T/w1.log" || fail "the cancel did not find an upload in mid-transfer"
grep -q "refused upload.*job is not running" "$T/coord.log" || fail "the dropped upload was never completed and refused"
J2=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --method pt --spp 40 --width 32 --height 32 $H | tail -1)
timeout 60 "$B/pcbpt-coord" wait "$J2" $H >/dev/null || fail "the next job did not complete"
[ "$(job_field "$J2" iterations)" = 40 ] || fail "iterations $(job_field "$J2" iterations) != 40"
grep -E "out of order|does not match|worker 'w1' left" "$T/coord.log" && fail "the worker's connection was dropped"
[ "$(grep -c "connected to" "$T/w1.log")" = 1 ] || fail "the worker reconnected"
CK=$(ls "$T/data/jobs/$J2"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$S/scenes/furnace/scene.xml" --method pt --spp 40 --width 32 --height 32 >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "image not exact"; }
echo PASS
