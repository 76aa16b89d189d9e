# bad_upload.sh: a worker that uploads a delta holding a NaN, one that uploads a finite sum
# no radiance reaches (1.7e308: two such add to +inf, one overflows the image's floats; issue
# 10, failure 6), one of 2^64-1 iterations whose first + count wraps, one that uploads a delta
# of the wrong size, one whose trace holds another range's iteration, and a client sending a scene bundle whose content does not match its hash are
# each refused with a log line, while a concurrent job completes with its exact image.
. "$(dirname "$0")/lib.inc"
start_coord
start_worker w1
J=$("$B/pcbpt-coord" submit "$S/scenes/furnace/scene.xml" --spp 800 --width 64 --height 64 $H | tail -1)
# the test workers take ranges of the running job (a fair share each) while w1 renders
"$B/tests/farm_tool" upload 127.0.0.1:$PORT "$T/tok" nan >"$T/nan.out" 2>&1 || { cat "$T/nan.out"; fail "NaN upload not refused"; }
"$B/tests/farm_tool" upload 127.0.0.1:$PORT "$T/tok" huge >"$T/huge.out" 2>&1 || { cat "$T/huge.out"; fail "1.7e308 upload not refused"; }
"$B/tests/farm_tool" upload 127.0.0.1:$PORT "$T/tok" wrap >"$T/wrap.out" 2>&1 || { cat "$T/wrap.out"; fail "2^64-1 iterations not refused"; }
"$B/tests/farm_tool" upload 127.0.0.1:$PORT "$T/tok" size >"$T/size.out" 2>&1 || { cat "$T/size.out"; fail "wrong-size upload not refused"; }
"$B/tests/farm_tool" upload 127.0.0.1:$PORT "$T/tok" trace >"$T/trace.out" 2>&1 || { cat "$T/trace.out"; fail "upload tracing another range's iteration not refused"; }
"$B/tests/farm_tool" bundle 127.0.0.1:$PORT "$T/tok" >"$T/bundle.out" 2>&1 || { cat "$T/bundle.out"; fail "bad bundle not refused"; }
timeout 50 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "job did not complete"
[ "$(job_field "$J" iterations)" = 800 ] || fail "iterations $(job_field "$J" iterations) != 800"
grep -q "refused upload .*non-finite sum" "$T/coord.log" || fail "no log line for the NaN upload"
grep -q "refused upload .*beyond any radiance for 1 samples" "$T/coord.log" || fail "no log line for the 1.7e308 upload"
grep -q "refused upload .*iterations outside the range" "$T/coord.log" || fail "no log line for the wrapping upload"
grep -q "refused upload .*wrong resolution" "$T/coord.log" || fail "no log line for the wrong-size upload"
grep -q "refused upload .*its trace holds 1 iterations, not exactly its 1" "$T/coord.log" || fail "no log line for the upload with another range's trace"
grep -q "refused scene bundle .*content hash does not match" "$T/coord.log" || fail "no log line for the bad bundle"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" exact "$CK" "$S/scenes/furnace/scene.xml" --spp 800 --width 64 --height 64 >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "the refused uploads changed the image"; }
[ "$(job_field "$J" state)" = done ] || fail "job not done"
grep -E "refused (upload|scene bundle)" "$T/coord.log" | sed 's/^/  log: /'
echo PASS
