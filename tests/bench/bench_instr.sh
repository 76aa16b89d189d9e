#!/usr/bin/env bash
# Benchmark (not a test): instructions executed by two builds of the same render, by callgrind,
# with the functions whose counts differ most. Instruction counts are deterministic for a seed,
# so they resolve the 1-5% cost changes that wall and CPU time on a shared or virtual machine
# cannot (there the same binary alternated with itself varied 1.70-2.41 s per run); memory
# stalls are not in them, so a change that moves data needs timing too. Two runs of one build
# differ by ~0.1% (the embedded farm's keys and temporary names). Needs valgrind
# and python3 (Debian: apt-get install valgrind python3); neither is installed by
# deploy/install-deps.sh, since no build or test needs them. Usage:
#   tests/bench/bench_instr.sh BIN_A BIN_B SCENE.xml [render flags...]
# e.g. tests/bench/bench_instr.sh /tmp/old/pcbpt-coord build/pcbpt-coord scenes/ajar-door/scene.xml \
#        --method pcbpt --spp 4 --width 128 --height 128 --pcbpt-candidates 3
# Renders on one thread with seed 3 unless the flags say otherwise (later flags win).
set -euo pipefail
a=${1:?usage: bench_instr.sh BIN_A BIN_B SCENE.xml [render flags...]}
b=${2:?second binary}
scene=${3:?scene}
shift 3
command -v valgrind >/dev/null || { echo "bench_instr.sh: valgrind is not installed (apt-get install valgrind)" >&2; exit 2; }
command -v callgrind_annotate >/dev/null || { echo "bench_instr.sh: callgrind_annotate is not installed" >&2; exit 2; }
command -v python3 >/dev/null || { echo "bench_instr.sh: python3 is not installed (apt-get install python3)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
i=0
for bin in "$a" "$b"; do
  i=$((i + 1))
  valgrind --tool=callgrind --dump-instr=no --callgrind-out-file="$tmp/cg.$i" \
    "$bin" render "$scene" --threads 1 --seed 3 --quiet "$@" --out "$tmp/out$i.exr" >"$tmp/log$i" 2>&1 ||
    { echo "bench_instr.sh: $bin failed:" >&2; tail -5 "$tmp/log$i" >&2; exit 1; }
  callgrind_annotate --threshold=100 "$tmp/cg.$i" >"$tmp/ann$i" 2>/dev/null
done
python3 - "$tmp/ann1" "$tmp/ann2" "$a" "$b" <<'PY'
import re, sys
def load(path):
    total, funcs = 0, {}
    for line in open(path):
        m = re.match(r'\s*([\d,]+) \(\s*[\d.]+%\)\s+(.*)', line)
        if not m:
            continue
        n, what = int(m.group(1).replace(',', '')), m.group(2)
        if what.startswith('PROGRAM TOTALS'):
            total = n
            continue
        name = what.split(' [')[0].split(':')[-1]
        funcs[name] = funcs.get(name, 0) + n
    return total, funcs
ta, fa = load(sys.argv[1])
tb, fb = load(sys.argv[2])
print(f"instructions: A {ta / 1e6:.1f}M ({sys.argv[3]}), B {tb / 1e6:.1f}M ({sys.argv[4]}), B/A {tb / ta:.4f}")
print("largest differences (M instructions, A -> B, by function):")
keys = sorted(set(fa) | set(fb), key=lambda k: -abs(fb.get(k, 0) - fa.get(k, 0)))
for k in keys[:15]:
    print(f"  {fa.get(k, 0) / 1e6:9.1f} -> {fb.get(k, 0) / 1e6:9.1f}  {(fb.get(k, 0) - fa.get(k, 0)) / 1e6:+8.1f}  {k}")
PY
