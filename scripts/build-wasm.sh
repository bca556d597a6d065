#!/usr/bin/env bash
# Builds the embeddable decoder (the decoder halves of format/ + decoder/, nothing else) to WebAssembly with Emscripten:
# build-wasm/ecrf_decoder.js + build-wasm/ecrf_decoder.wasm, for web/ (the viewer and its
# node smoke test). Not part of scripts/build.sh or the CMake build; scripts/test.sh (CI) runs it.
#
#   apt-get install -y emscripten      # Debian's emscripten 3.1.6
#   bash scripts/build-wasm.sh         # ECRF_WASM_OPT=-O2 to change the optimisation level
#   node web/smoke_test.mjs      # checks it against tests/conformance, prints timings
#
# No pthreads: the page renders with num_threads = 1, so the decoder never creates a std::thread.
set -euo pipefail
cd "$(dirname "$0")/.."

command -v emcc >/dev/null || { echo "emcc not found: apt-get install -y emscripten" >&2; exit 1; }
# Debian's emscripten runs its JS tools with the system node and expects Debian's node modules
# (node-acorn, ...) in /usr/share/nodejs; a node that does not search there (e.g. one from
# another repository) needs NODE_PATH.
if [ -d /usr/share/nodejs ]; then export NODE_PATH="/usr/share/nodejs${NODE_PATH:+:$NODE_PATH}"; fi
# One core for compiling and for building emscripten's system libraries on first use.
export EMCC_CORES="${EMCC_CORES:-1}"

OPT="${ECRF_WASM_OPT:--O3}"
# 128-bit wasm SIMD (every current browser, node >= 16.4): the decoder's generic 4-float vectors
# (decoder/mlp.cc) become simd128 instructions instead of scalar code. ECRF_WASM_SIMD=0: without.
SIMD=()
if [ "${ECRF_WASM_SIMD:-1}" != 0 ]; then SIMD=(-msimd128); fi
OUT=build-wasm
mkdir -p "$OUT/obj"

CXXFLAGS=(-std=c++17 "$OPT" "${SIMD[@]}" -fno-exceptions -fno-rtti -ffp-contract=off -Wall -Wextra -I. -Iinclude)
# Objects are reused while the flags and sources are unchanged.
if [ "$(cat "$OUT/obj/flags" 2>/dev/null)" != "${CXXFLAGS[*]}" ]; then
  rm -f "$OUT"/obj/*.o
  echo "${CXXFLAGS[*]}" > "$OUT/obj/flags"
fi
objs=()
# Exactly the embeddable decoder's sources (the list libecrf_decoder is built from): no encoder code.
mapfile -t sources < <(grep -v '^#' cmake/decoder_sources.txt | sed '/^$/d')
for src in "${sources[@]}"; do
  obj="$OUT/obj/$(echo "${src%.cc}" | tr / _).o"
  if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ -n "$(find format decoder -name '*.h' -newer "$obj" -print -quit)" ]; then
    echo "emcc $src"
    em++ "${CXXFLAGS[@]}" -c "$src" -o "$obj"
  fi
  objs+=("$obj")
done

# The exports are the C API as include/ecrf/decoder.h declares it (every ECRF_API function), plus
# the allocator the viewer passes buffers through: the header is their one list.
mapfile -t api < <(sed -n 's/^ECRF_API .*[ *]\(ecrf_[a-z0-9_]*\)(.*/\1/p' include/ecrf/decoder.h)
[ ${#api[@]} -gt 0 ] || { echo "no ECRF_API functions found in include/ecrf/decoder.h" >&2; exit 1; }
EXPORTS="[$(printf '"_%s",' "${api[@]}")\"_malloc\",\"_free\"]"
RUNTIME='["cwrap","ccall","UTF8ToString","HEAPU8","HEAP32","HEAPU32","HEAPF32"]'

echo "link $OUT/ecrf_decoder.js"
em++ "$OPT" "${SIMD[@]}" -fno-exceptions -fno-rtti "${objs[@]}" -o "$OUT/ecrf_decoder.js" \
  -sMODULARIZE=1 -sEXPORT_NAME=createEcrfDecoder -sENVIRONMENT=web,worker,node \
  -sALLOW_MEMORY_GROWTH=1 -sFILESYSTEM=0 -sWASM_BIGINT=0 \
  -sEXPORTED_FUNCTIONS="$EXPORTS" -sEXPORTED_RUNTIME_METHODS="$RUNTIME"

ls -l "$OUT/ecrf_decoder.js" "$OUT/ecrf_decoder.wasm"
