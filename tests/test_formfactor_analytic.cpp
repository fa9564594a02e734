// The analytic back end (Baum, Rushmeier and Winget 1989, eq. 9) against Howell's closed forms
// (references.md): B-3, the centred square, the off-axis disk, B-2, and a closed cube.
#include "aarad/core/error.h"
#include "aarad/formfactor/analytic.h"
#include "formfactor_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace aarad::formfactor {
namespace {

using namespace testing;

double analytic(const Shooter& s, const Polygon& p) {
  ReceiverView view;
  add(view, p, 0, 0);
  std::vector<double> out(1, -1.0);
  AnalyticBackend backend;
  backend.compute(s, view, {}, out);
  return out[0];
}

const Shooter kUp = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));

TEST(FormfactorAnalytic, HowellB3Corner) {
  EXPECT_NEAR(howell_b3(1, 1, 1), 0.1385316060, 1e-10);
  EXPECT_NEAR(analytic(kUp, rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0})), 0.1385316060, 1e-10);
  EXPECT_NEAR(analytic(kUp, rectangle({0, 0, 1.5}, {0, 0.7, 0}, {2.0, 0, 0})), howell_b3(2.0, 0.7, 1.5), 1e-12);
}

TEST(FormfactorAnalytic, CentredSquare) {
  EXPECT_NEAR(analytic(kUp, rectangle({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0})), 0.2394565, 5e-8);
}

// The factor depends only on directions: a centred square of half-width H at height H gets (4 / pi) atan(1 / sqrt 2)
// / sqrt 2 at every scale. Lengths overflowed from 1e77 (giving 0) and at 1e200 (nan); products underflowed at 1e-200
// (giving 0). Through a view with the plane given by hand (plane_of's own offset overflows far sooner), the check of
// the polygon's winding took the nan of its overflowed vector area for a pass.
TEST(FormfactorAnalytic, EveryScaleGivesTheSameFactor) {
  const double exact = 4.0 / kPi / std::sqrt(2.0) * std::atan(1.0 / std::sqrt(2.0));
  for (const double h : {1e-310, 2e-308, 1e-300, 1e-200, 1e-100, 1e-5, 1.0, 1e5, 1e77, 1e150, 1e200, 1e300}) {
    const Polygon square = rectangle({-h, -h, h}, {0, 2 * h, 0}, {2 * h, 0, 0});
    EXPECT_NEAR(polygon_form_factor(Vec3(0.0), Vec3(0, 0, 1), square), exact, 1e-15) << h;
    ReceiverView view;
    view.add(square, Plane{{0, 0, -1}, h}, 0, 0);
    std::vector<double> out(1, -1.0);
    AnalyticBackend().compute(kUp, view, {}, out);
    EXPECT_NEAR(out[0], exact, 1e-15) << h;
  }
}

TEST(FormfactorAnalytic, OffAxisDisk) {
  EXPECT_NEAR(howell_disk(1, 1, 0.5), 0.4379826, 5e-8);
  // An inscribed 4096-gon falls short of the disk by about (2 pi / m)^2 / 6 of its area.
  EXPECT_NEAR(analytic(kUp, disk_facing_down(0.5, 0, 1, 1, 4096)), 0.4379826, 1e-6);
}

TEST(FormfactorAnalytic, PerpendicularRectangleHowellB2) {
  // Rectangle in the plane x = 0.7, y in [0, 0.9], z in [0, 1.3], facing the point.
  const Polygon p = rectangle({0.7, 0, 0}, {0, 0, 1.3}, {0, 0.9, 0});
  EXPECT_NEAR(analytic(kUp, p), howell_b2(1.3, 0.9, 0.7), 1e-12);
}

TEST(FormfactorAnalytic, ClosedCubeSumsToOne) {
  ReceiverView view;
  add_box(view, Vec3(0), Vec3(1), 1);
  for (const Vec3& n : {Vec3(0, 0, 1), glm::normalize(Vec3(0.3, -0.2, 1.0)), glm::normalize(Vec3(1, 1, 1))}) {
    const Shooter s = Shooter::from_normal({0.3, 0.6, 0.45}, n);
    std::vector<double> out(view.size(), 0.0);
    AnalyticBackend().compute(s, view, {}, out);
    double sum = 0.0;
    for (double f : out) sum += f;
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  // From the centre of the floor, the ceiling is C-11's point version: 4 B-3(0.5, 0.5, 1).
  std::vector<double> out(view.size(), 0.0);
  AnalyticBackend().compute(Shooter::from_normal({0.5, 0.5, 0}, {0, 0, 1}), view, {}, out);
  EXPECT_NEAR(out[1], 4 * howell_b3(0.5, 0.5, 1), 1e-12);
  EXPECT_EQ(out[0], 0.0);  // the floor itself is culled
}

TEST(FormfactorAnalytic, ClipsToTheFrontAndCullsBackFaces) {
  // A wall crossing the shooter's plane: only its upper part counts (B-2 on that part).
  const Polygon wall = rectangle({0.7, 0, -0.8}, {0, 0, 2.1}, {0, 0.9, 0});
  EXPECT_NEAR(analytic(kUp, wall), howell_b2(1.3, 0.9, 0.7), 1e-12);
  // Entirely behind: 0; facing away: 0.
  EXPECT_EQ(analytic(kUp, rectangle({0, 0, -1}, {0, 1, 0}, {1, 0, 0})), 0.0);
  EXPECT_EQ(analytic(kUp, rectangle({0, 0, 1}, {1, 0, 0}, {0, 1, 0})), 0.0);
}

// A corner exactly on the shooter's plane that follows a corner behind it is kept: the wall x = 0.7 with its corner
// (y, z) = (0, 0) on the plane and (0.9, -1) below it has in front exactly B-2's rectangle y in [0, 0.9], z in
// [0, 1.3]. Taking the on-plane corner for one behind dropped it (and no crossing replaced it): a triangle was left.
TEST(FormfactorAnalytic, ACornerOnTheShootersPlaneAfterOneBehindItIsKept) {
  const Polygon wall{{0.7, 0, 0}, {0.7, 0, 1.3}, {0.7, 0.9, 1.3}, {0.7, 0.9, -1}};
  EXPECT_NEAR(analytic(kUp, wall), howell_b2(1.3, 0.9, 0.7), 1e-12);
  // The same corners one place on: the on-plane corner now follows one in front.
  const Polygon turned{wall[3], wall[0], wall[1], wall[2]};
  EXPECT_NEAR(analytic(kUp, turned), howell_b2(1.3, 0.9, 0.7), 1e-12);
}

// A corner a rounding (1e-20) behind the shooter's plane between two well in front: both crossings land on the corner
// itself, bit for bit, and the clipped polygon has a zero-length edge, which adds nothing (its direction is undefined:
// 0 / 0 gave NaN). The factor is the triangle's with that corner on the plane, to the precision of the formula.
TEST(FormfactorAnalytic, ACornerARoundingBehindThePlaneGivesTheFactorOfTheCornerOnIt) {
  const Polygon dipped{{0.7, 0, 1.3}, {0.7, 0.9, 1.3}, {0.7, 0.45, -1e-20}};
  const Polygon touching{{0.7, 0, 1.3}, {0.7, 0.9, 1.3}, {0.7, 0.45, 0}};
  const double reference = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), touching);
  ASSERT_GT(reference, 0.0);
  const double f = analytic(kUp, dipped);
  ASSERT_TRUE(std::isfinite(f));
  EXPECT_NEAR(f, reference, 1e-14 * reference);
}

TEST(FormfactorAnalytic, SubsetLeavesOthersUntouched) {
  ReceiverView view;
  add(view, rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 0);
  add(view, rectangle({-1, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 1);
  std::vector<double> out = {-1.0, -1.0};
  const std::vector<std::uint32_t> subset = {1};
  AnalyticBackend().compute(kUp, view, subset, out);
  EXPECT_EQ(out[0], -1.0);
  EXPECT_NEAR(out[1], 0.1385316060, 1e-10);
}

// Every back end refuses a shot it cannot compute instead of returning wrong numbers or crashing: a frame written
// by hand around a normal other than +z (the default tangents then make a left-handed frame: the analytic value came
// out negative), a normal without a direction (its NaN frame crashed GMP with SIGFPE), and an output span of the
// wrong size (the analytic back end wrote past it).
TEST(FormfactorBackends, ShotsWithABadFrameOrOutputSizeAreRefused) {
  ReceiverView view;
  add(view, rectangle({-0.5, -0.5, -1}, {1, 0, 0}, {0, 1, 0}), 0, 0);  // below, facing up to a shooter facing down
  const Shooter down = Shooter::from_normal(Vec3(0), Vec3(0, 0, -2));
  Shooter by_hand;
  by_hand.normal = Vec3(0, 0, -1);  // tangent and bitangent left at the +z defaults
  Shooter far = down;
  far.centre.x = std::numeric_limits<double>::infinity();
  for (const std::string& name : backend_names()) {
    auto backend = make_backend(name, {.resolution = 64});
    std::vector<double> out(view.size(), 0.0), short_out(view.size() - 1, 0.0);
    EXPECT_NO_THROW(backend->compute(down, view, {}, out)) << name;
    EXPECT_GT(out[0], 0.0) << name;
    EXPECT_THROW(backend->compute(by_hand, view, {}, out), Error) << name;
    EXPECT_THROW(backend->compute(far, view, {}, out), Error) << name;
    EXPECT_THROW(backend->compute(down, view, {}, short_out), Error) << name;
  }
  EXPECT_THROW(Shooter::from_normal(Vec3(0), Vec3(0)), Error);
  EXPECT_THROW(Shooter::from_normal(Vec3(0), Vec3(std::nan(""), 0, 1)), Error);
  // A normal whose length overflows or underflows still has a direction.
  const double half = std::sqrt(0.5);
  EXPECT_NEAR(glm::distance(Shooter::from_normal(Vec3(0), Vec3(1e200, 1e200, 0)).normal, Vec3(half, half, 0)), 0.0,
              1e-15);
  EXPECT_NEAR(glm::distance(Shooter::from_normal(Vec3(0), Vec3(1e-200, 0, 1e-200)).normal, Vec3(half, 0, half)), 0.0,
              1e-15);
  // Subnormal: 2^-ilogb overflows there, and a product with it gave a nan frame.
  EXPECT_NEAR(glm::distance(Shooter::from_normal(Vec3(0), Vec3(1e-310, 0, 1e-310)).normal, Vec3(half, 0, half)), 0.0,
              1e-15);
  try {
    Shooter::from_normal(Vec3(0), Vec3(0.0, 0.0, -0.0));
    ADD_FAILURE() << "no exception";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "Shooter::from_normal: the normal (0, 0, -0) has no direction; give a finite, non-zero "
                           "normal");
  }
}

// add_unoccluded writes one value per receiver: a span too short for the receivers the last shot reached is refused
// (it wrote past its end).
TEST(FormfactorBackends, AddUnoccludedIntoTooShortASpanIsRefused) {
  ReceiverView view;
  add(view, rectangle({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0}), 0, 0);
  add(view, rectangle({0.6, -0.5, 1}, {0, 1, 0}, {1, 0, 0}), 1, 1);
  const std::vector<std::uint8_t> wanted(view.size(), 1);
  for (const char* name : {"aa-hemicube", "hemicube"}) {
    auto backend = make_backend(name, {.resolution = 64});
    ASSERT_TRUE(backend->keep_unoccluded(wanted)) << name;
    std::vector<double> out(view.size(), 0.0);
    backend->compute(kUp, view, {}, out);
    std::vector<double> unoccluded(view.size(), 0.0);
    EXPECT_TRUE(backend->add_unoccluded(unoccluded)) << name;
    EXPECT_GT(unoccluded[1], 0.0) << name;
    double short_out[1] = {0.0};
    EXPECT_THROW(backend->add_unoccluded(std::span<double>(short_out, 1)), Error) << name;
    EXPECT_EQ(short_out[0], 0.0) << name;
  }
}

// A receiver with a corner or plane that is not finite is refused when it is added: a square 1e150 across has a
// plane that overflows to nan (plane_of squares its size), and a shot then aborted the process (the exact
// predicates' GMP raised SIGFPE on nan).
TEST(FormfactorBackends, AReceiverThatIsNotFiniteIsRefused) {
  ReceiverView view;
  const Polygon huge = rectangle({0, 0, 1e150}, {0, 1e150, 0}, {1e150, 0, 0});
  ASSERT_FALSE(std::isfinite(plane_of(huge).d));
  EXPECT_THROW(add(view, huge, 0, 0), Error);
  Polygon inf = rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0});
  inf[2].x = std::numeric_limits<double>::infinity();
  EXPECT_THROW(view.add(inf, plane_of(rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0})), 0, 0), Error);
  EXPECT_EQ(view.size(), 0u);
  add(view, rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0, 0);
  for (const std::string& name : backend_names()) {
    std::vector<double> out(1, 0.0);
    make_backend(name, {.resolution = 64})->compute(kUp, view, {}, out);
    // Howell's B-3 for a unit square with a corner over the point at distance 1; the square is one quadrant of the
    // top face, whose pixel edges it follows at N = 64, so the hemicubes get it to rounding too.
    EXPECT_NEAR(out[0], 0.1385316060, 1e-9) << name;
  }
}

// A subset naming a receiver the view does not have: every back end crashed (a segmentation fault reading past the
// view's arrays) instead of saying so.
TEST(FormfactorBackends, ASubsetEntryBeyondTheReceiversIsRefused) {
  ReceiverView view;
  add(view, rectangle({-0.5, -0.5, -1}, {1, 0, 0}, {0, 1, 0}), 0, 0);
  const Shooter down = Shooter::from_normal(Vec3(0), Vec3(0, 0, -1));
  const std::vector<std::uint32_t> beyond = {0, 1};
  for (const std::string& name : backend_names()) {
    auto backend = make_backend(name, {.resolution = 64});
    std::vector<double> out(view.size(), 0.0);
    try {
      backend->compute(down, view, beyond, out);
      ADD_FAILURE() << name << ": no exception";
    } catch (const Error& e) {
      EXPECT_STREQ(e.what(), "form factors: subset entry 1 is receiver 1, but there are 1 receivers; pass receiver "
                             "indices below 1")
          << name;
    }
    const std::vector<std::uint32_t> within = {0};
    EXPECT_NO_THROW(backend->compute(down, view, within, out)) << name;
    EXPECT_GT(out[0], 0.0) << name;
  }
}

// A wall next to the point, perpendicular to its plane, at a distance g: as g -> 0 it covers the quarter of the
// sphere of directions in front of it and above the plane, which is half the hemisphere's projected area, so its
// factor tends to 0.5 (within about g of it for a wall 2 x 1). The cross product of its bottom edge with the vector
// to it is about g long; its squared length underflowed below g = 1e-154, the edge was dropped, and a wall 1e-200
// away got -2.5e-201 (a reviewer's case).
TEST(FormfactorAnalytic, AWallAsCloseAsADoubleAllowsGetsHalf) {
  const auto wall = [](double g) { return analytic(kUp, rectangle({g, -1, 0}, {0, 0, 1}, {0, 2, 0})); };
  for (const double g : {1e-12, 1e-100, 1e-160, 1e-200, 1e-300}) EXPECT_NEAR(wall(g), 0.5, 1e-11) << g;
}

// A receiver small against its distance: the factor approaches the point-to-point kernel cos cos A / (pi r^2).
// The contour integral's R_{i+1} x R_i cancelled between two nearly parallel long vectors: at a size of 1e-8 of
// the distance the result was off by 35 %, at 1e-9 negative.
TEST(FormfactorAnalytic, ReceiversSmallAgainstTheirDistanceApproachThePointKernel) {
  const Vec3 at(1.3, 0.7, 1.0);
  const Vec3 towards = glm::normalize(-at);  // the receiver faces the shooting point
  const Vec3 u = glm::normalize(glm::cross(towards, Vec3(0, 0, 1))), v = glm::cross(towards, u);
  // Below 1e-9 the contour's terms, each of order size / r, cancel to a sum of order (size / r)^2: the sum keeps
  // about 1e-16 / (size / r) of relative precision, a property of the contour formula itself.
  for (const double size : {1e-3, 1e-5, 1e-7, 1e-9}) {
    const Polygon square = rectangle(at - 0.5 * size * (u + v), size * u, size * v);
    const double r2 = glm::dot(at, at);
    const double kernel = (at.z / std::sqrt(r2)) * size * size / (kPi * r2);  // the receiver faces the point: cos 1
    // The point kernel differs from the exact factor by O((size / r)^2).
    EXPECT_NEAR(analytic(kUp, square), kernel, 1e-6 * kernel) << "size " << size;
  }
}

}  // namespace
}  // namespace aarad::formfactor
