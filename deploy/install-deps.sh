#!/usr/bin/env bash
# Installs every Debian 12 package pcbpt needs to build, test and run. Idempotent; needs root.
set -euo pipefail
pkgs=(
  build-essential cmake pkg-config git clang
  libembree-dev libopenexr-dev libuv1-dev libprotobuf-c-dev protobuf-c-compiler
  libexpat1-dev libsqlite3-dev libzstd-dev libsodium-dev libcmocka-dev
  libpng-dev libjpeg-dev libcairo2-dev libclang-rt-14-dev libstb-dev
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages (${missing[*]}); run as root" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
apt-get install -y -q --no-install-recommends "${missing[@]}"
