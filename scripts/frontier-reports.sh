#!/usr/bin/env bash
# Regenerates (or continues) the frontier sweeps of issue #31 (docs/reports/frontier/{chair,mic}):
# the named rate points trained 4500 iterations instead of the `fast` preset's 3000 (every
# milestone scales with them), ratios against the baseline's 3000-iteration lambda = 0 float32
# model (--reference), then `ecrf report compare` against the baseline into compare_baseline.*.
# About 45-60 minutes per point on 2 cores. Finished runs under REPORT/runs are reused (their
# committed config.json and metrics.json suffice), so each session can add points.
#
# TARGETS adds file sizes (`report sweep --targets`); chair's committed sweep has TARGETS=316KB,127KB,
# the largest files of at least 80x and 200x against the 25,438,668-byte reference.
#
#   bash scripts/frontier-reports.sh [chair mic]   # RATES=medium,low, TARGETS=, DATA_ROOT=../shared/data/nerf_synthetic_400, ECRF=build/tools/ecrf
set -euo pipefail
cd "$(dirname "$0")/.."
ecrf="${ECRF:-build/tools/ecrf}"
data_root="${DATA_ROOT:-../shared/data/nerf_synthetic_400}"
rates="${RATES:-medium,low}"
targets=()
[ -z "${TARGETS:-}" ] || targets=(--targets "$TARGETS")
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(chair mic)
for scene in "${scenes[@]}"; do
  out="docs/reports/frontier/$scene"
  "$ecrf" report sweep --data "$data_root/$scene" --rates "$rates" "${targets[@]}" --iters 4500 --test-stride 10 \
    --reference "docs/reports/baseline_2026_11/$scene" -o "$out"
  # BD-rate needs two points on each curve: with RATES=medium alone there is nothing to compare.
  if ! "$ecrf" report compare "docs/reports/baseline_2026_11/$scene" "$out" \
    --json "$out/compare_baseline.json" --plot "$out/compare_baseline.png" >"$out/compare_baseline.txt"; then
    rm -f "$out/compare_baseline.txt"
    echo "frontier: $scene not compared (each curve needs two points)"
  fi
  [ ! -f "$out/compare_baseline.txt" ] || cat "$out/compare_baseline.txt"
  # Keep what describes each run (settings and scores), not the checkpoints and files.
  find "$out/runs" -type f ! -name config.json ! -name metrics.json -delete
done
