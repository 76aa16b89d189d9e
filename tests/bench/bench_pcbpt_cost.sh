#!/usr/bin/env bash
# Benchmark (not a test): the issue-16 figure "PCBPT (K=1) time per iteration against BDPT's".
# Per scene, the CPU time (user + sys of the whole process) of one iteration of bdpt and of
# pcbpt --pcbpt-k 1 at SIZExSIZE on one render thread, as the difference between renders of
# HI and LO iterations divided by HI - LO (so loading, the embedded farm's start and the last
# image write cancel), and their ratio. With BASE_BUILD set, the same for that build too (e.g.
# main's), so a change is measured against its base in the same conditions. Runs rotate
# (base bdpt, base pcbpt, build bdpt, build pcbpt, ...) so a load that comes and goes on a
# shared machine spreads over all of them; the spread between rounds says how far to trust
# the means. Usage:
#   tests/bench/bench_pcbpt_cost.sh [BUILD_DIR] [SCENES] [ROUNDS]
#   (defaults: build "ajar-door slit-room" 8; env: BASE_BUILD, SIZE=128, LO=4, HI=32)
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$top/build}
scenes=${2:-ajar-door slit-room}
rounds=${3:-8}
size=${SIZE:-128}
lo=${LO:-4}
hi=${HI:-32}
builds=("$build")
[ -n "${BASE_BUILD:-}" ] && builds=("$BASE_BUILD" "$build")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for scene in $scenes; do
  : > "$tmp/times"
  for _ in $(seq "$rounds"); do
    for b in "${builds[@]}"; do
      for spp in "$lo" "$hi"; do
        for m in bdpt pcbpt; do
          /usr/bin/time -f "%U %S" -o "$tmp/t" "$b/pcbpt-coord" render "$top/scenes/$scene/scene.xml" --method "$m" \
            --pcbpt-k 1 --spp "$spp" --width "$size" --height "$size" --threads 1 --quiet --out "$tmp/o.exr" > /dev/null
          read -r u s < "$tmp/t"
          echo "$b $m $spp $u $s" >> "$tmp/times"
        done
      done
    done
  done
  echo "$scene ${size}x${size}, 1 thread, CPU per iteration from $lo and $hi iterations, $rounds rounds:"
  awk -v lo="$lo" -v hi="$hi" '
    { t = $4 + $5; k = $1 SUBSEP $2 SUBSEP $3; sum[k] += t; n[k]++
      if (!(k in mn) || t < mn[k]) mn[k] = t; if (!(k in mx) || t > mx[k]) mx[k] = t; if (!($1 in seen)) { seen[$1] = 1; order[nb++] = $1 } }
    END {
      for (i = 0; i < nb; i++) {
        b = order[i]
        for (j = 0; j < 2; j++) {
          m = j ? "pcbpt" : "bdpt"; kl = b SUBSEP m SUBSEP lo; kh = b SUBSEP m SUBSEP hi
          per[m] = (sum[kh] / n[kh] - sum[kl] / n[kl]) / (hi - lo)
          spread[m] = sprintf("%.2f-%.2f s", mn[kh], mx[kh])
        }
        printf "  %s: bdpt %.1f ms, pcbpt %.1f ms per iteration, ratio %.3f (runs of %d iterations: bdpt %s, pcbpt %s)\n",
               b, 1000 * per["bdpt"], 1000 * per["pcbpt"], per["pcbpt"] / per["bdpt"], hi, spread["bdpt"], spread["pcbpt"]
      }
    }' "$tmp/times"
done
