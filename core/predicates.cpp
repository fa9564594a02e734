#include "aarad/core/predicates.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>

#include <cmath>
#include <limits>

namespace aarad {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

Sign to_sign(CGAL::Sign s) { return static_cast<Sign>(static_cast<int>(s)); }
Kernel::Point_2 point(const Vec2& v) { return {v.x, v.y}; }
Kernel::Point_3 point(const Vec3& v) { return {v.x, v.y, v.z}; }

// Sign of a . s + d with a floating-point filter: the error bound of the double evaluation follows
// Shewchuk's style estimate; when the result is inside it, fall back to exact rationals.
Sign exact_linear_sign(const Vec3& a, double d, const Vec3& s) {
  const double t0 = a.x * s.x, t1 = a.y * s.y, t2 = a.z * s.z;
  const double value = t0 + t1 + t2 + d;
  const double magnitude = std::abs(t0) + std::abs(t1) + std::abs(t2) + std::abs(d);
  // The relative bound fails where products underflow (their error is absolute, up to half the smallest
  // subnormal each): below kPredicateFilterFloor the filter decides nothing.
  const double bound = 8.0 * std::numeric_limits<double>::epsilon() * magnitude;
  if (magnitude >= kPredicateFilterFloor) {
    if (value > bound) return Sign::kPositive;
    if (value < -bound) return Sign::kNegative;
  }
  using Q = CGAL::Exact_rational;
  const Q exact = Q(a.x) * Q(s.x) + Q(a.y) * Q(s.y) + Q(a.z) * Q(s.z) + Q(d);
  return to_sign(CGAL::sign(exact));
}

}  // namespace

Sign orientation(const Vec2& a, const Vec2& b, const Vec2& c) {
  return to_sign(CGAL::orientation(point(a), point(b), point(c)));
}

Sign orientation(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  // CGAL's orientation(p, q, r, s) is POSITIVE when s lies on the positive side of the oriented plane
  // pqr, the side (q - p) x (r - p) points to (the sign of det[q - p, r - p, s - p]): the convention
  // documented above, with no flip (tests/test_polygon.cpp checks it).
  return to_sign(CGAL::orientation(point(p), point(q), point(r), point(s)));
}

Sign side_of_plane(const Vec3& origin, const Vec3& n, const Vec3& s) {
  // n . (s - origin) = n . s - n . origin; evaluate with exact arithmetic on the inputs as given.
  bool certain = false;
  const double value = side_of_plane_value(origin, n, s, certain);
  if (certain) return value > 0.0 ? Sign::kPositive : Sign::kNegative;
  using Q = CGAL::Exact_rational;
  const Q exact = Q(n.x) * (Q(s.x) - Q(origin.x)) + Q(n.y) * (Q(s.y) - Q(origin.y)) + Q(n.z) * (Q(s.z) - Q(origin.z));
  return to_sign(CGAL::sign(exact));
}

Sign sign_of_linear(const Vec3& a, double d, const Vec3& s) { return exact_linear_sign(a, d, s); }

bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  return CGAL::do_intersect(Kernel::Segment_2(point(a), point(b)), Kernel::Segment_2(point(c), point(d)));
}

}  // namespace aarad
