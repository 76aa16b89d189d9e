#!/usr/bin/env bash
# Installs every Debian 12 package pcbpt needs to build, test and run. Idempotent; needs root.
set -euo pipefail
pkgs=(
  build-essential cmake pkg-config git clang
  libembree-dev libopenexr-dev libuv1-dev libprotobuf-c-dev protobuf-c-compiler
  libexpat1-dev zlib1g-dev libsqlite3-dev libzstd-dev libsodium-dev libcmocka-dev
  libpng-dev libjpeg-dev libcairo2-dev libclang-rt-14-dev libstb-dev
  slurm-wlm munge systemd iproute2 iptables libnetfilter-queue-dev
  chromium-headless-shell
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node.js only validates the Kubernetes manifests (tests/deploy/k8s_manifests.sh); a node
# that is already there (with its own npm) is kept.
command -v node >/dev/null || missing+=(nodejs)
command -v npm >/dev/null || missing+=(npm)
tools=/opt/pcbpt-tools
node_pkgs=(kubernetes-models@4.5.1 yaml@2)
if [ ${#missing[@]} -eq 0 ] && [ -d "$tools/node_modules/kubernetes-models" ]; then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages (${missing[*]} ${node_pkgs[*]}); run as root" >&2
  exit 1
fi
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
if [ ! -d "$tools/node_modules/kubernetes-models" ]; then
  mkdir -p "$tools"
  npm install --prefix "$tools" --no-audit --no-fund --silent "${node_pkgs[@]}"
fi
