#!/usr/bin/env bash
# Regenerates (or continues) the per-head sweeps of issue #57 (docs/reports/heads/): for each
# scene, one `ecrf report sweep --head H` per head at the frontier's sizes (the per-sample
# head's own curve is docs/reports/frontier/SCENE), then `ecrf report compare` of every head
# against it into SCENE.{json,csv,png} and SCENE_cost.png. 12-50 minutes per point on 2 cores.
# Finished runs under REPORT/runs are reused (their committed config.json and metrics.json
# suffice), so each session can add points; a head with one point so far is drawn, not compared.
#
#   bash scripts/heads-reports.sh [chair mic]   # HEADS="deferred sh sh_d3 deferred_h32", DATA_ROOT=../shared/data/nerf_synthetic_400, ECRF=build/tools/ecrf
set -euo pipefail
cd "$(dirname "$0")/.."
ecrf="${ECRF:-build/tools/ecrf}"
data_root="${DATA_ROOT:-../shared/data/nerf_synthetic_400}"
read -r -a heads <<<"${HEADS:-deferred sh sh_d3 deferred_h32}"
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(chair mic)
# The frontier's medium size and its smaller point, per scene.
declare -A targets=([chair]="602657B,316KB" [mic]="426623B,158KB")
for scene in "${scenes[@]}"; do
  compare=(--label "mlp (per sample, hidden 128)" "docs/reports/frontier/$scene")
  for head in "${heads[@]}"; do
    case "$head" in
      deferred) flags=(--head deferred) label="deferred (hidden 128)" ;;
      deferred_h32) flags=(--head deferred --mlp-hidden 32) label="deferred (hidden 32)" ;;
      sh) flags=(--head sh --sh-degree 2) label="sh (degree 2)" ;;
      sh_d3) flags=(--head sh --sh-degree 3) label="sh (degree 3)" ;;
      *) echo "heads-reports: unknown head $head (deferred, deferred_h32, sh, sh_d3)" >&2; exit 2 ;;
    esac
    out="docs/reports/heads/${scene}_$head"
    "$ecrf" report sweep --data "$data_root/$scene" --targets "${targets[$scene]}" "${flags[@]}" \
      --eval-every 0 --test-stride 10 -o "$out"
    compare+=(--label "$label" "$out")
  done
  # Exits non-zero when no head has two points yet; the plots are drawn either way.
  "$ecrf" report compare "${compare[@]}" --json "docs/reports/heads/$scene.json" \
    --plot "docs/reports/heads/$scene.png" || echo "heads: $scene not compared yet (each curve needs two points)"
done
