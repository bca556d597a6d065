#!/usr/bin/env bash
# The embeddable decoder's render speed at two commits, measured in one run: the decoder sources
# of each (cmake/decoder_sources.txt) built as a distribution builds the library (portable:
# `g++ -O3`, no -march; the MLP kernel is picked at run time) and as scripts/build.sh builds it
# (native: -march=native), each linked to benchmarks/decoder_speed.c (C API only, so it builds
# against either). For every scene and build it prints both commits' milliseconds per view (best
# of the repetitions, the two binaries run alternately), their ratio, and whether every pixel of
# every view is the same (a hash of the RGBA bytes). --builds wasm adds WebAssembly builds (em++
# with scripts/build-wasm.sh's flags, one thread, timed in node by benchmarks/decoder_speed.mjs).
#
#   bash scripts/decoder-speed.sh [--base COMMIT] [--head COMMIT] [--views N] [--size N]
#                                 [--threads N] [--reps N] [--builds portable,native,wasm]
#                                 [--step-scale S] [--early-stop T] SCENE...
#
# --step-scale and --early-stop set the renderer's knobs of SPEC.md 7.8 for both commits (their
# C API must have them); without them the library's defaults.
# --base defaults to 949596a, main when issue #32 (a native renderer twice as fast at identical
# pixels) was filed; --head to the working tree. Needs g++ and gcc (and em++, node for wasm);
# takes a few minutes.
set -euo pipefail
cd "$(dirname "$0")/.."

base=949596a head="" views=4 size=400 threads=2 reps=3 builds=portable,native render=()
scenes=()
while [ $# -gt 0 ]; do
  case "$1" in
    --base) base="$2"; shift 2 ;;
    --head) head="$2"; shift 2 ;;
    --views) views="$2"; shift 2 ;;
    --size) size="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --reps) reps="$2"; shift 2 ;;
    --builds) builds="$2"; shift 2 ;;
    --step-scale) step_scale="$2"; shift 2 ;;
    --early-stop) early_stop="$2"; shift 2 ;;
    -h|--help) sed -n '2,21p' "$0"; exit 0 ;;
    -*) echo "decoder-speed: unknown option $1" >&2; exit 2 ;;
    *) [ -f "$1" ] || { echo "decoder-speed: no file $1" >&2; exit 2; }
       scenes+=("$(realpath "$1")"); shift ;;
  esac
done
[ ${#scenes[@]} -gt 0 ] || { echo "decoder-speed: name at least one .ecrf file" >&2; exit 2; }
# Positional in both benchmark programs: the step scale first (1, the default, when only the
# early stop is given).
if [ -n "${step_scale:-}${early_stop:-}" ]; then render=("${step_scale:-1}"); fi
if [ -n "${early_stop:-}" ]; then render+=("$early_stop"); fi
git rev-parse --verify -q "$base^{commit}" >/dev/null || { echo "decoder-speed: no commit $base" >&2; exit 2; }

work="$(mktemp -d /tmp/ecrf_decoder_speed.XXXXXX)"
trap 'rm -rf "$work"' EXIT
paths=(format decoder include cmake/decoder_sources.txt)
mkdir -p "$work/base" "$work/head"
git archive "$base" "${paths[@]}" | tar -x -C "$work/base"
if [ -n "$head" ]; then
  git archive "$head" "${paths[@]}" | tar -x -C "$work/head"
else
  cp -r format decoder include "$work/head/"
  mkdir -p "$work/head/cmake" && cp cmake/decoder_sources.txt "$work/head/cmake/"
fi
head_name="${head:-working tree}"

jobs="$(nproc)"
build() {  # build TREE FLAVOUR -> TREE/decoder_speed_FLAVOUR
  local tree="$1" flavour="$2" march=()
  [ "$flavour" = native ] && march=(-march=native)
  local obj="$tree/obj_$flavour"
  mkdir -p "$obj"
  (cd "$tree" && grep -v '^#' cmake/decoder_sources.txt | sed '/^$/d' |
     xargs -P "$jobs" -I{} sh -c 'g++ -std=c++17 -O3 "$@" -fno-exceptions -fno-rtti -ffp-contract=off -I. -Iinclude -c {} -o "'"$obj"'/$(echo {} | tr / _).o"' _ "${march[@]}")
  gcc -std=c99 -O2 -I"$tree/include" -I. -c benchmarks/decoder_speed.c -o "$obj/decoder_speed.o"
  g++ "$obj"/*.o -o "$tree/decoder_speed_$flavour" -pthread -lm
}

build_wasm() {  # build_wasm TREE -> TREE/wasm/ecrf_speed.js (+ .wasm)
  local tree="$1"
  if [ -d /usr/share/nodejs ]; then export NODE_PATH="/usr/share/nodejs${NODE_PATH:+:$NODE_PATH}"; fi
  export EMCC_CORES="${EMCC_CORES:-1}"
  mkdir -p "$tree/wasm"
  (cd "$tree" && grep -v '^#' cmake/decoder_sources.txt | sed '/^$/d' |
     xargs -P "$jobs" -I{} sh -c 'em++ -std=c++17 -O3 -msimd128 -fno-exceptions -fno-rtti -ffp-contract=off -I. -Iinclude -c {} -o "wasm/$(echo {} | tr / _).o"')
  em++ -O3 -msimd128 -fno-exceptions -fno-rtti "$tree"/wasm/*.o -o "$tree/wasm/ecrf_speed.js" \
    -sMODULARIZE=1 -sEXPORT_NAME=createEcrfDecoder -sENVIRONMENT=node -sALLOW_MEMORY_GROWTH=1 \
    -sFILESYSTEM=0 -sWASM_BIGINT=0 -sEXPORTED_RUNTIME_METHODS='["HEAPU8","HEAP32","HEAPF32"]' \
    -sEXPORTED_FUNCTIONS='["_ecrf_scene_create","_ecrf_scene_decode","_ecrf_scene_render","_ecrf_render_options_default","_malloc","_free"]'
}

IFS=, read -r -a flavours <<< "$builds"
for f in "${flavours[@]}"; do
  case "$f" in portable|native|wasm) ;; *) echo "decoder-speed: --builds takes portable, native and wasm" >&2; exit 2 ;; esac
  echo "building $f: $base and $head_name" >&2
  if [ "$f" = wasm ]; then
    build_wasm "$work/base"
    build_wasm "$work/head"
  else
    build "$work/base" "$f"
    build "$work/head" "$f"
  fi
done

run() {  # run TREE FLAVOUR SCENE
  if [ "$2" = wasm ]; then
    node benchmarks/decoder_speed.mjs "$1/wasm/ecrf_speed.js" "$3" "$views" "$size" "$reps" "${render[@]}"
  else
    "$1/decoder_speed_$2" "$3" "$views" "$size" "$threads" "$reps" "${render[@]}"
  fi
}

field() { sed -n "s/.*$1=\([^ ]*\).*/\1/p"; }
printf '%s\n' "| scene | build | $base ms/view | $head_name ms/view | ratio | pixels |"
printf '%s\n' "|---|---|---|---|---|---|"
for s in "${scenes[@]}"; do
  for f in "${flavours[@]}"; do
    best_b="" best_h="" hash_b="" hash_h=""
    for round in 1 2; do  # alternate the binaries so that both see the same machine
      out_b="$(run "$work/base" "$f" "$s")"
      out_h="$(run "$work/head" "$f" "$s")"
      mb="$(echo "$out_b" | field ms_per_view)" mh="$(echo "$out_h" | field ms_per_view)"
      hash_b="$(echo "$out_b" | field hash)" hash_h="$(echo "$out_h" | field hash)"
      best_b="$(python3 -c "print(min(x for x in ($mb, ${best_b:-1e30})))")"
      best_h="$(python3 -c "print(min(x for x in ($mh, ${best_h:-1e30})))")"
    done
    same=$([ "$hash_b" = "$hash_h" ] && echo "identical ($hash_h)" || echo "DIFFER ($hash_b / $hash_h)")
    ratio="$(python3 -c "print(f'{$best_b / $best_h:.2f}x')")"
    printf '| %s | %s | %s | %s | %s | %s |\n' "$(basename "$(dirname "$s")")/$(basename "$s")" \
      "$f" "$best_b" "$best_h" "$ratio" "$same"
  done
done
echo "($views orbit views of ${size}x$size, $threads threads (wasm: 1), step scale ${step_scale:-1}, early stop ${early_stop:-default}, best of $reps x 2 repetitions; $(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'), $(nproc) cores)"
