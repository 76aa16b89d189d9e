#!/usr/bin/env bash
# Installs the dependencies, builds pcbpt and renders the default scene (scenes/cornell-box)
# to an EXR and a PNG preview. Run from anywhere inside the repository, as root on Debian 12.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
"$top/deploy/install-deps.sh"
cmake -S "$top" -B "$top/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$top/build" -j"$(nproc)"
"$top/build/pcbpt-coord" render "$top/scenes/cornell-box/scene.xml" --spp "${PCBPT_SPP:-64}" \
  --out "$top/build/cornell-box.exr"
echo "image:   $top/build/cornell-box.exr"
echo "preview: $top/build/cornell-box.png"
