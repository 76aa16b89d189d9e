# furnace_kill.sh: the white furnace (L = 2 for maxDepth -1) rendered as one job over two
# workers, one SIGKILLed once the job is under way (its first iterations acknowledged; a fixed
# 3-second wait let a quick farm finish first): the job finishes with exactly --spp 96 iterations and
# its mean is 2 within 2%, and its merged sums and per-iteration squares (beauty_sq, the
# variance data) are exactly those of a single-process render, and its per-pixel largest
# iterations (beauty_max) the same bit for bit. The method is PCBPT (METHOD=... runs another one; FK_SIZE sets the
# resolution, FK_TIMEOUT the seconds allowed).
. "$(dirname "$0")/lib.inc"
SCENE="$S/scenes/furnace/scene.xml"
METHOD=${METHOD:-pcbpt}
SIZE=${FK_SIZE:-128}
echo "method: $METHOD, ${SIZE}x${SIZE}, 96 iterations"
start_coord
start_worker w1; W1=$LAST
start_worker w2
J=$("$B/pcbpt-coord" submit "$SCENE" --method "$METHOD" --spp 96 --width "$SIZE" --height "$SIZE" $H | tail -1)
for _ in $(seq 30); do [ "$(job_field "$J" iterations)" -gt 0 ] && break; sleep 0.1; done
[ "$(job_field "$J" state)" = running ] || fail "the job was $(job_field "$J" state) at the kill: nothing tested (lower FK_SIZE?)"
kill -9 "$W1"
echo "killed w1 at $(job_field "$J" iterations) acknowledged iterations"
timeout "${FK_TIMEOUT:-55}" "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait"
[ "$(job_field "$J" state)" = done ] || fail "job $(job_field "$J" state)"
[ "$(job_field "$J" iterations)" = 96 ] || fail "iterations $(job_field "$J" iterations) != 96"
CK=$(ls "$T/data/jobs/$J"/ckpt.* | sort -t. -k2 -n | tail -1)
"$B/tests/farm_tool" mean "$CK" "$SIZE" "$SIZE" 2 0.02 || fail "$METHOD: furnace mean is not 2 within 2%"
"$B/tests/farm_tool" exact "$CK" "$SCENE" --method "$METHOD" --spp 96 --width "$SIZE" --height "$SIZE" >"$T/exact.out" \
  || { cat "$T/exact.out"; fail "$METHOD: the merged sums, squares or maxima differ from a single-process render"; }
grep -E "beauty_sq|beauty_max|estimated" "$T/exact.out"
echo "PASS ($METHOD)"
