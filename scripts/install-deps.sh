#!/usr/bin/env bash
# Installs the Debian packages ecrf builds with; `--test` adds those the test suite needs.
# Skips apt when all are present.
set -euo pipefail
# libexif-dev reads the orientation of camera JPEGs; python3-matplotlib draws the plots of `ecrf report` (which works without it: tables and CSV).
packages=(build-essential cmake ninja-build pkg-config libgtest-dev libeigen3-dev libpng-dev
          libjpeg-dev libexif-dev libzstd-dev nlohmann-json3-dev libcli11-dev zstd python3-matplotlib)
if [ "${1:-}" = "--test" ]; then
  # clang and emscripten build the decoder for scripts/conformance-matrix.sh and the web viewer;
  # clang-format and clang-tidy check the sources (scripts/check-format.sh, check-tidy.sh); the
  # ARM cross compilers and qemu-user run the conformance checks as aarch64 and armhf binaries;
  # chromium runs the viewer's browser tests; pybind11, python3-dev and numpy the Python module;
  # ffmpeg (with ffprobe) the `ecrf render --video` tests; Slurm's daemons and client with munge
  # a one-node cluster for the job-array test of `ecrf report sweep --plan`, parallel its local run;
  # colmap poses a rendered capture for the `ecrf prepare` test; universal-ctags finds where each
  # function begins and ends for the function size check (tests/check_function_size.py).
  packages+=(clang clang-format clang-tidy emscripten chromium pybind11-dev python3-dev python3-numpy
             g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user ffmpeg slurmctld slurmd
             slurm-client munge parallel colmap universal-ctags)
  # npm installs the browser tests' driver (playwright-core); a machine may have its own node.
  command -v npm >/dev/null 2>&1 || packages+=(npm)
fi
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
