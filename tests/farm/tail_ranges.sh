# tail_ranges.sh: two workers render an iteration-bounded job; its ranges tile exactly the
# requested iterations and shrink at the end of the job (guided self-scheduling), so neither
# worker is left idle behind a long last range of the other.
. "$(dirname "$0")/lib.inc"
start_coord
start_worker w1
start_worker w2
J=$("$B/pcbpt-coord" submit "$S/scenes/cornell-box/scene.xml" --spp 3000 --method pt --width 64 --height 64 $H | tail -1)
timeout 55 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait"
[ "$(job_field "$J" iterations)" = 3000 ] || fail "iterations $(job_field "$J" iterations) != 3000"
grep -o "job $J: range [0-9]* \[[0-9]*,+[0-9]*) -> w[12]" "$T/coord.log" | sed 's/.*\[\([0-9]*\),+\([0-9]*\)) -> \(w[12]\)/\1 \2 \3/' >"$T/ranges"
python3 - "$T/ranges" <<'PY' || fail "ranges"
import sys
rows = [tuple(l.split()) for l in open(sys.argv[1])]
ranges = sorted((int(f), int(n)) for f, n, _ in rows)
pos = 0
for f, n in ranges:
    assert f == pos, f"ranges do not tile: {f} after {pos}"
    pos += n
assert pos == 3000, f"ranges cover {pos} iterations"
counts = [int(n) for _, n, _ in rows]
assert {w for _, _, w in rows} == {"w1", "w2"}, "a worker got no range"
assert counts[-1] < max(counts) and counts[-2] < max(counts), f"the last ranges did not shrink: {counts}"
print("ranges:", counts)
PY
echo PASS
