#!/usr/bin/env bash
# benchmarks/decoder_speed.c, the timing program of scripts/decoder-speed.sh: it decodes and
# renders through the C API and prints its line; its pixel hash covers the image (another size
# gives another hash) and not the thread count (the renderer's output does not depend on it); a
# truncated stream is an error, not a timing.
set -euo pipefail
prog="$1" scene="$2"
hash() { sed -n 's/.*hash=\([0-9a-f]\{16\}\).*/\1/p'; }
one="$("$prog" "$scene" 2 32 1 1)"
two="$("$prog" "$scene" 2 32 2 2)"
echo "$one"
echo "$two"
h1="$(echo "$one" | hash)" h2="$(echo "$two" | hash)"
[ -n "$h1" ] && [ "$h1" = "$h2" ] || { echo "FAIL: 1 and 2 threads give hashes '$h1' and '$h2'"; exit 1; }
h3="$("$prog" "$scene" 2 33 1 1 | hash)"
[ -n "$h3" ] && [ "$h3" != "$h1" ] || { echo "FAIL: 32x32 and 33x33 views give the same hash"; exit 1; }
tmp="$(mktemp)"
trap 'rm -f "$tmp"' EXIT
head -c 100 "$scene" > "$tmp"
if "$prog" "$tmp" 1 16 1 1 > /dev/null 2>&1; then echo "FAIL: a truncated stream was timed"; exit 1; fi
echo "ok"
