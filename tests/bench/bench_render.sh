#!/usr/bin/env bash
# Benchmark (not a test): samples/s and Mrays/s of each method on cornell-box 512x512,
# maxDepth 10, with 1 and 2 threads, and the thread speed-up. Usage:
#   tests/bench/bench_render.sh [BUILD_DIR] [METHODS] [SPP]     (defaults: build "pt bdpt" 16)
# Run it on a quiet machine: every figure is wall-clock.
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$top/build}
methods=${2:-pt bdpt}
spp=${3:-16}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for m in $methods; do
  declare -A rate=()
  for t in 1 2; do
    line=$("$build/pcbpt-coord" render "$top/scenes/cornell-box/scene.xml" --method "$m" --max-depth 10 \
      --width 512 --height 512 --spp "$spp" --threads "$t" --quiet --out "$tmp/b.exr")
    echo "$line"
    rate[$t]=$(echo "$line" | head -1 | sed -E 's/.* ([0-9]+) samples\/s.*/\1/')
  done
  awk -v a="${rate[1]}" -v b="${rate[2]}" -v m="$m" 'BEGIN { printf "%s: speed-up 1 -> 2 threads: %.2fx\n", m, b / a }'
done
