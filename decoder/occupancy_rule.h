// The occupancy test of the alpha mask (SPEC.md 7.4): a sample is occupied when the trilinear
// interpolation of the 0/1 mask at its continuous index is positive, that is when a corner
// with non-zero weight is set. Header-only and shared by the decoder (a bit-packed mask) and the
// trainer (a byte per voxel), so that training skips exactly the samples rendering will skip.
#ifndef ECRF_DECODER_OCCUPANCY_RULE_H_
#define ECRF_DECODER_OCCUPANCY_RULE_H_

#include <cmath>

namespace ecrf {

// idx: continuous voxel index per axis; res: the mask's resolution; is_set(x, y, z): the voxel.
// Corners with non-zero weight: floor(idx) always (its weight 1 - f is never 0), floor(idx) + 1
// when f > 0. Corners outside the mask are zero padding.
template <typename IsSet>
inline bool AnyWeightedCornerSet(const float idx[3], const int res[3], const IsSet& is_set) {
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const float fl = std::floor(idx[a]);
    if (!(fl > -2.f && fl < static_cast<float>(res[a]))) return false;
    const int i = static_cast<int>(fl);
    lo[a] = i;
    hi[a] = idx[a] > fl ? i + 1 : i;
    if (lo[a] < 0) lo[a] = 0;
    if (hi[a] > res[a] - 1) hi[a] = res[a] - 1;
    if (lo[a] > hi[a]) return false;
  }
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x)
        if (is_set(x, y, z)) return true;
  return false;
}

}  // namespace ecrf

#endif  // ECRF_DECODER_OCCUPANCY_RULE_H_
