#!/usr/bin/env bash
# What a unit of charged decoder work costs on each build (#60): builds benchmarks/budget_costs.cc
# (format/ and decoder/ only) natively and, where the cross compilers and qemu-user are installed,
# for aarch64 and armhf (static, under qemu, as scripts/conformance-matrix.sh builds them), runs
# each, and prints every costly class's nanoseconds per unit of decode and of render work, each
# relative to the same build's reference class: decode units to the entropy decoding of
# full-length blocks, render units to the density taps of dense_density (both plain arithmetic).
# qemu emulates: its absolute times say nothing about a device, but a class whose relative cost
# is far higher under emulation of a target than natively is one to measure on that device.
#
#   bash scripts/budget-costs.sh            # ECRF_BUDGET_ARM=0 skips ARM; ~20 minutes with ARM
#   bash scripts/budget-costs.sh --table    # the table of the last runs again
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=build-budget-costs
mkdir -p "$OUT"
mapfile -t sources < <(grep -v '^#' cmake/decoder_sources.txt | sed '/^$/d' | grep '^decoder/')
mapfile -t -O "${#sources[@]}" sources < <(find format -name '*.cc' | sort)
sources+=(benchmarks/budget_costs.cc)
flags=(-std=c++17 -O2 -fno-exceptions -fno-rtti -ffp-contract=off -I. -Iinclude)

table_only=0
[ "${1:-}" = --table ] && table_only=1
builds=("native:g++::")
if [ "${ECRF_BUDGET_ARM:-1}" != 0 ]; then
  for target in aarch64-linux-gnu:qemu-aarch64 arm-linux-gnueabihf:qemu-arm; do
    IFS=: read -r triple qemu <<<"$target"
    if command -v "$triple-g++" >/dev/null && command -v "$qemu" >/dev/null; then
      builds+=("$triple:$triple-g++:$qemu:-static")
    else
      echo "($triple-g++ or $qemu not installed: $triple skipped)"
    fi
  done
fi
for b in "${builds[@]}"; do
  IFS=: read -r name cxx runner link <<<"$b"
  [ "$table_only" = 1 ] && continue
  echo "== $name: build"
  # shellcheck disable=SC2086
  "$cxx" "${flags[@]}" "${sources[@]}" -pthread $link -o "$OUT/$name"
  echo "== $name: run${runner:+ (under $runner)}"
  # shellcheck disable=SC2086
  $runner "$OUT/$name" >"$OUT/$name.txt"
done

python3 - "$OUT" "${builds[@]%%:*}" <<'EOF'
import sys
out, names = sys.argv[1], sys.argv[2:]
rows = {}
for name in names:
    for line in open(f"{out}/{name}.txt"):
        if line.startswith("#"):
            continue
        cls, du, ds, ru, rs, outcome = line.rstrip("\n").split(" ", 5)
        rows.setdefault(cls, {})[name] = (int(du), float(ds), int(ru), float(rs), outcome)
def ns(units, seconds):  # under a millisecond the clock, not the work, is measured
    return seconds * 1e9 / units if units > 0 and seconds >= 1e-3 else None
dref = {n: ns(*rows["full_length_blocks"][n][0:2]) for n in names}
rref = {n: ns(*rows["dense_density"][n][2:4]) for n in names}
cell = lambda v, r: "" if v is None else f"{v:.2f} ({v / r:.2f}x)"
print("ns per unit (in brackets: relative to the build's reference class, full_length_blocks for")
print("decode units, dense_density for render units):")
print("| class | outcome | " + " | ".join(f"{n} decode | {n} render" for n in names) + " |")
print("|---|---|" + "---|---|" * len(names))
for cls, by in rows.items():
    cells = []
    for n in names:
        du, ds, ru, rs, outcome = by[n]
        cells += [cell(ns(du, ds), dref[n]), cell(ns(ru, rs), rref[n])]
    print(f"| {cls} | {by[names[0]][4]} | " + " | ".join(cells) + " |")
EOF
