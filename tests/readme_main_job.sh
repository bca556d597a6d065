#!/usr/bin/env bash
# Runs the README's main-job `ecrf train` command line (fewer iterations) in an empty temporary
# directory, as a user on a fresh clone would: the command must create its output path (40
# iterations: every phase, the rate objective included, in a few seconds).
#   readme_main_job.sh ECRF_BINARY README.md
set -euo pipefail
ecrf="$1"
readme="$2"
# The first fenced command that runs `build/tools/ecrf train`; keep only that part of the line.
line="$(grep -m1 -o 'build/tools/ecrf train [^&]*' "$readme" | sed 's/[[:space:]]*$//')"
if [ -z "$line" ]; then
  echo "no 'build/tools/ecrf train' command in $readme" >&2
  exit 1
fi
args="${line#build/tools/ecrf train }"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
echo "in $work: ecrf train $args --iters 40"
# shellcheck disable=SC2086  # the README's arguments are plain words
"$ecrf" train $args --iters 40 --threads 2
out="$(echo "$args" | sed -n 's/.*-o \([^ ]*\).*/\1/p')"
for f in scene.ecrf metrics.json checkpoint.ckpt; do
  [ -s "$out/$f" ] || { echo "missing $out/$f after the main job" >&2; exit 1; }
done
echo "ReadmeMainJob: 1 passed, 0 failed"
