#!/usr/bin/env bash
# check_decoder_symbols.sh must fail when what it guards breaks: it passes on the real libraries,
# then is run on inputs broken one way each (a header that declares a function the library lacks
# or lacks one it defines, an archive with an undeclared C function, with an encoder object, with
# an encoder-named function, a source list without one of the archive's objects), and must fail
# on each, naming the fault.
#
#   check_decoder_symbols_test.sh SOURCE_DIR DECODER_LIB FORMAT_ENCODER_LIB [ENCODER_LIB...]
#   (CC and CXX: the compilers of the objects added to broken archives)
set -euo pipefail
src="$1"; decoder="$2"; shift 2
encoders=("$@")
check="$(dirname "$0")/check_decoder_symbols.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0

# expect_failure CASE PATTERN SOURCE_DIR DECODER_LIB: the check must exit non-zero, saying PATTERN.
expect_failure() {
  local out
  if out=$(bash "$check" "$3" "$4" "${encoders[@]}" 2>&1); then
    echo "FAIL: $1: the check passed"; status=1
  elif ! grep -q -- "$2" <<<"$out"; then
    echo "FAIL: $1: the check failed without naming '$2':"; echo "$out"; status=1
  else
    echo "ok: $1: $(grep -m1 -- "$2" <<<"$out")"
  fi
}
# A source directory of copies (the header and the list), for editing.
copy_sources() {
  mkdir -p "$work/$1/include/ecrf" "$work/$1/cmake"
  cp "$src/include/ecrf/decoder.h" "$work/$1/include/ecrf/"
  cp "$src/cmake/decoder_sources.txt" "$work/$1/cmake/"
  echo "$work/$1"
}
# A copy of the decoder archive with OBJECT added.
archive_with() {
  cp "$decoder" "$work/$1.a"
  ar q "$work/$1.a" "$2"
  echo "$work/$1.a"
}

bash "$check" "$src" "$decoder" "${encoders[@]}" >/dev/null || { echo "FAIL: the real inputs do not pass"; exit 1; }

dir=$(copy_sources declared_only)
echo 'ECRF_API int ecrf_declared_only(void);' >>"$dir/include/ecrf/decoder.h"
expect_failure "a declared function the library lacks" ecrf_declared_only "$dir" "$decoder"

dir=$(copy_sources undeclared)
sed -i '/^ECRF_API int ecrf_scene_check_render(/d' "$dir/include/ecrf/decoder.h"
expect_failure "a defined function the header lacks" ecrf_scene_check_render "$dir" "$decoder"

echo 'int ecrf_undeclared(void) { return 0; }' >"$work/undeclared.c"
"${CC:-cc}" -c "$work/undeclared.c" -o "$work/undeclared.c.o"
expect_failure "an undeclared C function in the archive" ecrf_undeclared "$src" \
  "$(archive_with undeclared_c "$work/undeclared.c.o")"

mkdir "$work/encoder_objects"
format_encoder=$(realpath "${encoders[0]}")
(cd "$work/encoder_objects" && ar x "$format_encoder")
encoder_object=$(find "$work/encoder_objects" -name '*.o' | sort | head -1)
expect_failure "an encoder object in the archive" "defines encoder symbols" "$src" \
  "$(archive_with encoder_object "$encoder_object")"

echo 'namespace ecrf { int WriteChunkTable(int n) { return n + 1; } }' >"$work/writer.cc"
"${CXX:-c++}" -c "$work/writer.cc" -o "$work/writer.cc.o"
expect_failure "an encoder-named function in the archive" "encoder-side names" "$src" \
  "$(archive_with writer "$work/writer.cc.o")"

dir=$(copy_sources unlisted)
sed -i '/^decoder\/version\.cc$/d' "$dir/cmake/decoder_sources.txt"
expect_failure "an object the source list lacks" "differ from cmake/decoder_sources.txt" "$dir" "$decoder"

[ "$status" = 0 ] && echo "check_decoder_symbols.sh fails on each broken input"
exit "$status"
