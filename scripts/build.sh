#!/usr/bin/env bash
# Configures and builds ecrf into build/ (Release, tuned for this CPU unless ECRF_NATIVE=OFF).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DECRF_NATIVE="${ECRF_NATIVE:-ON}" >/dev/null
cmake --build build -j"$(nproc)"
