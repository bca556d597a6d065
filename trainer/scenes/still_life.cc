#include "trainer/scenes/still_life.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ecrf::trainer::procedural {
namespace {

enum class Pattern { kSlabChecker, kSphereChecker, kSphereBands, kBoxGrid, kBoxStripes };

struct Material {
  Vec3 colour_a, colour_b;
  Pattern pattern;
  double specular;
  double shininess;
};

struct Shape {
  bool is_sphere;
  Vec3 centre;  // sphere
  double radius;
  Vec3 lo, hi;  // box
  Material material;
};

// A slab with four objects on it, centred on the origin the cameras look at; everything lies
// within the bounding sphere below (radius 1.7), so the whole scene stays inside the
// Blender box and mostly within the 40 degree view from 4 units away.
const Shape kShapes[] = {
    {false,
     {},
     0,
     {-1.0, -1.0, kStillLifeBottom},
     {1.0, 1.0, -0.4},
     {{0.88, 0.86, 0.80}, {0.30, 0.42, 0.52}, Pattern::kSlabChecker, 0.05, 8}},
    {true,
     {-0.35, -0.25, 0.15},
     0.55,
     {},
     {},
     {{0.90, 0.22, 0.12}, {0.98, 0.80, 0.20}, Pattern::kSphereChecker, 0.45, 40}},
    {true,
     {0.6, 0.55, -0.1},
     0.3,
     {},
     {},
     {{0.15, 0.30, 0.85}, {0.95, 0.95, 0.95}, Pattern::kSphereBands, 0.6, 80}},
    {false,
     {},
     0,
     {0.15, -0.9, -0.4},
     {0.8, -0.25, 0.25},
     {{0.25, 0.70, 0.30}, {0.08, 0.25, 0.10}, Pattern::kBoxGrid, 0.15, 20}},
    {false,
     {},
     0,
     {-0.95, 0.35, -0.4},
     {-0.6, 0.75, 0.95},
     {{0.60, 0.30, 0.75}, {0.95, 0.75, 0.40}, Pattern::kBoxStripes, 0.25, 30}},
};
constexpr int kShapeCount = sizeof(kShapes) / sizeof(kShapes[0]);
// Testing the bounding sphere first roughly halves render time: about half the rays miss it.
constexpr double kBoundingRadius = kStillLifeRadius;

const Vec3 kLight = Normalized({0.45, 0.3, 1.0});  // towards the light
constexpr double kAmbient = 0.35;
constexpr double kEpsilon = 1e-6;

struct Hit {
  double t = INFINITY;
  int shape = -1;
  Vec3 normal;
};

bool IntersectSphere(const Shape& s, Vec3 origin, Vec3 dir, double t_max, double* t, Vec3* normal) {
  const Vec3 oc = origin - s.centre;
  const double b = Dot(oc, dir);
  const double c = Dot(oc, oc) - s.radius * s.radius;
  const double disc = b * b - c;
  if (disc < 0) return false;
  const double root = std::sqrt(disc);
  double hit = -b - root;
  if (hit <= kEpsilon) hit = -b + root;
  if (hit <= kEpsilon || hit >= t_max) return false;
  *t = hit;
  *normal = (origin + dir * hit - s.centre) * (1.0 / s.radius);
  return true;
}

bool IntersectBox(const Shape& s, Vec3 origin, Vec3 dir, double t_max, double* t, Vec3* normal) {
  double t_near = -INFINITY, t_far = INFINITY;
  int near_axis = 0, far_axis = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double o = Axis(origin, axis), d = Axis(dir, axis);
    const double lo = Axis(s.lo, axis), hi = Axis(s.hi, axis);
    if (std::abs(d) < 1e-12) {
      if (o < lo || o > hi) return false;
      continue;
    }
    double t0 = (lo - o) / d, t1 = (hi - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) t_near = t0, near_axis = axis;
    if (t1 < t_far) t_far = t1, far_axis = axis;
  }
  if (t_near > t_far) return false;
  const bool from_outside = t_near > kEpsilon;
  const double hit = from_outside ? t_near : t_far;
  if (hit <= kEpsilon || hit >= t_max) return false;
  const int axis = from_outside ? near_axis : far_axis;
  const double sign = (Axis(dir, axis) > 0) == from_outside ? -1.0 : 1.0;
  *normal = {axis == 0 ? sign : 0.0, axis == 1 ? sign : 0.0, axis == 2 ? sign : 0.0};
  *t = hit;
  return true;
}

Hit Trace(Vec3 origin, Vec3 dir, double t_max) {
  Hit best;
  best.t = t_max;
  for (int i = 0; i < kShapeCount; ++i) {
    double t;
    Vec3 normal;
    const bool hit = kShapes[i].is_sphere
                         ? IntersectSphere(kShapes[i], origin, dir, best.t, &t, &normal)
                         : IntersectBox(kShapes[i], origin, dir, best.t, &t, &normal);
    if (hit) best = {t, i, normal};
  }
  return best;
}

// Shadow rays only need to know whether anything is in the way, not what is closest.
bool Occluded(Vec3 origin, Vec3 dir) {
  for (const Shape& shape : kShapes) {
    double t;
    Vec3 normal;
    if (shape.is_sphere ? IntersectSphere(shape, origin, dir, INFINITY, &t, &normal)
                        : IntersectBox(shape, origin, dir, INFINITY, &t, &normal)) {
      return true;
    }
  }
  return false;
}

int Parity(double a, double b) { return static_cast<int>(std::floor(a) + std::floor(b)) & 1; }

// Picks colour_a or colour_b from surface position; patterns have a few cells per object so
// they are resolvable at 64x64 but still need the model to learn detail.
Vec3 Albedo(const Shape& shape, Vec3 p, Vec3 normal) {
  const Material& m = shape.material;
  bool use_b = false;
  switch (m.pattern) {
    case Pattern::kSlabChecker:
      use_b = Parity(p.x * 2.5, p.y * 2.5);
      break;
    case Pattern::kSphereChecker: {
      const Vec3 q = (p - shape.centre) * (1.0 / shape.radius);
      const double longitude = std::atan2(q.y, q.x) / (2 * kPi) + 0.5;
      const double latitude = std::acos(std::clamp(q.z, -1.0, 1.0)) / kPi;
      use_b = Parity(longitude * 10, latitude * 5);
      break;
    }
    case Pattern::kSphereBands:
      use_b = static_cast<int>(std::floor((p.z - shape.centre.z) / shape.radius * 3.0)) & 1;
      break;
    case Pattern::kBoxGrid: {
      // Grid lines on the two axes tangent to the face.
      const int axis = std::abs(normal.x) > 0.5 ? 0 : (std::abs(normal.y) > 0.5 ? 1 : 2);
      for (int a = 0; a < 3; ++a) {
        if (a == axis) continue;
        const double u = Axis(p, a) * 6.0;
        if (u - std::floor(u) < 0.18) use_b = true;
      }
      break;
    }
    case Pattern::kBoxStripes:
      use_b = static_cast<int>(std::floor((p.z + p.x) * 5.0)) & 1;
      break;
  }
  return use_b ? m.colour_b : m.colour_a;
}

bool MissesBoundingSphere(Vec3 origin, Vec3 dir) {
  const double b = Dot(origin, dir);
  return b * b - (Dot(origin, origin) - kBoundingRadius * kBoundingRadius) < 0;
}

}  // namespace

Vec3 StillLifeLight() { return kLight; }

bool StillLifeOccludes(Vec3 origin, Vec3 dir) { return Occluded(origin, dir); }

bool StillLifeHitDistance(Vec3 origin, Vec3 dir, double* t) {
  if (MissesBoundingSphere(origin, dir)) return false;
  const Hit hit = Trace(origin, dir, INFINITY);
  *t = hit.t;
  return hit.shape >= 0;
}

bool ShadeStillLife(Vec3 origin, Vec3 dir, Vec3* out) {
  if (MissesBoundingSphere(origin, dir)) return false;
  const Hit hit = Trace(origin, dir, INFINITY);
  if (hit.shape < 0) return false;
  const Shape& shape = kShapes[hit.shape];
  const Vec3 p = origin + dir * hit.t;
  const Vec3 albedo = Albedo(shape, p, hit.normal);
  const double lambert = std::max(0.0, Dot(hit.normal, kLight));
  const bool lit = lambert > 0 && !Occluded(p + hit.normal * 1e-5, kLight);
  Vec3 colour = albedo * kAmbient;
  if (lit) {
    const Vec3 half = Normalized(kLight - dir);
    const double highlight =
        shape.material.specular *
        std::pow(std::max(0.0, Dot(hit.normal, half)), shape.material.shininess);
    colour = colour + albedo * ((1.0 - kAmbient) * lambert) + Vec3{highlight, highlight, highlight};
  }
  *out = {std::min(colour.x, 1.0), std::min(colour.y, 1.0), std::min(colour.z, 1.0)};
  return true;
}

}  // namespace ecrf::trainer::procedural
