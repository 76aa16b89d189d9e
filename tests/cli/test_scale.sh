#!/usr/bin/env bash
# Scale and placement do not change the image: the Cornell box scaled by 1/1000 and by 1000
# renders the same as the original with the same seed (every method draws the same numbers; only
# rounding differs), and moved 10^4 units off the origin (where a float's step is 10^-3 of the
# 2-unit box) it keeps its brightness; a black plane 10^5 wide far behind the camera changes
# nothing. Ray offsets off surfaces must be relative to the coordinates of the primitive they
# leave: with an absolute part (1e-4 x max(1, |p|, ...)) the small box came out 0.4-0.9% off and
# the moved one 13-28% (an offset of 1 unit, half the box); with the scene's radius as a floor
# the plane moved the box's image by 0.8-1.4%.
set -u
. "$(dirname "$0")/lib.inc"
cp -r "$src/scenes/cornell-box/meshes" "$tmp/meshes"
python3 - "$src/scenes/cornell-box/scene.xml" "$tmp" <<'PY' || fail=1
import re, sys
src, out = open(sys.argv[1]).read(), sys.argv[2]
assert '<lookat origin="0, 1, 6.8" target="0, 1, 0" up="0, 1, 0"/>' in src, "the Cornell box's camera changed: update this test"
for name, scale, ox in (("unit", 1, 0), ("small", 1e-3, 0), ("big", 1e3, 0), ("far", 1, 1e4)):
    pt = lambda x, y, z: "%.9g, %.9g, %.9g" % (x * scale + ox, y * scale, z * scale)
    s = src.replace('<lookat origin="0, 1, 6.8" target="0, 1, 0" up="0, 1, 0"/>',
                    '<lookat origin="%s" target="%s" up="0, 1, 0"/>' % (pt(0, 1, 6.8), pt(0, 1, 0)))
    s, n = re.subn(r'(<string name="filename" value="meshes/[^"]+"/>)',
                   r'\1<transform name="toWorld"><scale value="%.9g"/><translate x="%.9g" y="0" z="0"/></transform>' % (scale, ox), s)
    assert n == 8, "the Cornell box's meshes changed: update this test"
    open("%s/%s.xml" % (out, name), "w").write(s)
# a black plane 10^5 wide, 10^5 behind the camera, facing the box: what leaves the box ends on it
# as it ended in the void, but the scene's radius is now 10^5
plane = ('  <shape type="rectangle"><transform name="toWorld"><scale value="1e5"/><rotate y="1" angle="180"/>'
         '<translate z="1e5"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></shape>\n')
open("%s/ground.xml" % out, "w").write(open("%s/unit.xml" % out).read().replace("</scene>", plane + "</scene>"))
PY
# compare's beauty row: RMSE relMSE L1 mean mean(ref)
beauty() { awk '$1 == "beauty" { print $3, $5, $6 }' "$tmp/out"; }
# Renders $tmp/<prefix>unit.xml and each variant with every method and compares each variant's
# image with unit's: relMSE below the variant's bound (a Python dict by variant, else a default)
# and the mean within a relative tolerance.
same_image() {
  local prefix=$1 variants=$2 bounds=$3 default=$4 meantol=$5
  for m in pt lt bdpt pcbpt; do
    for v in unit $variants; do
      check "$prefix$m-$v" 0 "$m: 8 iterations" -- "$bin" render "$tmp/$prefix$v.xml" --method "$m" --spp 8 --width 32 \
        --height 32 --threads 2 --quiet --out "$tmp/$prefix$v-$m.exr"
    done
    for v in $variants; do
      check "$prefix$m-$v-compare" 0 "beauty" -- "$bin" compare "$tmp/$prefix$v-$m.exr" "$tmp/${prefix}unit-$m.exr"
      read -r rel mean ref <<<"$(beauty)"
      python3 -c "
import ast, sys
v, bounds = sys.argv[1], ast.literal_eval(sys.argv[5])
rel, mean, ref, default, meantol = map(float, sys.argv[2:5] + sys.argv[6:8])
sys.exit(0 if rel < bounds.get(v, default) and abs(mean / ref - 1) < meantol else 1)" \
        "$v" "$rel" "$mean" "$ref" "$bounds" "$default" "$meantol" ||
        { echo "FAIL $prefix$m-$v: relMSE $rel, mean $mean against $ref"; fail=1; continue; }
      echo "ok   $prefix$m-$v: relMSE $rel, mean $mean against $ref"
    done
  done
}
# the same samples up to rounding: the scaled boxes agree far below the noise (relMSE below
# 3e-5; 1.3e-2 to 1.5e-1 with the absolute offset), so does the box beside the plane (0 for
# pt, lt and bdpt, 2.4e-3 for pcbpt; 2.4e-2 and 1.4e-1 for pt and lt with the radius as the
# floor); the moved one's geometry is rounded to 10^-3, which moves some samples (2.7e-2 for
# lt, 2e-3 to 4e-3 for the others; 0.09 to 5.7 with the absolute offset), but not the
# brightness
same_image "" "small big far ground" "{'far': 0.05, 'ground': 0.01}" 1e-3 0.02
# The same for exact cylinders (an emitting tube and an open two-sided one over a floor), whose
# hits are solved in double from float rays and offset by their own coordinates: 1/1000 and
# 1000 times the size agree with the original to rounding (relMSE ~1e-13 for pt, bdpt and lt,
# 1e-6 for pcbpt, whose records round differently), 10^4 units away keeps the brightness to 0.04%.
python3 - "$tmp" <<'PY' || fail=1
import sys
out = sys.argv[1]
for name, sc, ox in (("unit", 1, 0), ("small", 1e-3, 0), ("big", 1e3, 0), ("far", 1, 1e4)):
    pt = lambda x, y, z: "%.9g, %.9g, %.9g" % (x * sc + ox, y * sc, z * sc)
    move = '<scale value="%.9g"/><translate x="%.9g"/></transform>' % (sc, ox)
    open("%s/cyl-%s.xml" % (out, name), "w").write(
        '<scene version="0.6.0"><integrator type="path"><integer name="maxDepth" value="5"/></integrator>'
        '<sensor type="perspective"><float name="fov" value="50"/><transform name="toWorld">'
        '<lookat origin="%s" target="%s" up="0, 1, 0"/></transform></sensor>' % (pt(0, 3, 5), pt(0, 0.5, 0)) +
        '<shape type="rectangle"><transform name="toWorld"><scale value="4"/><rotate x="1" angle="-90"/>' + move +
        '<bsdf type="diffuse"/></shape>'
        '<shape type="cylinder"><float name="radius" value="0.15"/><transform name="toWorld"><scale z="2"/>'
        '<rotate y="1" angle="90"/><translate x="-1" y="1.6"/>' + move +
        '<emitter type="area"><rgb name="radiance" value="8, 6, 4"/></emitter></shape>'
        '<shape type="cylinder"><float name="radius" value="0.5"/><transform name="toWorld"><rotate x="1" angle="-90"/>'
        '<translate x="0.3"/>' + move + '<bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape></scene>')
PY
same_image cyl- "small big far" "{'far': 0.05}" 1e-4 0.01
exit $fail
