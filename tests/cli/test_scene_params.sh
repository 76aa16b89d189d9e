#!/usr/bin/env bash
# Published-scene conventions from the command line, through the embedded farm (so the worker
# loads the job's bundle): -D values and $names (the worker gets the same ones), <include> from
# a folder beside the scene with --scene-root, ignored settings warned about once on stderr,
# --strict making them errors, and one-line refusals of include loops and self-expanding $names.
set -u
. "$(dirname "$0")/lib.inc"
mkdir -p "$tmp/root/scene/meshes" "$tmp/root/common"
cp "$src"/scenes/cornell-box/meshes/*.obj "$tmp/root/scene/meshes/"
cat >"$tmp/root/common/integrator.xml" <<'XML'
<scene version="0.6.0"><default name="depth" value="5"/>
  <integrator type="$method"><integer name="maxDepth" value="$depth"/><boolean name="strictNormals" value="true"/></integrator>
</scene>
XML
cat >"$tmp/root/scene/loop.xml" <<'XML'
<scene version="0.6.0"><include filename="loop.xml"/></scene>
XML
cat >"$tmp/root/scene/scene.xml" <<'XML'
<scene version="0.6.0">
  <default name="method" value="path"/>
  <include filename="../common/integrator.xml"/>
  <sensor type="perspective"><float name="fov" value="19.5"/>
    <transform name="toWorld"><lookat origin="0, 1, 6.8" target="0, 1, 0" up="0, 1, 0"/></transform>
    <sampler type="ldsampler"><integer name="sampleCount" value="3"/></sampler>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/>
      <boolean name="banner" value="false"/><rfilter type="catmullrom"/></film>
  </sensor>
  <shape type="obj"><string name="filename" value="meshes/00_Floor.obj"/><bsdf type="diffuse"><float name="foo" value="1"/></bsdf></shape>
  <shape type="obj"><string name="filename" value="meshes/02_BackWall.obj"/><bsdf type="diffuse"><float name="foo" value="1"/></bsdf></shape>
  <shape type="obj"><string name="filename" value="meshes/07_Light.obj"/>
    <emitter type="area"><spectrum name="radiance" value="$light"/></emitter></shape>
</scene>
XML
s="$tmp/root/scene/scene.xml"
r="--scene-root $tmp/root --threads 1"
check needs-define 1 "undefined parameter" -- "$bin" render "$s" $r --out "$tmp/a.exr"
check outside-root 1 "outside the scene's folder" -- "$bin" render "$s" -D light=1 --threads 1 --out "$tmp/a.exr"
check self-define 2 "expands to itself" -- "$bin" render "$s" $r -D 'light=$light' --out "$tmp/a.exr"
check strict 1 "under --strict" -- "$bin" render "$s" $r -D light=1 --strict --out "$tmp/a.exr"
check render-a 0 "3 iterations" -- "$bin" render "$s" $r -D light=1 -D method=bdpt --out "$tmp/a.exr"
# each ignored setting once, on stderr, naming file and line (the two unread 'foo's are one)
for w in "scene.xml:6: warning: sampler 'ldsampler'" "scene.xml:8: warning: film 'hdrfilm': parameter 'banner'" \
         "scene.xml:8: warning: rfilter 'catmullrom'" "integrator.xml:2: warning: integrator 'bdpt': parameter 'strictNormals'"; do
  grep -q "$w" "$tmp/err" || { echo "FAIL warnings: lacks '$w'"; cat "$tmp/err"; fail=1; }
done
[ "$(grep -c "parameter 'foo'" "$tmp/err")" = 1 ] || { echo "FAIL warnings: 'foo' not warned exactly once"; cat "$tmp/err"; fail=1; }
grep -q "method bdpt\|bdpt" "$tmp/out" || { echo "FAIL render-a: not rendered with bdpt"; cat "$tmp/out"; fail=1; }
check render-a2 0 "3 iterations" -- "$bin" render "$s" $r -Dlight=1 -D method=bdpt --out "$tmp/a2.exr"
check render-b 0 "3 iterations" -- "$bin" render "$s" $r -D light=4 -D method=bdpt --out "$tmp/b.exr"
check same-define 0 "beauty" -- "$bin" compare "$tmp/a.exr" "$tmp/a2.exr"
grep -q "^beauty *0.000000e+00" "$tmp/out" || { echo "FAIL same-define: images differ"; cat "$tmp/out"; fail=1; }
check other-define 0 "beauty" -- "$bin" compare "$tmp/a.exr" "$tmp/b.exr"
grep -q "^beauty *0.000000e+00" "$tmp/out" && { echo "FAIL other-define: -D light=4 made no difference"; fail=1; }
check include-loop 1 "includes itself" -- "$bin" render "$tmp/root/scene/loop.xml" --threads 1
exit $fail
