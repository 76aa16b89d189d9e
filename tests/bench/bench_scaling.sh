#!/usr/bin/env bash
# Benchmark (not a test): how the cost grows along three axes, for pt, bdpt and pcbpt (K=1):
#   triangles  1k, 100k, 1M, 5M (the cornell box with a tessellated ball, gen_tess_scene.py),
#              256x256, maxDepth 10;
#   resolution 256x256 .. 3840x2160 on cornell-box, maxDepth 10;
#   maxDepth   5, 10, 20, 50 on cornell-box 256x256.
# Per row: CPU seconds per iteration, measured as the difference of the whole process's CPU time
# (user + sys, render threads and embedded farm) between a render of 1+EXTRA iterations and
# one of 1, divided by EXTRA, so loading, the BVH build and the image writes cancel; the setup
# CPU (the 1-iteration run less one iteration); peak resident memory of the longer run; and
# the growth of the per-iteration cost from the axis's first row next to the growth of the
# work (pixels, maxDepth, or 1 for triangles). CPU time is used because the machine may be
# shared (wall-clock phase timers are disturbed there). Usage:
#   tests/bench/bench_scaling.sh [BUILD_DIR] [AXES] [EXTRA]   (defaults: build "tris res depth" 6;
#   the resolution axis uses one extra iteration: its iterations are long enough to time)
#   METHODS="pt bdpt pcbpt" (default) chooses the methods.
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$top/build}
axes=${2:-tris res depth}
extra=${3:-6}
methods=${METHODS:-pt bdpt pcbpt}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cornell=$top/scenes/cornell-box/scene.xml

# cpu SPP SCENE W H DEPTH METHOD: CPU seconds and peak MB of one render into $tmp/cpu
cpu() {
  /usr/bin/time -f "%U %S %M" -o "$tmp/time" "$build/pcbpt-coord" render "$2" --method "$6" --max-depth "$5" \
    --width "$3" --height "$4" --spp "$1" --threads 2 --quiet --out "$tmp/o.exr" > "$tmp/out" 2>&1 || return 1
  awk '{ printf "%.3f %.0f\n", $1 + $2, $3 / 1024 }' "$tmp/time" > "$tmp/cpu"
}

# run LABEL WORK SCENE W H DEPTH METHOD: one row of the table
declare -A first
run() {
  local label=$1 work=$2 scene=$3 w=$4 h=$5 depth=$6 m=$7 c1 c2 rss
  cpu 1 "$scene" "$w" "$h" "$depth" "$m" && read -r c1 _ < "$tmp/cpu" &&
    cpu $((1 + extra)) "$scene" "$w" "$h" "$depth" "$m" && read -r c2 rss < "$tmp/cpu" ||
    { echo "$label $m: render failed: $(tail -1 "$tmp/out")"; return 0; }
  local it
  it=$(awk -v a="$c1" -v b="$c2" -v n="$extra" 'BEGIN { printf "%.3f", (b - a) / n }')
  local key="$axis/$m"
  [ -n "${first[$key]:-}" ] || first[$key]="$it $work"
  awk -v l="$label" -v m="$m" -v it="$it" -v c1="$c1" -v rss="$rss" -v work="$work" -v f="${first[$key]}" 'BEGIN {
    split(f, a, " "); printf "%-12s %-6s %12.3f %9.2f %8d %9.2fx %9.2fx\n", l, m, it, c1 - it, rss, it / a[1], work / a[2] }'
}

header() {
  echo
  echo "== $1 (2 threads)"
  printf "%-12s %-6s %12s %9s %8s %10s %10s\n" "$2" method "CPU s/iter" "setup s" "peak MB" "cost x" "work x"
}

for axis in $axes; do
  case $axis in
  tris)
    header "triangles: cornell box with a tessellated ball, 256x256, maxDepth 10" triangles
    for n in 1000 100000 1000000 5000000; do
      python3 "$top/tests/bench/gen_tess_scene.py" "$n" "$tmp/tess" > /dev/null
      for m in $methods; do run "$n" 1 "$tmp/tess/scene.xml" 256 256 10 "$m"; done
      rm -rf "$tmp/tess"
    done ;;
  res)
    header "resolution: cornell-box, maxDepth 10" size
    saved=$extra extra=1
    for wh in 256x256 512x512 1024x1024 1920x1080 3840x2160; do
      w=${wh%x*} h=${wh#*x}
      for m in $methods; do run "$wh" $((w * h)) "$cornell" "$w" "$h" 10 "$m"; done
    done
    extra=$saved ;;
  depth)
    header "path length: cornell-box 256x256" maxDepth
    for d in 5 10 20 50; do
      for m in $methods; do run "$d" "$d" "$cornell" 256 256 "$d" "$m"; done
    done ;;
  *) echo "unknown axis '$axis' (tris, res, depth)" >&2; exit 2 ;;
  esac
done
