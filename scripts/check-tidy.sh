#!/usr/bin/env bash
# Runs .clang-tidy's checks on format/, decoder/ and encoder/ (the code that parses untrusted
# bytes or writes the bitstream), with the compile commands of a configured build directory.
#
#   bash scripts/check-tidy.sh [BUILD_DIR]      # default build/ (scripts/test.sh configures it)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
command -v clang-tidy >/dev/null || { echo "clang-tidy not found: apt-get install -y clang-tidy" >&2; exit 1; }
[ -f "$build/compile_commands.json" ] || { echo "$build/compile_commands.json missing: configure $build first" >&2; exit 1; }
mapfile -t files < <( (grep -v '^#' cmake/decoder_sources.txt | sed '/^$/d'; git ls-files 'format/*.cc' 'encoder/*.cc') | sort -u)
clang-tidy -p "$build" --quiet "${files[@]}" 2> >(grep -v 'warnings generated\|^Suppressed\|Use -header-filter\|NOLINT' >&2)
echo "clang-tidy: ${#files[@]} files pass .clang-tidy"
