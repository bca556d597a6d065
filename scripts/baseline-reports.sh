#!/usr/bin/env bash
# Regenerates the committed rate-distortion baseline (docs/reports/baseline_2026_11/{chair,mic}):
# the coherent sweep of `ecrf report sweep`, `fast` preset, the named rate points low, medium and
# high, two lambda_e values between low and medium on the default (medium) base, and the plain
# TensoRF reference (rate point none) every ratio is measured against. Each point is the run
# `ecrf train --data DATA --rate R` (or `--lambda-e X`) writes, scored on every 10th test view.
# About 80 minutes per scene on 2 cores. Finished runs under REPORT/runs are reused, so an
# interrupted run continues; the committed runs/*/{config,metrics}.json let it resume without the
# checkpoints.
#
#   bash scripts/baseline-reports.sh [chair mic]   # DATA_ROOT=../shared/data/nerf_synthetic_400, ECRF=build/tools/ecrf
set -euo pipefail
cd "$(dirname "$0")/.."
ecrf="${ECRF:-build/tools/ecrf}"
data_root="${DATA_ROOT:-../shared/data/nerf_synthetic_400}"
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(chair mic)
for scene in "${scenes[@]}"; do
  out="docs/reports/baseline_2026_11/$scene"
  # --iters 3000: the baseline's schedule (the low and medium rate points train 4500 since #31).
  "$ecrf" report sweep --data "$data_root/$scene" --rates none,low,medium,high --lambdas 1e-10,6e-11 \
    --iters 3000 --eval-every 0 --anchors docs/reports/anchors_paper.json -o "$out"
  # Keep what describes each run (settings and scores), not the checkpoints and files.
  find "$out/runs" -type f ! -name config.json ! -name metrics.json -delete
done
