# three_workers.sh: three worker processes render a job; its merged sums equal a single-process
# render of the same iterations exactly (up to summation order: relative 1e-9 per layer total
# and per pixel), on cornell-box with PT (pt and nee layers) and PCBPT (every layer) and on the white furnace, whose
# image must also be L = 2 (maxDepth -1) within 1.5%; and on ajar-door with PCBPT's resampled
# connections tracing the candidates' visibility, which the workers must get from the job's
# settings (a render with the records' visibility has other sums), and with the dark-vertex
# rule's settings, which they must get the same way.
. "$(dirname "$0")/lib.inc"
start_coord
for w in w1 w2 w3; do start_worker $w; done
ckpt() { ls "$T/data/jobs/$1"/ckpt.* | sort -t. -k2 -n | tail -1; }
run() { # scene spp method [render flags]
  local scene=$1 spp=$2 method=$3
  shift 3
  J=$("$B/pcbpt-coord" submit "$S/scenes/$scene/scene.xml" --spp "$spp" --method "$method" --width 64 --height 64 "$@" $H | tail -1)
  timeout 50 "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "wait $scene"
  [ "$(job_field "$J" iterations)" = "$spp" ] || fail "$scene: iterations $(job_field "$J" iterations) != $spp"
  [ "$(grep -c "job $J: range .* -> w" "$T/coord.log" | tr -d ' ')" -ge 3 ] || fail "$scene: fewer than three ranges"
  "$B/tests/farm_tool" exact "$(ckpt "$J")" "$S/scenes/$scene/scene.xml" --spp "$spp" --method "$method" --width 64 --height 64 "$@" \
    || fail "$scene: the farm's sums differ from a single-process render"
}
run cornell-box 24 pt
run furnace 48 pt
"$B/tests/farm_tool" mean "$(ckpt "$J")" 64 64 2 0.015 || fail "furnace mean is not 2 within 1.5%"
"$B/pcbpt-coord" fetch "$J" --out "$T/out.exr" $H >/dev/null || fail "fetch"
[ -s "$T/out.exr" ] || fail "empty image"
run cornell-box 12 pcbpt
run ajar-door 12 pcbpt --pcbpt-candidates 4 --pcbpt-candidate-visibility traced
"$B/tests/farm_tool" exact "$(ckpt "$J")" "$S/scenes/ajar-door/scene.xml" --spp 12 --method pcbpt --width 64 --height 64 \
  --pcbpt-candidates 4 --pcbpt-candidate-visibility records 2>/dev/null && fail "ajar-door: the candidate visibility changes nothing"
# the dark-vertex rule's settings travel to the workers too
run ajar-door 12 pcbpt --pcbpt-dark-seen 0.5 --pcbpt-dark-candidates 4 --pcbpt-dark-mix 0.7
"$B/tests/farm_tool" exact "$(ckpt "$J")" "$S/scenes/ajar-door/scene.xml" --spp 12 --method pcbpt --width 64 --height 64 \
  --pcbpt-dark-seen 0.5 --pcbpt-dark-candidates 4 --pcbpt-dark-mix 0.5 2>/dev/null && fail "ajar-door: the dark mix changes nothing"
for w in w1 w2 w3; do grep -q "range .* -> $w" "$T/coord.log" || fail "worker $w got no range"; done
echo PASS
