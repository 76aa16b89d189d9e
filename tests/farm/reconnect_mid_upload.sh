# reconnect_mid_upload.sh: a worker's connection cut while an upload is half sent. The worker
# hands an upload to its connection a few chunks at a time; the coordinator drops what it had of
# the upload with the connection, so after reconnecting the worker must send the upload again
# from its first chunk, and the job must count its iterations exactly once. The worker reaches
# the coordinator through relay.py, which holds back each upload chunk 25 ms and cuts the
# connection once 1 MB of an upload (126 chunks of a 1024x1024 film) is through.
. "$(dirname "$0")/lib.inc"
start_coord
start_relay 0.025
start_worker w1 "$RPORT"
SC="$S/scenes/cornell-box/scene.xml"
J=$("$B/pcbpt-coord" submit "$SC" --method pt --spp 3 --width 1024 --height 1024 $H | tail -1)
up() { find "$T/cap" -name '1.c2s' -size +1024k | head -1; }
for _ in $(seq 300); do [ -n "$(up)" ] && break; sleep 0.1; done
[ -n "$(up)" ] || fail "no upload began"
touch "$T/cap/cut"
timeout 120 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "the job did not complete"
[ -e "$T/cap/cut" ] && fail "the relay never cut the connection"
[ "$(grep -c "connected to" "$T/w1.log")" -ge 2 ] || fail "the worker did not reconnect"
[ -e "$T/cap/2.c2s" ] || fail "no second connection"
[ "$(job_field "$J" iterations)" = 3 ] || fail "iterations $(job_field "$J" iterations) != 3"
grep -E "out of order|does not match" "$T/coord.log" && fail "an upload was resumed mid-stream"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$SC" --method pt --spp 3 --width 1024 --height 1024 >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "image not exact"; }
echo PASS
