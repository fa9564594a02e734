// Hemicube geometry: delta form-factor tables (Cohen and Greenberg 1985; references.md), the shooter's frame,
// culling, and exact clipping to the five faces (Chandran et al. section 3.2).
#include "aarad/core/error.h"
#include "aarad/formfactor/analytic.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/hemicube_geometry.h"
#include "formfactor_fixtures.h"

#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace aarad::formfactor {
namespace {

using testing::Polygon;

// The exactness arguments of hemicube_geometry.h take every product as rounded before the sum it feeds. aarad_core
// passes -ffp-contract=off to everything that includes its headers; without it, GCC fuses a * b + c into one fma
// whenever the target has FMA (-march=native), and the office scene's adaptive mesh came out different, with a
// non-manifold vertex. Here a * b = 1 - 2^-54 exactly, which rounds to 1: a * b - 1 is 0 rounded twice and -2^-54
// fused. The operands are read through volatile, so the compiler cannot fold the expression.
TEST(HemicubeGeometry, ProductsAreRoundedBeforeTheyAreAdded) {
  volatile double va = 1.0 + 0x1p-27, vb = 1.0 - 0x1p-27, vc = -1.0;
  const double a = va, b = vb, c = vc;
  EXPECT_EQ(a * b + c, 0.0);
}

TEST(HemicubeGeometry, ExactDeltaTablesSumToOne) {
  for (int n : {2, 7, 100, 101, 300}) {
    const HemicubeGeometry g(n);
    EXPECT_LT(std::abs(g.total() - 1.0), 5e-5) << n;
    EXPECT_NEAR(g.total(), 1.0, 1e-12) << n;
    EXPECT_NEAR(g.face_total(HemicubeFace::kTop), 0.5541264, 5e-8) << n;
    for (HemicubeFace f : {HemicubeFace::kPosU, HemicubeFace::kNegU, HemicubeFace::kPosV, HemicubeFace::kNegV})
      EXPECT_NEAR(g.face_total(f), 0.1114684, 5e-8) << n;
  }
}

// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n from the Chebyshev guesses), for quadratures in
// these tests that share nothing with the code under test.
struct GaussLegendre {
  std::vector<double> x, w;
  explicit GaussLegendre(int n) {
    for (int i = 0; i < n; ++i) {
      double t = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = t;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (t * p1 - p0) / (t * t - 1.0);
        const double step = p1 / dp;
        t -= step;
        if (std::abs(step) < 1e-17) break;
      }
      x.push_back(t);
      w.push_back(2.0 / ((1.0 - t * t) * dp * dp));
    }
  }
  // The integral of f(y, z) over [y0, y1] x [z0, z1], each side cut into `panels` equal panels.
  template <typename F>
  double integrate(F f, double y0, double y1, double z0, double z1, int panels) const {
    double sum = 0.0;
    const double hy = (y1 - y0) / panels, hz = (z1 - z0) / panels;
    for (int a = 0; a < panels; ++a)
      for (int b = 0; b < panels; ++b)
        for (std::size_t i = 0; i < x.size(); ++i)
          for (std::size_t j = 0; j < x.size(); ++j) {
            const double y = y0 + hy * (a + 0.5 * (x[i] + 1.0)), z = z0 + hz * (b + 0.5 * (x[j] + 1.0));
            sum += 0.25 * hy * hz * w[i] * w[j] * f(y, z);
          }
    return sum;
  }
};

// The side-face delta form-factor kernel of references.md (Cohen and Greenberg 1985): a cell at lateral
// coordinate y and height z above the base of a side face at distance 1 gets z dA / (pi (y^2 + z^2 + 1)^2).
double side_kernel(double y, double z) {
  const double q = y * y + z * z + 1.0;
  return z / (kPi * q * q);
}
// The top-face kernel of references.md: dA / (pi (x^2 + y^2 + 1)^2).
double top_kernel(double x, double y) {
  const double q = x * x + y * y + 1.0;
  return 1.0 / (kPi * q * q);
}

TEST(HemicubeGeometry, MidpointDeltaTablesMatchPublishedQuantisation) {
  // references.md: sum - 1 is about 8.6e-3 at R = 8, 5.3e-4 at R = 32, 3.3e-5 at R = 128.
  EXPECT_NEAR(HemicubeGeometry(8, DeltaRule::kMidpoint).total() - 1.0, 8.6e-3, 0.05e-3);
  EXPECT_NEAR(HemicubeGeometry(32, DeltaRule::kMidpoint).total() - 1.0, 5.3e-4, 0.05e-4);
  EXPECT_NEAR(HemicubeGeometry(128, DeltaRule::kMidpoint).total() - 1.0, 3.3e-5, 0.05e-5);
  // O(1 / R^2): doubling R quarters the error.
  for (int n : {16, 64, 256}) {
    const double e1 = HemicubeGeometry(n, DeltaRule::kMidpoint).total() - 1.0;
    const double e2 = HemicubeGeometry(2 * n, DeltaRule::kMidpoint).total() - 1.0;
    EXPECT_NEAR(e1 / e2, 4.0, 0.01) << n;
  }
  // At N = 100 (even: no half row) the midpoint table is references.md's two formulas at the cell centres,
  // summed here cell by cell: the top face's N x N cells and four side faces of N x N/2 cells, each of side
  // 2/N. The code's table must give that sum to rounding.
  const int n = 100;
  const double cell = 2.0 / n;
  double sum = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) sum += top_kernel(-1.0 + (i + 0.5) * cell, -1.0 + (j + 0.5) * cell) * cell * cell;
  for (int r = 0; r < n / 2; ++r)
    for (int i = 0; i < n; ++i) sum += 4.0 * side_kernel(-1.0 + (i + 0.5) * cell, (r + 0.5) * cell) * cell * cell;
  const double midpoint_100 = HemicubeGeometry(n, DeltaRule::kMidpoint).total() - 1.0;
  std::printf("N = 100 midpoint table: sum - 1 = %.4e (references.md formulas summed here: %.4e)\n", midpoint_100,
              sum - 1.0);
  EXPECT_NEAR(midpoint_100, sum - 1.0, 1e-12);
  // And the published O(1/R^2) law: 3.3e-5 at R = 128 (two digits, so +-0.05e-5) scaled by (128/100)^2 gives
  // 5.41e-5 +- 0.08e-5 at N = 100. The midpoint rule's error there is why the back ends use the exact cell
  // integrals.
  const double scaled = 3.3e-5 * (128.0 / 100.0) * (128.0 / 100.0), scaled_slack = 0.05e-5 * (128.0 / 100.0) * (128.0 / 100.0);
  EXPECT_NEAR(midpoint_100, scaled, scaled_slack);
}

TEST(HemicubeGeometry, OddResolutionHalfRow) {
  const HemicubeGeometry g(7);
  EXPECT_EQ(g.height(HemicubeFace::kPosU), 4);
  EXPECT_DOUBLE_EQ(g.sample_y(HemicubeFace::kPosU, 3), 3.25);
  EXPECT_DOUBLE_EQ(g.sample_y(HemicubeFace::kPosU, 2), 2.5);
  // The half row's delta form factor is the integral over its lower half only: heights z in [6/7, 1] (pixel
  // rows [3, 3.5) at N/2 = 3.5 rows per unit height), lateral y in [-1, 1]. Face +u: a = u, l1 = v, l2 = w, so
  // on the face u = 1 the lateral coordinate is v and the height w, and the kernel is references.md's
  // z / (pi (y^2 + z^2 + 1)^2). Integrated here by Gauss-Legendre quadrature, independently of the tables.
  const GaussLegendre gl(20);
  const double half_row = gl.integrate(side_kernel, -1.0, 1.0, 6.0 / 7.0, 1.0, 4);
  const double coarser = gl.integrate(side_kernel, -1.0, 1.0, 6.0 / 7.0, 1.0, 2);
  ASSERT_NEAR(half_row, coarser, 1e-15);  // the quadrature has converged
  // The whole side face by the same quadrature is references.md's 0.1114684, so the kernel and region are right.
  EXPECT_NEAR(gl.integrate(side_kernel, -1.0, 1.0, 0.0, 1.0, 4), 0.1114684, 5e-8);
  double row = 0.0;
  for (int x = 0; x < 7; ++x) row += g.delta(HemicubeFace::kPosU)[3 * 7 + x];
  std::printf("N = 7 half row: table %.17g, quadrature %.17g (difference %.1e)\n", row, half_row, row - half_row);
  EXPECT_NEAR(row, half_row, 1e-13);
  // The full row below it, z in [4/7, 6/7], for contrast: the half row is not simply half of a full row.
  double below = 0.0;
  for (int x = 0; x < 7; ++x) below += g.delta(HemicubeFace::kPosU)[2 * 7 + x];
  EXPECT_NEAR(below, gl.integrate(side_kernel, -1.0, 1.0, 4.0 / 7.0, 6.0 / 7.0, 4), 1e-13);
}

// The sums above telescope: the exact tables are differences of corner form factors, so a face's sum is its outer
// corners' value whatever the cells in between hold. Here every cell on its own against Gauss-Legendre quadrature
// of references.md's kernels over the cell, which shares nothing with the tables' closed forms. Top face: pixel
// (x, y) is [-1 + 2x/N, -1 + 2(x+1)/N] x [-1 + 2y/N, -1 + 2(y+1)/N] of the plane at distance 1. Side faces: column
// x spans the lateral [-1 + 2x/N, -1 + 2(x+1)/N], row r the heights [2r/N, 2(r+1)/N] cut at 1 (the half row of an
// odd N). Both kernels are even in each coordinate, so the direction in which the tables count does not matter.
TEST(HemicubeGeometry, EveryExactCellIsTheIntegralOfTheKernelOverIt) {
  const GaussLegendre gl(12);
  for (int n : {2, 7, 12, 31, 100}) {
    const HemicubeGeometry g(n);
    const double cell = 2.0 / n;
    double worst = 0.0;
    const auto top = g.delta(HemicubeFace::kTop);
    ASSERT_EQ(top.size(), static_cast<std::size_t>(n) * n);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double x0 = -1.0 + x * cell, y0 = -1.0 + y * cell;
        const double expected = gl.integrate(top_kernel, x0, x0 + cell, y0, y0 + cell, 1);
        worst = std::max(worst, std::abs(top[static_cast<std::size_t>(y) * n + x] - expected));
      }
    const int rows = g.height(HemicubeFace::kPosU);
    EXPECT_EQ(rows, (n + 1) / 2) << n;
    const auto side = g.delta(HemicubeFace::kPosU);
    for (int r = 0; r < rows; ++r)
      for (int x = 0; x < n; ++x) {
        const double y0 = -1.0 + x * cell, z0 = r * cell, z1 = std::min(1.0, z0 + cell);
        const double expected = gl.integrate(side_kernel, y0, y0 + cell, z0, z1, 1);
        worst = std::max(worst, std::abs(side[static_cast<std::size_t>(r) * n + x] - expected));
      }
    // A cell is a difference of corner values up to 1/4 (cancellation grows with N), so the bound is absolute: a
    // few roundings of the corners. A cell read from the wrong corners is off by about a cell, 1e-4 at N = 31.
    std::printf("N = %d: worst difference of a cell from its quadrature %.2e\n", n, worst);
    EXPECT_LT(worst, 1e-15) << n;
  }
}

TEST(HemicubeGeometry, ShooterFrameIsRightHandedAndDeterministic) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  for (int k = 0; k < 100; ++k) {
    const Vec3 n = glm::normalize(Vec3(g(rng), g(rng), g(rng)));
    const Shooter s = Shooter::from_normal(Vec3(1, 2, 3), n);
    EXPECT_NEAR(glm::length(s.tangent), 1.0, 1e-15);
    EXPECT_NEAR(glm::dot(s.tangent, s.normal), 0.0, 1e-15);
    EXPECT_NEAR(glm::length(glm::cross(s.tangent, s.bitangent) - s.normal), 0.0, 1e-15);
    const Shooter again = Shooter::from_normal(Vec3(1, 2, 3), n);
    EXPECT_EQ(s.tangent, again.tangent);
  }
  const Shooter up = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  EXPECT_EQ(up.tangent, Vec3(1, 0, 0));
  EXPECT_EQ(up.bitangent, Vec3(0, 1, 0));
}

TEST(HemicubeGeometry, BackFaceCullingIsExact) {
  ReceiverView view;
  testing::add(view, testing::rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 0);  // faces down: seen
  testing::add(view, testing::rectangle({0, 0, 1}, {1, 0, 0}, {0, 1, 0}), 1, 1);  // faces up: culled
  testing::add(view, testing::rectangle({1, 0, 0}, {1, 0, 0}, {0, 1, 0}), 2, 2);  // coplanar with the point
  // A second piece of patch 0 with a plane that would not face the point: the patch decides.
  view.add(testing::rectangle({0, 0, 2}, {1, 0, 0}, {0, 1, 0}), Plane{{0, 0, 1}, -2.0}, 0, 0);
  BackFaceCulling culling;
  const auto faces = [&](const ReceiverView& v) {
    culling.decide(Vec3(0), v);
    std::vector<bool> result;
    for (std::size_t i = 0; i < v.size(); ++i) result.push_back(culling.faces(i));
    // Each patch decided when first asked gives the same, asked in reverse order (patch 0 first through its second
    // piece, whose plane would not face the point: its first receiver still decides).
    culling.decide_when_asked(Vec3(0), v);
    for (std::size_t i = v.size(); i-- > 0;) EXPECT_EQ(culling.faces(i), result[i]) << "asked, receiver " << i;
    return result;
  };
  EXPECT_EQ(faces(view), (std::vector<bool>{true, false, false, true}));
  EXPECT_TRUE(faces_point(Plane{{0, 0, -1}, 1.0}, Vec3(0, 0, 1.0 - 1e-16)));
  EXPECT_FALSE(faces_point(Plane{{0, 0, -1}, 1.0}, Vec3(0, 0, 1.0)));

  // The deciding receivers are kept between shots and found again when the view changes: a new receiver of a new
  // patch; the same number of receivers with other patches; another view; sparse patch ids (per receiver).
  testing::add(view, testing::rectangle({0, 0, 3}, {0, 1, 0}, {1, 0, 0}), 3, 7);  // faces down: seen
  EXPECT_EQ(faces(view), (std::vector<bool>{true, false, false, true, true}));
  ReceiverView other;
  testing::add(other, testing::rectangle({0, 0, 1}, {1, 0, 0}, {0, 1, 0}), 1, 0);  // faces up: culled
  testing::add(other, testing::rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 1);  // faces down: seen
  EXPECT_EQ(faces(other), (std::vector<bool>{false, true}));
  other.clear();  // the same size again, each patch now first met at the other receiver
  testing::add(other, testing::rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 1);
  testing::add(other, testing::rectangle({0, 0, 1}, {1, 0, 0}, {0, 1, 0}), 1, 0);
  EXPECT_EQ(faces(other), (std::vector<bool>{true, false}));
  ReceiverView sparse;
  testing::add(sparse, testing::rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 1u << 30);
  EXPECT_EQ(faces(sparse), (std::vector<bool>{true}));
  sparse.add(testing::rectangle({0, 0, 2}, {1, 0, 0}, {0, 1, 0}), Plane{{0, 0, 1}, -2.0}, 0, 1u << 30);
  EXPECT_EQ(faces(sparse), (std::vector<bool>{true, false}));  // each receiver's own plane
}

TEST(HemicubeGeometry, ReceiverViewRefusesConflictingKeysAndStaysAsItWas) {
  // Keys 0 to 3 name a square's corners; a second square reusing key 2 for another point is refused, and the
  // view is left as before the call: the same points and corners, and its new keys (4, 5) still free.
  using testing::rectangle;
  const Polygon first = rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0});
  const Polygon second = rectangle({2, 0, 1}, {0, 1, 0}, {1, 0, 0});
  const Plane plane{{0, 0, -1}, 1.0};
  const std::uint32_t first_keys[4] = {0, 1, 2, 3}, conflicting[4] = {4, 5, 2, 6}, fresh[4] = {4, 5, 6, 7};
  ReceiverView view;
  view.add(first, first_keys, plane, 0, 0);
  const std::vector<Vec3> points(view.points().begin(), view.points().end());
  const std::vector<std::uint32_t> corners(view.corner_points().begin(), view.corner_points().end());
  EXPECT_THROW(view.add(second, conflicting, plane, 0, 1), Error);
  EXPECT_EQ(view.size(), 1u);
  EXPECT_EQ(std::vector<Vec3>(view.points().begin(), view.points().end()), points);
  EXPECT_EQ(std::vector<std::uint32_t>(view.corner_points().begin(), view.corner_points().end()), corners);
  // Keys 4 and 5 were bound to the second square's first corners before the conflict: free again, they take new
  // points, and every corner names its own polygon's vertex.
  view.add(second, fresh, plane, 0, 1);
  ASSERT_EQ(view.size(), 2u);
  ASSERT_EQ(view.corner_points().size(), view.vertices().size());
  for (std::size_t k = 0; k < view.vertices().size(); ++k)
    EXPECT_EQ(view.points()[view.corner_points()[k]], view.vertices()[k]) << k;
}

// A receiver wound clockwise round its plane's normal got -0.2395 from the analytic back end and 0 from both
// hemicubes (a back face): refused, by both add()s, with the view left as it was. A polygon of zero area passes.
TEST(HemicubeGeometry, ReceiverViewRefusesAPolygonWoundAgainstItsPlane) {
  using testing::rectangle;
  const Plane down{{0, 0, -1}, 1.0};  // z = 1, facing a shooter at the origin
  const Polygon counter = rectangle({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0});  // counter-clockwise round -z
  const Polygon clockwise(counter.rbegin(), counter.rend());
  const std::uint32_t keys[4] = {0, 1, 2, 3};
  ReceiverView view;
  view.add(counter, down, 0, 0);
  const std::uint64_t revision = view.revision();
  try {
    view.add(clockwise, down, 0, 1);
    ADD_FAILURE() << "no exception";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "ReceiverView::add: receiver 1 runs clockwise seen from the side its plane's normal points "
                           "to; reverse its corners or its plane");
  }
  EXPECT_THROW(view.add(clockwise, keys, down, 0, 1), Error);
  EXPECT_EQ(view.size(), 1u);
  EXPECT_EQ(view.points().size(), 4u);
  EXPECT_EQ(view.revision(), revision);
  const Polygon flat = {{0, 0, 1}, {1, 0, 1}, {2, 0, 1}};
  EXPECT_NO_THROW(view.add(flat, down, 0, 2));
  EXPECT_NO_THROW(view.add(counter, keys, down, 0, 3));
}

TEST(HemicubeGeometry, ReceiverViewRevisionNamesItsContents) {
  // What back ends keep between shots is keyed on the view's revision: every change of contents gives a new one,
  // never one another view had; a copy, with the same contents, keeps its original's.
  ReceiverView a, b;
  EXPECT_NE(a.revision(), b.revision());
  std::vector<std::uint64_t> seen{a.revision(), b.revision()};
  const auto fresh = [&](std::uint64_t r) {
    const bool is_new = std::find(seen.begin(), seen.end(), r) == seen.end();
    seen.push_back(r);
    return is_new;
  };
  testing::add(a, testing::rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 0);
  EXPECT_TRUE(fresh(a.revision()));
  const ReceiverView copy = a;
  EXPECT_EQ(copy.revision(), a.revision());
  b.start_from_points_of(a);
  EXPECT_TRUE(fresh(b.revision()));
  b.append_from(a, 0, 1);
  EXPECT_TRUE(fresh(b.revision()));
  const std::uint64_t before = b.revision();
  b.append_from(a, 1, 1);  // nothing appended: the same contents
  EXPECT_EQ(b.revision(), before);
  a.clear();
  EXPECT_TRUE(fresh(a.revision()));
  testing::add(a, testing::rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 0);
  EXPECT_TRUE(fresh(a.revision()));  // contents equal to an earlier revision's: a new one all the same
}

TEST(HemicubeGeometry, OutcodesAreTheFacePlaneSigns) {
  // Bit 4 f + k of frustum_outcode is set exactly when the point is outside plane k of face f, in that face's
  // coordinates (a, l1, l2): a - l1, a + l1, a - l2, and a + l2 on the top or l2 on a side, negative. Points on
  // the planes (a == +-l) and on the horizon (w == 0, +-0.0) included. Two more bits: u <= 0 and u >= 0.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 2000; ++i) points.push_back({uniform(rng), uniform(rng), uniform(rng)});
  for (double a : {-0.5, 0.0, -0.0, 0.5})
    for (double b : {-0.5, 0.0, -0.0, 0.5}) {
      points.push_back({a, b, 0.0});
      points.push_back({a, a, b});
      points.push_back({a, -a, b});
      points.push_back({b, a, a});
      points.push_back({b, a, -a});
      points.push_back({a, b, a});
    }
  for (const Vec3& q : points) {
    const std::uint32_t code = frustum_outcode(q);
    for (int f = 0; f < kHemicubeFaces; ++f) {
      const auto face = static_cast<HemicubeFace>(f);
      const Vec3 p = to_face(face, q);
      const bool top = face == HemicubeFace::kTop;
      const bool outside[4] = {p.x - p.y < 0.0, p.x + p.y < 0.0, p.x - p.z < 0.0, (top ? p.x + p.z : p.z) < 0.0};
      for (int k = 0; k < 4; ++k) EXPECT_EQ(((code >> (4 * f + k)) & 1u) != 0, outside[k]) << f << " " << k;
    }
    // The sides of the lines where face tasks meet: u = 0 and v = 0 (+-0.0 is on both sides), and the top face's
    // quarter lines 2u = -w and 2u = w, with their margin.
    EXPECT_EQ((code & kOutcodeUNotPositive) != 0, !(q.x > 0.0));
    EXPECT_EQ((code & kOutcodeUNotNegative) != 0, !(q.x < 0.0));
    EXPECT_EQ((code & kOutcodeVNotPositive) != 0, !(q.y > 0.0));
    EXPECT_EQ((code & kOutcodeVNotNegative) != 0, !(q.y < 0.0));
    const double margin = 1e-9 * (std::abs(q.x) + std::abs(q.z));
    EXPECT_EQ((code & kOutcodeNotRightOfQuarter) != 0, !(2.0 * q.x + q.z > margin));
    EXPECT_EQ((code & kOutcodeNotLeftOfQuarter) != 0, !(2.0 * q.x + q.z < -margin));
    EXPECT_EQ((code & kOutcodeNotRightOfThreeQuarters) != 0, !(2.0 * q.x - q.z > margin));
    EXPECT_EQ((code & kOutcodeNotLeftOfThreeQuarters) != 0, !(2.0 * q.x - q.z < -margin));
  }
}

// A receiver that reaches a face but is left off one of its tasks' lists (its face mask lacks a side bit of the
// task's mask) has nothing in that task's columns: clipped to the face and projected, it lies wholly on one side of
// them. Random triangles round the shooter, four in five with a vertex on a line where tasks meet, at
// resolutions divisible by 4, odd, and even but not divisible by 4.
TEST(HemicubeGeometry, TaskListsKeepEveryReceiverThatReachesATask) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  ReceiverView view;
  std::uint32_t added = 0;
  for (int k = 0; k < 4000; ++k) {
    const Vec3 centre(coord(rng), coord(rng), 0.1 + 0.9 * std::abs(coord(rng)));
    Polygon triangle;
    for (int v = 0; v < 3; ++v) triangle.push_back(centre + 0.3 * Vec3(coord(rng), coord(rng), coord(rng)));
    if (k % 5 == 1) triangle[0].x = 0.0;                    // on u = 0
    if (k % 5 == 2) triangle[1].y = 0.0;                    // on v = 0
    if (k % 5 == 3) triangle[2].x = -0.5 * triangle[2].z;  // on the quarter line 2u = -w
    if (k % 5 == 4) triangle[0].x = 0.5 * triangle[0].z;   // on the three-quarter line 2u = w
    Vec3 normal = glm::cross(triangle[1] - triangle[0], triangle[2] - triangle[0]);
    if (!(glm::length(normal) > 1e-6)) continue;
    if (glm::dot(normal, triangle[0]) > 0.0) std::swap(triangle[1], triangle[2]);  // facing the shooter
    testing::add(view, triangle, added, added);
    ++added;
  }
  const Shooter shooter = Shooter::from_normal(Vec3(0.0), Vec3(0.0, 0.0, 1.0));
  for (const int resolution : {100, 101, 102}) {
    PreparedReceivers prepared;
    prepared.prepare(shooter, view);
    const double half = 0.5 * resolution;
    std::vector<Vec3> local(3), scratch(clipped_capacity(3)), clipped(clipped_capacity(3));
    std::vector<Vec2> projected(clipped_capacity(3));
    std::size_t left_off = 0;
    for (std::size_t i = 0; i < view.size(); ++i) {
      for (const FaceTask& task : face_tasks(resolution)) {
        const auto face = static_cast<FaceMask>(1u << static_cast<int>(task.face));
        const FaceMask need = task_mask(task, resolution);
        if ((prepared.face_mask(i) & face) == 0 || (prepared.face_mask(i) & need) == need) continue;
        ++left_off;
        const std::size_t m =
            clip_to_face(prepared.local_polygon(i, local), task.face, prepared.outside_mask(i), scratch, clipped);
        ProjectedBox box;
        if (m == 0 || !project_clipped(task.face, std::span<const Vec3>(clipped.data(), m), half, 0.0, projected, box))
          continue;
        EXPECT_TRUE(box.x_max <= task.x0 || box.x_min >= task.x1)
            << "N " << resolution << " receiver " << i << " face " << static_cast<int>(task.face) << " columns ["
            << task.x0 << ", " << task.x1 << ") box [" << box.x_min << ", " << box.x_max << "]";
      }
    }
    EXPECT_GT(left_off, view.size() / 4) << "N " << resolution;  // the lines leave many receivers off some tasks
  }
}

// Clips a polygon (local coordinates) to every face and returns the face pieces back in local coordinates.
std::vector<Polygon> clip_to_all_faces(const Polygon& local) {
  std::vector<Polygon> pieces;
  std::uint32_t any = 0;
  for (const Vec3& v : local) any |= frustum_outcode(v);
  std::vector<Vec3> scratch(clipped_capacity(local.size())), out(clipped_capacity(local.size()));
  for (int f = 0; f < kHemicubeFaces; ++f) {
    const auto face = static_cast<HemicubeFace>(f);
    const std::size_t m = clip_to_face(local, face, any, scratch, out);
    Polygon piece;  // (a, l1, l2) back to (u, v, w)
    for (std::size_t k = 0; k < m; ++k) piece.push_back(testing::from_face(face, out[k]));
    if (!piece.empty()) pieces.push_back(piece);
  }
  return pieces;
}

TEST(HemicubeGeometry, FacePiecesTileTheFrontPart) {
  // Random triangles around the shooter: the form factors of the five face pieces add up to that of the
  // part in front of the shooter's plane (complementary pieces: no gap, no overlap).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int k = 0; k < 500; ++k) {
    Polygon tri = {{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}};
    if (glm::dot(glm::cross(tri[1] - tri[0], tri[2] - tri[0]), tri[0]) > 0) tri = testing::reversed(tri);
    std::vector<Vec3> front(4);
    front.resize(clip_to_front(tri, front));
    const double whole = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), front);
    double sum = 0.0;
    for (const Polygon& piece : clip_to_all_faces(tri)) sum += polygon_form_factor(Vec3(0), Vec3(0, 0, 1), piece);
    EXPECT_NEAR(sum, whole, 1e-12) << k;
  }
}

TEST(HemicubeGeometry, SeamCutsLandExactlyOnFaceBorders) {
  // A triangle across the seam between the top and the +u face: both pieces' seam vertices project exactly
  // onto the shared border (x = N on the top, y = N/2 on the side), with equal lateral coordinates.
  const Polygon tri = {{0.5, -0.3, 0.9}, {1.7, 0.2, 0.4}, {0.4, 0.6, 1.1}};
  std::uint32_t any = 0;
  for (const Vec3& v : tri) any |= frustum_outcode(v);
  std::vector<Vec3> scratch(8), top(8), side(8);
  const std::size_t mt = clip_to_face(tri, HemicubeFace::kTop, any, scratch, top);
  const std::size_t ms = clip_to_face(tri, HemicubeFace::kPosU, any, scratch, side);
  ASSERT_GT(mt, 0u);
  ASSERT_GT(ms, 0u);
  std::vector<double> top_seam, side_seam;
  for (std::size_t k = 0; k < mt; ++k) {
    const Vec2 p = project_to_pixels(HemicubeFace::kTop, top[k], 50.0);
    if (p.x == 100.0) top_seam.push_back(p.y);
  }
  for (std::size_t k = 0; k < ms; ++k) {
    const Vec2 p = project_to_pixels(HemicubeFace::kPosU, side[k], 50.0);
    if (p.y == 50.0) side_seam.push_back(p.x);
  }
  ASSERT_EQ(top_seam.size(), 2u);
  ASSERT_EQ(side_seam.size(), 2u);
  std::sort(top_seam.begin(), top_seam.end());
  std::sort(side_seam.begin(), side_seam.end());
  EXPECT_NEAR(top_seam[0], side_seam[0], 1e-12);
  EXPECT_NEAR(top_seam[1], side_seam[1], 1e-12);
}

TEST(HemicubeGeometry, SharedEdgeCutsAreBitIdentical) {
  // Two triangles sharing an edge that crosses a frustum plane get the same cut point.
  const Vec3 a{1.4, 0.3, 0.8}, b{0.2, -0.1, 1.2};
  const Polygon t1 = {a, b, {0.9, 0.8, 1.0}}, t2 = {b, a, {0.6, -0.9, 0.9}};
  std::vector<Vec3> scratch(8), o1(8), o2(8);
  const std::size_t m1 = clip_to_face(t1, HemicubeFace::kTop, ~0u, scratch, o1);
  const std::size_t m2 = clip_to_face(t2, HemicubeFace::kTop, ~0u, scratch, o2);
  int shared = 0;
  for (std::size_t i = 0; i < m1; ++i)
    for (std::size_t j = 0; j < m2; ++j) shared += o1[i] == o2[j];
  EXPECT_EQ(shared, 2);  // b and the cut point on the seam plane
}

TEST(HemicubeGeometry, SharedEdgeCutsAreBitIdenticalOnEveryFace) {
  // The same on random shared edges, on all five faces: every vertex of the clipped t1 that lies on the line of
  // the shared edge (a kept end or a cut of the edge) is bit-identical to a vertex of the clipped t2, which walks
  // the edge the other way. The cut point computed from either end would differ in its last bits on some edges.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0), up(0.05, 2.0);
  std::vector<Vec3> scratch(16), o1(16), o2(16);
  int on_edge = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec3 a{u(rng), u(rng), up(rng)}, b{u(rng), u(rng), up(rng)};
    const Vec3 c{u(rng), u(rng), up(rng)}, d{u(rng), u(rng), up(rng)};
    const Polygon t1 = {a, b, c}, t2 = {b, a, d};
    const Vec3 along = glm::normalize(b - a);
    for (int f = 0; f < kHemicubeFaces; ++f) {
      const auto face = static_cast<HemicubeFace>(f);
      const std::size_t m1 = clip_to_face(t1, face, ~0u, scratch, o1);
      const std::size_t m2 = clip_to_face(t2, face, ~0u, scratch, o2);
      const Vec3 fa = to_face(face, a);
      const Vec3 fb = to_face(face, b);
      for (std::size_t i = 0; i < m1; ++i) {
        const Vec3 p = o1[i];
        // On the edge's line (in face coordinates, which keep distances): c, d and the face's corners are not,
        // in general position.
        const Vec3 off = (p - fa) - glm::dot(p - fa, to_face(face, along)) * to_face(face, along);
        if (glm::length(off) > 1e-9 * (1.0 + glm::length(fb - fa))) continue;
        ++on_edge;
        bool found = false;
        for (std::size_t j = 0; j < m2; ++j) found = found || o2[j] == p;
        EXPECT_TRUE(found) << "trial " << trial << " face " << f;
      }
    }
  }
  std::printf("%d clipped vertices on a shared edge checked\n", on_edge);
  EXPECT_GE(on_edge, 400);  // the loop checks something
}

TEST(HemicubeGeometry, InverseDepthIsAffineInPixels) {
  const Shooter s = testing::rotated_shooter(Vec3(0.1, 0.2, 0.3), glm::normalize(Vec3(0.2, -0.1, 1.0)), 0.4);
  const Polygon quad = testing::rectangle({-2, -2, 2.5}, {0, 5, 0.5}, {5, 0, 0.3});
  const Plane local = plane_to_local(s, plane_of(quad));
  int checked = 0;
  for (int f = 0; f < kHemicubeFaces; ++f) {
    const auto face = static_cast<HemicubeFace>(f);
    const InverseDepth d = inverse_depth(face, local, 50.0);
    for (const Vec3& v : quad) {
      const Vec3 q = to_face(face, to_local(s, v));
      if (q.x <= 0) continue;  // behind the face's plane: no projection
      ++checked;
      const Vec2 p = project_to_pixels(face, q, 50.0);
      EXPECT_NEAR(d.at(p.x, p.y), 1.0 / q.x, 1e-12);
    }
  }
  // Only corners in front of a face's plane are checked. Measured: 12 of the 20 corner-face pairs; at least
  // half must be, so the skip cannot empty the test.
  std::printf("%d of 20 corner-face pairs in front of the face checked\n", checked);
  EXPECT_GE(checked, 10);
}

TEST(HemicubeGeometry, SharedPointsGiveTheSameFormFactors) {
  // A 6 x 6 grid of quads on a wall, added once with a point per corner and once keyed by grid vertex (so
  // that a vertex is transformed once per shot, not once per quad): the view shares the points, and both
  // hemicubes give bit-identical form factors either way.
  ReceiverView plain, keyed;
  const int n = 6;
  const Plane wall{{0.0, 0.0, -1.0}, 2.0};  // z = 2, facing the shooter at the origin
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const auto at = [&](int a, int b) { return Vec3(-1.5 + 0.5 * a, -1.5 + 0.5 * b, 2.0); };
      const Vec3 quad[4] = {at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)};  // counter-clockwise seen from below
      const auto key = [&](int a, int b) { return static_cast<std::uint32_t>(a * (n + 1) + b); };
      const std::uint32_t keys[4] = {key(i, j), key(i, j + 1), key(i + 1, j + 1), key(i + 1, j)};
      plain.add(quad, wall, 0, 0);
      keyed.add(quad, keys, wall, 0, 0);
    }
  EXPECT_EQ(plain.points().size(), 4u * n * n);
  EXPECT_EQ(keyed.points().size(), static_cast<std::size_t>((n + 1) * (n + 1)));
  ASSERT_EQ(keyed.corner_points().size(), keyed.vertices().size());
  for (std::size_t v = 0; v < keyed.vertices().size(); ++v)
    EXPECT_EQ(keyed.points()[keyed.corner_points()[v]], keyed.vertices()[v]);
  const Shooter shooter = Shooter::from_normal(Vec3(0.1, -0.2, 0.0), glm::normalize(Vec3(0.2, 0.1, 1.0)));
  for (const char* name : {"aa-hemicube", "hemicube"}) {
    auto backend = make_backend(name, {51});
    std::vector<double> a(plain.size()), b(keyed.size());
    backend->compute(shooter, plain, {}, a);
    backend->compute(shooter, keyed, {}, b);
    EXPECT_EQ(a, b) << name;
    EXPECT_GT(a[14], 0.0) << name;
  }
  // A key may name only one point.
  const Vec3 tri[3] = {{0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
  const std::uint32_t reused[3] = {0, 1, 2};
  EXPECT_THROW(keyed.add(tri, reused, wall, 0, 0), Error);
}

TEST(HemicubeGeometry, ResolutionOutOfRangeIsRefused) {
  EXPECT_THROW(make_backend("aa-hemicube", {.resolution = 1}), Error);
  EXPECT_THROW(make_backend("hemicube", {.resolution = 8193}), Error);
  // Refused before anything is computed from it: N + 1 overflowed at the largest int (undefined; the sanitizer
  // build's check).
  for (const int n : {std::numeric_limits<int>::max(), std::numeric_limits<int>::min()}) {
    EXPECT_THROW(HemicubeGeometry{n}, Error) << n;
    EXPECT_THROW(make_backend("aa-hemicube", {.resolution = n}), Error) << n;
  }
  EXPECT_NO_THROW(make_backend("hemicube", {.resolution = 2}));
  try {
    make_backend("raycast");
    FAIL();
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("aa-hemicube"), std::string::npos);
    EXPECT_NE(what.find("hemicube"), std::string::npos);
    EXPECT_NE(what.find("analytic"), std::string::npos);
  }
  for (const std::string& name : backend_names()) EXPECT_EQ(make_backend(name)->name(), name);
}

TEST(HemicubeGeometry, TileMaskMarksThePixelsOfItsBoxes) {
  TileMask small;  // 50 x 30 pixels: one pixel per tile
  small.reset(50, 30);
  EXPECT_TRUE(small.empty());
  EXPECT_FALSE(small.overlaps(0.0, 50.0, 0.0, 30.0));
  small.add(10.2, 12.0, 5.5, 5.9);  // pixels 10 .. 12 of row 5 (12 is touched only at its edge: kept, to be safe)
  EXPECT_FALSE(small.empty());
  EXPECT_TRUE(small.overlaps(12.0, 13.5, 5.0, 5.1));
  EXPECT_TRUE(small.overlaps(0.0, 10.0, 0.0, 29.0));
  EXPECT_FALSE(small.overlaps(13.0, 20.0, 5.0, 6.0));  // right of it
  EXPECT_FALSE(small.overlaps(10.0, 12.0, 6.0, 9.0));   // above it
  EXPECT_FALSE(small.overlaps(0.0, 9.99, 0.0, 29.0));   // left of it
  small.add(-5.0, 0.5, 28.5, 40.0);  // clamped to pixel (0, 28) .. (0, 29)
  EXPECT_TRUE(small.overlaps(-1.0, 0.2, 29.5, 31.0));
  EXPECT_FALSE(small.overlaps(60.0, 70.0, 0.0, 29.0));  // outside the viewport
  EXPECT_FALSE(small.overlaps(1.0, 3.0, 28.0, 29.0));
  // Marks added below and above the first: a tall region finds each, whatever the order they came in.
  small.reset(50, 30);
  small.add(30.0, 30.5, 20.2, 20.8);
  small.add(40.0, 40.5, 3.2, 3.8);
  small.add(45.0, 45.5, 25.2, 25.8);
  EXPECT_TRUE(small.overlaps(40.0, 40.9, 0.0, 29.0));
  EXPECT_TRUE(small.overlaps(45.0, 45.9, 0.0, 29.0));
  EXPECT_TRUE(small.overlaps(30.0, 30.9, 0.0, 29.0));
  EXPECT_FALSE(small.overlaps(31.0, 39.9, 0.0, 29.0));
  EXPECT_FALSE(small.overlaps(40.0, 40.9, 4.0, 29.0));

  TileMask large;  // 1000 pixels wide: 16-pixel tiles, 63 to a row
  large.reset(1000, 500);
  large.add(999.5, 1200.0, 499.0, 499.5);
  EXPECT_TRUE(large.overlaps(992.0, 992.5, 496.0, 496.5));  // same tile (62, 31)
  EXPECT_FALSE(large.overlaps(975.0, 991.9, 496.0, 499.0));  // tile 60 .. 61
  EXPECT_FALSE(large.overlaps(992.0, 999.0, 480.0, 495.9));  // tile row 30
  large.reset(1000, 500);
  EXPECT_TRUE(large.empty());
  EXPECT_FALSE(large.overlaps(992.0, 992.5, 496.0, 496.5));

  // 65 pixels wide: 64 one-pixel tiles would leave pixel 64 without a bit of the 64-bit row, so tiles are two
  // pixels wide (33 to a row) and the last pixel is tile 32, apart from tile 0 and from pixels 62 and 63.
  TileMask edge;
  edge.reset(65, 4);
  edge.add(64.2, 64.8, 1.0, 1.5);
  EXPECT_TRUE(edge.overlaps(64.5, 65.0, 0.0, 3.0));
  EXPECT_FALSE(edge.overlaps(0.0, 1.9, 0.0, 3.0));
  EXPECT_FALSE(edge.overlaps(62.0, 63.9, 0.0, 3.0));
}

}  // namespace
}  // namespace aarad::formfactor
