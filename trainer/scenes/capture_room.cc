#include "trainer/scenes/capture_room.h"

#include <algorithm>
#include <cmath>

#include "trainer/scenes/still_life.h"

namespace ecrf::trainer::procedural {
namespace {

// Lighter than the still life's 0.35 ambient: a room is lit by its own bounce light, and the
// contrast keeps the object the thing to look at.
constexpr double kRoomAmbient = 0.6;
// Lines are at least this wide (metres) so that at 120x90 they cover a pixel or more.
constexpr double kLine = 0.045;

double Fract(double v) { return v - std::floor(v); }
Vec3 Mix(Vec3 a, Vec3 b, double t) { return a + (b - a) * t; }

bool OnLine(double coordinate, double period) {
  return Fract(coordinate / period) * period < kLine;
}

// Planks 0.25 m wide run along x in segments of 1.8 m whose joints sit at a random place per
// plank; each segment has its own shade of oak, grain phase and, most of the time, a dark knot.
Vec3 Floor(Vec3 p) {
  const int plank = int(std::floor(p.y / 0.25));
  const double along = p.x + 1.8 * LatticeHash(plank, 3);
  const int segment = int(std::floor(along / 1.8));
  if (OnLine(p.y, 0.25) || OnLine(along, 1.8)) return {0.22, 0.14, 0.08};
  const double tone = LatticeHash(plank, segment);
  const double knot_x = 1.8 * (segment + 0.15 + 0.7 * LatticeHash(segment, plank + 101));
  const double knot_y = 0.25 * (plank + 0.3 + 0.4 * LatticeHash(plank + 57, segment));
  const double kx = (along - knot_x) / 0.07, ky = (p.y - knot_y) / 0.03;
  if (LatticeHash(segment + 13, plank) < 0.7 && kx * kx + ky * ky < 1) return {0.30, 0.18, 0.09};
  const double grain = 0.5 + 0.5 * std::sin(p.x * 7.0 + 6.3 * LatticeHash(plank, segment + 29) +
                                            1.5 * std::sin(p.y * 9.0));
  const Vec3 light{0.72, 0.52, 0.32}, dark{0.50, 0.33, 0.18};
  return Mix(Mix(light, dark, tone), dark, 0.35 * grain);
}

Vec3 Ceiling(Vec3 p) {
  if (OnLine(p.x, 0.6) || OnLine(p.y, 0.6)) return {0.62, 0.62, 0.60};
  // A lamp's glow fades out from the middle of the ceiling; tiles differ a little in shade.
  const double glow = std::exp(-(p.x * p.x + p.y * p.y) / 1.5);
  const double tile = LatticeHash(int(std::floor(p.x / 0.6)) + 31, int(std::floor(p.y / 0.6)));
  return Mix(Vec3{0.80, 0.80, 0.78}, Vec3{1.0, 0.97, 0.88}, glow) * (0.88 + 0.12 * tile);
}

Vec3 StripedWallpaper(double u, double v) {  // wall at +x
  const double stripe = Fract(u / 0.3);
  const double shade = 0.8 + 0.2 * LatticeHash(int(std::floor(u / 0.3)), 41);
  if (stripe < 0.2) return Vec3{0.85, 0.82, 0.62} * shade;
  const Vec3 paper =
      Mix(Vec3{0.45, 0.60, 0.45}, Vec3{0.35, 0.50, 0.38}, 0.5 + 0.5 * std::sin(v * 5.0));
  return paper * shade;
}

// Bricks of 0.4 m give or take 0.08, each row shifted by its own random amount.
Vec3 Brick(double u, double v) {  // wall at -y
  const int row = int(std::floor(v / 0.18));
  const double shifted = u + 0.4 * LatticeHash(row, 17);
  auto joint = [&](int k) { return 0.4 * k + 0.16 * (LatticeHash(k, row + 211) - 0.5); };
  int brick = int(std::floor(shifted / 0.4));
  if (shifted < joint(brick)) --brick;
  if (shifted >= joint(brick + 1)) ++brick;
  if (OnLine(v, 0.18) || shifted - joint(brick) < kLine) return {0.80, 0.78, 0.72};
  const double tone = LatticeHash(brick, row);
  const Vec3 red = Mix(Vec3{0.70, 0.32, 0.20}, Vec3{0.42, 0.19, 0.14}, tone);
  return red;
}

Vec3 WindowWall(double u, double v) {  // wall at +y: a window and a picture beside it
  const double wu = u - 0.6, wv = v - 1.3;
  if (std::abs(wu) < 0.8 && std::abs(wv) < 0.55) {
    if (std::abs(wu) > 0.72 || std::abs(wv) > 0.47 || std::abs(wu) < 0.04)
      return {0.95, 0.95, 0.93};
    return Mix(Vec3{0.55, 0.75, 0.95}, Vec3{0.85, 0.92, 1.0},
               std::clamp(wv / 0.94 + 0.5, 0.0, 1.0));
  }
  const double pu = u + 1.6, pv = v - 1.2;
  if (std::abs(pu) < 0.4 && std::abs(pv) < 0.3) {
    if (std::abs(pu) > 0.34 || std::abs(pv) > 0.24) return {0.30, 0.20, 0.10};
    return (pv > 0.08 * std::sin(pu * 12.0)) ? Vec3{0.95, 0.70, 0.30} : Vec3{0.20, 0.45, 0.60};
  }
  return {0.72, 0.76, 0.82};
}

Vec3 Diamonds(double u, double v) {  // wall at -x; each diamond a shade of its own
  const double a = (u + v) / 0.5, b = (u - v) / 0.5;
  const bool inside = (Fract(a) < 0.5) != (Fract(b) < 0.5);
  const double shade =
      0.75 + 0.25 * LatticeHash(int(std::floor(2 * a)), int(std::floor(2 * b)) + 5);
  const Vec3 colour = inside ? Vec3{0.85, 0.55, 0.42} * shade : Vec3{0.93, 0.80, 0.66};
  return colour;
}

Vec3 Wall(int axis, bool positive, Vec3 p, double floor_z) {
  const double height = p.z - floor_z;
  if (height < 0.12) return {0.93, 0.93, 0.90};  // skirting board
  const double u = axis == 0 ? p.y : p.x;
  if (axis == 0) return positive ? StripedWallpaper(u, height) : Diamonds(u, height);
  return positive ? WindowWall(u, height) : Brick(u, height);
}

// From inside a box the ray leaves through the nearest of the three faces it heads for.
double Exit(const double room_min[3], const double room_max[3], Vec3 origin, Vec3 dir,
            int* exit_axis) {
  double t_exit = INFINITY;
  *exit_axis = 2;
  for (int axis = 0; axis < 3; ++axis) {
    const double d = Axis(dir, axis);
    if (d == 0) continue;
    const double t = ((d > 0 ? room_max[axis] : room_min[axis]) - Axis(origin, axis)) / d;
    if (t < t_exit) t_exit = t, *exit_axis = axis;
  }
  return t_exit;
}

}  // namespace

double RoomExitDistance(const double room_min[3], const double room_max[3], Vec3 origin, Vec3 dir) {
  int axis;
  return Exit(room_min, room_max, origin, dir, &axis);
}

Vec3 ShadeRoom(const double room_min[3], const double room_max[3], Vec3 origin, Vec3 dir) {
  int exit_axis;
  const double t_exit = Exit(room_min, room_max, origin, dir, &exit_axis);
  const bool positive = Axis(dir, exit_axis) > 0;
  const Vec3 p = origin + dir * t_exit;
  Vec3 normal;  // facing into the room
  (exit_axis == 0 ? normal.x : exit_axis == 1 ? normal.y : normal.z) = positive ? -1.0 : 1.0;

  Vec3 albedo;
  if (exit_axis == 2) {
    albedo = positive ? Ceiling(p) : Floor(p);
  } else {
    albedo = Wall(exit_axis, positive, p, room_min[2]);
  }
  const Vec3 light = StillLifeLight();
  double lambert = std::max(0.0, Dot(normal, light));
  // Only the still life casts shadows: the room's own would need a light inside it.
  if (lambert > 0 && StillLifeOccludes(p + normal * 1e-5, light)) lambert = 0;
  const Vec3 colour = albedo * (kRoomAmbient + (1.0 - kRoomAmbient) * lambert);
  return {std::min(colour.x, 1.0), std::min(colour.y, 1.0), std::min(colour.z, 1.0)};
}

}  // namespace ecrf::trainer::procedural
