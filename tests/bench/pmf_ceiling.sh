#!/usr/bin/env bash
# Benchmark (not a test): error per iteration and CPU time per iteration of PCBPT settings, for
# the cached-versus-exact connection PMF (issue 17). Error after a fixed number of iterations
# is deterministic for a seed, so unlike equal-time studies it is not disturbed by other load;
# CPU time (user + sys of the whole render, 1 thread) is less disturbed than wall time; the
# render's own wall time per iteration per phase (paths, light tracing, PMF build, connections)
# is printed too. Usage:
#   tests/bench/pmf_ceiling.sh REFS_DIR SCENE ITERATIONS "SEEDS" 'FLAGS' ['FLAGS' ...]
# e.g. tests/bench/pmf_ceiling.sh refs ajar-door 64 "11 12 13" '' '--pmf exact' '--pcbpt-candidates 4'
# prints, per FLAGS, one line per seed (inner and beauty relMSE against REFS_DIR/SCENE.exr,
# CPU ms per iteration) and the mean over the seeds. Renders at the reference's size given by
# SIZE (default 128x128); METHOD (default pcbpt), BUILD (default build) from the environment.
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
refs=${1:?usage: pmf_ceiling.sh REFS_DIR SCENE ITERATIONS \"SEEDS\" FLAGS...}
scene=${2:?scene name}
its=${3:?iterations}
seeds=${4:?seeds}
shift 4
[ $# -gt 0 ] || set -- ''
build=${BUILD:-$top/build}
size=${SIZE:-128x128}
ref="$refs/$scene.exr"
[ -f "$ref" ] || { echo "pmf_ceiling.sh: no reference $ref" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for flags in "$@"; do
  read -r -a extra <<<"$flags"
  sum_i=0 sum_b=0 sum_t=0 n=0
  for seed in $seeds; do
    /usr/bin/time -f "%U %S" -o "$tmp/time" "$build/pcbpt-coord" render "$top/scenes/$scene/scene.xml" \
      --method "${METHOD:-pcbpt}" --spp "$its" --threads 1 --width "${size%x*}" --height "${size#*x}" --seed "$seed" \
      --out "$tmp/a.exr" ${extra[@]+"${extra[@]}"} >"$tmp/log"
    phases=$(sed -n 's/^per iteration (ms): path generation \([0-9.]*\), light tracing \([0-9.]*\), PMF build \([0-9.]*\), sample+connect \([0-9.]*\).*/paths \1 lt \2 pmf \3 connect \4/p' "$tmp/log")
    cmp=$("$build/pcbpt-coord" compare "$tmp/a.exr" "$ref")
    inner=$(echo "$cmp" | awk '$1 == "inner" { print $3 }')
    beauty=$(echo "$cmp" | awk '$1 == "beauty" { print $3 }')
    ms=$(awk -v n="$its" '{ printf "%.1f", ($1 + $2) * 1000 / n }' "$tmp/time")
    echo "$scene [$flags] seed $seed: inner $inner beauty $beauty cpu_ms/it $ms wall_ms/it: $phases"
    read -r sum_i sum_b sum_t n < <(awk -v a="$sum_i" -v b="$sum_b" -v c="$sum_t" -v k="$n" -v i="$inner" -v e="$beauty" -v t="$ms" \
      'BEGIN { print a + i, b + e, c + t, k + 1 }')
  done
  awk -v a="$sum_i" -v b="$sum_b" -v c="$sum_t" -v k="$n" -v s="$scene" -v f="$flags" -v it="$its" \
    'BEGIN { printf "%s [%s] mean of %d seeds after %d iterations: inner %.4g beauty %.4g cpu_ms/it %.1f\n", s, f, k, it, a / k, b / k, c / k }'
done
