#!/usr/bin/env bash
# Builds and installs ecrf into a temporary prefix, then uses only that prefix, as a user would:
# the C example through find_package(ecrf) (shared and static) and through pkg-config, the C++
# trainer example through ecrf::trainer, the ABI checks, the Python unittest suite against the
# installed module, a decoder-only build that needs no trainer dependency; prints the library
# sizes and exports.
#
# Debian packages: build-essential cmake ninja-build pkg-config libeigen3-dev libpng-dev
#   libjpeg-dev libexif-dev libzstd-dev nlohmann-json3-dev pybind11-dev python3-dev python3-numpy
#
#   bash scripts/test-install.sh    # ECRF_JOBS=N (default 2), PYTHON=... (default /usr/bin/python3),
#                                   # ECRF_INSTALL_BUILD_DIR=DIR (default: build build-install/),
#                                   # ECRF_TRAIN_ITERS=N for the trainer example (default 30)
set -euo pipefail
cd "$(dirname "$0")/.."
src="$PWD"
jobs="${ECRF_JOBS:-2}"
python="${PYTHON:-/usr/bin/python3}"
prefix="$(mktemp -d)"
work="$(mktemp -d)"
trap 'rm -rf "$prefix" "$work"' EXIT

# ECRF_INSTALL_BUILD_DIR: install from a build tree already configured with
# -DECRF_BUILD_PYTHON=ON -DCMAKE_INSTALL_LIBDIR=lib (scripts/test.sh passes its own) instead of
# building build-install/ from scratch.
build="${ECRF_INSTALL_BUILD_DIR:-build-install}"
echo "== build ($build) and install into $prefix"
if [ -z "${ECRF_INSTALL_BUILD_DIR:-}" ]; then
  cmake -S . -B build-install -G Ninja -DCMAKE_BUILD_TYPE=Release -DECRF_BUILD_TESTS=OFF \
        -DECRF_BUILD_PYTHON=ON -DPython_EXECUTABLE="$python" -DCMAKE_INSTALL_LIBDIR=lib >/dev/null
fi
cmake --build "$build" -j"$jobs"
cmake --install "$build" --prefix "$prefix" >/dev/null
(cd "$prefix" && find . -type f -o -type l | sort | grep -v '/ecrf-trainer/' | sed 's/^\./  /')
echo "  ($(find "$prefix/include/ecrf-trainer" -name '*.h' | wc -l) trainer headers in include/ecrf-trainer)"

echo "== examples with find_package(ecrf CONFIG)"
cmake -S examples -B "$work/cmake" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/cmake" -j"$jobs"
"$work/cmake/decode_render" tests/conformance/scene_builtin.ecrf "$work/cmake.ppm"
# ldd's output is read whole first: with pipefail, `ldd | grep -q` fails whenever grep exits
# before ldd has written everything (SIGPIPE).
libs="$(ldd "$work/cmake/decode_render")"
grep -q "$prefix/lib/libecrf_decoder.so" <<<"$libs" \
  || { echo "FAIL: decode_render does not use the installed shared library"; exit 1; }
cmake -S examples -B "$work/cmake-static" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$prefix" -DECRF_USE_STATIC_LIBS=ON >/dev/null
cmake --build "$work/cmake-static" -j"$jobs" --target decode_render
"$work/cmake-static/decode_render" tests/conformance/scene_builtin.ecrf "$work/static.ppm" >/dev/null
libs="$(ldd "$work/cmake-static/decode_render")"
! grep -q libecrf_decoder <<<"$libs" \
  || { echo "FAIL: ECRF_USE_STATIC_LIBS still links the shared library"; exit 1; }

echo "== example with pkg-config"
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
cc -std=c99 -Wall -Wextra -pedantic -Werror examples/decode_render.c \
   $(pkg-config --cflags --libs ecrf-decoder) -lm \
   -Wl,-rpath,"$(pkg-config --variable=libdir ecrf-decoder)" -o "$work/decode_render"
"$work/decode_render" tests/conformance/scene_builtin.ecrf "$work/pkg-config.ppm" >/dev/null
cmp "$work/cmake.ppm" "$work/pkg-config.ppm"
cmp "$work/cmake.ppm" "$work/static.ppm"
if "$work/decode_render" tests/conformance/scene_builtin.png "$work/bad.ppm" 2>"$work/bad.txt"; then
  echo "FAIL: decode_render accepted a PNG"; exit 1
fi
echo "  error path: $(cat "$work/bad.txt")"

echo "== trainer example against ecrf::trainer"
"$work/cmake/train_encode" "${ECRF_TRAIN_ITERS:-30}"

echo "== installed ecrf tool"
info="$("$prefix/bin/ecrf" info tests/conformance/scene_builtin.ecrf)"
head -3 <<<"$info"

echo "== ABI"
bash tests/install/check_abi.sh "$prefix"

echo "== Python module ($python)"
PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$(echo "$prefix"/lib/python3*/site-packages)" ECRF_SOURCE_DIR="$src" \
  "$python" -m unittest discover -s tests/python -v

echo "== decoder-only build: no trainer dependency"
cmake -S . -B build-install-decoder -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DECRF_BUILD_TRAINER=OFF -DECRF_BUILD_TESTS=OFF -DCMAKE_INSTALL_LIBDIR=lib >/dev/null
if grep -E '^(Eigen3_DIR|PNG_LIBRARY|JPEG_LIBRARY|nlohmann_json_DIR|ZSTD_LIBRARY|OpenMP_CXX_FLAGS)' \
     build-install-decoder/CMakeCache.txt; then
  echo "FAIL: the decoder-only configure looked for a trainer dependency"; exit 1
fi
cmake --build build-install-decoder -j"$jobs"
cmake --install build-install-decoder --prefix "$work/decoder-only" >/dev/null
PKG_CONFIG_PATH="$work/decoder-only/lib/pkgconfig" cc -std=c99 examples/decode_render.c \
  $(PKG_CONFIG_PATH="$work/decoder-only/lib/pkgconfig" pkg-config --cflags --libs ecrf-decoder) -lm \
  -Wl,-rpath,"$work/decoder-only/lib" -o "$work/decode_render_decoder_only"
"$work/decode_render_decoder_only" tests/conformance/scene_builtin.ecrf "$work/decoder-only.ppm" >/dev/null
cmp "$work/cmake.ppm" "$work/decoder-only.ppm"
[ ! -e "$work/decoder-only/lib/cmake/ecrf/ecrfTargets.cmake" ] || \
  ! grep -q 'ecrf::trainer' "$work/decoder-only/lib/cmake/ecrf/ecrfTargets.cmake"

echo "== sizes and exports"
so="$(readlink -f "$prefix/lib/libecrf_decoder.so")"
strip --strip-all -o "$work/stripped.so" "$so"
printf '  %-34s %8d bytes\n' "libecrf_decoder.a" "$(stat -c %s "$prefix/lib/libecrf_decoder.a")" \
  "$(basename "$so")" "$(stat -c %s "$so")" "$(basename "$so") (stripped)" "$(stat -c %s "$work/stripped.so")"
nm -D --defined-only "$so" | awk '{print "  " $3}'
echo "install test passed"
