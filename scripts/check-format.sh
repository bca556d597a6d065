#!/usr/bin/env bash
# Checks (or with --fix, applies) the C++ formatting of every tracked source against .clang-format
# (clang-format 14, Debian 12's). Exits 1 naming the files that differ.
#
#   bash scripts/check-format.sh          # CI: scripts/test.sh runs it first
#   bash scripts/check-format.sh --fix    # reformat in place
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null || { echo "clang-format not found: apt-get install -y clang-format" >&2; exit 1; }
mapfile -t files < <(git ls-files '*.cc' '*.h' 2>/dev/null || find format decoder encoder conformance trainer tools benchmarks python tests examples -name '*.cc' -o -name '*.h')
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
bad=()
for f in "${files[@]}"; do
  clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if [ ${#bad[@]} -gt 0 ]; then
  printf 'not formatted (bash scripts/check-format.sh --fix):\n' >&2
  printf '  %s\n' "${bad[@]}" >&2
  exit 1
fi
echo "formatting: ${#files[@]} files as .clang-format says"
