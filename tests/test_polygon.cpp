// Tests of core/polygon.h and core/predicates.h against exact values: areas of known polygons, convexity
// and simplicity (bow-tie, collinear and touching cases), and exact predicates on collinear and coplanar
// inputs near 1e-300 and near 1e300, checked against CGAL's exact rationals.
#include "aarad/core/polygon.h"
#include "aarad/core/predicates.h"

#include <CGAL/Exact_rational.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace aarad {
namespace {

using Q = CGAL::Exact_rational;

std::vector<Vec3> lift(const std::vector<Vec2>& p, double z = 0.0) {
  std::vector<Vec3> out;
  for (const Vec2& v : p) out.emplace_back(v.x, v.y, z);
  return out;
}

std::vector<Vec2> reversed(std::vector<Vec2> p) {
  std::reverse(p.begin(), p.end());
  return p;
}

const std::vector<Vec2> kUnitSquare{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
// L-shape of three unit squares: area 3, centroid (5/6, 5/6).
const std::vector<Vec2> kLShape{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
const std::vector<Vec2> kBowTie{{0, 0}, {1, 1}, {1, 0}, {0, 1}};

// ---- Areas, normals, centroids -------------------------------------------------------------------------

TEST(Polygon, polygon_area_of_known_polygons) {
  EXPECT_DOUBLE_EQ(area(lift(kUnitSquare)), 1.0);
  EXPECT_DOUBLE_EQ(area(lift({{0, 0}, {4, 0}, {0, 3}})), 6.0);  // 3-4-5 right triangle
  EXPECT_DOUBLE_EQ(area(lift(kLShape)), 3.0);
  // Regular hexagon of circumradius 2: 3 sqrt(3) / 2 r^2 = 6 sqrt(3).
  std::vector<Vec2> hexagon;
  for (int i = 0; i < 6; ++i) hexagon.emplace_back(2.0 * std::cos(i * kPi / 3.0), 2.0 * std::sin(i * kPi / 3.0));
  EXPECT_NEAR(area(lift(hexagon)), 6.0 * std::sqrt(3.0), 1e-14);
  // Clockwise has the same area; the signed 2D area tells the winding.
  EXPECT_DOUBLE_EQ(area(lift(reversed(kLShape))), 3.0);
  EXPECT_DOUBLE_EQ(signed_area(kLShape), 3.0);
  EXPECT_DOUBLE_EQ(signed_area(reversed(kLShape)), -3.0);
  EXPECT_DOUBLE_EQ(signed_area(kBowTie), 0.0);  // the two lobes cancel
}

TEST(Polygon, polygon_area_in_tilted_plane_and_far_from_origin) {
  // A 3 x 2 rectangle in the plane x + y + z = const, spanned by orthonormal u, v.
  const Vec3 u = glm::normalize(Vec3(1, -1, 0)), v = glm::normalize(Vec3(1, 1, -2));
  const Vec3 o(1e8, -2e8, 3e8);
  const std::vector<Vec3> rect{o, o + 3.0 * u, o + 3.0 * u + 2.0 * v, o + 2.0 * v};
  EXPECT_NEAR(area(rect), 6.0, 6.0 * 1e-7);
  const Vec3 n = normal(rect);
  EXPECT_NEAR(glm::dot(n, glm::normalize(glm::cross(u, v))), 1.0, 1e-12);
  // Unit square far from the origin: Newell relative to the first vertex keeps it exact.
  std::vector<Vec3> far = lift(kUnitSquare, 0.0);
  for (Vec3& p : far) p += Vec3(1e9, 1e9, 0.0);
  EXPECT_EQ(area(far), 1.0);
}

TEST(Polygon, polygon_normal_follows_winding) {
  EXPECT_EQ(normal(lift(kUnitSquare)), Vec3(0, 0, 1));
  EXPECT_EQ(normal(lift(reversed(kUnitSquare))), Vec3(0, 0, -1));
  EXPECT_EQ(normal(lift({{0, 0}, {1, 0}, {2, 0}})), Vec3(0.0));  // zero area: zero normal
  EXPECT_EQ(vector_area(lift(kLShape)), Vec3(0, 0, 3));
}

TEST(Polygon, polygon_centroid_of_known_polygons) {
  const Vec3 c = centroid(lift(kLShape));
  EXPECT_NEAR(c.x, 5.0 / 6.0, 1e-15);
  EXPECT_NEAR(c.y, 5.0 / 6.0, 1e-15);
  // A triangle's centroid is its vertex mean; a square's its middle, however many collinear vertices.
  const Vec3 t = centroid(lift({{0, 0}, {6, 0}, {0, 3}}));
  EXPECT_NEAR(t.x, 2.0, 1e-15);
  EXPECT_NEAR(t.y, 1.0, 1e-15);
  const Vec3 s = centroid(lift({{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}}));
  EXPECT_NEAR(s.x, 1.0, 1e-15);
  EXPECT_NEAR(s.y, 1.0, 1e-15);
  // Zero area: the vertex mean.
  EXPECT_EQ(centroid(lift({{0, 0}, {1, 0}, {5, 0}})), Vec3(2, 0, 0));
}

// A comb is not star-shaped from its first vertex: some fan triangles from (0, 0) run clockwise (the one to (4, 2) and
// (4, 1)) and must count negatively. A strip 5 x 1 and three 1 x 1 teeth on it: area 8, centroid x 5/2 by symmetry,
// y (5 x 1/2 + 3 x 3/2) / 8 = 7/8.
TEST(Polygon, polygon_centroid_of_a_polygon_not_star_shaped_from_its_first_vertex) {
  const std::vector<Vec2> comb{{0, 0}, {5, 0}, {5, 2}, {4, 2}, {4, 1}, {3, 1},
                               {3, 2}, {2, 2}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  EXPECT_DOUBLE_EQ(area(lift(comb)), 8.0);
  const Vec3 c = centroid(lift(comb));
  EXPECT_NEAR(c.x, 2.5, 1e-15);
  EXPECT_NEAR(c.y, 0.875, 1e-15);
}

TEST(Polygon, polygon_planarity_and_plane) {
  EXPECT_EQ(planarity_deviation(lift(kLShape, 7.0)), 0.0);
  const Plane p = plane_of(lift(kLShape, 7.0));
  EXPECT_EQ(p.normal, Vec3(0, 0, 1));
  EXPECT_DOUBLE_EQ(p.d, -7.0);
  // Unit square with one corner lifted by h: Newell normal (-h, -h, 2); the area centroid of the two
  // equal-weight fan triangles is (1/2, 1/2, h/3), so the farthest vertices lie 2h / (3 sqrt(2 h^2 + 4))
  // from plane_of.
  const double h = 0.25;
  const std::vector<Vec3> bent{{0, 0, 0}, {1, 0, 0}, {1, 1, h}, {0, 1, 0}};
  EXPECT_NEAR(planarity_deviation(bent), 2.0 * h / (3.0 * std::sqrt(2.0 * h * h + 4.0)), 1e-15);
  const Vec3 n = normal(bent);
  EXPECT_NEAR(n.x, -h / std::sqrt(2.0 * h * h + 4.0), 1e-15);
  EXPECT_NEAR(n.z, 2.0 / std::sqrt(2.0 * h * h + 4.0), 1e-15);
}

// ---- Convexity and simplicity -------------------------------------------------------------------------

TEST(Polygon, polygon_convexity) {
  EXPECT_TRUE(is_convex(kUnitSquare));
  EXPECT_TRUE(is_convex(reversed(kUnitSquare)));  // either winding
  EXPECT_TRUE(is_convex(std::vector<Vec2>{{0, 0}, {1, 0}, {0, 1}}));
  EXPECT_FALSE(is_convex(kLShape));
  EXPECT_FALSE(is_convex(kBowTie));
  // A collinear vertex in the middle of an edge keeps a polygon convex.
  EXPECT_TRUE(is_convex(std::vector<Vec2>{{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}}));
  // All vertices on one line: not a convex polygon.
  EXPECT_FALSE(is_convex(std::vector<Vec2>{{0, 0}, {1, 1}, {3, 3}}));
  // A pentagram turns one way only but winds twice.
  std::vector<Vec2> star;
  for (int i = 0; i < 5; ++i) star.emplace_back(std::cos(4.0 * kPi * i / 5.0), std::sin(4.0 * kPi * i / 5.0));
  EXPECT_FALSE(is_convex(star));
  // A vertex one ulp inside (reflex) or outside (convex) an edge's line is seen exactly.
  EXPECT_FALSE(is_convex(std::vector<Vec2>{{0, 0}, {2, 0}, {2, 2}, {1, std::nextafter(2.0, 0.0)}, {0, 2}}));
  EXPECT_TRUE(is_convex(std::vector<Vec2>{{0, 0}, {2, 0}, {2, 2}, {1, std::nextafter(2.0, 3.0)}, {0, 2}}));
  EXPECT_FALSE(is_convex(std::vector<Vec2>{{0, 0}, {1, std::nextafter(0.0, 1.0)}, {2, 0}, {2, 2}, {0, 2}}));
  EXPECT_TRUE(is_convex(std::vector<Vec2>{{0, 0}, {1, -std::nextafter(0.0, 1.0)}, {2, 0}, {2, 2}, {0, 2}}));
}

TEST(Polygon, polygon_simplicity) {
  EXPECT_TRUE(is_simple(kUnitSquare));
  EXPECT_TRUE(is_simple(kLShape));
  EXPECT_TRUE(is_simple(reversed(kLShape)));
  EXPECT_FALSE(is_simple(kBowTie));
  // Asymmetric bow-tie (nonzero signed area) is still self-intersecting.
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {3, 2}, {3, 0}, {0, 1}}));
  // A straight-through collinear vertex is fine; a fold back along the same line is not.
  EXPECT_TRUE(is_simple(std::vector<Vec2>{{0, 0}, {1, 0}, {2, 0}, {2, 2}}));
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {2, 0}, {1, 0}, {1, 1}}));
  // A vertex touching a non-adjacent edge, a repeated vertex, a zero-length edge, too few vertices.
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {4, 0}, {4, 4}, {2, 0}, {0, 4}}));
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {2, 0}, {1, 1}, {2, 2}, {0, 2}, {1, 1}}));
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {1, 0}, {1, 0}, {0, 1}}));
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {1, 0}}));
  // All collinear: the closing edge folds back over the others.
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {1, 0}, {2, 0}}));
  // Near-touching by the smallest subnormal stays simple; touching does not (above).
  EXPECT_TRUE(is_simple(std::vector<Vec2>{{0, 0}, {4, 0}, {4, 4}, {2, std::nextafter(0.0, 1.0)}, {0, 4}}));
  EXPECT_FALSE(is_simple(std::vector<Vec2>{{0, 0}, {4, 0}, {4, 4}, {2, -std::nextafter(0.0, 1.0)}, {0, 4}}));
}

// is_simple tests only the pairs of edges whose bounding boxes meet (a circle of 50 000 vertices took 11 s when
// it tested all). Against every pair, on random polygons with vertices on a small integer grid, where edges touch,
// overlap and cross at vertices, and on long thin ones: the same answer.
TEST(Polygon, polygon_simplicity_matches_testing_every_pair) {
  const auto every_pair = [](const std::vector<Vec2>& p) {
    const std::size_t n = p.size();
    for (std::size_t i = 0; i < n; ++i)
      if (p[i] == p[(i + 1) % n]) return false;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) {
        const Vec2 &a = p[i], &b = p[(i + 1) % n], &c = p[j], &d = p[(j + 1) % n];
        if (j == i + 1 || (i == 0 && j == n - 1)) {
          const Vec2& shared = j == i + 1 ? b : a;
          const Vec2& u = j == i + 1 ? a : b;
          const Vec2& w = j == i + 1 ? d : c;
          if (orientation(u, shared, w) == Sign::kZero && glm::dot(u - shared, w - shared) > 0.0) return false;
        } else if (segments_intersect(a, b, c, d)) {
          return false;
        }
      }
    return true;
  };
  std::mt19937 rng(7);
  int simple = 0, not_simple = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int n = 3 + static_cast<int>(rng() % 8), grid = 2 + static_cast<int>(rng() % 5);
    const double squash = trial % 3 == 0 ? 1e-3 : 1.0;  // a third of them long and thin
    std::vector<Vec2> p;
    for (int k = 0; k < n; ++k)
      p.emplace_back(static_cast<double>(rng() % grid), static_cast<double>(rng() % grid) * squash);
    const bool expected = every_pair(p);
    ASSERT_EQ(is_simple(p), expected) << "trial " << trial;
    (expected ? simple : not_simple) += 1;
  }
  EXPECT_GT(simple, 500);  // both answers are exercised
  EXPECT_GT(not_simple, 500);
  // A large polygon: a circle of 20 000 vertices is simple; with one vertex pulled across it, it is not.
  std::vector<Vec2> circle;
  for (int k = 0; k < 20000; ++k) circle.emplace_back(std::cos(k * 2 * kPi / 20000), std::sin(k * 2 * kPi / 20000));
  EXPECT_TRUE(is_simple(circle));
  circle[5000] = Vec2(0.0, -2.0);
  EXPECT_FALSE(is_simple(circle));
}

TEST(Polygon, polygon_projection_keeps_winding) {
  // A counter-clockwise triangle seen from n projects to a counter-clockwise 2D triangle, whichever
  // axis n is closest to and whichever way it points.
  const std::vector<Vec3> axes{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {1, 2, 3}, {-3, 1, -2}};
  for (const Vec3& axis : axes) {
    const Vec3 n = glm::normalize(axis);
    const Vec3 a = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
    const Vec3 b = glm::cross(n, a);
    const std::vector<Vec3> tri{Vec3(0.0), 2.0 * a, 3.0 * b};
    ASSERT_GT(glm::dot(normal(tri), n), 0.99);
    std::vector<Vec2> flat(3);
    project_to_2d(tri, n, flat);
    EXPECT_GT(signed_area(flat), 0.0) << "normal " << n.x << " " << n.y << " " << n.z;
  }
}

// ---- Exact predicates ----------------------------------------------------------------------------------

Sign exact_orientation(const Vec2& a, const Vec2& b, const Vec2& c) {
  const Q det = (Q(b.x) - Q(a.x)) * (Q(c.y) - Q(a.y)) - (Q(b.y) - Q(a.y)) * (Q(c.x) - Q(a.x));
  return static_cast<Sign>(static_cast<int>(CGAL::sign(det)));
}

TEST(Predicates, predicate_orientation_collinear_near_1e_300_and_1e300) {
  for (const double scale : {1e-300, 1e-310, 1e300}) {
    // Multiplying by a power of two is exact (also for subnormals as long as nothing is lost).
    const Vec2 p(0.75 * scale, 0.5 * scale), q = 2.0 * p, r = 4.0 * p;
    EXPECT_EQ(orientation(p, q, r), Sign::kZero) << scale;
    EXPECT_EQ(orientation(r, q, p), Sign::kZero) << scale;
    // One ulp above or below the line through the origin direction (3, 2).
    const Vec2 above(r.x, std::nextafter(r.y, std::numeric_limits<double>::infinity()));
    const Vec2 below(r.x, std::nextafter(r.y, -std::numeric_limits<double>::infinity()));
    EXPECT_EQ(orientation(p, q, above), Sign::kPositive) << scale;
    EXPECT_EQ(orientation(p, q, below), Sign::kNegative) << scale;
    EXPECT_EQ(orientation(q, p, above), Sign::kNegative) << scale;
  }
}

TEST(Predicates, predicate_orientation_matches_exact_on_near_collinear_grid) {
  // Shewchuk's classic failure of the naive determinant: points within a few ulps of the line y = x
  // against (12, 12) and (24, 24).
  const double ulp = std::nextafter(0.5, 1.0) - 0.5;
  int zero = 0;
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 64; ++j) {
      const Vec2 a(0.5 + i * ulp, 0.5 + j * ulp), b(12, 12), c(24, 24);
      const Sign expected = exact_orientation(a, b, c);
      ASSERT_EQ(orientation(a, b, c), expected) << i << " " << j;
      zero += expected == Sign::kZero;
    }
  EXPECT_EQ(zero, 64);  // exactly the diagonal i == j is collinear
}

// contains() decides each crossing with the exact orientation, so a point one ulp off an edge is classified as
// exact arithmetic says. The crossing abscissa in doubles gets about 6 % of such points wrong (the initial meshing
// asks it about the centroids of Delaunay triangles, slivers among them).
TEST(Polygon, polygon_contains_points_one_ulp_from_an_edge) {
  // A case the crossing abscissa in doubles gets wrong: p is one ulp left of the upward edge lo -> hi, inside.
  const Vec2 lo(0.47224524357611664, 0.37961522332372777), hi(0.20995480637147712, 0.48785665652414756);
  const std::vector<Vec2> triangle{lo, hi, Vec2(0.1, 0.3)};
  const Vec2 p(0.23793672592131898, 0.4763091403125266);
  ASSERT_EQ(exact_orientation(lo, hi, p), Sign::kPositive);
  EXPECT_TRUE(contains(triangle, p));
  const Vec2 q(std::nextafter(p.x, 1.0), p.y);  // one ulp to the right: outside
  ASSERT_EQ(exact_orientation(lo, hi, q), Sign::kNegative);
  EXPECT_FALSE(contains(triangle, q));

  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int tested = 0;
  for (int t = 0; t < 4000; ++t) {
    std::vector<Vec2> tri{Vec2(unit(random), unit(random)), Vec2(unit(random), unit(random)),
                          Vec2(unit(random), unit(random))};
    if (exact_orientation(tri[0], tri[1], tri[2]) != Sign::kPositive) std::swap(tri[1], tri[2]);
    if (exact_orientation(tri[0], tri[1], tri[2]) != Sign::kPositive) continue;
    const Vec2 a = tri[t % 3], b = tri[(t + 1) % 3];
    const double s = unit(random);
    Vec2 point = a + s * (b - a);
    point.x = std::nextafter(point.x, t % 2 == 0 ? -1.0 : 2.0);
    bool inside = true, on_boundary = false;
    for (int k = 0; k < 3; ++k) {
      const Sign side = exact_orientation(tri[k], tri[(k + 1) % 3], point);
      inside = inside && side == Sign::kPositive;
      on_boundary = on_boundary || side == Sign::kZero;
    }
    if (on_boundary) continue;
    ++tested;
    ASSERT_EQ(contains(tri, point), inside) << t;
  }
  EXPECT_GT(tested, 3000);
}

TEST(Predicates, predicate_orientation_3d_coplanar_near_1e_300_and_1e300) {
  // Powers of two near 1e-300, 1e-310 (subnormal) and 1e300, so that 1.5 x scale etc. are exact.
  for (const double scale : {std::ldexp(1.0, -997), std::ldexp(1.0, -1030), std::ldexp(1.0, 996)}) {
    const Vec3 p(0.0), q(scale, 0.0, 0.0), r(0.0, scale, 0.0), s(0.5 * scale, 0.25 * scale, 0.0);
    EXPECT_EQ(orientation(p, q, r, s), Sign::kZero) << scale;
    const double tiny = std::numeric_limits<double>::denorm_min();
    EXPECT_EQ(orientation(p, q, r, Vec3(s.x, s.y, tiny)), Sign::kPositive) << scale;  // the side (q-p)x(r-p) = +z
    EXPECT_EQ(orientation(p, q, r, Vec3(s.x, s.y, -tiny)), Sign::kNegative) << scale;
    // The tilted plane z = x + y through exactly representable points; the normal a x b points to -z.
    const Vec3 a(scale, 0.5 * scale, 1.5 * scale), b(0.25 * scale, scale, 1.25 * scale), c(0.0), d(2 * scale, 2 * scale, 4 * scale);
    EXPECT_EQ(orientation(c, a, b, d), Sign::kZero) << scale;
    EXPECT_EQ(orientation(c, a, b, Vec3(d.x, d.y, std::nextafter(d.z, 0.0))), Sign::kNegative) << scale;
  }
  // The documented convention with plain numbers.
  EXPECT_EQ(orientation(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)), Sign::kPositive);
}

TEST(Predicates, predicate_linear_sign_and_side_of_plane_match_exact) {
  // Points placed on a plane through the origin (computed in double at unit scale, then scaled by a
  // power of two so the residual is whatever the rounding left) are classified like exact rationals do,
  // also where products underflow to subnormals (scale near 1e-300) or overflow (near 1e300).
  std::mt19937_64 rng(20240611);
  std::uniform_real_distribution<double> unit(1.0, 2.0);
  int decided = 0;
  // Products of size 2^exponent: subnormal below -1022, overflowing sums at 1024.
  for (const int exponent : {-1060, -1040, -1030, -1000, 0, 1000, 1024}) {
    for (int trial = 0; trial < 20000; ++trial) {
      Vec3 a(unit(rng), unit(rng), -unit(rng));
      Vec3 s(unit(rng), unit(rng), 0.0);
      s.z = (a.x * s.x + a.y * s.y) / -a.z;
      a = Vec3(std::ldexp(a.x, exponent / 2), std::ldexp(a.y, exponent / 2), std::ldexp(a.z, exponent / 2));
      s = Vec3(std::ldexp(s.x, exponent / 2), std::ldexp(s.y, exponent / 2), std::ldexp(s.z, exponent / 2));
      const Q exact = Q(a.x) * Q(s.x) + Q(a.y) * Q(s.y) + Q(a.z) * Q(s.z);
      const Sign expected = static_cast<Sign>(static_cast<int>(CGAL::sign(exact)));
      ASSERT_EQ(sign_of_linear(a, 0.0, s), expected) << "2^" << exponent << " trial " << trial;
      ASSERT_EQ(side_of_plane(Vec3(0.0), a, s), expected) << "2^" << exponent << " trial " << trial;
      decided += expected != Sign::kZero;
    }
  }
  EXPECT_GT(decided, 0);
}

TEST(Predicates, predicate_side_of_plane_exact_zero_and_one_ulp) {
  // Powers of two near 1e-300 and 1e300, so that 1.25 x scale etc. are exact.
  for (const double scale : {std::ldexp(1.0, -997), 1.0, std::ldexp(1.0, 996)}) {
    const Vec3 origin(0.5 * scale, 0.25 * scale, scale), n(1.0, 2.0, -1.0);
    const Vec3 on(0.25 * scale, 0.5 * scale, 1.25 * scale);  // on - origin = (-0.25, 0.25, 0.25) scale: n . it = 0
    EXPECT_EQ(side_of_plane(origin, n, on), Sign::kZero) << scale;
    EXPECT_EQ(side_of_plane(origin, n, Vec3(on.x, on.y, std::nextafter(on.z, 0.0))), Sign::kPositive) << scale;
    EXPECT_EQ(side_of_plane(origin, n, Vec3(on.x, on.y, std::nextafter(on.z, 2.0 * on.z))), Sign::kNegative) << scale;
    // The same plane as the linear form n . s + d with d = -n . origin = -(0.5 + 0.5 - 1) scale = 0.
    EXPECT_EQ(sign_of_linear(n, 0.0, on), Sign::kZero) << scale;
  }
  // Overflowing products: n . s = 1e300 * 1e300 - 1e300 * 1e300 is exactly zero.
  EXPECT_EQ(sign_of_linear(Vec3(1e300, -1e300, 0.0), 0.0, Vec3(1e300, 1e300, 0.0)), Sign::kZero);
  EXPECT_EQ(sign_of_linear(Vec3(1e300, -1e300, 0.0), 0.0, Vec3(1e300, std::nextafter(1e300, 0.0), 0.0)),
            Sign::kPositive);
}

TEST(Predicates, predicate_segments_intersect_touching_and_collinear) {
  EXPECT_TRUE(segments_intersect({0, 0}, {2, 2}, {0, 2}, {2, 0}));    // crossing
  EXPECT_TRUE(segments_intersect({0, 0}, {1, 0}, {1, 0}, {1, 1}));    // shared endpoint
  EXPECT_TRUE(segments_intersect({0, 0}, {2, 0}, {1, 0}, {1, 1}));    // T touch
  EXPECT_TRUE(segments_intersect({0, 0}, {2, 0}, {1, 0}, {3, 0}));    // collinear overlap
  EXPECT_FALSE(segments_intersect({0, 0}, {1, 0}, {2, 0}, {3, 0}));   // collinear, apart
  EXPECT_FALSE(segments_intersect({0, 0}, {1, 0}, {0, 1}, {1, 1}));   // parallel
  const double t = 1e-300;
  EXPECT_TRUE(segments_intersect({0, 0}, {2 * t, 0}, {t, 0}, {t, t}));
  EXPECT_FALSE(segments_intersect({0, 0}, {2 * t, 0}, {t, std::nextafter(0.0, 1.0)}, {t, t}));
  const double big = 1e300, tiny = std::numeric_limits<double>::denorm_min();
  EXPECT_TRUE(segments_intersect({-big, -big}, {big, big}, {-big, big}, {big, -big}));
  EXPECT_FALSE(segments_intersect({-big, 0}, {big, 0}, {-big, tiny}, {big, tiny}));  // parallel, one subnormal apart
  EXPECT_TRUE(segments_intersect({-big, 0}, {big, 0}, {-big, tiny}, {big, -tiny}));  // crossing at the origin
}

TEST(Polygon, polygon_convex_intersection_areas) {
  const std::vector<Vec2> unit{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const std::vector<Vec2> shifted{{0.5, 0.5}, {1.5, 0.5}, {1.5, 1.5}, {0.5, 1.5}};
  const std::vector<Vec2> apart{{2, 0}, {3, 0}, {3, 1}, {2, 1}};
  const std::vector<Vec2> inside{{0.25, 0.25}, {0.75, 0.25}, {0.5, 0.75}};
  const std::vector<Vec2> neighbour{{1, 0}, {2, 0}, {2, 1}, {1, 1}};  // shares an edge
  EXPECT_DOUBLE_EQ(convex_intersection_area(unit, shifted), 0.25);
  EXPECT_DOUBLE_EQ(convex_intersection_area(shifted, unit), 0.25);
  EXPECT_EQ(convex_intersection_area(unit, apart), 0.0);
  EXPECT_DOUBLE_EQ(convex_intersection_area(unit, inside), 0.125);
  EXPECT_DOUBLE_EQ(convex_intersection_area(inside, unit), 0.125);
  EXPECT_EQ(convex_intersection_area(unit, neighbour), 0.0);
  // A square turned by 45 degrees over the unit square, centred on it: an octagon of area 2 (sqrt(2) - 1).
  const double r = std::sqrt(0.5);
  const std::vector<Vec2> diamond{{0.5, 0.5 - r}, {0.5 + r, 0.5}, {0.5, 0.5 + r}, {0.5 - r, 0.5}};
  EXPECT_NEAR(convex_intersection_area(unit, diamond), 2.0 * (std::sqrt(2.0) - 1.0), 1e-15);
}

TEST(Polygon, polygon_ear_clip_covers_a_concave_polygon) {
  // An L of area 3 and a comb: the triangles add up to the polygon's area, all counter-clockwise.
  const std::vector<std::vector<Vec2>> polygons = {
      {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}},
      {{0, 0}, {5, 0}, {5, 2}, {4, 2}, {4, 1}, {3, 1}, {3, 2}, {2, 2}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}};
  for (const auto& p : polygons) {
    std::vector<std::array<std::size_t, 3>> triangles;
    ear_clip(p, triangles);
    EXPECT_EQ(triangles.size(), p.size() - 2);
    double sum = 0.0;
    for (const auto& t : triangles) {
      const std::vector<Vec2> tri{p[t[0]], p[t[1]], p[t[2]]};
      EXPECT_GE(signed_area(tri), 0.0);
      sum += signed_area(tri);
    }
    EXPECT_DOUBLE_EQ(sum, signed_area(p));
  }
}

// Polygons over 64 vertices are clipped with a ring and a grid (ear clipping restarted from the first vertex took
// 82 s for a non-planar face of 100 000). A wavy circle, a comb of 100 teeth and a spiral, each of thousands of
// vertices: n - 2 triangles, none clockwise, covering the polygon's area.
TEST(Polygon, polygon_ear_clip_of_large_concave_polygons) {
  std::vector<std::vector<Vec2>> polygons;
  {
    std::vector<Vec2> wavy;
    for (int i = 0; i < 3000; ++i) {
      const double angle = 2.0 * std::acos(-1.0) * i / 3000.0, radius = 1.0 + 0.2 * std::sin(40.0 * angle);
      wavy.emplace_back(radius * std::cos(angle), radius * std::sin(angle));
    }
    polygons.push_back(wavy);
  }
  {
    std::vector<Vec2> comb{{0, 0}, {200, 0}};
    for (int tooth = 99; tooth >= 0; --tooth) {
      const double x = 2.0 * tooth;
      comb.insert(comb.end(), {{x + 2, 5}, {x + 1, 5}, {x + 1, 1}});
      if (tooth > 0) comb.emplace_back(x, 1);
    }
    comb.emplace_back(0, 5);
    polygons.push_back(comb);
  }
  {
    std::vector<Vec2> spiral;  // a band wound twice round: the outer edge out, the inner one back
    const int steps = 1000;
    for (int i = 0; i <= steps; ++i) {
      const double angle = 4.0 * std::acos(-1.0) * i / steps, r = 1.0 + angle;
      spiral.emplace_back(r * std::cos(angle), r * std::sin(angle));
    }
    for (int i = steps; i >= 0; --i) {
      const double angle = 4.0 * std::acos(-1.0) * i / steps, r = 0.5 + angle;
      spiral.emplace_back(r * std::cos(angle), r * std::sin(angle));
    }
    polygons.push_back(spiral);
  }
  {
    // A circle of radius 1e308: its span overflows a double, and the grid's cell index was a nan cast to an integer
    // (a crash): it gets the triangles of the unit circle.
    std::vector<Vec2> huge, same;
    for (int i = 0; i < 65; ++i) {
      const double angle = 2.0 * std::acos(-1.0) * i / 65.0;
      huge.emplace_back(1e308 * std::cos(angle), 1e308 * std::sin(angle));
      same.emplace_back(std::cos(angle), std::sin(angle));
    }
    std::vector<std::array<std::size_t, 3>> of_huge, of_same;
    ear_clip(huge, of_huge);
    ear_clip(same, of_same);
    EXPECT_EQ(of_huge.size(), 63u);
    EXPECT_EQ(of_huge, of_same);
  }
  for (const auto& p : polygons) {
    ASSERT_TRUE(is_simple(p));
    ASSERT_GT(signed_area(p), 0.0);
    std::vector<std::array<std::size_t, 3>> triangles;
    ear_clip(p, triangles);
    EXPECT_EQ(triangles.size(), p.size() - 2);
    double sum = 0.0;
    std::size_t clockwise = 0;
    for (const auto& t : triangles) {
      const std::vector<Vec2> tri{p[t[0]], p[t[1]], p[t[2]]};
      clockwise += signed_area(tri) < 0.0;
      sum += signed_area(tri);
    }
    EXPECT_EQ(clockwise, 0u);
    EXPECT_NEAR(sum, signed_area(p), 1e-9 * signed_area(p));
  }
}

}  // namespace
}  // namespace aarad
