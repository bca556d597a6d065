// IEEE 754 binary16 ("half") <-> binary32 conversion, written out in integer arithmetic so that
// every platform produces the same bits (the MLPW chunk stores weights as binary16 by default).
#ifndef ECRF_FORMAT_HALF_FLOAT_H_
#define ECRF_FORMAT_HALF_FLOAT_H_

#include <cstdint>

namespace ecrf {

// Exact: every binary16 value (including subnormals, infinities, NaN) has a binary32 equal.
float HalfToFloat(uint16_t h);
// Round to nearest, ties to even; overflow gives +-infinity, NaN stays NaN.
uint16_t FloatToHalf(float f);
inline bool HalfIsFinite(uint16_t h) { return (h & 0x7C00u) != 0x7C00u; }

}  // namespace ecrf

#endif  // ECRF_FORMAT_HALF_FLOAT_H_
