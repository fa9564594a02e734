// Exact geometric predicates over CGAL's Exact_predicates_inexact_constructions_kernel: decide "which side"
// exactly, compute "where" in doubles (CGAL's filtered-predicate design).
#pragma once

#include "aarad/core/math.h"

#include <cmath>
#include <limits>

namespace aarad {

enum class Sign : int { kNegative = -1, kZero = 0, kPositive = 1 };

// Sign of the area of triangle (a, b, c): positive when counter-clockwise (y up).
Sign orientation(const Vec2& a, const Vec2& b, const Vec2& c);
// Which side of the plane through p, q, r the point s lies on: positive when s sees p, q, r
// counter-clockwise (s lies on the side the normal (q - p) x (r - p) points to).
Sign orientation(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s);
// Side of point s relative to the plane through `origin` with normal `n`: sign of n . (s - origin),
// evaluated exactly for the given doubles.
Sign side_of_plane(const Vec3& origin, const Vec3& n, const Vec3& s);

// Below this sum of |terms| a double evaluation may have underflowed (subnormal products carry an absolute
// error of up to 2^-1075 each, which no relative bound covers), so the filters below decide nothing. Above it
// those absolute errors are far below 8 eps times the magnitude.
inline constexpr double kPredicateFilterFloor = 1e-280;

// The floating-point stage of side_of_plane, for callers that need the value too: returns n . (s - origin) in
// doubles (terms added in the order x, y, z, as glm::dot does) and sets `certain` when its sign is the exact
// one. Otherwise side_of_plane decides.
inline double side_of_plane_value(const Vec3& origin, const Vec3& n, const Vec3& s, bool& certain) {
  const double t0 = n.x * (s.x - origin.x), t1 = n.y * (s.y - origin.y), t2 = n.z * (s.z - origin.z);
  const double value = t0 + t1 + t2;
  const double magnitude = std::abs(t0) + std::abs(t1) + std::abs(t2);
  const double bound = 8.0 * std::numeric_limits<double>::epsilon() * magnitude;
  certain = magnitude >= kPredicateFilterFloor && (value > bound || value < -bound);
  return value;
}
// Sign of the linear form a . s + d, exactly for the given doubles.
Sign sign_of_linear(const Vec3& a, double d, const Vec3& s);
// Whether segments [a, b] and [c, d] share at least one point.
bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

}  // namespace aarad
