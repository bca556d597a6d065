// Where a sample falls in the VM grids (SPEC.md 7.3): the lower corner and the upper corner's
// weight per axis, align_corners=True, clamped. Header-only and shared by the decoder and the
// trainer, so that training samples the grids exactly where rendering will.
#ifndef ECRF_DECODER_GRID_POINT_H_
#define ECRF_DECODER_GRID_POINT_H_

#include <array>

namespace ecrf {

// Lower corner index and upper-corner weight per axis of one sample (shared by the density and
// appearance grids, which always have the same resolution).
struct GridPoint {
  int i0[3];
  float f[3];
};

// c: normalized coordinates in [-1,1]^3 (c = (x - min) * 2/(max - min) - 1), res[a] >= 2.
// Continuous index (c+1)/2*(res-1) clamped to [0, res-1] (NaN -> 0); i0 in [0, res-2], f in [0,1].
inline void LocateGridPoint(const float c[3], const int res[3], GridPoint* gp) {
  for (int a = 0; a < 3; ++a) {
    const int n = res[a];
    float idx = (c[a] + 1.f) / 2.f * static_cast<float>(n - 1);
    if (!(idx > 0.f)) idx = 0.f;  // also maps NaN to 0
    if (idx > static_cast<float>(n - 1)) idx = static_cast<float>(n - 1);
    int i = static_cast<int>(idx);
    if (i > n - 2) i = n - 2;
    gp->i0[a] = i;
    gp->f[a] = idx - static_cast<float>(i);
  }
}

inline void LocateGridPoint(const float c[3], const std::array<int, 3>& res, GridPoint* gp) {
  LocateGridPoint(c, res.data(), gp);
}

}  // namespace ecrf

#endif  // ECRF_DECODER_GRID_POINT_H_
