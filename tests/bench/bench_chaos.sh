#!/usr/bin/env bash
# Benchmark (not a ctest test; ctest runs 3 trials as farm/chaos): tests/farm/chaos.sh with
# many trials of random SIGKILL/SIGSTOP of the coordinator and the workers, each checked for
# exactly the requested iterations and an exact image; prints one line per trial (events and
# seconds) and the total. Usage:
#   tests/bench/bench_chaos.sh [BUILD_DIR] [TRIALS] [SEED]     (defaults: build 20 random)
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
export PCBPT_BINARY_DIR=${1:-$top/build} PCBPT_SOURCE_DIR=$top
export CHAOS_TRIALS=${2:-20}
[ -n "${3:-}" ] && export CHAOS_SEED=$3
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
start=$(date +%s.%N)
bash "$top/tests/farm/chaos.sh" 2>&1 | grep -v " Killed "
echo "$CHAOS_TRIALS trials in $(echo "$(date +%s.%N) - $start" | bc | cut -c1-6) s"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
