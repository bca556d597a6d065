#!/usr/bin/env bash
# Installs the Debian packages ecrf builds and tests with. Skips apt when all are present.
set -euo pipefail
# python3-matplotlib draws the plots of `ecrf report` (which works without it: tables and CSV).
# clang and emscripten (which brings node) build the decoder for scripts/conformance-matrix.sh.
packages=(build-essential cmake ninja-build pkg-config libgtest-dev libeigen3-dev libpng-dev
          libjpeg-dev libzstd-dev nlohmann-json3-dev zstd python3-matplotlib clang emscripten)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update
$sudo apt-get install -y --no-install-recommends "${missing[@]}"
