#!/usr/bin/env bash
# Benchmark (not a test): farm scaling on cornell-box. Runs the same job on one worker and on
# two workers (one render thread each) and prints iterations/s and the speed-up (expect
# >= 1.9x on an idle machine with two free cores), the coordinator's CPU time
# (/proc/PID/stat utime+stime) per iteration and per upload merged (the count is from the
# coordinator's "done" log line), the bytes the workers sent per iteration and per upload
# (/proc/PID/io wchar: uploads, heartbeats and requests), and iterations per worker
# CPU-second (equal for 1 and 2 workers when the farm adds no work per iteration; on a busy
# machine the speed-up is bounded by the free cores, this figure is not), and what sealing the
# wire costs the coordinator: the bytes the workers sent times bench_seal's CPU per MB opened, as
# a share of the coordinator's CPU, and where perf works, the share of the coordinator's perf
# samples in libsodium (sealing, opening and hashing: the measured upper bound). Usage:
#   tests/bench/bench_farm.sh [BUILD_DIR] [SPP] [SIZE]     (defaults: build 128 256)
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
B=${1:-$top/build}
SPP=${2:-128}
SIZE=${3:-256}
T=$(mktemp -d /tmp/pcbpt-bench-XXXXXX)
PIDS=()
cleanup() { for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$T"; }
trap cleanup EXIT
echo "bench-token-$$-$RANDOM" >"$T/tok"; chmod 600 "$T/tok"
tick=$(getconf CLK_TCK)
cpu_s() { awk -v t="$tick" '{ print ($14 + $15) / t }' "/proc/$1/stat"; }
wchar() { awk '/^wchar/ { print $2 }' "/proc/$1/io"; }
run() { # nworkers
  local n=$1 dir="$T/run$1" W=()
  mkdir -p "$dir"
  "$B/pcbpt-coord" serve --listen 127.0.0.1:0 --data-dir "$dir/data" --token-file "$T/tok" --port-file "$dir/port" \
    >"$dir/coord.log" 2>&1 &
  local C=$!; PIDS+=("$C")
  for _ in $(seq 50); do [ -s "$dir/port" ] && break; sleep 0.1; done
  local H="--host 127.0.0.1:$(cat "$dir/port") --token-file $T/tok"
  for i in $(seq "$n"); do
    "$B/pcbpt-worker" --connect "127.0.0.1:$(cat "$dir/port")" --token-file "$T/tok" --threads 1 --name "w$i" \
      --cache-dir "$dir/cache$i" >"$dir/w$i.log" 2>&1 &
    W+=($!); PIDS+=($!)
  done
  sleep 1
  local P=""
  if [ -n "$PERF" ]; then
    perf record -q -F 999 -p "$C" -o "$dir/perf.data" >/dev/null 2>&1 &
    P=$!; PIDS+=("$P")
  fi
  local c0 w0=0 k0=0; c0=$(cpu_s "$C")
  for p in "${W[@]}"; do w0=$((w0 + $(wchar "$p"))); k0=$(echo "$k0 + $(cpu_s "$p")" | bc); done
  local J; J=$("$B/pcbpt-coord" submit "$top/scenes/cornell-box/scene.xml" --method pt --spp "$SPP" --width "$SIZE" \
    --height "$SIZE" $H | tail -1)
  "$B/pcbpt-coord" wait "$J" $H >/dev/null 2>&1
  local el; el=$("$B/pcbpt-coord" status "$J" $H --json | python3 -c "import json,sys; print(json.load(sys.stdin)['elapsed'])")
  local c1 w1=0 k1=0; c1=$(cpu_s "$C")
  for p in "${W[@]}"; do w1=$((w1 + $(wchar "$p"))); k1=$(echo "$k1 + $(cpu_s "$p")" | bc); done
  if [ -n "$P" ]; then kill -INT "$P"; wait "$P" || true; fi
  kill "$C" "${W[@]}"
  local ips; ips=$(awk -v s="$SPP" -v e="$el" 'BEGIN { printf "%.2f", s / e }')
  local up; up=$(sed -n "s/.*job $J: done, .*(\([0-9]*\) uploads merged.*/\1/p" "$dir/coord.log")
  printf "%d worker(s): %d iterations of %dx%d in %.2f s = %s it/s; coordinator CPU %.2f s (%.1f ms/iteration, %.1f ms/upload, %d uploads); workers sent %.0f KB/iteration (%.0f KB/upload); %.2f iterations per worker CPU-second\n" \
    "$n" "$SPP" "$SIZE" "$SIZE" "$el" "$ips" "$(echo "$c1 - $c0" | bc)" "$(echo "($c1 - $c0) * 1000 / $SPP" | bc -l)" \
    "$(echo "($c1 - $c0) * 1000 / ${up:-1}" | bc -l)" "${up:-0}" \
    "$(echo "($w1 - $w0) / 1024 / $SPP" | bc -l)" "$(echo "($w1 - $w0) / 1024 / ${up:-1}" | bc -l)" "$(echo "$SPP / ($k1 - $k0)" | bc -l)" >&2
  printf "  sealing: the coordinator opened about %.1f MB at %.3f ms/MB = %.1f ms, %.2f%% of its CPU" \
    "$(echo "($w1 - $w0) / 1048576" | bc -l)" "$OPEN_MS" "$(echo "($w1 - $w0) / 1048576 * $OPEN_MS" | bc -l)" \
    "$(echo "($w1 - $w0) / 1048576 * $OPEN_MS / ($c1 - $c0) / 10" | bc -l)" >&2
  if [ -n "$P" ]; then
    local lib; lib=$(perf report -i "$dir/perf.data" --no-children --sort dso --stdio 2>/dev/null |
      awk '/libsodium/ { s += $1 } END { printf "%.2f", s }')
    printf "; perf: %s%% of its samples in libsodium" "$lib" >&2
  fi
  echo >&2
  echo "$ips"
}
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
OPEN_MS=$("$B/tests/bench_seal" 64 | sed -n 's/.*opening costs \([0-9.]*\) ms\/MB.*/\1/p')
PERF=""
if command -v perf >/dev/null && perf record -q -o "$T/probe.data" true >/dev/null 2>&1; then PERF=1
else echo "perf cannot record here: the libsodium share is not measured"; fi
# not in $(...): that subshell's PIDS would be lost to the cleanup if the bench is stopped
run 1 >"$T/r1"; r1=$(cat "$T/r1")
run 2 >"$T/r2"; r2=$(cat "$T/r2")
awk -v a="$r1" -v b="$r2" 'BEGIN { printf "speed-up 1 -> 2 workers: %.2fx\n", b / a }'
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
