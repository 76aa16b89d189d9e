#!/usr/bin/env bash
# Benchmark (not a test): the farm over impaired links with a 60 s stall of one worker's link
# (tests/deploy/netns_farm.sh with a longer stall and job). Prints the clean and impaired job
# times, their throughput ratio and the stalled job's time; fails if a count is not exact.
# Needs root (network namespaces). Usage: tests/bench/bench_netns.sh [BUILD_DIR] [STALL_S] [SPP]
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
export PCBPT_BINARY_DIR=${1:-$top/build} PCBPT_SOURCE_DIR=$top
export NETNS_STALL=${2:-60} NETNS_SPP=${3:-600}
exec bash "$top/tests/deploy/netns_farm.sh"
