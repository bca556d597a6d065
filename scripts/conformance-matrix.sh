#!/usr/bin/env bash
# Proves that decoding does not depend on the platform (SPEC.md 6.5): builds format/ + decoder/ +
# tests/decoder/conformance_checksums.cc with every available compiler at -O0 and at -O3
# -march=native, for WebAssembly under node when em++ is installed, and for 64-bit and 32-bit ARM
# (aarch64, armhf) under qemu-user when the cross compilers are installed, decodes every vector of
# tests/conformance with each build, and fails unless all builds print the same checksums (grids,
# occupancy, MLP, coefficient outputs) and those match the checked-in ones. The reference-camera
# renders must be bit-identical too: SPEC.md 7.7 allows differences between renderers, but ours,
# built with -ffp-contract=off (7: no fused multiply-add), gives the same pixels everywhere we
# build it, and a difference means a compiler changed the arithmetic (ECRF_MATRIX_RENDERS=report
# only reports them, e.g. for a platform whose libm rounds exp differently).
#
#   bash scripts/conformance-matrix.sh   # ECRF_MATRIX_WASM=0 skips WebAssembly, ECRF_MATRIX_ARM=0 ARM
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=build-matrix
mkdir -p "$OUT"
jobs="$(nproc)"
mapfile -t sources < <(grep -v '^#' cmake/decoder_sources.txt | sed '/^$/d')
sources+=(tests/decoder/conformance_checksums.cc)
common=(-std=c++17 -fno-exceptions -fno-rtti -ffp-contract=off -Wall -Wextra -Werror -I. -Iinclude)

# build NAME COMPILER EXECUTABLE FLAGS...: compiles every source in parallel, links
# $OUT/NAME/EXECUTABLE with the flags and LINK_EXTRA.
build() {
  local name="$1" cxx="$2" exe="$3"; shift 3
  local dir="$OUT/$name" objs=() pids=() src obj
  mkdir -p "$dir"
  for src in "${sources[@]}"; do
    obj="$dir/$(echo "${src%.cc}" | tr / _).o"
    objs+=("$obj")
    "$cxx" "${common[@]}" "$@" -c "$src" -o "$obj" &
    pids+=($!)
    if [ "${#pids[@]}" -ge "$jobs" ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
  done
  for p in "${pids[@]}"; do wait "$p"; done
  "$cxx" "$@" "${objs[@]}" -o "$dir/$exe" "${LINK_EXTRA[@]}"
}

configs=()
for cxx in g++ clang++; do
  command -v "$cxx" >/dev/null || { echo "($cxx not installed: skipped)"; continue; }
  configs+=("$cxx-O0:$cxx:-O0" "$cxx-O3-native:$cxx:-O3 -march=native")
done

status=0
reference=""
for c in "${configs[@]}"; do
  IFS=: read -r name cxx flags <<<"$c"
  echo "== $name"
  LINK_EXTRA=(-pthread)
  # shellcheck disable=SC2086
  build "$name" "$cxx" checker $flags
  "$OUT/$name/checker" tests/conformance >"$OUT/$name/out.txt" || status=1
done

if [ "${ECRF_MATRIX_WASM:-1}" != 0 ] && command -v em++ >/dev/null; then
  echo "== wasm (em++ -O3, node)"
  if [ -d /usr/share/nodejs ]; then export NODE_PATH="/usr/share/nodejs${NODE_PATH:+:$NODE_PATH}"; fi
  export EMCC_CORES="${EMCC_CORES:-$jobs}"
  # SINGLE_FILE: the wasm travels inside the .js; node >= 18 would otherwise fetch() it by path.
  LINK_EXTRA=(-sNODERAWFS=1 -sALLOW_MEMORY_GROWTH=1 -sENVIRONMENT=node -sSINGLE_FILE=1)
  build wasm em++ checker.js -O3
  node "$OUT/wasm/checker.js" tests/conformance >"$OUT/wasm/out.txt" || status=1
  configs+=("wasm:em++:-O3")
else
  echo "(em++ not installed or ECRF_MATRIX_WASM=0: WebAssembly skipped)"
fi

# 64-bit and 32-bit ARM, the small devices the decoder is for: Debian's cross compilers, the
# checker linked statically and run under qemu-user (no target sysroot needed at run time).
# Each checker runs single-threaded under qemu for about a minute: both run side by side.
if [ "${ECRF_MATRIX_ARM:-1}" != 0 ]; then
  arm_runs=()
  for target in aarch64-linux-gnu:qemu-aarch64 arm-linux-gnueabihf:qemu-arm; do
    IFS=: read -r triple qemu <<<"$target"
    if command -v "$triple-g++" >/dev/null && command -v "$qemu" >/dev/null; then
      name="$triple-O2"
      echo "== $name (under $qemu)"
      LINK_EXTRA=(-static -pthread)
      build "$name" "$triple-g++" checker -O2
      "$qemu" "$OUT/$name/checker" tests/conformance >"$OUT/$name/out.txt" &
      arm_runs+=($!)
      configs+=("$name:$triple-g++:-O2")
    else
      echo "($triple-g++ or $qemu not installed: $triple skipped)"
    fi
  done
  for p in "${arm_runs[@]}"; do wait "$p" || status=1; done
fi

for c in "${configs[@]}"; do
  name="${c%%:*}"
  grep -v '^render ' "$OUT/$name/out.txt" >"$OUT/$name/checksums.txt"
  grep '^render ' "$OUT/$name/out.txt" >"$OUT/$name/renders.txt" || true
  if [ -z "$reference" ]; then reference="$name"; continue; fi
  if ! cmp -s "$OUT/$reference/checksums.txt" "$OUT/$name/checksums.txt"; then
    echo "checksums of $name differ from $reference:"
    diff "$OUT/$reference/checksums.txt" "$OUT/$name/checksums.txt" || true
    status=1
  fi
  if cmp -s "$OUT/$reference/renders.txt" "$OUT/$name/renders.txt"; then
    echo "renders of $name: bit-identical to $reference"
  else
    echo "renders of $name: $(diff "$OUT/$reference/renders.txt" "$OUT/$name/renders.txt" | grep -c '^>') of $(wc -l <"$OUT/$name/renders.txt") differ from $reference"
    [ "${ECRF_MATRIX_RENDERS:-strict}" = report ] || status=1
  fi
done
cat "$OUT/$reference/checksums.txt"
echo "builds: ${configs[*]%%:*}"
[ "$status" = 0 ] && echo "conformance matrix: identical checksums on every build" || echo "conformance matrix: FAILED"
exit "$status"
