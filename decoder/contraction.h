// The unbounded scene model (SPEC.md 7.2.1): world points are normalised by the region of
// interest (the HEAD box) and contracted per axis into the cube [-2, 2]^3 that the grids cover,
// and rays are sampled with a step that is constant in contracted distance.
//
// Header-only and shared by the trainer and the decoder so that both compute every sample
// position with the same binary32 operations in the same order (the files that include it are
// compiled with -ffp-contract=off or its equivalent for the decoder; the trainer's agreement
// tests check the result).
#ifndef ECRF_DECODER_CONTRACTION_H_
#define ECRF_DECODER_CONTRACTION_H_

#include <cmath>

namespace ecrf {

// Half-width of the contracted cube the grids and the occupancy mask span.
inline constexpr float kContractedExtent = 2.f;

// x inside [-1, 1] is kept; outside, sign(x) (2 - 1/|x|): monotone, continuous with a
// continuous first derivative at |x| = 1, and +-infinity maps to +-2.
inline float ContractCoordinate(float x) {
  if (x >= -1.f && x <= 1.f) return x;
  return x > 0.f ? 2.f - 1.f / x : -2.f - 1.f / x;
}

// Inverse of ContractCoordinate on (-2, 2) (for tests and for placing things; not used by
// rendering).
inline float UncontractCoordinate(float y) {
  if (y >= -1.f && y <= 1.f) return y;
  return y > 0.f ? 1.f / (2.f - y) : -1.f / (2.f + y);
}

// One ray of an unbounded scene: its sample positions in contracted coordinates and the
// parameter of the next sample. roi_min / roi_scale are the HEAD box's lower corner and
// (1 / (max - min)) * 2 per axis, as 7.4 computes them.
struct ContractedRay {
  float o[3], d[3];
  float roi_min[3], roi_scale[3];
  float step;  // distance between samples in contracted coordinates

  ContractedRay(const float* origin, const float* dir, const float* min, const float* scale,
                float sample_step)
      : step(sample_step) {
    for (int a = 0; a < 3; ++a) {
      o[a] = origin[a];
      d[a] = dir[a];
      roi_min[a] = min[a];
      roi_scale[a] = scale[a];
    }
  }

  // Normalised point q (the ROI box is [-1, 1]^3) and its contraction x at parameter t.
  void At(float t, float q[3], float x[3]) const {
    for (int a = 0; a < 3; ++a) {
      const float p = o[a] + d[a] * t;
      q[a] = (p - roi_min[a]) * roi_scale[a] - 1.f;
      x[a] = ContractCoordinate(q[a]);
    }
  }

  // Ray parameter increment after the sample at normalised point q: `step` divided by the speed
  // of the contracted point, | d x / d t | = sqrt(sum_a (d[a] roi_scale[a] / Max(1, q[a]^2))^2).
  // +infinity once the speed underflows (the ray has reached the edge of the cube).
  float Increment(const float q[3]) const {
    float sum = 0.f;
    for (int a = 0; a < 3; ++a) {
      const float qq = q[a] * q[a];
      const float g = d[a] * roi_scale[a] / (qq > 1.f ? qq : 1.f);
      sum = sum + g * g;
    }
    return step / std::sqrt(sum);
  }
};

}  // namespace ecrf

#endif  // ECRF_DECODER_CONTRACTION_H_
