// Vector types and small helpers shared by every layer. aarad computes in double precision throughout:
// form factors of tiny elements and exact coverage tests need the headroom.
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/geometric.hpp>

#include <numbers>

namespace aarad {

using Vec2 = glm::dvec2;
using Vec3 = glm::dvec3;

inline constexpr double kPi = std::numbers::pi;

// A plane n . x + d = 0 with unit normal n; the front side is where n . x + d > 0.
struct Plane {
  Vec3 normal{0.0, 0.0, 1.0};
  double d = 0.0;

  double signed_distance(const Vec3& p) const { return glm::dot(normal, p) + d; }
};

// The smallest integer >= v, for |v| < 2^31: the cast truncates toward zero, which is the ceiling for v <= 0 and
// the floor for v > 0. Cheaper than std::ceil and a cast where the compiler may not use SSE4.1's rounding.
inline int ceil_to_int(double v) {
  const int t = static_cast<int>(v);
  return t + (static_cast<double>(t) < v);
}

// The largest integer <= v, for |v| < 2^31.
inline int floor_to_int(double v) {
  const int t = static_cast<int>(v);
  return t - (static_cast<double>(t) > v);
}

}  // namespace aarad
