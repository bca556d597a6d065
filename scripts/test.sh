#!/usr/bin/env bash
# Builds and runs every test suite: the formatting and clang-tidy checks, an optimised build of
# everything, then format/ and decoder/ again under AddressSanitizer + UndefinedBehaviorSanitizer
# (they parse untrusted bytes), then the
# conformance vectors decoded by g++, clang++ and WebAssembly builds (identical checksums), the
# installed tree (examples, ABI, Python), the web viewer in headless chromium, then a short run of
# every fuzz target.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="$(nproc)"

# The same build/ as scripts/build.sh (Release, tuned for this CPU), with the Python module: after
# this command build/tools/ecrf is there, and every command the README shows next works as written.
echo "== formatting (.clang-format)"
bash scripts/check-format.sh

echo "== release build (build/, as scripts/build.sh) and tests"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DECRF_NATIVE="${ECRF_NATIVE:-ON}" \
      -DECRF_BUILD_PYTHON=ON -DPython_EXECUTABLE=/usr/bin/python3 -DCMAKE_INSTALL_LIBDIR=lib >/dev/null
cmake --build build -j"$jobs"
bash scripts/check-tidy.sh build
ctest --test-dir build -j"$jobs" --output-on-failure

echo "== install tree: CMake package, pkg-config, C and C++ examples, ABI, Python module"
ECRF_INSTALL_BUILD_DIR=build ECRF_JOBS="$jobs" bash scripts/test-install.sh

echo "== format/ and decoder/ as the main job builds them (Release -O3, -Werror sees more there)"
cmake -S . -B build-embedded -G Ninja -DCMAKE_BUILD_TYPE=Release -DECRF_NATIVE=ON \
      -DECRF_BUILD_TRAINER=OFF -DECRF_BUILD_TESTS=OFF >/dev/null
cmake --build build-embedded -j"$jobs"

echo "== format/ and decoder/ under ASan+UBSan"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DECRF_SANITIZE=ON \
      -DECRF_BUILD_TRAINER=OFF >/dev/null
cmake --build build-asan -j"$jobs"
ctest --test-dir build-asan -j"$jobs" --output-on-failure

echo "== conformance checksums on every compiler, -O0 / -O3 -march=native, WebAssembly (node), aarch64 and armhf (qemu)"
bash scripts/conformance-matrix.sh

echo "== web viewer: WebAssembly build, node smoke test, headless chromium (GPU and CPU paths, UI)"
bash scripts/build-wasm.sh
node web/smoke_test.mjs
(cd web/test && npm ci --no-audit --no-fund --loglevel=error)
node web/test/gpu_test.mjs
node web/test/viewer_test.mjs

echo "== fuzz targets, 10 s each (ASan + UBSan, every finding aborts; longer: bash scripts/fuzz.sh 600)"
bash scripts/fuzz.sh 10
