// The near-field correction (refine/near_field.h): a unit floor patch shooting into the wall it meets, cut into
// small elements, against the patch-to-element factors F(A_s -> e) integrated from the elements' side; the shot's
// total kept; receivers far away only scaled, receivers as large as the patch shaped from the patch's side; occlusion
// kept.
#include "aarad/core/polygon.h"
#include "aarad/core/quadrature.h"
#include "aarad/formfactor/analytic.h"
#include "aarad/formfactor/backend.h"
#include "aarad/refine/near_field.h"
#include "aarad/refine/solver.h"
#include "tests/solver_test_scenes.h"
#include "tests/formfactor_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace aarad::refine {
namespace {

using formfactor::ReceiverView;
using formfactor::testing::Polygon;
using formfactor::testing::add_surface;
using formfactor::testing::grid;
using formfactor::testing::rectangle;

// F(A_s -> e) for the rectangle e = origin + [0, 1] e1 + [0, 1] e2 with unit normal `normal`, by reciprocity
// from e's side: (1 / A_s) integral over e of the exact point-to-polygon factor to the patch (Baum et al. eq. 9),
// with 12 x 12 Gauss points (the integrand is smooth over e: at most 1/2, at a junction).
double patch_to_element(const Polygon& patch, double patch_area, const Vec3& origin, const Vec3& e1, const Vec3& e2,
                        const Vec3& normal) {
  std::vector<double> nodes, weights;
  gauss_legendre(12, nodes, weights);
  double sum = 0.0;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    for (std::size_t j = 0; j < nodes.size(); ++j)
      sum += weights[i] * weights[j] *
             formfactor::polygon_form_factor(origin + nodes[i] * e1 + nodes[j] * e2, normal, patch);
  return sum * glm::length(glm::cross(e1, e2)) / patch_area;
}

struct Junction {
  Polygon floor = rectangle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));  // the shooting patch, facing +z
  Vec3 centroid{0.5, 0.5, 0.0};
  Vec3 normal{0.0, 0.0, 1.0};
  ReceiverView view;
  std::vector<std::uint32_t> wall, ceiling;
  int n = 8;

  // The wall x = 1 (facing -x) meets the floor along its edge; the ceiling z = 4 (facing down, 2 x 2 pieces of
  // 20 x 20) is far away and takes most of what the patch sends, as in a room.
  Junction() {
    wall = add_surface(view, grid(Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0), n, n), 1, 10);
    ceiling = add_surface(view, grid(Vec3(-19.5, -19.5, 4), Vec3(0, 40, 0), Vec3(40, 0, 0), 2, 2), 2, 200);
  }
  // The back end's factors from the patch's centroid (lifted off the floor, as the solver does).
  std::vector<double> shoot(formfactor::FormFactorBackend& backend) const {
    std::vector<double> ff(view.size(), 0.0);
    backend.compute(formfactor::Shooter::from_normal(centroid + Vec3(0, 0, 1e-9), normal), view, {}, ff);
    return ff;
  }
  // The shooting point the back ends use, and the patch as the correction sees it.
  std::vector<Vec3> points{centroid + Vec3(0, 0, 1e-9)};
  std::vector<double> weights{1.0};
  NearFieldShooter shooter() const { return {floor, centroid, normal, 1.0, points, weights, {}}; }
  // `ff` corrected by `correction` (reach 4) as a whole shot.
  std::vector<double> corrected(std::vector<double> ff, NearFieldCorrection& correction) const {
    correction.apply(shooter(), view, {}, ff);
    return ff;
  }
  // F(A_s -> e) for the wall element in row i (along z) and column j (along y).
  double exact(int i, int j) const {
    const double h = 1.0 / n;
    return patch_to_element(floor, 1.0, Vec3(1, j * h, i * h), Vec3(0, 0, h), Vec3(0, h, 0), Vec3(-1, 0, 0));
  }
};

TEST(NearField, JunctionElementsGetThePatchFactorNotTheCentroids) {
  Junction scene;
  formfactor::AnalyticBackend backend;
  const std::vector<double> before = scene.shoot(backend);
  NearFieldCorrection correction(4.0);
  const std::vector<double> after = scene.corrected(before, correction);
  EXPECT_EQ(correction.last_corrected().size(), scene.wall.size());

  // Row i = 0 touches the floor: seen edge on from the centroid, it gets far too little; rows above get too much.
  std::vector<double> exact(scene.wall.size());
  double exact_total = 0.0, total = 0.0;
  for (int i = 0; i < scene.n; ++i) {
    for (int j = 0; j < scene.n; ++j) {
      const auto k = static_cast<std::size_t>(j * scene.n + i);  // grid(): along z first
      exact[k] = scene.exact(i, j);
      exact_total += exact[k];
      total += after[scene.wall[k]];
    }
  }
  // The pieces add up to the closed form for two unit squares at right angles (Howell C-14): 0.2000438.
  EXPECT_NEAR(exact_total, 0.2000438, 2e-7);
  double worst_before = 0.0, worst_after = 0.0, worst_row0_before = 0.0, worst_shape = 0.0;
  for (int i = 0; i < scene.n; ++i) {
    for (int j = 0; j < scene.n; ++j) {
      const auto k = static_cast<std::size_t>(j * scene.n + i);
      const std::uint32_t r = scene.wall[k];
      worst_shape = std::max(worst_shape, std::abs((after[r] / total) / (exact[k] / exact_total) - 1.0));
      const double error_before = std::abs(before[r] / exact[k] - 1.0);
      const double error_after = std::abs(after[r] / exact[k] - 1.0);
      worst_before = std::max(worst_before, error_before);
      worst_after = std::max(worst_after, error_after);
      if (i == 0) worst_row0_before = std::max(worst_row0_before, error_before);
    }
  }
  std::printf("wall of 8 x 8 next to a unit floor patch: worst relative error of F(A_s -> e) %.4f from the centroid, "
              "%.4f corrected (row at the junction %.4f from the centroid); the wall's total corrected %.6f, exact "
              "%.6f; worst error of the shape (factor / total) %.4f\n",
              worst_before, worst_after, worst_row0_before, total, exact_total, worst_shape);
  EXPECT_GT(worst_row0_before, 0.3);
  EXPECT_LT(worst_after, 0.005);
}

TEST(NearField, KeepsTheShotsTotalAndShapesLargeReceiversFromThePatchsSide) {
  Junction scene;
  // A receiver as large as the patch next to it: its centroid is no better than the patch's, so it is shaped from
  // points over the patch, which give the patch-to-patch factor of two unit squares meeting at a right angle,
  // C-14(1,1,1) = 0.2000438 (references.md), where the patch's centroid sees the wall with the point factor 0.1901.
  const std::uint32_t large = add_surface(scene.view, {rectangle(Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(1, 0, 0))},
                                          3, 300).front();  // the wall y = 0, facing +y
  formfactor::AnalyticBackend backend;
  const std::vector<double> before = scene.shoot(backend);
  NearFieldCorrection correction(4.0);
  const std::vector<double> after = scene.corrected(before, correction);
  EXPECT_EQ(correction.last_corrected().size(), scene.wall.size() + 1);
  EXPECT_NEAR(after[large], 0.2000438, 1e-4);
  EXPECT_NEAR(before[large], 0.1901, 1e-4);  // the centroid's factor is not the patch's
  double total_before = 0.0, total_after = 0.0, near_before = 0.0, near_after = 0.0;
  for (std::size_t r = 0; r < before.size(); ++r) {
    total_before += before[r];
    total_after += after[r];
  }
  for (std::uint32_t r : scene.wall) {
    near_before += before[r];
    near_after += after[r];
  }
  near_before += before[large];
  near_after += after[large];
  EXPECT_NEAR(total_after, total_before, 1e-15);
  // The far receivers (the ceiling) give up what the near field gained, in proportion.
  const double far_scale = (total_before - near_after) / (total_before - near_before);
  EXPECT_LT(far_scale, 1.0);
  EXPECT_DOUBLE_EQ(correction.far_scale(), far_scale);
  EXPECT_EQ(correction.near_scale(), 1.0);
  EXPECT_FALSE(correction.far_refused());
  for (std::uint32_t r : scene.ceiling) {
    EXPECT_GT(before[r], 0.0);
    EXPECT_DOUBLE_EQ(after[r], before[r] * far_scale);
  }
  // Off, nothing changes.
  NearFieldCorrection off(0.0);
  EXPECT_EQ(scene.corrected(before, off), before);
}

TEST(NearField, WithoutAFarFieldTheNearFieldKeepsItsTotal) {
  // Only the wall: there is nothing far to take up the change, so the near receivers share what they got.
  Junction scene;
  ReceiverView wall_only;
  add_surface(wall_only, grid(Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0), scene.n, scene.n), 1, 10);
  scene.view = wall_only;
  formfactor::AnalyticBackend backend;
  const std::vector<double> before = scene.shoot(backend);
  NearFieldCorrection correction(4.0);
  const std::vector<double> after = scene.corrected(before, correction);
  double sum_before = 0.0, sum_after = 0.0;
  for (std::size_t r = 0; r < before.size(); ++r) {
    sum_before += before[r];
    sum_after += after[r];
  }
  EXPECT_NEAR(sum_after, sum_before, 1e-15);
  EXPECT_EQ(correction.far_scale(), 1.0);
  EXPECT_GT(correction.near_scale(), 0.9);
  EXPECT_LT(correction.near_scale(), 1.0);
}

TEST(NearField, AaHemicubeSeesAJunctionWhole) {
  // The AA hemicube's factor for an element seen edge on through a side face's bottom row is off by up to a factor
  // of two (the cosine kernel is zero at the horizon), but the same pixels with nothing occluding are off alike:
  // the fraction it saw is 1, and the corrected factors are those of the exact back end.
  Junction scene;
  auto aa = formfactor::make_backend("aa-hemicube", {100});
  formfactor::AnalyticBackend exact_backend;
  // The back end keeps the unoccluded factors of the wall only (the ceiling is not asked for).
  std::vector<std::uint8_t> wanted(scene.view.size(), 0);
  for (std::uint32_t r : scene.wall) wanted[r] = 1;
  ASSERT_TRUE(aa->keep_unoccluded(wanted));
  std::vector<double> aa_ff = scene.shoot(*aa), exact_ff = scene.shoot(exact_backend);
  std::vector<double> unoccluded(scene.view.size(), 0.0);
  ASSERT_TRUE(aa->add_unoccluded(unoccluded));
  for (std::uint32_t r : scene.wall) EXPECT_NEAR(unoccluded[r], aa_ff[r], 1e-12 * aa_ff[r]) << r;  // nothing in front
  for (std::uint32_t r : scene.ceiling) {
    EXPECT_GT(aa_ff[r], 0.0);
    EXPECT_EQ(unoccluded[r], 0.0);
  }
  NearFieldShooter shooter = scene.shooter();
  NearFieldCorrection correction(4.0);
  correction.apply(shooter, scene.view, {}, exact_ff);
  shooter.unoccluded = unoccluded;
  correction.apply(shooter, scene.view, {}, aa_ff);
  for (std::uint32_t r : scene.wall) EXPECT_NEAR(aa_ff[r], exact_ff[r], 1e-12 * exact_ff[r]) << r;
}

TEST(NearField, CandidatesListGivesWhatEveryReceiverGives) {
  // After candidates(), apply() to the whole shot looks only at the receivers of near patches that it listed; a
  // correction that was never asked for candidates looks at every receiver. Both give the same factors, bit for
  // bit, also when candidates() was last asked for another shooter (its list is then stale and not used).
  Junction scene;
  // Every receiver is a patch of its own here: the table of patches, so that near patches are told from far ones.
  std::vector<Vec3> centroids;
  std::vector<double> radii;
  for (std::uint32_t i = 0; i < scene.view.size(); ++i) {
    const std::uint32_t patch = scene.view.patch(i);
    centroids.resize(std::max<std::size_t>(centroids.size(), patch + 1), Vec3(0.0));
    radii.resize(centroids.size(), -1.0);
    const std::span<const Vec3> polygon = scene.view.polygon(i);
    centroids[patch] = centroid(polygon);
    radii[patch] = 0.0;
    for (const Vec3& corner : polygon) radii[patch] = std::max(radii[patch], glm::length(corner - centroids[patch]));
  }
  auto aa = formfactor::make_backend("aa-hemicube", {100});
  const std::vector<double> shot = scene.shoot(*aa);
  NearFieldShooter shooter = scene.shooter();
  // The same patch moved 3.5 along y: from there only the far end of the wall is near.
  std::vector<Vec3> moved(shooter.polygon.begin(), shooter.polygon.end());
  for (Vec3& corner : moved) corner.y += 3.5;
  NearFieldShooter away = shooter;
  away.polygon = moved;
  away.centroid.y += 3.5;

  for (const NearFieldShooter* asked : {&shooter, &away}) {
    NearFieldCorrection listing(4.0), scanning(4.0);
    listing.set_patches(centroids, radii);
    scanning.set_patches(centroids, radii);
    const std::span<const std::uint8_t> flags = listing.candidates(*asked, scene.view);
    const auto flagged = std::count(flags.begin(), flags.end(), std::uint8_t{1});
    EXPECT_GT(flagged, 0);
    if (asked == &away) {
      EXPECT_LT(flagged, static_cast<long>(scene.wall.size()));  // fewer than the whole wall
    }
    std::vector<double> listed = shot, scanned = shot;
    listing.apply(shooter, scene.view, {}, listed);
    scanning.apply(shooter, scene.view, {}, scanned);
    EXPECT_EQ(listed, scanned);
    EXPECT_NE(listed, shot);  // the correction changed something
  }
  // A view that changed after candidates() (a piece added to a near patch) gets its new receiver listed.
  NearFieldCorrection correction(4.0);
  correction.set_patches(centroids, radii);
  EXPECT_EQ(correction.candidates(shooter, scene.view)[scene.wall[0]], 1);
  // A copy of the piece's corners: add() appends to the array polygon() reads from.
  const std::vector<Vec3> piece(scene.view.polygon(scene.wall[0]).begin(), scene.view.polygon(scene.wall[0]).end());
  const Plane plane = scene.view.plane(scene.wall[0]);
  const std::uint32_t added =
      scene.view.add(piece, plane, scene.view.surface(scene.wall[0]), scene.view.patch(scene.wall[0]));
  const std::span<const std::uint8_t> flags = correction.candidates(shooter, scene.view);
  ASSERT_EQ(flags.size(), scene.view.size());
  EXPECT_EQ(flags[added], 1);
}

TEST(NearField, HiddenPartsStayHidden) {
  // A screen between the floor's centroid and the lower half of the wall: those elements get nothing from the
  // AA hemicube, and the correction gives them nothing either; the row the screen's edge crosses keeps the part
  // the back end saw; the upper rows are reshaped as without the screen.
  Junction open, screened;
  add_surface(screened.view, {rectangle(Vec3(0.9, -1, 0), Vec3(0, 0, 0.45), Vec3(0, 3, 0))}, 4, 400);  // facing -x
  const auto corrected = [&](const Junction& scene) {
    auto aa = formfactor::make_backend("aa-hemicube", {100});
    NearFieldCorrection correction(4.0);
    NearFieldShooter shooter = scene.shooter();
    EXPECT_TRUE(aa->keep_unoccluded(correction.candidates(shooter, scene.view)));
    std::vector<double> ff = scene.shoot(*aa);
    std::vector<double> unoccluded(scene.view.size(), 0.0);
    EXPECT_TRUE(aa->add_unoccluded(unoccluded));
    shooter.unoccluded = unoccluded;
    correction.apply(shooter, scene.view, {}, ff);
    return ff;
  };
  const std::vector<double> lit = corrected(open), shaded = corrected(screened);
  for (int i = 0; i < open.n; ++i) {
    for (int j = 0; j < open.n; ++j) {
      const std::uint32_t r = open.wall[static_cast<std::size_t>(j * open.n + i)];  // grid(): along z first
      // The screen's top edge, seen from (0.5, 0.5, 0), hides the wall below z = 0.45 x 0.5 / 0.4 = 0.5625.
      if ((i + 1) / 8.0 <= 0.5) {
        EXPECT_NEAR(shaded[r], 0.0, 1e-15) << i << " " << j;
      } else if (i / 8.0 < 0.5625) {  // row 4, z in [0.5, 0.625]: about half of it seen
        EXPECT_GT(shaded[r], 0.3 * lit[r]) << i << " " << j;
        EXPECT_LT(shaded[r], 0.7 * lit[r]) << i << " " << j;
      } else {
        EXPECT_NEAR(shaded[r] / lit[r], shaded[open.wall.back()] / lit[open.wall.back()], 1e-9) << i << " " << j;
      }
    }
  }
}

// A wall element crossing the shooting patch's plane (a wall running past a shelf): only its part in front of the
// patch sees it. Taken from the element's own centroid, its factor was 0 with the centroid 0.01 below the plane,
// and 0.123 with it 0.01 above (seen from the junction, the patch fills half the hemisphere), against the exact
// 0.0485 and 0.0515; the far field paid for the excess (scaled by 0.90).
TEST(NearField, ReceiversCrossingThePatchsPlaneAreShapedByTheirPartInFront) {
  const Polygon floor = rectangle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));  // facing +z
  for (const double lift : {-0.01, 0.01, -0.2}) {
    ReceiverView view;
    // Wall x = 1 facing -x: the element y in [0.25, 0.75], z in [-0.25, 0.25] + lift, and one above it.
    const double low = -0.25 + lift, high = 0.25 + lift;
    const std::uint32_t crossing =
        add_surface(view, {rectangle(Vec3(1, 0.25, low), Vec3(0, 0, high - low), Vec3(0, 0.5, 0)),
                           rectangle(Vec3(1, 0.25, high), Vec3(0, 0, 0.5), Vec3(0, 0.5, 0))},
                    1, 10)[0];
    add_surface(view, grid(Vec3(-19.5, -19.5, 4), Vec3(0, 40, 0), Vec3(40, 0, 0), 2, 2), 2, 200);
    formfactor::AnalyticBackend backend;
    const std::vector<Vec3> points{Vec3(0.5, 0.5, 1e-9)};
    const std::vector<double> weights{1.0};
    std::vector<double> ff(view.size(), 0.0);
    backend.compute(formfactor::Shooter::from_normal(points[0], Vec3(0, 0, 1)), view, {}, ff);
    NearFieldCorrection correction(4.0);
    correction.apply({floor, Vec3(0.5, 0.5, 0.0), Vec3(0, 0, 1), 1.0, points, weights, {}}, view, {}, ff);
    const double front = std::max(0.0, low);
    const double exact = patch_to_element(floor, 1.0, Vec3(1, 0.25, front), Vec3(0, 0, high - front),
                                          Vec3(0, 0.5, 0), Vec3(-1, 0, 0));
    EXPECT_NEAR(ff[crossing], exact, 0.03 * exact) << "lift " << lift;
  }
}

// A wall standing on the floor whose plane runs through a floor patch's centroid (a partition in the middle of a
// room, patches on a regular grid): the shooting point sees the wall edge on, and the AA hemicube gives a wall
// leaf a rounding's sliver of a factor, which the near-field correction makes what the part of the patch in front
// of the wall sends it, and the leaf's pieces nothing at all. Scaled to the leaf's factor, nothing stayed nothing:
// the leaf's share was taken back and not given out again. A closed room 4 x 3 x 4 lit from its ceiling, floor
// patches centred at x = 0.4, 1.2, 2, 2.8, 3.6 (the default sizes), a one-sided wall at x = 2: 1.28e-3 of the
// emitted flux was lost in the 16th shot (from the floor patch at (2, 0, 2.8)). The pieces now share it by area.
TEST(NearField, PiecesOfALeafSeenEdgeOnShareItsFactor) {
  Scene scene;
  scene.name = "partition";
  const auto white = scene.add_material({"white", Rgb(0.7), Rgb(0.0)});
  const auto red = scene.add_material({"red", Rgb(0.6, 0.1, 0.1), Rgb(0.0)});
  const auto light = scene.add_material({"light", Rgb(0.5), Rgb(10.0)});
  const std::uint32_t room = scene.add_group("room");
  test::add_facing(scene, room, white, {{0, 0, 0}, {4, 0, 0}, {4, 0, 4}, {0, 0, 4}}, {0, 1, 0});
  test::add_facing(scene, room, white, {{0, 3, 0}, {4, 3, 0}, {4, 3, 4}, {0, 3, 4}}, {0, -1, 0});
  test::add_facing(scene, room, white, {{0, 0, 0}, {0, 3, 0}, {0, 3, 4}, {0, 0, 4}}, {1, 0, 0});
  test::add_facing(scene, room, white, {{4, 0, 0}, {4, 3, 0}, {4, 3, 4}, {4, 0, 4}}, {-1, 0, 0});
  test::add_facing(scene, room, white, {{0, 0, 0}, {4, 0, 0}, {4, 3, 0}, {0, 3, 0}}, {0, 0, 1});
  test::add_facing(scene, room, white, {{0, 0, 4}, {4, 0, 4}, {4, 3, 4}, {0, 3, 4}}, {0, 0, -1});
  test::add_facing(scene, scene.add_group("light"), light,
                   {{1.5, 2.996, 1.5}, {2.5, 2.996, 1.5}, {2.5, 2.996, 2.5}, {1.5, 2.996, 2.5}}, {0, -1, 0});
  test::add_facing(scene, scene.add_group("wall"), red, {{2, 0, 0.5}, {2, 0, 3.5}, {2, 2, 3.5}, {2, 2, 0.5}},
                   {-1, 0, 0});
  scene.build_surfaces();
  SolverOptions options;  // the defaults of aarad solve: AA hemicube N = 100, near field 4, adaptive
  Solver solver(scene, options);
  double worst = 0.0;
  for (int shot = 0; shot < 20; ++shot) {
    ASSERT_TRUE(solver.shoot_once());
    worst = std::max(worst, std::abs(solver.escaped_flux().sum() / solver.emitted_flux().sum()));
  }
  EXPECT_GT(solver.splits(), 0);
  std::printf("a wall through a shooting point: worst |escaped| in 20 shots %.3g of the emitted flux\n", worst);
  EXPECT_LT(worst, 1e-9);
}

// A leaf on the edge of the near field, split in the shot that corrected it, can have no corrected piece: its
// centroid lies within reach of the shooter's centroid and its pieces' centroids, a quarter of it off to every
// side, do not. Its pieces got the back end's factors (times the far field's scale), not the corrected factor
// taken back from it, and the difference was lost or made: in the closed unit cube with the analytic back end,
// whose factors from any point add up to 1, the first shot (3 x 3 patches, elements of 1/4, every leaf split)
// left 4.7e-6 of the emitted flux unaccounted for, and 3.7e-7 with --shooter-samples 2 after 8 shots (the
// balance elsewhere: 1e-14).
TEST(NearField, LeavesSplitAtTheEdgeOfTheNearFieldKeepTheBalance) {
  const Scene cube = test::unit_cube();
  struct Case {
    int samples, shots;
    double element_size, gradient;
    int max_level;
  };
  for (const Case& c : {Case{1, 1, 0.25, 0.001, 3}, Case{2, 8, 0.34, 0.1, 8}}) {
    SolverOptions options;
    options.backend = "analytic";  // exact and closed: every shot's factors add up to 1
    options.shooter_samples = c.samples;
    options.meshing.patch_size = 0.34;
    options.meshing.element_size = c.element_size;
    options.meshing.max_level = c.max_level;
    options.gradient = c.gradient;
    Solver solver(cube, options);
    for (int shot = 0; shot < c.shots; ++shot) {
      ASSERT_TRUE(solver.shoot_once());
      const double escaped = solver.escaped_flux().sum() / solver.emitted_flux().sum();
      EXPECT_LT(std::abs(escaped), 1e-12) << "samples " << c.samples << " shot " << shot;
    }
    EXPECT_GT(solver.splits(), 0);
  }
}

// The near field reaches `reach` times the patch's radius (its farthest corner from its centroid) from the patch's
// centroid: with reach 4 and the unit floor patch, 4 x sqrt(0.5) = 2.828. Two small elements on the wall x = 1, their
// centroids 2.80 and 2.86 from the patch's centroid (0.5, 0.5, 0): the first is corrected, the second only scaled
// with the far field.
TEST(NearField, ReachIsMeasuredInPatchRadiiFromThePatchsCentroid) {
  Junction scene;
  const auto element_at = [&](double distance, std::uint32_t patch) {
    const double y = 0.5 + std::sqrt(distance * distance - 0.5);  // centroid (1, y, 0.5): 0.5^2 + 0.5^2 off in x, z
    return add_surface(scene.view, {rectangle(Vec3(1, y - 0.05, 0.45), Vec3(0, 0, 0.1), Vec3(0, 0.1, 0))}, 1, patch)
        .front();
  };
  const std::uint32_t inside = element_at(2.80, 500), outside = element_at(2.86, 501);
  EXPECT_NEAR(glm::length(centroid(scene.view.polygon(inside)) - scene.centroid), 2.80, 1e-12);
  EXPECT_NEAR(glm::length(centroid(scene.view.polygon(outside)) - scene.centroid), 2.86, 1e-12);
  formfactor::AnalyticBackend backend;
  const std::vector<double> before = scene.shoot(backend);
  ASSERT_GT(before[inside], 0.0);
  ASSERT_GT(before[outside], 0.0);
  NearFieldCorrection correction(4.0);
  const std::vector<double> after = scene.corrected(before, correction);
  const auto corrected = correction.last_corrected();
  EXPECT_NE(std::find(corrected.begin(), corrected.end(), inside), corrected.end());
  EXPECT_EQ(std::find(corrected.begin(), corrected.end(), outside), corrected.end());
  EXPECT_EQ(corrected.size(), scene.wall.size() + 1);
  EXPECT_DOUBLE_EQ(after[outside], before[outside] * correction.far_scale());
}

// When taking up the near field's change would scale the far receivers by more than a quarter, the near receivers
// keep the total the back end gave them and the far ones are left alone. The unit wall at the junction gets 0.1901
// from the patch's centroid and 0.2000 from its own side; a far unit square 3 above the centroid gets about 0.034,
// which would have to give up about 0.01 of it (a scale near 0.7, below 1 / 1.25).
TEST(NearField, AFarFieldThatWouldChangeByMoreThanAQuarterIsLeftAlone) {
  Junction scene;
  ReceiverView view;
  scene.wall = add_surface(view, grid(Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0), scene.n, scene.n), 1, 10);
  const std::uint32_t far =
      add_surface(view, {rectangle(Vec3(0, 0, 3), Vec3(0, 1, 0), Vec3(1, 0, 0))}, 2, 200).front();  // facing down
  scene.view = view;
  formfactor::AnalyticBackend backend;
  const std::vector<double> before = scene.shoot(backend);
  NearFieldCorrection correction(4.0);
  const std::vector<double> after = scene.corrected(before, correction);
  ASSERT_EQ(correction.last_corrected().size(), scene.wall.size());
  double near_before = 0.0, near_after = 0.0;
  for (std::uint32_t r : scene.wall) {
    near_before += before[r];
    near_after += after[r];
  }
  EXPECT_NEAR(near_before, 0.1901, 1e-4);
  EXPECT_GT(before[far], 0.03);
  EXPECT_LT(before[far], 0.04);
  // What the far square would have been scaled by: (its factor - the near field's gain) / its factor.
  const double unscaled_gain = near_before / correction.near_scale() - near_before;
  EXPECT_NEAR(unscaled_gain, 0.2000 - 0.1901, 3e-4);
  EXPECT_LT((before[far] - unscaled_gain) / before[far], 1.0 / 1.25);
  EXPECT_EQ(correction.far_scale(), 1.0);
  EXPECT_EQ(after[far], before[far]);
  EXPECT_NEAR(near_after, near_before, 1e-15);
  EXPECT_NEAR(correction.near_scale(), 0.1901 / 0.2000, 2e-3);
}

// A receiver whose part in front of the patch is a triangle: a diamond on the wall x = 1 with its top corner 0.1
// above the floor's plane. Only the triangle above the plane (base 0.2 along y at z = 0, apex (1, 0.5, 0.1), area
// 0.01) sees the patch, and its factor is that triangle's F(A_s -> e).
TEST(NearField, AReceiverWhosePartInFrontIsATriangleIsShapedByIt) {
  const Polygon floor = rectangle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));  // facing +z
  ReceiverView view;
  // Counter-clockwise seen from -x: bottom, y = 0.3, top, y = 0.7.
  const std::uint32_t diamond =
      add_surface(view, {{Vec3(1, 0.5, -0.3), Vec3(1, 0.3, -0.1), Vec3(1, 0.5, 0.1), Vec3(1, 0.7, -0.1)}}, 1, 10)[0];
  ASSERT_LT(view.plane(diamond).normal.x, -0.99);
  add_surface(view, grid(Vec3(-19.5, -19.5, 4), Vec3(0, 40, 0), Vec3(40, 0, 0), 2, 2), 2, 200);
  formfactor::AnalyticBackend backend;
  const std::vector<Vec3> points{Vec3(0.5, 0.5, 1e-9)};
  const std::vector<double> weights{1.0};
  std::vector<double> ff(view.size(), 0.0);
  backend.compute(formfactor::Shooter::from_normal(points[0], Vec3(0, 0, 1)), view, {}, ff);
  ASSERT_GT(ff[diamond], 0.0);
  NearFieldCorrection correction(4.0);
  correction.apply({floor, Vec3(0.5, 0.5, 0.0), Vec3(0, 0, 1), 1.0, points, weights, {}}, view, {}, ff);
  ASSERT_EQ(correction.near_scale(), 1.0);
  // The triangle apex a, base b0 -> b1, mapped from the unit square (Duffy): a + u (b0 - a) + u v (b1 - b0),
  // Jacobian u |(b0 - a) x (b1 - b0)|.
  const Vec3 apex(1, 0.5, 0.1), b0(1, 0.4, 0.0), b1(1, 0.6, 0.0);
  std::vector<double> nodes, gauss_weights;
  gauss_legendre(12, nodes, gauss_weights);
  double exact = 0.0;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    for (std::size_t j = 0; j < nodes.size(); ++j) {
      const double u = nodes[i], v = nodes[j];
      const Vec3 point = apex + u * (b0 - apex) + u * v * (b1 - b0);
      exact += gauss_weights[i] * gauss_weights[j] * u * glm::length(glm::cross(b0 - apex, b1 - b0)) *
               formfactor::polygon_form_factor(point, Vec3(-1, 0, 0), floor);
    }
  EXPECT_NEAR(area(std::vector<Vec3>{apex, b0, b1}), 0.01, 1e-15);
  EXPECT_NEAR(ff[diamond], exact, 0.03 * exact);
}

// The fraction of a receiver the back end saw is its factor over its unoccluded factor, clamped to 1; where the back
// end kept no unoccluded factor (0), the receiver counts as seen whole. Either way the analytic back end's factors
// are corrected as with the exact unoccluded factors.
TEST(NearField, TheFractionSeenIsClampedToOneAndIsOneWithoutAnUnoccludedFactor) {
  Junction scene;
  formfactor::AnalyticBackend backend;
  const std::vector<double> shot = scene.shoot(backend);
  NearFieldCorrection correction(4.0);
  const std::vector<double> exact = scene.corrected(shot, correction);
  for (const double share : {0.5, 0.0}) {
    std::vector<double> unoccluded(shot.size());
    for (std::size_t r = 0; r < shot.size(); ++r) unoccluded[r] = share * shot[r];
    NearFieldShooter shooter = scene.shooter();
    shooter.unoccluded = unoccluded;
    std::vector<double> ff = shot;
    correction.apply(shooter, scene.view, {}, ff);
    ASSERT_EQ(correction.last_corrected().size(), scene.wall.size());
    for (std::uint32_t r : scene.wall) EXPECT_NEAR(ff[r], exact[r], 1e-12 * exact[r]) << "share " << share << " " << r;
  }
}

// Receivers the back end gave nothing (hidden) are not reshaped, and a shot whose near receivers all see nothing of
// the patch from their own side (elements of the floor beside the patch, in its plane) is left as the back end
// gave it.
TEST(NearField, NothingToShapeLeavesTheShotAsItWas) {
  Junction scene;
  formfactor::AnalyticBackend backend;
  std::vector<double> ff = scene.shoot(backend);
  const std::uint32_t hidden = scene.wall[3];
  ff[hidden] = 0.0;
  NearFieldCorrection correction(4.0);
  const std::vector<double> after = scene.corrected(ff, correction);
  const auto corrected = correction.last_corrected();
  EXPECT_EQ(corrected.size(), scene.wall.size() - 1);
  EXPECT_EQ(std::find(corrected.begin(), corrected.end(), hidden), corrected.end());
  EXPECT_EQ(after[hidden], 0.0);

  ReceiverView beside;  // 4 elements of the floor x in [1, 1.25], facing up like the patch
  add_surface(beside, grid(Vec3(1, 0, 0), Vec3(0.25, 0, 0), Vec3(0, 1, 0), 1, 4), 1, 10);
  scene.view = beside;
  const std::vector<double> given(beside.size(), 0.01);  // what a back end might give them from a lifted point
  const std::vector<double> left = scene.corrected(given, correction);
  EXPECT_TRUE(correction.last_corrected().empty());
  EXPECT_EQ(left, given);
  EXPECT_EQ(correction.near_scale(), 1.0);
  EXPECT_EQ(correction.far_scale(), 1.0);
}

// With a table of patches, the receivers of every near patch are candidates, also of the patch with the largest id
// (the table's last), and apply() to a whole shot looks at receivers added to the view since candidates() (the
// add changes the view's revision, so the candidates are found again).
TEST(NearField, CandidatesCoverTheLastPatchAndReceiversAddedSince) {
  Junction scene;
  // The wall's pieces are patches 10 .. 73, the table's last; the ceiling's ids lie past the table (never near).
  std::vector<Vec3> centroids(74, Vec3(0.0));
  std::vector<double> radii(74, -1.0);
  for (std::uint32_t r : scene.wall) {
    const std::uint32_t patch = scene.view.patch(r);
    centroids[patch] = centroid(scene.view.polygon(r));
    radii[patch] = glm::length(scene.view.polygon(r)[0] - centroids[patch]);
  }
  NearFieldCorrection correction(4.0);
  correction.set_patches(centroids, radii);
  const NearFieldShooter shooter = scene.shooter();
  const std::span<const std::uint8_t> flags = correction.candidates(shooter, scene.view);
  for (std::uint32_t r : scene.wall) EXPECT_EQ(flags[r], 1) << r;
  for (std::uint32_t r : scene.ceiling) EXPECT_EQ(flags[r], 0) << r;
  // A piece of the last patch added after candidates(): a whole shot corrects it too.
  const std::vector<Vec3> piece(scene.view.polygon(scene.wall.back()).begin(),
                                scene.view.polygon(scene.wall.back()).end());
  const std::uint32_t added = scene.view.add(piece, scene.view.plane(scene.wall.back()),
                                             scene.view.surface(scene.wall.back()), 73);
  formfactor::AnalyticBackend backend;
  const std::vector<double> shot = scene.shoot(backend);
  std::vector<double> listed = shot, scanned = shot;
  correction.apply(shooter, scene.view, {}, listed);
  const auto corrected = correction.last_corrected();
  EXPECT_NE(std::find(corrected.begin(), corrected.end(), added), corrected.end());
  NearFieldCorrection scanning(4.0);
  scanning.apply(shooter, scene.view, {}, scanned);
  EXPECT_EQ(listed, scanned);
  EXPECT_NE(listed[added], shot[added]);
}

// The patch's radius is its farthest corner's distance from its centroid, whatever the order of its corners: the
// triangle (1, 0), (0, 1), (0, 0) has its centroid at (1/3, 1/3), its first two corners sqrt 5 / 3 from it and its
// last sqrt 2 / 3, so with reach 4 the near field reaches 4 sqrt 5 / 3 = 2.981. A small element facing the patch
// from the wall x = 2.8, its centroid 2.485 from the patch's, is corrected; one on the wall x = 3.4, 3.081 away, is
// not.
TEST(NearField, ThePatchsRadiusIsItsFarthestCornersDistanceInAnyOrder) {
  const Polygon triangle{{1, 0, 0}, {0, 1, 0}, {0, 0, 0}};
  const Vec3 centroid(1.0 / 3.0, 1.0 / 3.0, 0.0);
  ReceiverView view;
  const auto element_at = [&](double x) {  // 0.2 x 0.2, centred at (x, 1/3, 0.3), facing -x
    return formfactor::testing::add(view, rectangle(Vec3(x, 1.0 / 3.0 - 0.1, 0.2), Vec3(0, 0, 0.2), Vec3(0, 0.2, 0)),
                                    1, 10);
  };
  const std::uint32_t near = element_at(2.8), far = element_at(3.4);
  const double reach = 4.0 * std::sqrt(5.0) / 3.0;
  EXPECT_NEAR(glm::length(aarad::centroid(view.polygon(near)) - centroid), std::hypot(2.8 - 1.0 / 3.0, 0.3), 1e-12);
  EXPECT_LT(glm::length(aarad::centroid(view.polygon(near)) - centroid), reach);
  EXPECT_GT(glm::length(aarad::centroid(view.polygon(far)) - centroid), reach);
  const std::vector<Vec3> points{centroid + Vec3(0, 0, 1e-9)};
  const std::vector<double> weights{1.0};
  const NearFieldShooter shooter{triangle, centroid, Vec3(0, 0, 1), 0.5, points, weights, {}};
  std::vector<double> ff(view.size(), 0.0);
  formfactor::AnalyticBackend().compute(formfactor::Shooter::from_normal(points[0], Vec3(0, 0, 1)), view, {}, ff);
  ASSERT_GT(ff[near], 0.0);
  ASSERT_GT(ff[far], 0.0);
  NearFieldCorrection correction(4.0);
  correction.apply(shooter, view, {}, ff);
  EXPECT_EQ(std::vector<std::uint32_t>(correction.last_corrected().begin(), correction.last_corrected().end()),
            std::vector<std::uint32_t>{near});
}

// The back end's factors from several points are weighted means, and so are the unoccluded factors the correction
// computes from the points when the back end gives none: the patch's centroid given twice with weights 1/2 is the
// centroid, and corrects the shot as the centroid alone does, bit for bit.
TEST(NearField, UnoccludedFactorsFromThePointsAreWeightedLikeTheFactors) {
  Junction scene;
  formfactor::AnalyticBackend backend;
  const std::vector<double> shot = scene.shoot(backend);
  NearFieldCorrection once(4.0), twice(4.0);
  const std::vector<double> from_one = scene.corrected(shot, once);
  const std::vector<Vec3> points{scene.points[0], scene.points[0]};
  const std::vector<double> halves{0.5, 0.5};
  NearFieldShooter doubled = scene.shooter();
  doubled.points = points;
  doubled.weights = halves;
  std::vector<double> from_two = shot;
  twice.apply(doubled, scene.view, {}, from_two);
  EXPECT_EQ(from_two, from_one);
  EXPECT_NE(from_one, shot);
}

// A re-shot subset rewrites the factors of its receivers only: its near receivers get what the whole shot gave them,
// its far ones the back end's factor times the whole shot's far scale, and every receiver outside the subset keeps
// its factor (already corrected and scaled by the whole shot) as it was.
TEST(NearField, ASubsetRewritesItsOwnReceiversOnly) {
  Junction scene;
  formfactor::AnalyticBackend backend;
  const std::vector<double> shot = scene.shoot(backend);
  NearFieldCorrection correction(4.0);
  const std::vector<double> whole = scene.corrected(shot, correction);
  ASSERT_LT(correction.far_scale(), 1.0);
  const std::vector<std::uint32_t> subset{scene.wall[5], scene.ceiling[1]};
  std::vector<double> ff = whole;
  for (std::uint32_t i : subset) ff[i] = shot[i];  // what the back end gives the re-shot receivers
  correction.apply(scene.shooter(), scene.view, subset, ff);
  EXPECT_EQ(ff, whole);
}

// apply() after candidates() looks at the listed receivers in receiver order, as a scan of every receiver does, also
// when the patch ids run the other way: the same receivers corrected in the same order, the same factors bit for bit.
TEST(NearField, CandidatesAreListedInReceiverOrderWhateverThePatchIds) {
  Junction scene;
  ReceiverView view;
  std::vector<Polygon> pieces = grid(Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0), scene.n, scene.n);
  const std::uint32_t count = static_cast<std::uint32_t>(pieces.size());
  std::vector<Vec3> centroids(count);
  std::vector<double> radii(count);
  const Plane plane = plane_of(pieces.front());
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::uint32_t patch = count - 1 - k;  // the last receiver is patch 0
    view.add(pieces[k], plane, 1, patch);
    centroids[patch] = centroid(pieces[k]);
    radii[patch] = glm::length(pieces[k][0] - centroids[patch]);
  }
  scene.view = view;
  formfactor::AnalyticBackend backend;
  const std::vector<double> shot = scene.shoot(backend);
  NearFieldCorrection listing(4.0), scanning(4.0);
  listing.set_patches(centroids, radii);
  listing.candidates(scene.shooter(), scene.view);
  std::vector<double> listed = shot, scanned = shot;
  listing.apply(scene.shooter(), scene.view, {}, listed);
  scanning.apply(scene.shooter(), scene.view, {}, scanned);
  const auto order = [](std::span<const std::uint32_t> s) { return std::vector<std::uint32_t>(s.begin(), s.end()); };
  EXPECT_EQ(order(listing.last_corrected()), order(scanning.last_corrected()));
  EXPECT_EQ(listing.last_corrected().size(), pieces.size());
  EXPECT_EQ(listed, scanned);
}

// Howell's C-14: the factor from a rectangle w wide to a rectangle h high that meets it at a right angle along their
// common edge of length l (thermalradiation.net; C-14(1, 1, 1) = 0.2000438, references.md).
double perpendicular_rectangles(double l, double w, double h) {
  const double W = w / l, H = h / l, WH = W * W + H * H;
  const double angles =
      W * std::atan(1.0 / W) + H * std::atan(1.0 / H) - std::sqrt(WH) * std::atan(1.0 / std::sqrt(WH));
  const double logs = std::log((1.0 + W * W) * (1.0 + H * H) / (1.0 + WH)) +
                      W * W * std::log(W * W * (1.0 + WH) / ((1.0 + W * W) * WH)) +
                      H * H * std::log(H * H * (1.0 + WH) / ((1.0 + H * H) * WH));
  return (angles + 0.25 * logs) / (std::acos(-1.0) * W);
}

// A lamp strip 0.003 wide along the foot of a wall, in a closed unit cube that absorbs all but the wall: the wall's
// mean radiosity is rho E F A_lamp / A_wall with F the strip's C-14 factor. The strip's patches (0.217 x 0.003, at
// the default sizes) have a radius of 0.108 and the wall's elements 0.077: smaller than 3/4 of the radius, the
// elements were corrected from their centroids, which see a strip that narrow at a tenth of its mean factor over
// them, and the wall got 48 % of its light (52 % went to the far field); without the correction it gets 100.4 %.
// Compared with the strip's width, the elements are too large to be corrected.
// A receiver facing the patch 0.002 above its plane, across the patch's edge x = 1: a quarter of it lies over the
// patch, where the factor to the patch is about 1, and the rest beyond the edge, where it is about 0. Its centroid,
// 0.05 beyond the edge, sees the patch at a grazing angle and stands for it badly (G = 1.6e-5), so the factor is
// averaged over the receiver. Reference: the mean of the exact point factor over the receiver by the midpoint rule,
// 400 and 1 200 columns on the two sides of the edge by 8 rows (G = 0.0100025).
TEST(NearField, AReceiverFacingThePatchAcrossItsEdgeCloseByIsAveragedOverItself) {
  Junction scene;
  const double h = 0.002;
  const std::uint32_t plate =
      add_surface(scene.view, {rectangle(Vec3(0.95, 0.4, h), Vec3(0, 0.2, 0), Vec3(0.2, 0, 0))}, 3, 300).front();
  const auto mean_over = [&](double x0, double x1, int columns) {
    double sum = 0.0;
    for (int i = 0; i < columns; ++i) {
      for (int j = 0; j < 8; ++j) {
        const Vec3 point(x0 + (i + 0.5) * (x1 - x0) / columns, 0.4 + (j + 0.5) * 0.2 / 8, h);
        sum += formfactor::polygon_form_factor(point, Vec3(0, 0, -1), scene.floor);
      }
    }
    return sum / (8.0 * columns);
  };
  const double exact = (0.05 * mean_over(0.95, 1.0, 400) + 0.15 * mean_over(1.0, 1.15, 1200)) / 0.2 * 0.04;
  EXPECT_NEAR(exact, 0.0100025, 1e-6);
  const double centroid = formfactor::polygon_form_factor(Vec3(1.05, 0.5, h), Vec3(0, 0, -1), scene.floor) * 0.04;
  EXPECT_LT(centroid, 1e-4);
  formfactor::AnalyticBackend backend;
  const std::vector<double> before = scene.shoot(backend);
  ASSERT_GT(before[plate], 0.0);
  NearFieldCorrection correction(4.0);
  const std::vector<double> after = scene.corrected(before, correction);
  EXPECT_EQ(correction.near_scale(), 1.0);
  EXPECT_NEAR(after[plate], exact, 0.01 * exact);
}

TEST(NearField, ReceiversNextToASliverAreSmallerThanItsWidth) {
  const double width = 0.003;
  Scene scene;
  scene.name = "sliver-lamp";
  const auto lamp = scene.add_material({"lamp", Rgb(0.0), Rgb(1.0)});
  const auto black = scene.add_material({"black", Rgb(0.0), Rgb(0.0)});
  const auto grey = scene.add_material({"grey", Rgb(0.5), Rgb(0.0)});
  test::add_facing(scene, scene.add_group("lamp"), lamp, {{0, 0, 0}, {1, 0, 0}, {1, 0, width}, {0, 0, width}},
                   {0, 1, 0});
  test::add_facing(scene, scene.add_group("floor"), black, {{0, 0, width}, {1, 0, width}, {1, 0, 1}, {0, 0, 1}},
                   {0, 1, 0});
  test::add_facing(scene, scene.add_group("ceiling"), black, {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}}, {0, -1, 0});
  test::add_facing(scene, scene.add_group("wall_x0"), black, {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}}, {1, 0, 0});
  test::add_facing(scene, scene.add_group("wall_x1"), black, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}, {-1, 0, 0});
  test::add_facing(scene, scene.add_group("wall"), grey, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {0, 0, 1});
  test::add_facing(scene, scene.add_group("wall_z1"), black, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, {0, 0, -1});
  scene.build_surfaces();
  SolverOptions options;
  options.backend = "analytic";  // exact point factors: the near field's error alone
  options.adaptive = false;
  Solver solver(scene, options);
  solver.run();
  ASSERT_TRUE(solver.converged());
  const std::uint32_t wall = *scene.find_group("wall");
  double flux = 0.0, area = 0.0;
  for (mesh::NodeId leaf : solver.hierarchy().leaves()) {
    if (scene.surfaces[solver.hierarchy().surface(leaf)].group != wall) continue;
    flux += solver.hierarchy().radiosity(leaf).g * solver.hierarchy().area(leaf);
    area += solver.hierarchy().area(leaf);
  }
  const double exact = 0.5 * perpendicular_rectangles(1.0, width, 1.0) * width / area;
  std::printf("wall next to a lamp strip %g wide: mean radiosity %.6g, exact %.6g (%+.2f %%)\n", width, flux / area,
              exact, 100.0 * (flux / area / exact - 1.0));
  EXPECT_NEAR(perpendicular_rectangles(1.0, 1.0, 1.0), 0.2000438, 1e-7);
  EXPECT_NEAR(flux / area, exact, 0.02 * exact);
}

}  // namespace
}  // namespace aarad::refine
