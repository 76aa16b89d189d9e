#!/usr/bin/env bash
# Benchmark (not a test): how the cost grows along three axes, for pt, bdpt and pcbpt (K=1):
#   triangles  1k, 100k, 1M, 5M (the cornell box with a tessellated ball, gen_tess_scene.py),
#              256x256, maxDepth 10;
#   resolution 256x256 .. 3840x2160 on cornell-box, maxDepth 10;
#   maxDepth   5, 10, 20, 50 on cornell-box 256x256, and on the furnace with albedo 0.95 at
#              128x128 (axis "survive"), where paths last long enough for the connections' and
#              PCBPT's record build's growth with the square of the path length to show.
# Per row: CPU seconds per iteration of the render threads, as the render reports it (its
# "per iteration" line: the worker's render CPU over the iterations, so loading, the BVH build,
# the embedded farm and the image writes are not in it); the setup CPU (the whole process's
# user + sys less the iterations'); peak resident memory; and the growth of the per-iteration
# cost from the axis's first row next to the growth of the work (pixels, maxDepth, or 1 for
# triangles). CPU time is used because the machine may be shared (wall-clock phase timers are
# disturbed there). (A first version took the difference of two whole renders of 1 and 1+N
# iterations: at 1M-5M triangles the setup's spread, ~0.5 s, swamped it.) Usage:
#   tests/bench/bench_scaling.sh [BUILD_DIR] [AXES] [ITERATIONS]   (defaults: build
#   "tris res depth survive" 8; the resolution axis renders 3 past 1024x1024)
#   METHODS="pt bdpt pcbpt" (default) chooses the methods.
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$top/build}
axes=${2:-tris res depth survive}
iters=${3:-8}
methods=${METHODS:-pt bdpt pcbpt}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cornell=$top/scenes/cornell-box/scene.xml

# run LABEL WORK SCENE W H DEPTH METHOD [ITERATIONS]: one row of the table
declare -A first
run() {
  local label=$1 work=$2 scene=$3 w=$4 h=$5 depth=$6 m=$7 n=${8:-$iters}
  /usr/bin/time -f "%U %S %M" -o "$tmp/time" "$build/pcbpt-coord" render "$scene" --method "$m" --max-depth "$depth" \
    --width "$w" --height "$h" --spp "$n" --threads 2 --quiet --out "$tmp/o.exr" > "$tmp/out" 2>&1 ||
    { echo "$label $m: render failed: $(tail -1 "$tmp/out")"; return 0; }
  local it
  it=$(sed -n 's/^per iteration (ms):.*; CPU \([0-9.]*\),.*/\1/p' "$tmp/out")
  [ -n "$it" ] || { echo "$label $m: no per-iteration CPU in the render's report"; return 0; }
  it=$(awk -v ms="$it" 'BEGIN { printf "%.4f", ms / 1000 }')
  local key="$axis/$m"
  [ -n "${first[$key]:-}" ] || first[$key]="$it $work"
  read -r user sys rss < "$tmp/time"
  awk -v l="$label" -v m="$m" -v it="$it" -v n="$n" -v u="$user" -v s="$sys" -v rss="$rss" -v work="$work" -v f="${first[$key]}" 'BEGIN {
    split(f, a, " "); printf "%-12s %-6s %12.4f %9.2f %8d %9.2fx %9.2fx\n", l, m, it, u + s - n * it, rss / 1024, it / a[1], work / a[2] }'
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
    for wh in 256x256 512x512 1024x1024 1920x1080 3840x2160; do
      w=${wh%x*} h=${wh#*x} n=$iters
      [ $((w * h)) -le $((1024 * 1024)) ] || n=3
      for m in $methods; do run "$wh" $((w * h)) "$cornell" "$w" "$h" 10 "$m" "$n"; done
    done ;;
  depth)
    header "path length: cornell-box 256x256" maxDepth
    for d in 5 10 20 50; do
      for m in $methods; do run "$d" "$d" "$cornell" 256 256 "$d" "$m"; done
    done ;;
  survive)
    # cornell-box's roulette ends its paths by ~10 vertices; here they last ~20 (q = 0.95), so
    # what grows with the square of the path length shows (BDPT's connections, PCBPT's R x V)
    header "path length where paths survive: the furnace with albedo 0.95, 128x128" maxDepth
    sed 's/value="0.5, 0.5, 0.5"/value="0.95, 0.95, 0.95"/' "$top/scenes/furnace/scene.xml" > "$tmp/bright.xml"
    grep -q '0.95, 0.95, 0.95' "$tmp/bright.xml" || { echo "scenes/furnace: no albedo 0.5 to raise" >&2; exit 1; }
    for d in 5 10 20 50; do
      for m in $methods; do run "$d" "$d" "$tmp/bright.xml" 128 128 "$d" "$m" 4; done
    done ;;
  *) echo "unknown axis '$axis' (tris, res, depth, survive)" >&2; exit 2 ;;
  esac
done
