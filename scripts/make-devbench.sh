#!/usr/bin/env bash
# Fills .devbench/ for scripts/device-gl-bench.sh (a GPU machine without a browser): builds
# ecrf_gl_replay (benchmarks/gl_replay.cc), records GL traces of the web viewer's WebGL2 renderer
# (web/test/gl_record.mjs: web/gpu_renderer.js + web/gpu_shaders.js on a mock context) and renders
# the native reference images (build/tools/ecrf render, same cameras).
#
#   bash scripts/make-devbench.sh [NAME=PATH.ecrf ...]
#
# Recorded: every scene vector of tests/conformance/manifest.json at its manifest camera (no early
# termination, as the reference renders; reference = the manifest PNG), the vectors in BIG
# (default: one per scene model, scene_builtin = object, scene_unbounded, scene_forward) with that
# camera scaled to SIZES (default 800x800,1920x1080) and the viewer's default options (early stop
# 1e-4; reference = ecrf render of the same camera and early stop), and each NAME=PATH.ecrf at
# SIZES from the viewer's default view (orbit az -60, el 26, r 4; a forward-facing scene's home
# view). Over 40 MiB in all, setups over 1 MiB are zstd-compressed. Needs build-wasm/ (built here
# if missing: scripts/build-wasm.sh), node, zstd. Builds with -j1 (JOBS to change). DEVBENCH: another
# folder than .devbench (emptied first).
set -euo pipefail
cd "$(dirname "$0")/.."
DEV="${DEVBENCH:-.devbench}"  # emptied first
SIZES="${SIZES:-800x800,1920x1080}"
BIG="${BIG:-scene_builtin scene_unbounded scene_forward}"
JOBS="${JOBS:-1}"
PNG_BACK="${PNG_BACK:-5}"  # runs whose image device-gl-bench.sh returns as PNG (800x800 ones first)
for spec in "$@"; do
  [[ "$spec" == *=*.ecrf && -f "${spec#*=}" ]] || { echo "make-devbench: '$spec' is not NAME=PATH.ecrf of an existing file" >&2; exit 2; }
done

grep -qx '/.devbench/' .git/info/exclude 2>/dev/null || echo '/.devbench/' >> .git/info/exclude

if [ ! -d build ]; then cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null; fi
# EXCLUDE_FROM_ALL (benchmarks/CMakeLists.txt): a plain build does not make it.
cmake --build build --target ecrf_gl_replay -j"$JOBS"
[ -x build/tools/ecrf ] || cmake --build build --target ecrf -j"$JOBS"
[ -f build-wasm/ecrf_decoder.js ] || bash scripts/build-wasm.sh

rm -rf "$DEV"
mkdir -p "$DEV/traces" "$DEV/refs" "$DEV/include"
cp build/benchmarks/ecrf_gl_replay "$DEV/"
# Khronos headers, for device-gl-bench.sh to compile the replay there if this binary does not start
# (a glibc older than this machine's).
for h in EGL GLES3 KHR; do cp -r "/usr/include/$h" "$DEV/include/"; done
strip "$DEV/ecrf_gl_replay" 2>/dev/null || true
# The binary must need nothing the GPU machine lacks: EGL, GLESv2 (glvnd, from .gl/*.deb), libc, libm.
needed=$(readelf -d "$DEV/ecrf_gl_replay" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | tr '\n' ' ')
for lib in $needed; do
  case "$lib" in
    libEGL.so.1|libGLESv2.so.2|libc.so.6|libm.so.6|ld-linux-x86-64.so.2|libstdc++.so.6|libgcc_s.so.1) ;;
    *) echo "make-devbench: ecrf_gl_replay needs $lib (only libEGL, libGLESv2, libc, libm allowed)" >&2; exit 1 ;;
  esac
done
glibc=$(objdump -T "$DEV/ecrf_gl_replay" | grep -o 'GLIBC_[0-9.]*' | sort -uV | tail -1)
echo "ecrf_gl_replay needs: $needed(newest symbol version $glibc)"

PY=python3
"$PY" -c 'import numpy' 2>/dev/null || PY=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# An unfiltered PNG (fast to read without Pillow on the GPU machine).
unfiltered() {
  node --input-type=module -e "
    import {readFileSync, writeFileSync} from 'node:fs';
    import {deflateSync} from 'node:zlib';
    import {readPng} from './web/test/gpu_common.mjs';
    const p = readPng(new Uint8Array(readFileSync(process.argv[1])));
    const rows = [];
    for (let y = 0; y < p.height; ++y) {
      const row = Buffer.alloc(1 + 3 * p.width);
      for (let x = 0; x < p.width; ++x) for (let k = 0; k < 3; ++k) row[1 + 3 * x + k] = p.data[p.channels * (y * p.width + x) + (p.channels === 1 ? 0 : k)];
      rows.push(row);
    }
    const crcTable = Array.from({length: 256}, (_, n) => { let c = n; for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1; return c >>> 0; });
    const crc = (b) => { let c = 0xffffffff; for (const x of b) c = crcTable[(c ^ x) & 255] ^ (c >>> 8); return (c ^ 0xffffffff) >>> 0; };
    const chunk = (type, body) => { const t = Buffer.concat([Buffer.from(type, 'latin1'), body]); const len = Buffer.alloc(4); len.writeUInt32BE(body.length); const c = Buffer.alloc(4); c.writeUInt32BE(crc(t)); return Buffer.concat([len, t, c]); };
    const ihdr = Buffer.alloc(13); ihdr.writeUInt32BE(p.width, 0); ihdr.writeUInt32BE(p.height, 4); ihdr[8] = 8; ihdr[9] = 2;
    writeFileSync(process.argv[2], Buffer.concat([Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]), chunk('IHDR', ihdr),
                                                  chunk('IDAT', deflateSync(Buffer.concat(rows), {level: 9})), chunk('IEND', Buffer.alloc(0))]));
  " "$1" "$2"
}
# runs.tsv: trace, reference, min PSNR, return the PNG (1/0), label.
runs_big=()
runs_small=()
pngs=0
# native NAME FILE SIZE EARLYSTOP: the reference of traces/NAME_SIZE.frame.glt.
native() {
  local name=$1 file=$2 size=$3 early=$4
  node -e "const c = require(require('path').resolve('$DEV/traces/${name}_${size}.camera.json')); require('fs').writeFileSync('$tmp/path.json', JSON.stringify(c.transforms));"
  rm -rf "$tmp/r" && mkdir -p "$tmp/r"
  local t0=$SECONDS
  build/tools/ecrf render "$file" --path "$tmp/path.json" --early-stop "$early" --threads 1 -o "$tmp/r" >/dev/null
  unfiltered "$tmp/r/path_000.png" "$DEV/refs/${name}_${size}.png"
  echo "  native ${name} ${size}: $((SECONDS - t0)) s"
}
add_big() {  # NAME SIZE LABEL
  local back=0
  if [[ "$2" == 800x800 && $pngs -lt $PNG_BACK ]]; then back=1; pngs=$((pngs + 1)); fi
  runs_big+=("traces/$1_$2.frame.glt	refs/$1_$2.png	40	$back	$3")
}

conf=tests/conformance
mapfile -t vectors < <(node -e "for (const v of require('./$conf/manifest.json').scene_vectors) console.log(v.file.replace(/\.ecrf\$/, ''), v.scene_model || 'object', v.render.png)")
for line in "${vectors[@]}"; do
  read -r name model png <<<"$line"
  node web/test/gl_record.mjs "$conf/$name.ecrf" --manifest --options '{"earlyStop":0}' --out "$DEV/traces" >/dev/null
  size=$(node -e "const c = require('./$conf/manifest.json').scene_vectors.find((v) => v.file === '$name.ecrf').render.camera; console.log(c.width + 'x' + c.height)")
  unfiltered "$conf/$png" "$DEV/refs/${name}_${size}.png"
  runs_small+=("traces/${name}_${size}.frame.glt	refs/${name}_${size}.png	40	0	$name ($model) manifest camera")
  if [[ " $BIG " == *" $name "* ]]; then
    # The same setup (setScene does not depend on the options): the file is rewritten identically.
    node web/test/gl_record.mjs "$conf/$name.ecrf" --manifest --sizes "$SIZES" --out "$DEV/traces" >/dev/null
    for size in ${SIZES//,/ }; do
      native "$name" "$conf/$name.ecrf" "$size" 0.0001
      add_big "$name" "$size" "$name ($model) manifest camera scaled"
    done
  fi
done
for spec in "$@"; do
  name=${spec%%=*} file=${spec#*=}
  node web/test/gl_record.mjs "$file" --name "$name" --sizes "$SIZES" --out "$DEV/traces" >/dev/null
  for size in ${SIZES//,/ }; do
    native "$name" "$file" "$size" 0.0001
    add_big "$name" "$size" "$name viewer default view"
  done
done
# The big scenes first: the device script may run out of time before the end.
printf '%s\n' "${runs_big[@]}" "${runs_small[@]}" > "$DEV/runs.tsv"

# Over 40 MiB: the setups over 1 MiB are zstd-compressed (ecrf_gl_replay reads them when built
# with libzstd, as here; a replay compiled on the GPU machine needs its zstd.h).
if [ "$(du -sm "$DEV" | cut -f1)" -gt 40 ]; then
  for f in "$DEV"/traces/*.setup.glt; do
    if [ "$(stat -c %s "$f")" -gt 1048576 ]; then zstd -q -f -10 "$f" -o "$f.zst" && mv "$f.zst" "$f"; fi
  done
fi
# Check every trace parses.
cut -f1 "$DEV/runs.tsv" | sed "s|^|$DEV/|" | xargs "$DEV/ecrf_gl_replay" --check >/dev/null
echo "make-devbench: $(wc -l < "$DEV/runs.tsv") runs in $DEV/runs.tsv, $(du -sh "$DEV" | cut -f1) in $DEV"
