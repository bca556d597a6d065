#!/usr/bin/env bash
# Frame times and image check of the web viewer's WebGL2 renderer on a GPU machine without a
# browser: replays the traces of .devbench/ (scripts/make-devbench.sh) with .devbench/ecrf_gl_replay
# (compiled here from benchmarks/gl_replay.cc, gl_player.cc, gl_replay_context.cc and gl_trace.cc
# when that binary does not start) on a headless EGL + OpenGL ES 3 context, and compares each image
# with its native reference (benchmarks/gl_replay_compare.py, PSNR >= 40 dB). Run from the
# repository root with .gl/*.deb (glvnd's libEGL / libGLESv2) and .devbench/ beside it:
#
#   bash scripts/device-gl-bench.sh
#
# Writes to $OUT (default /tmp/devbench-out): results.jsonl (one JSON line per run: the replay's
# line, ms per frame min / median, GL strings, plus psnr, max_diff, within2, pass), log.txt, and
# the PNGs of the runs runs.tsv marks (at most a handful). FRAMES (20), MAX_SECONDS per run (5),
# RUN_TIMEOUT (120 s) and DEADLINE (420 s for the whole script, after which the remaining runs are
# skipped and listed) can be set in the environment.
set -uo pipefail
cd "$(dirname "$0")/.."
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig;
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
# (Elsewhere, e.g. a Mesa machine trying this script: glvnd's own vendor files.)
[ -f "$__EGL_VENDOR_LIBRARY_FILENAMES" ] || unset __EGL_VENDOR_LIBRARY_FILENAMES
# The NVIDIA user-space driver (libEGL_nvidia.so.0, ...) where such containers mount it.
for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib; do
  [ -d "$d" ] && export LD_LIBRARY_PATH="$d${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
done

OUT="${OUT:-/tmp/devbench-out}"
FRAMES="${FRAMES:-20}"
MAX_SECONDS="${MAX_SECONDS:-5}"
RUN_TIMEOUT="${RUN_TIMEOUT:-120}"
DEADLINE="${DEADLINE:-420}"
DEV="${DEVBENCH:-.devbench}"
mkdir -p "$OUT"
LOG="$OUT/log.txt"
RES="$OUT/results.jsonl"
: > "$RES"
PY=python3
"$PY" -c 'import numpy' 2>/dev/null || PY=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

main() {
  echo "== $(date -u +%FT%TZ) $(uname -m) $(nproc) cores"
  nvidia-smi || echo "nvidia-smi failed"
  echo "== EGL vendor file:"; cat "${__EGL_VENDOR_LIBRARY_FILENAMES:-/dev/null}" 2>&1
  echo "== NVIDIA GL/EGL libraries:"
  ls /usr/local/nvidia/lib64 /usr/lib/x86_64-linux-gnu 2>/dev/null | grep -E 'EGL_nvidia|GLESv2_nvidia|nvidia-eglcore|nvidia-glsi|nvidia-glcore' | sort -u | tr '\n' ' '; echo
  ldconfig -p | grep -E 'libEGL\.so\.1|libGLESv2\.so\.2|libEGL_nvidia' || true
  echo "== ecrf_gl_replay:"; ldd "$DEV/ecrf_gl_replay"
  REPLAY="$DEV/ecrf_gl_replay"
  if ! "$REPLAY" --help >/dev/null 2>&1; then
    # Built on a newer glibc than this one: compile it here (headers carried in $DEV/include).
    echo "prebuilt ecrf_gl_replay does not start: $("$REPLAY" --help 2>&1 | head -2 | tr '\n' ' ')- compiling it"
    zstd=()
    if echo '#include <zstd.h>' | c++ -E -x c++ - >/dev/null 2>&1; then zstd=(-DECRF_GL_REPLAY_ZSTD -lzstd); fi
    lib=$(dirname "$(ldconfig -p | grep -m1 'libEGL\.so\.1 ' | sed 's/.*=> //')")
    c++ -O2 -std=c++17 -I. -I"$DEV/include" benchmarks/gl_replay.cc benchmarks/gl_player.cc \
      benchmarks/gl_replay_context.cc benchmarks/gl_trace.cc -o "$tmp/ecrf_gl_replay" \
      "$lib/libEGL.so.1" "$lib/libGLESv2.so.2" "${zstd[@]}" && REPLAY="$tmp/ecrf_gl_replay"
  fi
  if [ ! -f "$DEV/runs.tsv" ]; then echo "no $DEV/runs.tsv: run scripts/make-devbench.sh first"; return 1; fi

  start=$SECONDS
  n=0 pass=0 fail=0 skipped=()
  while IFS=$'\t' read -r trace ref minpsnr back label; do
    [ -n "$trace" ] || continue
    if [ $((SECONDS - start)) -ge "$DEADLINE" ]; then skipped+=("$trace"); continue; fi
    n=$((n + 1))
    stem=$(basename "$trace" .frame.glt)
    rm -f "$tmp/line.json" "$tmp/$stem.ppm"
    t0=$SECONDS
    timeout "$RUN_TIMEOUT" "$REPLAY" --frames "$FRAMES" --max-seconds "$MAX_SECONDS" \
      --out-dir "$tmp" "$DEV/$trace" > "$tmp/line.json"
    rc=$?
    if [ $rc -ne 0 ] && ! grep -q '"ok": false' "$tmp/line.json" 2>/dev/null; then
      echo "{\"trace\": \"$DEV/$trace\", \"ok\": false, \"error\": \"exit status $rc (124: timeout after $RUN_TIMEOUT s)\"}" > "$tmp/line.json"
    fi
    pngarg=()
    [ "$back" = 1 ] && pngarg=(--png "$OUT/$stem.png")
    if [ -f "$tmp/$stem.ppm" ]; then
      "$PY" benchmarks/gl_replay_compare.py "$tmp/$stem.ppm" "$DEV/$ref" --min-psnr "$minpsnr" \
        --merge "$tmp/line.json" "${pngarg[@]}" > "$tmp/full.json"
    else
      "$PY" -c 'import json,sys; d=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1]); d["pass"]=False; print(json.dumps(d))' \
        "$tmp/line.json" > "$tmp/full.json" 2>/dev/null || cp "$tmp/line.json" "$tmp/full.json"
    fi
    "$PY" -c 'import json,sys; d=json.loads(open(sys.argv[1]).read()); d["label"]=sys.argv[2]; print(json.dumps(d))' \
      "$tmp/full.json" "$label" >> "$RES" 2>/dev/null || cat "$tmp/full.json" >> "$RES"
    line=$(tail -1 "$RES")
    if grep -q '"pass": true' <<<"$line"; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
    "$PY" -c '
import json, sys
d = json.loads(sys.argv[1])
if d.get("ok"):
    print("%-40s %4dx%-4d median %9.3f ms  min %9.3f ms  (%d frames, setup %.0f ms)  PSNR %s dB  max diff %s  %s" % (
        d["trace"].split("/")[-1], d["width"], d["height"], d["ms_median"], d["ms_min"], d["frames"],
        d["setup_ms"], d.get("psnr"), d.get("max_diff"), "ok" if d.get("pass") else "FAIL"))
else:
    print("%-46s FAIL: %s" % (d.get("trace", "?").split("/")[-1], d.get("error") or d.get("compare_error")))
' "$line" 2>/dev/null || echo "$line"
    echo "   ($((SECONDS - t0)) s)"
  done < "$DEV/runs.tsv"

  echo "== $n runs: $pass passed, $fail failed, ${#skipped[@]} skipped (deadline ${DEADLINE} s) in $((SECONDS - start)) s"
  for s in "${skipped[@]}"; do echo "skipped: $s"; done
  [ "$fail" -eq 0 ] && [ ${#skipped[@]} -eq 0 ]
}

main 2>&1 | tee "$LOG"
exit "${PIPESTATUS[0]}"
