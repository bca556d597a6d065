#!/usr/bin/env bash
# The decoder library holds decoder code only, behind the C API of include/ecrf/decoder.h: the C
# symbols it defines are exactly the functions the header declares, it defines none of the symbols
# that the encoder libraries define (format/'s encoder halves, encoder/), and its objects are the
# sources listed in cmake/decoder_sources.txt (which the WebAssembly build and the conformance
# matrix compile too). A decoder object that pulled in an encoder half would show up here.
# tests/install/check_decoder_symbols_test.sh shows that each step fails on a bad input.
#
#   check_decoder_symbols.sh SOURCE_DIR DECODER_LIB ENCODER_LIB...
set -euo pipefail
src="$1"; decoder="$2"; shift 2
fail() { echo "FAIL: $*" >&2; exit 1; }
header="$src/include/ecrf/decoder.h"

# 1. The C symbols of the archive (neither mangled, _Z..., nor reserved to the implementation,
#    __..., as sanitizers add) are the ECRF_API functions of the header, no more, no fewer: a
#    declared function left undefined breaks the user's link, and a C name outside the header is
#    an undocumented export that may clash with the user's own.
declared=$(sed -n 's/^ECRF_API .*[ *]\(ecrf_[a-z0-9_]*\)(.*/\1/p' "$header" | sort)
[ -n "$declared" ] || fail "no ECRF_API function read from $header"
c_symbols=$(nm --defined-only -g "$decoder" | awk '$2 ~ /^[TDBR]$/ && $3 !~ /^_/ {print $3}' | sort -u)
[ "$declared" = "$c_symbols" ] || fail "the C symbols of $decoder differ from the functions of $header (< declared, > defined):
$(diff <(echo "$declared") <(echo "$c_symbols") || true)"

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

# 4. The objects of the archive are the listed sources, no more, no fewer: a source that a CMake
#    file added beside the list would be missing from the WebAssembly build and the matrix.
expected=$(grep -v '^#' "$src/cmake/decoder_sources.txt" | sed '/^$/d' | xargs -n1 basename | sed 's/\.cc$//' | sort)
actual=$(ar t "$decoder" | sed 's/\.cc\.o$//; s/\.c\.o$//; s/\.o$//' | sort)
[ "$expected" = "$actual" ] || fail "objects of $decoder differ from cmake/decoder_sources.txt:
$(diff <(echo "$expected") <(echo "$actual") || true)"
echo "decoder library: the $(echo "$declared" | wc -l) C functions of decoder.h," \
     "$(echo "$actual" | wc -l) objects, no encoder code ($(echo "$encoder_symbols" | wc -l) encoder symbols checked)"
