#!/usr/bin/env bash
# Equal-time studies (not a test): for each scene with a reference REFS/<scene>.exr, runs
# `pcbpt-coord study` and prints one summary line per scene (final relMSE ratios and time-to-
# error ratios against the first method), for equal-time tables in issue notes. Usage:
#   tests/bench/study.sh REFS_DIR [SCENES] [METHODS] [SECONDS]
# SCENES: space-separated names (default: every REFS/<name>.exr whose scene is found);
# METHODS: default pcbpt,bdpt,pt (the first is the baseline of every ratio); SECONDS: default 60.
# Scenes are looked up as scenes/<name>/scene.xml, then ../shared/scenes/<name>/scene.xml.
# Environment: BUILD (default build), THREADS (default 0 = every core), OUT (default a temporary
# folder, removed at the end; set it to keep each study's CSV, JSON, charts and images),
# STUDY_FLAGS (more flags for every study, e.g. "--layer inner --max-depth 10").
# The reference must have the size the study renders (the scene's film, or --width/--height in
# STUDY_FLAGS) and should use another seed than the study's (default 1).
set -euo pipefail
top=$(cd "$(dirname "$0")/../.." && pwd)
refs=${1:?usage: tests/bench/study.sh REFS_DIR [SCENES] [METHODS] [SECONDS]}
scenes=${2:-}
methods=${3:-pcbpt,bdpt,pt}
seconds=${4:-60}
build=${BUILD:-$top/build}
threads=${THREADS:-0}
read -r -a extra <<<"${STUDY_FLAGS:-}"
if [ -n "${OUT:-}" ]; then
  out=$OUT
  mkdir -p "$out"
else
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi

find_scene() {
  local d
  for d in "$top/scenes" "$top/../shared/scenes"; do
    [ -f "$d/$1/scene.xml" ] && { echo "$d/$1/scene.xml"; return 0; }
  done
  return 1
}

if [ -z "$scenes" ]; then
  for ref in "$refs"/*.exr; do
    [ -e "$ref" ] || continue
    name=$(basename "$ref" .exr)
    find_scene "$name" >/dev/null && scenes="$scenes $name"
  done
fi
[ -n "$scenes" ] || { echo "study.sh: no scene with a reference in $refs" >&2; exit 2; }

status=0
for name in $scenes; do
  scene=$(find_scene "$name") || { echo "$name: scene not found"; status=1; continue; }
  ref="$refs/$name.exr"
  [ -f "$ref" ] || { echo "$name: no reference $ref"; status=1; continue; }
  log="$out/$name.log"
  if ! "$build/pcbpt-coord" study "$scene" --methods "$methods" --seconds "$seconds" --reference "$ref" \
      --out "$out/$name" --threads "$threads" ${extra[@]+"${extra[@]}"} >"$log" 2>&1; then
    echo "$name: study failed: $(tail -1 "$log")"
    status=1
    continue
  fi
  # The sentences after the table are the summary (see pc_study_headline).
  summary=$(grep -E ' needs |does not reach|leaves the ' "$log" | paste -sd '|' | sed 's/|/ | /g')
  echo "$name (${seconds} s each, $methods): $summary"
done
exit $status
