#!/usr/bin/env bash
# ABI checks of an installed decoder: the shared library exports exactly the functions of
# ecrf/decoder.h (nothing of format/, decoder/ internals or the C++ library), has the SONAME of
# the library version, and the header compiles as strict C99 and as C++.
#
#   bash tests/install/check_abi.sh PREFIX [LIBDIR]     (LIBDIR: default PREFIX/lib)
set -euo pipefail
prefix="$1"
libdir="${2:-$prefix/lib}"
header="$prefix/include/ecrf/decoder.h"
so="$libdir/libecrf_decoder.so"
fail=0

exported="$(nm -D --defined-only "$so" | awk '{print $3}' | sed 's/@.*//' | sort)"
declared="$(sed -n 's/^ECRF_API .*[ *]\(ecrf_[a-z0-9_]*\)(.*/\1/p' "$header" | sort)"
if [ "$exported" != "$declared" ]; then
  echo "FAIL: exported symbols differ from the functions of decoder.h (< exported, > declared):"
  diff <(echo "$exported") <(echo "$declared") || true
  fail=1
fi
# The version as the installed header states it (ECRF_VERSION_*, its only source).
version_part() { sed -n "s/^#define ECRF_VERSION_$1 \([0-9]*\)$/\1/p" "$header"; }
major="$(version_part MAJOR)"; minor="$(version_part MINOR)"
version="$major.$minor.$(version_part PATCH)"
expected_soname="libecrf_decoder.so.$major"
[ "$major" = 0 ] && expected_soname="libecrf_decoder.so.0.$minor"
soname="$(readelf -d "$so" | sed -n 's/.*SONAME.*\[\(.*\)\]/\1/p')"
if [ "$soname" != "$expected_soname" ]; then
  echo "FAIL: SONAME $soname, expected $expected_soname (version $version)"
  fail=1
fi

CC="${CC:-cc}"
CXX="${CXX:-c++}"
echo '#include <ecrf/decoder.h>' | "$CC" -std=c99 -Wall -Wextra -pedantic -Werror -fsyntax-only \
  -I"$prefix/include" -x c - || { echo "FAIL: decoder.h as C99"; fail=1; }
echo '#include <ecrf/decoder.h>' | "$CXX" -std=c++11 -Wall -Wextra -pedantic -Werror -fsyntax-only \
  -I"$prefix/include" -x c++ - || { echo "FAIL: decoder.h as C++"; fail=1; }

if [ "$fail" = 0 ]; then
  echo "ABI ok: $soname exports the $(echo "$exported" | wc -l) functions of decoder.h only;" \
       "decoder.h compiles as C99 and C++ (-Wall -Wextra -pedantic -Werror)"
fi
exit "$fail"
