// Small vector maths, a hand-held camera pose and a portable random generator shared by the
// procedural scenes.
#ifndef ECRF_TRAINER_SCENES_PROCEDURAL_MATH_H_
#define ECRF_TRAINER_SCENES_PROCEDURAL_MATH_H_

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace ecrf::trainer::procedural {

inline constexpr double kPi = 3.14159265358979323846;

struct Vec3 {
  double x = 0, y = 0, z = 0;
};

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Vec3 Normalized(Vec3 a) { return a * (1.0 / std::sqrt(Dot(a, a))); }
inline double Axis(Vec3 v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }

// Turns the unit vectors a, b of a frame by `angle` in their plane.
inline void Rotate(Vec3* a, Vec3* b, double angle) {
  const Vec3 ra = *a * std::cos(angle) + *b * std::sin(angle);
  const Vec3 rb = *b * std::cos(angle) - *a * std::sin(angle);
  *a = ra;
  *b = rb;
}

// A cheap integer hash of a lattice point to [0, 1): shades, joints and knots that differ from
// tile to tile.
inline double LatticeHash(int a, int b, int c = 0) {
  uint32_t h = uint32_t(a) * 0x8da6b343u ^ uint32_t(b) * 0xd8163841u ^ uint32_t(c) * 0xcb1ab31fu;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return (h & 0xffffu) / 65536.0;
}

// Smooth value noise in [0, 1) on the unit lattice: LatticeHash at the corners, blended with
// smoothstep weights.
inline double ValueNoise(Vec3 p) {
  const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const int ix = int(fx), iy = int(fy), iz = int(fz);
  auto smooth = [](double t) { return t * t * (3 - 2 * t); };
  const double w[3] = {smooth(p.x - fx), smooth(p.y - fy), smooth(p.z - fz)};
  double layer[2];
  for (int dz = 0; dz < 2; ++dz) {
    double row[2];
    for (int dy = 0; dy < 2; ++dy) {
      const double a = LatticeHash(ix, iy + dy, iz + dz), b = LatticeHash(ix + 1, iy + dy, iz + dz);
      row[dy] = a + (b - a) * w[0];
    }
    layer[dz] = row[0] + (row[1] - row[0]) * w[1];
  }
  return layer[0] + (layer[1] - layer[0]) * w[2];
}

// Camera-to-world (OpenGL: looks down -z, +y up) of a hand-held camera at `position` aimed at
// `target` with the horizon level (z up), then turned by the hand's pitch, yaw and roll.
inline void LookAtPose(Vec3 position, Vec3 target, double roll, double pitch, double yaw,
                       double c2w[3][4]) {
  Vec3 forward = Normalized(target - position);
  Vec3 right = Normalized(Cross(forward, {0, 0, 1}));
  Vec3 up = Cross(right, forward);
  Rotate(&forward, &up, pitch);
  Rotate(&right, &forward, yaw);
  Rotate(&right, &up, roll);
  const Vec3 columns[4] = {right, up, forward * -1.0, position};
  for (int c = 0; c < 4; ++c) {
    c2w[0][c] = columns[c].x;
    c2w[1][c] = columns[c].y;
    c2w[2][c] = columns[c].z;
  }
}

// The arguments every procedural scene takes, checked alike: "NAME scene: ..." errors.
inline void CheckSceneArguments(const char* scene, const std::string& split, int width,
                                int height) {
  const std::string what = std::string(scene) + " scene: ";
  if (split != "train" && split != "val" && split != "test") {
    throw std::runtime_error(what + "unknown split '" + split + "' (expected train, val or test)");
  }
  if (width < 1 || height < 1 || width > 4096 || height > 4096) {
    throw std::runtime_error(what + "image size " + std::to_string(width) + "x" +
                             std::to_string(height) + " must be within 1..4096");
  }
}

// The frames of a captured sequence: every 8th is held out, so at least 2 leave one to train on.
inline void CheckFrameCount(const char* scene, int num_frames) {
  if (num_frames < 2) {
    throw std::runtime_error(
        std::string(scene) +
        " scene: num_frames must be >= 2 (frame 0 is the only test frame), got " +
        std::to_string(num_frames));
  }
}

// splitmix64: the same numbers on every platform, unlike std:: distributions.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  double Uniform() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
  }
  // Uniform in [-1, 1).
  double Signed() { return 2.0 * Uniform() - 1.0; }

 private:
  uint64_t state_;
};

}  // namespace ecrf::trainer::procedural

#endif  // ECRF_TRAINER_SCENES_PROCEDURAL_MATH_H_
