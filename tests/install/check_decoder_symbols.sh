#!/usr/bin/env bash
# The decoder library holds decoder code only: its objects are exactly the sources listed in
# cmake/decoder_sources.txt (which the WebAssembly build and the conformance matrix compile too),
# and it defines none of the symbols that the encoder libraries define (format/'s encoder halves,
# encoder/). A decoder object that pulled in an encoder half would show up here.
#
#   check_decoder_symbols.sh SOURCE_DIR DECODER_LIB ENCODER_LIB...
set -euo pipefail
src="$1"; decoder="$2"; shift 2
fail() { echo "FAIL: $*" >&2; exit 1; }

# 1. The objects of the archive are the listed sources, no more, no fewer.
expected=$(grep -v '^#' "$src/cmake/decoder_sources.txt" | sed '/^$/d' | xargs -n1 basename | sed 's/\.cc$//' | sort)
actual=$(ar t "$decoder" | sed 's/\.cc\.o$//; s/\.o$//' | sort)
[ "$expected" = "$actual" ] || fail "objects of $decoder differ from cmake/decoder_sources.txt:
$(diff <(echo "$expected") <(echo "$actual") || true)"

# 2. No symbol of an encoder library is defined in the decoder (weak and inline ones aside: the
#    C++ standard library's instantiations are defined in both).
defined() { nm --defined-only -g "$@" 2>/dev/null | awk '$2 ~ /^[TDBR]$/ {print $3}' | sort -u; }
encoder_symbols=$(defined "$@")
[ -n "$encoder_symbols" ] || fail "no symbols read from the encoder libraries ($*)"
shared=$(comm -12 <(echo "$encoder_symbols") <(defined "$decoder"))
[ -z "$shared" ] || fail "the decoder defines encoder symbols:
$(echo "$shared" | c++filt | head -20)"

# 3. And none whose name says encoder, whoever defines it.
named=$(nm -C --defined-only -g "$decoder" | awk '$2 ~ /^[TDBR]$/' |
        grep -E 'Encode|Encoder|Write[A-Z]|Writer|FloatToHalf|ForwardDct' || true)
[ -z "$named" ] || fail "encoder-side names in the decoder:
$named"
echo "decoder library: $(echo "$actual" | wc -l) objects, no encoder code ($(echo "$encoder_symbols" | wc -l) encoder symbols checked)"
