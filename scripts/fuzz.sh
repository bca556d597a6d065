#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz (clang, ASan + UBSan, every finding aborts) and runs
# each for SECONDS (default 60) on a corpus seeded from tests/conformance. A finding stops the
# script with the target's reproducer file (build-fuzz/findings/<target>/); rerun one with
#   build-fuzz/tests/fuzz/<target> build-fuzz/findings/<target>/crash-...
#
#   bash scripts/fuzz.sh [SECONDS]        # CI: bash scripts/fuzz.sh 10
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
command -v clang++ >/dev/null || { echo "clang++ not found: apt-get install -y clang" >&2; exit 1; }
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
      -DCMAKE_C_COMPILER=clang -DECRF_FUZZ=ON -DECRF_BUILD_TRAINER=OFF -DECRF_BUILD_TESTS=OFF >/dev/null
cmake --build build-fuzz -j"$(nproc)"

export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export ASAN_OPTIONS="detect_leaks=1"
status=0
for exe in build-fuzz/tests/fuzz/fuzz_*; do
  [ -x "$exe" ] || continue
  name="$(basename "$exe")"
  corpus="build-fuzz/corpus/$name"
  findings="build-fuzz/findings/$name"
  mkdir -p "$corpus" "$findings"
  # Seeds: the scene streams and the must-reject streams for the scene targets (the render target
  # reads a mode byte first), the raw coefficient streams for the coefficient target; the others
  # start from them too. A timeout (-timeout, 10 s) is a finding like a crash.
  case "$name" in
    fuzz_scene_render)
      for f in tests/conformance/*.ecrf tests/conformance/reject/*.ecrf; do
        { printf '\000'; cat "$f"; } >"$corpus/seed0_$(basename "$f")"
        { printf '\001'; cat "$f"; } >"$corpus/seed1_$(basename "$f")"
      done ;;
    fuzz_coef_decoder) cp tests/conformance/*.bin "$corpus/" ;;
    *) cp tests/conformance/*.ecrf tests/conformance/reject/*.ecrf "$corpus/" ;;
  esac
  log="build-fuzz/$name.log"
  echo "== $name: ${seconds} s"
  if ! "$exe" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
       -artifact_prefix="$findings/" "$corpus" >"$log" 2>&1; then
    echo "FINDING in $name (see $log):"
    grep -E 'ERROR|SUMMARY|runtime error|Test unit written' "$log" | head -20
    status=1
    continue
  fi
  runs="$(grep -E '^stat::number_of_executed_units' "$log" | awk '{print $2}')"
  rss="$(grep -E '^stat::peak_rss_mb' "$log" | awk '{print $2}')"
  cov="$(grep -E '#[0-9]+.*(DONE|pulse|NEW|REDUCE).*cov: [0-9]+' "$log" | tail -1 | sed -E 's/.*cov: ([0-9]+).*ft: ([0-9]+).*/cov \1, ft \2/')"
  echo "   ${runs:-?} executions, ${cov:-coverage ?}, peak RSS ${rss:-?} MB, corpus $(ls "$corpus" | wc -l) files, no finding"
done
[ "$status" = 0 ] && echo "fuzz: no finding" || echo "fuzz: FINDINGS (reproducers in build-fuzz/findings/)"
exit "$status"
