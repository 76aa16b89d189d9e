#!/usr/bin/env bash
# Benchmark (not a test): the issue-16 figure. BDPT (or METHOD) on cornell-box 512x512, maxDepth
# 10, 2 threads: samples/s by the wall clock, samples per CPU-second (getrusage of the whole
# process: render threads and the embedded farm), and, when `perf` is installed, the share of
# the CPU samples inside Embree, the embedded farm's packing and image writes (zstd, zlib,
# kernel), and the renderer's own code, with the top symbols; and by thread, the render threads
# against the embedded farm and the client (uploads, coordinator, worker loop, merges, image
# writes, the client's start, fetch and preview). On a shared machine the wall figure is
# disturbed; 2 x samples per CPU-second is what 2 free cores would give. Usage:
#   tests/bench/bench_cornell.sh [BUILD_DIR] [METHOD] [SPP] [SCENE] [SIZE]
#   (defaults: build bdpt 16 scenes/cornell-box/scene.xml 512)
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$top/build}
method=${2:-bdpt}
spp=${3:-16}
scene=${4:-$top/scenes/cornell-box/scene.xml}
size=${5:-512}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmd=("$build/pcbpt-coord" render "$scene" --method "$method" --max-depth 10 --width "$size" --height "$size"
     --spp "$spp" --threads 2 --quiet --out "$tmp/b.exr")
if command -v perf >/dev/null && perf record -q -o "$tmp/probe.data" true >/dev/null 2>&1; then
  perf record -q -F 2000 -o "$tmp/perf.data" -- /usr/bin/time -f "%U %S" -o "$tmp/time" "${cmd[@]}" > "$tmp/out"
else
  echo "(perf not available: no CPU split)"
  /usr/bin/time -f "%U %S" -o "$tmp/time" "${cmd[@]}" > "$tmp/out"
fi
cat "$tmp/out"
samples=$((size * size * spp))
read -r user sys < "$tmp/time"
awk -v n="$samples" -v u="$user" -v s="$sys" 'BEGIN {
  printf "CPU time %.2f s (user %.2f, sys %.2f): %.0f samples per CPU-second, %.0f samples/s on 2 free cores\n",
         u + s, u, s, n / (u + s), 2 * n / (u + s) }'
if [ -f "$tmp/perf.data" ]; then
  perf report -i "$tmp/perf.data" --no-children --sort dso -g none --percent-limit 0 2>/dev/null |
    awk '/^ +[0-9.]+%/ { p = $1; sub("%", "", p); d = $2
           if (d ~ /embree/) e += p; else if (d ~ /zstd|libz\.|OpenEXR|png|kernel/) f += p; else if (d ~ /pcbpt-coord|libm|vdso/) r += p; else o += p }
         END { printf "CPU share: Embree %.1f%%, farm+images (zstd, zlib, EXR, kernel) %.1f%%, renderer %.1f%%, other %.1f%%\n", e, f, r, o }'
  # By thread (threads are named for their role, pc_thread_set_name): the render threads
  # against the embedded farm and the client, which is the farm's own cost as issue 16 counts it.
  perf report -i "$tmp/perf.data" --no-children --sort comm -g none 2>/dev/null |
    awk '/^ +[0-9.]+%/ && $2 != "time" { p = $1; sub("%", "", p); if ($2 == "pc-render") r += p; else { f += p; part = part sprintf(", %s %.2f%%", $2 == "pcbpt-coord" ? "client" : $2, p) } }
         END { printf "CPU by thread: render threads %.1f%%, farm and client %.1f%% (%s)\n", r, f, substr(part, 3) }'
  echo "top symbols:"
  perf report -i "$tmp/perf.data" --no-children --sort dso,symbol -g none 2>/dev/null | grep -v '^#' | grep -v '^$' | head -15
fi
