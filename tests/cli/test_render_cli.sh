#!/usr/bin/env bash
# The render and compare verbs from the command line: help, flag errors that name the flag
# (non-zero exit, one line), and a small render that writes the EXR and the PNG preview.
set -u
. "$(dirname "$0")/lib.inc"
scene="$src/scenes/cornell-box/scene.xml"
check help 0 "--spp" -- "$bin" render --help
check verbs 0 "render" -- "$bin" --help
check unknown-verb 2 "unknown verb" -- "$bin" frobnicate
check unknown-flag 2 "--frob" -- "$bin" render "$scene" --frob
check bad-spp 2 "--spp" -- "$bin" render "$scene" --spp zero
check neg-spp 2 "--spp" -- "$bin" render "$scene" --spp -3
check bad-method 2 "--method" -- "$bin" render "$scene" --method magic
check bad-depth 2 "--max-depth" -- "$bin" render "$scene" --max-depth 0
check bad-width 2 "--width" -- "$bin" render "$scene" --width 100000
check missing-value 2 "--time" -- "$bin" render "$scene" --time
check bad-threads 2 "--threads" -- "$bin" render "$scene" --threads -1
check missing-scene 1 "nope.xml" -- "$bin" render "$tmp/nope.xml" --spp 1
check no-scene 2 "SCENE" -- "$bin" render --spp 1
check bad-halt-noise 2 "--halt-noise" -- "$bin" render "$scene" --halt-noise 0
check bad-candidate-visibility 2 "--pcbpt-candidate-visibility" -- "$bin" render "$scene" --pcbpt-candidate-visibility all
check bad-mis-count 2 "--mis: '0.5'" -- "$bin" render "$scene" --mis 0.5
check bad-mis 2 "--mis: 'fair'" -- "$bin" render "$scene" --mis fair
check bad-rate 2 "--pcbpt-rate: '0'" -- "$bin" render "$scene" --pcbpt-rate 0
check bad-rate-high 2 "--pcbpt-rate: '1.5'" -- "$bin" render "$scene" --pcbpt-rate 1.5
check bad-rate-float-zero 2 "--pcbpt-rate: '1e-300'" -- "$bin" render "$scene" --pcbpt-rate 1e-300
check bad-unseen-rate 2 "--pcbpt-unseen-rate: '0'" -- "$bin" render "$scene" --pcbpt-unseen-rate 0
check bad-unseen-rate-high 2 "--pcbpt-unseen-rate: '2'" -- "$bin" render "$scene" --pcbpt-unseen-rate 2
check bad-dark-seen 2 "--pcbpt-dark-seen: '1.5'" -- "$bin" render "$scene" --pcbpt-dark-seen 1.5
check bad-dark-candidates 2 "--pcbpt-dark-candidates: '0'" -- "$bin" render "$scene" --pcbpt-dark-candidates 0
check bad-dark-mix 2 "--pcbpt-dark-mix: '0'" -- "$bin" render "$scene" --pcbpt-dark-mix 0
# K past what can be resampled: no dark vertices then, and nothing overruns (ASan build)
check large-k 0 "pcbpt: 1 iterations" -- "$bin" render "$scene" --method pcbpt --pcbpt-k 80 --spp 1 --width 8 --height 8 \
  --threads 1 --out "$tmp/large-k.exr"
check small-rate 0 "pcbpt: 1 iterations" -- "$bin" render "$scene" --method pcbpt --pcbpt-rate 1e-7 --spp 1 --width 8 --height 8 \
  --threads 1 --out "$tmp/small-rate.exr"
# the PCBPT settings are in the image header as the flags that give them
check render-pcbpt 0 "pcbpt: 1 iterations" -- "$bin" render "$scene" --method pcbpt --spp 1 --width 16 --height 16 --threads 2 \
  --pcbpt-candidates 3 --pcbpt-candidate-visibility uncertain --mis 3.5 --pcbpt-rate 0.5 --pcbpt-unseen-rate 0.75 \
  --pcbpt-dark-seen 0.2 --pcbpt-dark-candidates 5 --pcbpt-dark-mix 0.7 --out "$tmp/pc.exr"
grep -aq -- "--pcbpt-rate 0.5 --pcbpt-unseen-rate 0.75 --pcbpt-candidates 3 --pcbpt-candidate-visibility uncertain --pcbpt-dark-seen 0.2 --pcbpt-dark-candidates 5 --pcbpt-dark-mix 0.7 .*--mis 3.5 " "$tmp/pc.exr" ||
  { echo "FAIL render-pcbpt: no PCBPT flags in the header"; fail=1; }
check render 0 "est. relMSE" -- "$bin" render "$scene" --method pt --spp 2 --width 32 --height 24 --threads 2 --out "$tmp/cb.exr"
# with 2 iterations it can tell how their errors spread (docs/variance.md)
grep -q "^error of single iterations (2 of them, 8x8 blocks): median" "$tmp/out" ||
  { echo "FAIL render: no per-iteration error line"; cat "$tmp/out"; fail=1; }
[ -s "$tmp/cb.exr" ] && [ -s "$tmp/cb.png" ] || { echo "FAIL render: outputs missing"; fail=1; }
check compare-self 0 "beauty" -- "$bin" compare "$tmp/cb.exr" "$tmp/cb.exr"
grep -q "^beauty *0.000000e+00" "$tmp/out" || { echo "FAIL compare-self: non-zero error"; cat "$tmp/out"; fail=1; }
check compare-json 0 '"layer": "inner"' -- "$bin" compare "$tmp/cb.exr" "$tmp/cb.exr" --json
grep -q '"layer": "variance"' "$tmp/out" || { echo "FAIL render: no variance layer"; fail=1; }
grep -q '"relmse_estimate": [0-9]' "$tmp/out" || { echo "FAIL compare: no estimate from the header"; fail=1; }
# --halt-noise alone bounds the render: it stops once the estimated relMSE is at most 0.05 (from
# 16 iterations on), and the image it writes says about that much
check halt-noise 0 "est. relMSE" -- "$bin" render "$scene" --method pt --halt-noise 0.05 --width 32 --height 24 --threads 2 \
  --quiet --out "$tmp/hn.exr"
sed -n 's/^pt: \([0-9]*\) iterations.*est. relMSE \([0-9.e-]*\).*/\1 \2/p' "$tmp/out" | {
  read -r it est; awk -v it="$it" -v est="$est" 'BEGIN { exit !(it >= 16 && est > 0 && est <= 0.06) }'; } ||
  { echo "FAIL halt-noise: $(cat "$tmp/out")"; fail=1; }
# Strategy layers compare only between images that weigh their strategies alike (the header's
# pcbpt.weights): PCBPT's inner strategies count 2 by default, BDPT's 1; --mis 1 makes them alike.
for m in "bdpt" "pcbpt" "pcbpt --mis 1"; do
  check "weights-$m" 0 "iterations" -- "$bin" render "$scene" --method $m --spp 2 --width 16 --height 16 --threads 2 \
    --out "$tmp/w-${m// /}.exr"
done
grep -aq "bidirectional balance n_lt=1 n_inner=2" "$tmp/w-pcbpt.exr" || { echo "FAIL weights: pcbpt's header"; fail=1; }
check compare-unlike 0 "strategy layers weighted unlike" -- "$bin" compare "$tmp/w-pcbpt.exr" "$tmp/w-bdpt.exr"
grep -Eq "^inner .*\(not comparable: weighted unlike\)" "$tmp/out" && ! grep -Eq "^beauty .*not comparable" "$tmp/out" ||
  { echo "FAIL compare-unlike: rows"; cat "$tmp/out"; fail=1; }
check compare-alike 0 "inner" -- "$bin" compare "$tmp/w-pcbpt--mis1.exr" "$tmp/w-bdpt.exr" --json
python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert all(l["comparable"] for l in d["layers"]), d; assert d["weights"] == d["weights_ref"] == "bidirectional balance n_lt=1 n_inner=1", d' "$tmp/out" ||
  { echo "FAIL compare-alike: $(cat "$tmp/out")"; fail=1; }
# ... and images of other path lengths are different quantities: said, the figures still printed
check weights-depth2 0 "iterations" -- "$bin" render "$scene" --method bdpt --max-depth 2 --spp 2 --width 16 --height 16 \
  --threads 2 --out "$tmp/w-d2.exr"
check compare-depth 0 "of different things (max depth 11 in the reference, 2 here)" -- "$bin" compare "$tmp/w-d2.exr" "$tmp/w-bdpt.exr"
# ... and so are images of other scene files (the header's hash of the scene's bundle): an edited
# copy is told apart, an unchanged copy elsewhere is the same scene
cp -r "$(dirname "$scene")" "$tmp/copy" && cp -r "$(dirname "$scene")" "$tmp/edited" &&
  sed -i 's/value="17, 12, 4"/value="17, 12, 5"/' "$tmp/edited/scene.xml" && ! cmp -s "$scene" "$tmp/edited/scene.xml" ||
  { echo "FAIL: could not make an edited copy of the scene"; fail=1; }
for v in copy edited; do
  check "render-$v" 0 "iterations" -- "$bin" render "$tmp/$v/scene.xml" --method bdpt --spp 2 --width 16 --height 16 --threads 2 \
    --out "$tmp/w-$v.exr"
done
check compare-edited 0 "of different things (other scene files in the reference" -- "$bin" compare "$tmp/w-edited.exr" "$tmp/w-bdpt.exr"
check compare-copy 0 "beauty" -- "$bin" compare "$tmp/w-copy.exr" "$tmp/w-bdpt.exr"
grep -q "other scene files" "$tmp/err" && { echo "FAIL compare-copy: an unchanged copy taken for another scene"; fail=1; }
# ... and images of other -D values of the same files: a value the scene uses is told apart (even
# one equal to its <default>); one it never names is warned of at the render and is no difference
cp -r "$(dirname "$scene")" "$tmp/param" &&
  sed -i 's/value="17, 12, 4"/value="$light"/; s|^<scene version="0.6.0">|&<default name="light" value="17, 12, 4"/>|' \
    "$tmp/param/scene.xml" && grep -q '<default name="light"' "$tmp/param/scene.xml" ||
  { echo "FAIL: could not make a copy of the scene with a parameter"; fail=1; }
for d in none light; do
  defs=(); [ $d = light ] && defs=(-D "light=17, 12, 4" -D zeta=1 -D alpha="a b")
  check "render-param-$d" 0 "iterations" -- "$bin" render "$tmp/param/scene.xml" --method bdpt --spp 2 --width 16 --height 16 \
    --threads 2 "${defs[@]}" --out "$tmp/w-param-$d.exr"
done
for v in zeta alpha; do
  grep -q "scene.xml:4: warning: -D $v=.*: the scene names no \$$v, so the value changes nothing" "$tmp/err" ||
    { echo "FAIL render-param-light: no warning of the unused -D $v"; cat "$tmp/err"; fail=1; }
done
grep -q "names no \$light" "$tmp/err" && { echo "FAIL render-param-light: the used -D light warned of"; fail=1; }
check compare-defines 0 "of different things (-D '' in the reference, 'light=17, 12, 4' here)" -- "$bin" compare \
  "$tmp/w-param-light.exr" "$tmp/w-param-none.exr"
grep -q "^beauty *0.000000e+00" "$tmp/out" || { echo "FAIL compare-defines: -D equal to the default changed the image"; fail=1; }
check render-unused 0 "iterations" -- "$bin" render "$tmp/copy/scene.xml" --method bdpt --spp 2 --width 16 --height 16 --threads 2 \
  -D zeta=1 --out "$tmp/w-unused.exr"
check compare-unused 0 "beauty" -- "$bin" compare "$tmp/w-unused.exr" "$tmp/w-copy.exr"
grep -q "of different things" "$tmp/err" && { echo "FAIL compare-unused: an unused -D taken for another image"; cat "$tmp/err"; fail=1; }
check strict-unused 1 "-D zeta=1: the scene names no \$zeta, so the value changes nothing (an error under --strict)" -- \
  "$bin" render "$tmp/copy/scene.xml" --spp 1 --width 16 --height 16 --threads 2 -D zeta=1 --strict --out "$tmp/w-strict.exr"
check compare-missing 1 "nope.exr" -- "$bin" compare "$tmp/cb.exr" "$tmp/nope.exr"
check compare-one 2 "two EXR" -- "$bin" compare "$tmp/cb.exr"
# Interrupted twice: the render stops at once, writes nothing, says so in one line and removes
# its temporary farm (whose log shows when the render is under way). SIGTERM then SIGINT: two
# signals of one kind sent at once may arrive as one.
mkdir "$tmp/farm"
TMPDIR="$tmp/farm" "$bin" render "$scene" --method pt --time 60 --width 32 --height 24 --threads 1 --out "$tmp/int.exr" \
  >"$tmp/int.out" 2>"$tmp/int.err" &
pid=$!
for _ in $(seq 200); do grep -qs -- "-> local" "$tmp"/farm/*/farm.log && break; sleep 0.05; done
kill -TERM $pid; kill -INT $pid
st=0; timeout 20 tail --pid=$pid -f /dev/null || st=124
wait $pid; st=$((st ? st : $?))
if [ $st -ne 1 ] || ! grep -q "interrupted twice" "$tmp/int.err" || [ "$(wc -l <"$tmp/int.err")" -ne 1 ] ||
   [ -e "$tmp/int.exr" ] || [ -n "$(ls -A "$tmp/farm")" ]; then
  echo "FAIL double-interrupt: exit $st"; cat "$tmp/int.err"; ls -A "$tmp/farm"; fail=1
else
  echo "ok   double-interrupt"
fi
# Interrupted once while the first iteration of a large image is under way: the worker has
# nothing to upload, says so, and the render ends at once (not after the coordinator's
# 13-second wait for an upload that never comes) with one line and no image.
TMPDIR="$tmp/farm" "$bin" render "$scene" --method pt --time 60 --width 1024 --height 1024 --threads 1 \
  --out "$tmp/big.exr" >"$tmp/int.out" 2>"$tmp/int.err" &
pid=$!
for _ in $(seq 200); do grep -qs -- "-> local" "$tmp"/farm/*/farm.log && break; sleep 0.05; done
kill -INT $pid
st=0; timeout 12 tail --pid=$pid -f /dev/null || st=124
wait $pid; st=$((st ? st : $?))
if [ $st -ne 1 ] || ! grep -q "no iteration finished" "$tmp/int.err" || [ -e "$tmp/big.exr" ]; then
  echo "FAIL interrupt-early: exit $st"; cat "$tmp/int.err"; fail=1
else
  echo "ok   interrupt-early"
fi

# PT on a scene whose point light shines through glass: the image lacks that light, and render
# says so on stderr; BDPT, which renders it, gets no warning
cat >"$tmp/point_glass.xml" <<'XML'
<scene version="0.6.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="toWorld"><lookat origin="0, 1, 4" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
  <emitter type="point"><point name="position" x="0" y="2" z="0"/></emitter>
  <shape type="sphere"><float name="radius" value="0.5"/><bsdf type="dielectric"/></shape>
  <shape type="rectangle"><transform name="toWorld"><rotate x="1" angle="-90"/><translate y="-0.5"/></transform></shape>
</scene>
XML
check pt-incomplete 0 "pt never samples the light a point, spot or directional light sends through a delta" -- \
  "$bin" render "$tmp/point_glass.xml" --method pt --spp 1 --width 8 --height 8 --threads 1 --out "$tmp/pg.exr"
check bdpt-complete 0 "" -- "$bin" render "$tmp/point_glass.xml" --method bdpt --spp 1 --width 8 --height 8 --threads 1 --out "$tmp/pg.exr"
if grep -q "pt never samples" "$tmp/err"; then echo "FAIL bdpt-complete: warned"; fail=1; fi
if grep -q "one-sided" "$tmp/err"; then echo "FAIL bdpt-complete: warned of backs"; fail=1; fi

# a surface nearer than the sensor's nearClip, which Mitsuba's path tracer would not see: render
# says how much of the image it is; the default clip range, which clips nothing here, says nothing
cat >"$tmp/clip.xml" <<'XML'
<scene version="0.6.0"><emitter type="constant"/>
  <sensor type="perspective"><float name="fov" value="45"/><float name="nearClip" value="4"/></sensor>
  <shape type="rectangle"><boolean name="flipNormals" value="true"/><transform name="toWorld"><scale x="9" y="9"/><translate z="5"/></transform></shape>
  <shape type="cube"><transform name="toWorld"><scale value="0.5"/><translate z="2.5"/></transform></shape>
</scene>
XML
check near-clip 0 "of the image is nearer than the sensor's nearClip (4) and 0.0% beyond its farClip (10000)" -- \
  "$bin" render "$tmp/clip.xml" --method pt --spp 1 --width 8 --height 8 --threads 1 --out "$tmp/clip.exr"
sed -i 's|<float name="nearClip" value="4"/>||' "$tmp/clip.xml"
check no-clip 0 "" -- "$bin" render "$tmp/clip.xml" --method pt --spp 1 --width 8 --height 8 --threads 1 --out "$tmp/clip.exr"
if grep -q "nearClip" "$tmp/err"; then echo "FAIL no-clip: warned"; fail=1; fi

# LT on the same scene misses the glass the camera sees (warned); on a scene of diffuse surfaces only
# it misses nothing
check lt-incomplete 0 "lt never sees a delta material from the camera" -- \
  "$bin" render "$tmp/point_glass.xml" --method lt --spp 1 --width 8 --height 8 --threads 1 --out "$tmp/pg.exr"
check lt-complete 0 "" -- "$bin" render "$scene" --method lt --spp 1 --width 8 --height 8 --threads 1 --out "$tmp/pg.exr"
if grep -q "lt never sees" "$tmp/err"; then echo "FAIL lt-complete: warned"; fail=1; fi

# A room whose walls face out of it (published conversions from renderers with two-sided
# materials): black as in Mitsuba, and render names the walls the camera sees from behind
cat >"$tmp/walls_out.xml" <<'XML'
<scene version="0.6.0">
  <sensor type="perspective"><float name="fov" value="40"/></sensor>
  <emitter type="point"><point name="position" x="0" y="0" z="2"/></emitter>
  <shape type="rectangle"><transform name="toWorld"><scale value="5"/><translate z="4"/></transform></shape>
</scene>
XML
check walls-out 0 "100% of the image is the back of one-sided materials, black as in Mitsuba 0.6 (they reflect only on the side their normals face): the shape at line 4 (100%)" -- \
  "$bin" render "$tmp/walls_out.xml" --method pt --spp 1 --width 8 --height 8 --threads 1 --out "$tmp/wo.exr"

# An emitter so bright that a pixel's sum is beyond what a film upload may hold: every worker
# renders the range's same refused film, so the range counts as one that could not be rendered
# and the job fails with the reason, instead of re-running it forever (it did: one render wrote
# 250k log lines in ten minutes)
cat >"$tmp/blinding.xml" <<'XML'
<scene version="0.6.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="toWorld"><lookat origin="0, 1, 4" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
  <shape type="rectangle"><transform name="toWorld"><rotate x="1" angle="90"/><translate y="2"/></transform>
    <emitter type="area"><rgb name="radiance" value="1e36, 1e36, 1e36"/></emitter></shape>
  <shape type="rectangle"><transform name="toWorld"><rotate x="1" angle="-90"/><translate y="-0.5"/></transform></shape>
</scene>
XML
check refused-film 1 "render failed on worker local: its film of iterations .* was refused [0-9]* times in a row: film: a sum in layer" -- \
  timeout 120 "$bin" render "$tmp/blinding.xml" --method bdpt --spp 2 --width 8 --height 8 --threads 1 --out "$tmp/bl.exr"
[ -e "$tmp/bl.exr" ] && { echo "FAIL refused-film: wrote an image"; fail=1; }
# A render whose films do not fit the machine's memory is one line before any farm starts (where
# the kernel overcommits, making them got the process killed). 16384x16384 takes 108 GiB of
# films; on a machine that has that much, the render would run, so the check is skipped there.
mem_kb=$(awk '/^MemTotal:/ {print $2}' /proc/meminfo)
if [ "${mem_kb:-0}" -lt 100000000 ]; then
  check films-too-large 1 "a 16384x16384 render on 2 threads takes 110592 MB of films (the coordinator's and the worker's), more than this machine's" -- \
    "$bin" render "$scene" --spp 1 --width 16384 --height 16384 --threads 2 --out "$tmp/huge.exr"
  [ -e "$tmp/huge.exr" ] && { echo "FAIL films-too-large: wrote an image"; fail=1; }
fi
exit $fail
