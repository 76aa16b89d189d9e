# three_workers.sh: three worker processes render a job; its merged sums equal a single-process
# render of the same iterations exactly (up to summation order: relative 1e-9 per layer total
# and per pixel), on cornell-box with PT (pt and nee layers) and PCBPT (every layer) and on the white furnace, whose
# image must also be L = 2 (maxDepth -1) within 1.5%.
. "$(dirname "$0")/lib.inc"
start_coord
for w in w1 w2 w3; do start_worker $w; done
ckpt() { ls "$T/data/jobs/$1"/ckpt.* | sort -t. -k2 -n | tail -1; }
run() { # scene spp method
  J=$("$B/pcbpt-coord" submit "$S/scenes/$1/scene.xml" --spp "$2" --method "$3" --width 64 --height 64 $H | tail -1)
  timeout 50 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait $1"
  [ "$(job_field "$J" iterations)" = "$2" ] || fail "$1: iterations $(job_field "$J" iterations) != $2"
  [ "$(grep -c "job $J: range .* -> w" "$T/coord.log" | tr -d ' ')" -ge 3 ] || fail "$1: fewer than three ranges"
  "$B/tests/farm_tool" exact "$(ckpt "$J")" "$S/scenes/$1/scene.xml" --spp "$2" --method "$3" --width 64 --height 64 \
    || fail "$1: the farm's sums differ from a single-process render"
}
run cornell-box 24 pt
run furnace 48 pt
"$B/tests/farm_tool" mean "$(ckpt "$J")" 64 64 2 0.015 || fail "furnace mean is not 2 within 1.5%"
"$B/pcbpt-coord" fetch "$J" --out "$T/out.exr" $H >/dev/null || fail "fetch"
[ -s "$T/out.exr" ] || fail "empty image"
run cornell-box 12 pcbpt
for w in w1 w2 w3; do grep -q "range .* -> $w" "$T/coord.log" || fail "worker $w got no range"; done
echo PASS
