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

}  // namespace aarad
