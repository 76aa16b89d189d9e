#!/usr/bin/env bash
# Benchmark (not a test): the farm at scale. Two jobs on cornell-box (PT):
#   many  - 32 workers with one thread each on a small film (default 64x64, 640 iterations);
#   4k    - a 3840x2160 job on 4 workers with one thread each (default 8 iterations).
# For each it prints the coordinator's CPU per upload merged, its peak memory (VmHWM) against
# the size of one film (layers x W x H x 3 doubles), the workers' peak memory, the bytes per
# upload (the workers' /proc/PID/io wchar: uploads, heartbeats and requests), and how long
# `status` took while the job ran (polled every 0.2 s; each figure includes starting the
# client process and its authentication). Exact counts are checked at the end. The workers run
# at nice 19: they stand in for other machines, and here share the coordinator's cores.
# Usage: tests/bench/bench_scale.sh [BUILD_DIR] [many|4k|both] (env: MANY_N, MANY_SIZE,
# MANY_SPP, K4_SPP)
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
B=${1:-$top/build}
WHAT=${2:-both}
T=$(mktemp -d /tmp/pcbpt-scale-XXXXXX)
PIDS=()
cleanup() { for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$T"; }
trap cleanup EXIT
echo "bench-token-$$-$RANDOM" >"$T/tok"; chmod 600 "$T/tok"
tick=$(getconf CLK_TCK)
cpu_s() { awk -v t="$tick" '{ print ($14 + $15) / t }' "/proc/$1/stat"; }
wchar() { awk '/^wchar/ { print $2 }' "/proc/$1/io"; }
hwm_mb() { awk '/^VmHWM/ { printf "%.0f", $2 / 1024 }' "/proc/$1/status"; }
run() { # label nworkers width height spp
  local label=$1 n=$2 w=$3 h=$4 spp=$5 dir="$T/$1" W=()
  mkdir -p "$dir"
  "$B/pcbpt-coord" serve --listen 127.0.0.1:0 --data-dir "$dir/data" --token-file "$T/tok" --port-file "$dir/port" \
    >"$dir/coord.log" 2>&1 &
  local C=$!; PIDS+=("$C")
  for _ in $(seq 100); do [ -s "$dir/port" ] && break; sleep 0.1; done
  local H="--host 127.0.0.1:$(cat "$dir/port") --token-file $T/tok"
  for i in $(seq "$n"); do
    nice -n 19 "$B/pcbpt-worker" --connect "127.0.0.1:$(cat "$dir/port")" --token-file "$T/tok" --threads 1 --name "w$i" \
      --cache-dir "$dir/cache$i" >"$dir/w$i.log" 2>&1 &
    W+=($!); PIDS+=($!)
  done
  for _ in $(seq 300); do
    [ "$("$B/pcbpt-coord" workers $H --json 2>/dev/null | python3 -c 'import json,sys; print(len(json.load(sys.stdin)))' \
      2>/dev/null || echo 0)" = "$n" ] && break
    sleep 0.2
  done
  local c0 w0=0; c0=$(cpu_s "$C")
  for p in "${W[@]}"; do w0=$((w0 + $(wchar "$p"))); done
  local J; J=$("$B/pcbpt-coord" submit "$top/scenes/cornell-box/scene.xml" --method pt --spp "$spp" --width "$w" \
    --height "$h" $H | tail -1)
  # status latency while the job runs
  python3 - "$B/pcbpt-coord" "$J" "$dir/lat" $H <<'PY' &
import json, subprocess, sys, time
coord, job, out, args = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
lat = []
while True:
    t0 = time.monotonic()
    r = subprocess.run([coord, "status", job, "--json"] + args, capture_output=True, text=True)
    lat.append(time.monotonic() - t0)
    if r.returncode != 0 or json.loads(r.stdout)["state"] != "running":
        break
    time.sleep(0.2)
lat.sort()
slow = sum(1 for x in lat if x > 0.1)
with open(out, "w") as f:
    f.write(f"{len(lat)} {1000 * lat[len(lat) // 2]:.1f} {1000 * lat[int(0.9 * (len(lat) - 1))]:.1f} {1000 * lat[-1]:.1f} {slow}\n")
PY
  local L=$!
  "$B/pcbpt-coord" wait "$J" $H >/dev/null 2>&1
  wait $L
  local st; st=$("$B/pcbpt-coord" status "$J" $H --json)
  local c1 w1=0 wh=0 whs=0; c1=$(cpu_s "$C")
  for p in "${W[@]}"; do
    w1=$((w1 + $(wchar "$p")))
    local m; m=$(hwm_mb "$p"); whs=$((whs + m)); [ "$m" -gt "$wh" ] && wh=$m
  done
  local ch; ch=$(hwm_mb "$C")
  kill "$C" "${W[@]}"
  local up; up=$(sed -n "s/.*job $J: done, .*(\([0-9]*\) uploads merged.*/\1/p" "$dir/coord.log")
  local it; it=$(echo "$st" | python3 -c "import json,sys; print(json.load(sys.stdin)['iterations'])")
  local el; el=$(echo "$st" | python3 -c "import json,sys; print(json.load(sys.stdin)['elapsed'])")
  [ "$it" = "$spp" ] || { echo "FAIL: $label: $it iterations, expected $spp"; exit 1; }
  # one film: pt, nee, lt, inner, beauty_sq x W x H x 3 doubles (FILM_LAYERS if it keeps others)
  local nl=${FILM_LAYERS:-5}
  local film_mb; film_mb=$(echo "$nl * $w * $h * 3 * 8 / 1048576" | bc -l)
  read -r nlat med p90 mx slow <"$dir/lat"
  printf "%s: %d workers x 1 thread, %dx%d, %d iterations in %.1f s (exact); %d uploads\n" "$label" "$n" "$w" "$h" "$it" "$el" "${up:-0}"
  printf "  coordinator: CPU %.2f s = %.1f ms per upload; peak memory %d MB = %.2f films of %.0f MB (%d layers)\n" \
    "$(echo "$c1 - $c0" | bc)" "$(echo "($c1 - $c0) * 1000 / ${up:-1}" | bc -l)" "$ch" "$(echo "$ch / $film_mb" | bc -l)" \
    "$film_mb" "$nl"
  printf "  workers: peak memory max %d MB, sum %d MB; sent %.0f KB per upload\n" "$wh" "$whs" \
    "$(echo "($w1 - $w0) / 1024 / ${up:-1}" | bc -l)"
  printf "  status while running: %d calls, median %s ms, p90 %s ms, max %s ms, %d over 100 ms\n" "$nlat" "$med" "$p90" "$mx" "$slow"
}
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
case $WHAT in many|both) run many "${MANY_N:-32}" "${MANY_SIZE:-64}" "${MANY_SIZE:-64}" "${MANY_SPP:-640}" ;; esac
case $WHAT in 4k|both) run 4k 4 3840 2160 "${K4_SPP:-8}" ;; esac
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
