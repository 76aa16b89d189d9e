#!/usr/bin/env bash
# Benchmark (not a test): issue 13's acceptance studies on a 2-worker loopback farm (one render
# thread each): ajar-door, bdpt against pcbpt, SECONDS per method, --runs RUNS, on 1 and 2
# workers (--workers 1,2: the 2-worker half is the plain 2-worker study), inner layer, against
# REF. Prints the study's tables (median curves; spread over the runs; scaling with speed-up,
# workers busy and iterations per worker-second) and keeps the folder (report.html). Takes
# about 2 x RUNS x 2 x SECONDS of wall time plus overheads. Usage:
#   tests/bench/farm_study.sh REF.exr [SECONDS] [RUNS] [SIZE] [OUT]
# (defaults: 60 3 128 a new /tmp/pcbpt-farm-study-XXXXXX); env WORKERS (default 1,2) and
# STUDY_FLAGS (e.g. "--pcbpt-k 2") go to the study; REF must be SIZExSIZE, e.g.
# ref-ajar-door.exr of the long reference renders (128x128).
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
ref=${1:?usage: tests/bench/farm_study.sh REF.exr [SECONDS] [RUNS] [SIZE] [OUT]}
seconds=${2:-60}
runs=${3:-3}
size=${4:-128}
B=${BUILD:-$top/build}
T=${5:-$(mktemp -d /tmp/pcbpt-farm-study-XXXXXX)}
mkdir -p "$T"
PIDS=()
cleanup() { for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
echo "bench-token-$$-$RANDOM" >"$T/tok"; chmod 600 "$T/tok"
"$B/pcbpt-coord" serve --listen 127.0.0.1:0 --data-dir "$T/data" --token-file "$T/tok" --port-file "$T/port" \
  >"$T/coord.log" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -s "$T/port" ] && break; sleep 0.1; done
H=(--host "127.0.0.1:$(cat "$T/port")" --token-file "$T/tok")
for w in wa wb; do
  "$B/pcbpt-worker" --connect "127.0.0.1:$(cat "$T/port")" --token-file "$T/tok" --threads 1 --name "$w" \
    --cache-dir "$T/cache-$w" >"$T/$w.log" 2>&1 &
  PIDS+=($!)
done
for _ in $(seq 100); do [ "$("$B/pcbpt-coord" workers "${H[@]}" | grep -c ' w[ab] ')" -ge 2 ] && break; sleep 0.1; done
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$B/pcbpt-coord" study "$top/scenes/ajar-door/scene.xml" --methods bdpt,pcbpt --seconds "$seconds" --runs "$runs" \
  --workers "${WORKERS:-1,2}" --layer inner --reference "$ref" ${STUDY_FLAGS:-} --width "$size" --height "$size" "${H[@]}" --out "$T/out" \
  | grep -v '^  ajar-door'
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "kept $T (report: $T/out/report.html)"
