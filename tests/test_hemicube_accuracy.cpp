// The classical and the anti-aliased hemicube against closed forms (Howell's catalog, references.md) and the
// analytic back end (Baum et al. eq. 9); the paper's Figure 1; the same-surface rule; occlusion; closed boxes;
// determinism across thread counts. Chandran, Kiran, Phani and Rai, sections 1.1 and 3.2.
#include "aarad/core/area_rasterizer.h"
#include "aarad/formfactor/aa_hemicube.h"
#include "aarad/formfactor/analytic.h"
#include "aarad/formfactor/hemicube.h"
#include "aarad/formfactor/hemicube_geometry.h"
#include "formfactor_fixtures.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/refine/receiver_cache.h"
#include "solver_test_scenes.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>

namespace aarad::formfactor {
namespace {

using namespace testing;

std::vector<double> run(FormFactorBackend& backend, const Shooter& s, const ReceiverView& view) {
  std::vector<double> out(view.size(), 0.0);
  backend.compute(s, view, {}, out);
  return out;
}

double single(FormFactorBackend& backend, const Shooter& s, const Polygon& p) {
  ReceiverView view;
  add(view, p, 0, 0);
  return run(backend, s, view)[0];
}

// The classical hemicube's quantisation bound for one unoccluded receiver: with exact cell integrals a fully
// covered pixel is exact, so the error is at most the delta form factors of the partially covered pixels
// (found with the exact area rasterizer).
double partial_pixel_bound(const Shooter& s, const Polygon& p, int n) {
  const HemicubeGeometry g(n);
  std::vector<Vec3> local;
  std::uint32_t any = 0;
  for (const Vec3& v : p) {
    local.push_back(to_local(s, v));
    any |= frustum_outcode(local.back());
  }
  std::vector<Vec3> scratch(clipped_capacity(p.size())), clipped(clipped_capacity(p.size()));
  double bound = 0.0;
  for (int f = 0; f < kHemicubeFaces; ++f) {
    const auto face = static_cast<HemicubeFace>(f);
    const std::size_t m = clip_to_face(local, face, any, scratch, clipped);
    std::vector<Vec2> projected;
    for (std::size_t k = 0; k < m; ++k) projected.push_back(project_to_pixels(face, clipped[k], 0.5 * n));
    AreaRasterizer raster(g.width(face), g.height(face));
    raster.rasterize(projected, [&](int x, int y, double a) {
      if (a < 1.0) bound += g.delta(face)[static_cast<std::size_t>(y) * g.width(face) + x];
    });
  }
  return bound;
}

struct Case {
  const char* name;
  Shooter shooter;
  Polygon polygon;
  double reference;
};

std::vector<Case> closed_form_cases() {
  const Shooter up = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  const Shooter turned = rotated_shooter(Vec3(0), Vec3(0, 0, 1), 0.3);  // edges oblique to the pixel grid
  std::vector<Case> cases = {
      {"B-3 corner", up, rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0.1385316060},
      {"B-3 corner, turned frame", turned, rectangle({0, 0, 1}, {0, 1, 0}, {1, 0, 0}), 0.1385316060},
      {"centred square, turned frame", turned, rectangle({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0}), 0.2394565},
      {"off-axis disk (720-gon)", up, disk_facing_down(0.5, 0, 1, 1, 720), 0.0},
      {"perpendicular rectangle B-2", turned, rectangle({0.7, 0, 0}, {0, 0, 1.3}, {0, 0.9, 0}), howell_b2(1.3, 0.9, 0.7)},
  };
  // The disk polygon's own exact value (the 720-gon is 1.3e-5 short of the disk, 0.4379826).
  cases[3].reference = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), cases[3].polygon);
  // A rectangle tilted 35 degrees across the seam of the top and a side face, seen from a tilted shooter.
  const double c = std::cos(0.61), sn = std::sin(0.61);
  Polygon tilted = rectangle({0.3, -0.4, 0.9}, {0, 0.9, 0}, {1.2 * c, 0, 1.2 * sn});
  if (glm::dot(glm::cross(tilted[1] - tilted[0], tilted[2] - tilted[0]), tilted[0]) > 0) tilted = reversed(tilted);
  const Shooter tilt = rotated_shooter(Vec3(0, 0, -0.05), glm::normalize(Vec3(-0.15, 0.1, 1.0)), 0.2);
  cases.push_back({"tilted rectangle across a seam", tilt, tilted, 0.0});
  ReceiverView v;
  add(v, tilted, 0, 0);
  std::vector<double> out(1);
  AnalyticBackend().compute(tilt, v, {}, out);
  cases.back().reference = out[0];
  return cases;
}

TEST(HemicubeAccuracy, AaHemicubeMatchesClosedFormsWithinHalfPercent) {
  AaHemicubeBackend aa(100);
  for (const Case& c : closed_form_cases()) {
    const double f = single(aa, c.shooter, c.polygon);
    EXPECT_LT(relative_error(f, c.reference), 0.005) << c.name << ": " << f << " vs " << c.reference;
    std::printf("%-32s AA N=100 relative error %.2e\n", c.name, relative_error(f, c.reference));
  }
  EXPECT_NEAR(howell_disk(1, 1, 0.5), 0.4379826, 5e-8);
}

const Case& case_named(const std::vector<Case>& cases, const std::string& name) {
  const auto it = std::find_if(cases.begin(), cases.end(), [&](const Case& c) { return c.name == name; });
  if (it == cases.end()) throw std::runtime_error("no case " + name);
  return *it;
}

TEST(HemicubeAccuracy, AaHemicubeMatchesTheOffAxisDiskClosedForm) {
  // references.md (Howell): the differential area at distance h = 1 below a parallel disk of radius a = 1,
  // off its axis by r = 0.5, sees F = 0.4379826. The 720-gon inscribed in that disk misses the area
  // pi (1 - sin(2 pi / 720) / (2 pi / 720)) = pi 1.27e-5, where the kernel cos^2 / (pi d^2) is at most 1 / pi:
  // its exact value lies in [0.4379826 - 1.27e-5, 0.4379826] (+- 5e-8 for the published rounding).
  const std::vector<Case> cases = closed_form_cases();
  const Case& disk = case_named(cases, "off-axis disk (720-gon)");
  const double published = 0.4379826, step = 2.0 * kPi / 720.0, missing = 1.0 - std::sin(step) / step;
  EXPECT_LE(disk.reference, published + 5e-8);
  EXPECT_GE(disk.reference, published - missing - 5e-8);
  // The AA hemicube at N = 100 against the published disk value directly: 0.5 % (issue 3).
  AaHemicubeBackend aa(100);
  const double f = single(aa, disk.shooter, disk.polygon);
  EXPECT_LT(relative_error(f, published), 0.005) << f;
  std::printf("off-axis disk: AA N=100 %.7f, published 0.4379826, relative %.2e\n", f, relative_error(f, published));
}

// A concave receiver: a comb in the plane x = 1, facing the shooter at the origin (normal +z), whose 21 teeth
// point up across the shooter's plane z = 0 and across the seam z = 1 between the top face and the +x side face.
// Its part in front of the shooter is 21 separate triangles (two of them halves at the ends).
struct Comb {
  Polygon polygon;
  std::vector<Polygon> teeth;  // the part with z >= 0, tooth by tooth
};

Comb comb_across_the_shooters_plane(int gaps) {
  const auto toward_shooter = [](Polygon p) { return normal(p).x > 0.0 ? reversed(std::move(p)) : p; };
  Comb comb;
  const double step = 0.1, apex = 2.0, valley = -1.0;
  comb.polygon.push_back({1.0, 0.0, -2.0});
  for (int i = 0; i <= 2 * gaps; ++i) comb.polygon.push_back({1.0, step * i, i % 2 == 0 ? apex : valley});
  comb.polygon.push_back({1.0, 2.0 * step * gaps, -2.0});
  comb.polygon = toward_shooter(comb.polygon);
  // Each slope crosses z = 0 at 2/3 of its run from the apex.
  const double half_base = step * apex / (apex - valley);
  for (int tooth = 0; tooth <= gaps; ++tooth) {
    const double y = 2.0 * step * tooth;
    const double left = tooth == 0 ? y : y - half_base, right = tooth == gaps ? y : y + half_base;
    comb.teeth.push_back(toward_shooter({{1.0, left, 0.0}, {1.0, right, 0.0}, {1.0, y, apex}}));
  }
  return comb;
}

TEST(HemicubeAccuracy, ConcaveReceiverClippedByTheShootersPlaneAndAFaceSeam) {
  const Comb comb = comb_across_the_shooters_plane(20);
  const Shooter s = Shooter::from_normal(Vec3(0.0), Vec3(0.0, 0.0, 1.0));
  AnalyticBackend analytic;
  double reference = 0.0;
  for (const Polygon& tooth : comb.teeth) reference += single(analytic, s, tooth);

  // Clipping to the front keeps every tooth: more vertices than a convex polygon could get (m + 1), within the
  // concave bound.
  std::vector<Vec3> local;
  for (const Vec3& v : comb.polygon) local.push_back(to_local(s, v));
  std::vector<Vec3> front(plane_clipped_capacity(local.size()));
  const std::size_t kept = clip_to_front(local, front);
  EXPECT_EQ(kept, 3 * comb.teeth.size());  // an apex and two crossings a tooth
  EXPECT_GT(kept, local.size() + 1);
  EXPECT_LE(kept, front.size());

  EXPECT_NEAR(single(analytic, s, comb.polygon), reference, 1e-12);
  AaHemicubeBackend aa(100);
  const double f = single(aa, s, comb.polygon);
  EXPECT_LT(relative_error(f, reference), 0.005) << f << " vs " << reference;
  HemicubeBackend classical(100);
  EXPECT_NEAR(single(classical, s, comb.polygon), reference, partial_pixel_bound(s, comb.polygon, 100));
  std::printf("comb of %zu vertices: exact %.9f, AA N=100 %.9f (relative %.2e)\n", comb.polygon.size(), reference, f,
              relative_error(f, reference));
}

TEST(HemicubeAccuracy, TiltedRectangleReallyCrossesAFaceSeam) {
  // The "tilted rectangle across a seam" case: its corners, in the shooter's frame, lie in front of the shooter
  // and in the frusta of at least two hemicube faces (frustum_outcode: no outside bit of that face), and the
  // exact clip gives at least two faces a piece carrying more than twice the 0.5 % tolerance of the accuracy
  // test, so losing or doubling the piece beyond the seam would fail that test. Measured: top 0.056477 and
  // -v side 0.001250 (2.2 %) of 0.057727.
  const std::vector<Case> cases = closed_form_cases();
  const Case& c = case_named(cases, "tilted rectangle across a seam");
  std::vector<Vec3> local;
  std::uint32_t any = 0;
  std::set<int> corner_faces;
  for (const Vec3& v : c.polygon) {
    local.push_back(to_local(c.shooter, v));
    ASSERT_GT(local.back().z, 0.0);  // in front of the shooter
    const std::uint32_t code = frustum_outcode(local.back());
    any |= code;
    for (int f = 0; f < kHemicubeFaces; ++f)
      if (((code >> (4 * f)) & 0xFu) == 0) corner_faces.insert(f);
  }
  EXPECT_GE(corner_faces.size(), 2u);
  std::vector<Vec3> scratch(clipped_capacity(local.size())), clipped(clipped_capacity(local.size()));
  int faces_with_share = 0;
  double total = 0.0;
  for (int f = 0; f < kHemicubeFaces; ++f) {
    const auto face = static_cast<HemicubeFace>(f);
    const std::size_t m = clip_to_face(local, face, any, scratch, clipped);
    if (m == 0) continue;
    Polygon piece;  // back from face coordinates (a, l1, l2) to local (u, v, w)
    for (std::size_t k = 0; k < m; ++k) piece.push_back(from_face(face, clipped[k]));
    const double share = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), piece);
    total += share;
    std::printf("tilted rectangle: face %d piece of %zu vertices, form factor %.6f of %.6f\n", f, m, share, c.reference);
    faces_with_share += share > 2.0 * 0.005 * c.reference;
  }
  EXPECT_GE(faces_with_share, 2);
  EXPECT_NEAR(total, c.reference, 1e-12);  // the pieces are the whole rectangle
}

TEST(HemicubeAccuracy, ClassicalHemicubeWithinItsQuantisation) {
  HemicubeBackend classical(100);
  for (const Case& c : closed_form_cases()) {
    const double f = single(classical, c.shooter, c.polygon);
    const double bound = partial_pixel_bound(c.shooter, c.polygon, 100);
    EXPECT_LE(std::abs(f - c.reference), bound + 1e-10) << c.name << ": " << f << " vs " << c.reference;
    EXPECT_LT(bound, 0.2 * c.reference) << c.name;  // and the bound is a real constraint
  }
}

// The classical hemicube's fill rule on the top face of N = 8, where pixel x spans u in [x / 4 - 1, (x + 1) / 4 - 1]
// and is sampled at its centre. The square u, v in [-1/8, 1/8] at height 1 has pixel centres on its lower-left corner
// (3.5, 3.5) and on its right and upper edges only: the half-open spans give it the one pixel (3, 3), whose exact
// delta form factor is Howell's B-3 for a quarter by a quarter with a corner above the point. The corner lies on
// the border of the top face's two column tasks (columns 0-3, 4-7), so the left task must not drop a receiver whose
// box starts at its last centre. The square u, v in [-0.2, 0.2] covers the centres of the four pixels around the
// axis, the square [-1/4, 1/4]^2: four times B-3; no pixel whose centre lies outside is taken.
TEST(HemicubeAccuracy, ClassicalHemicubeTakesThePixelsWhoseCentresItCoversHalfOpen) {
  const Shooter up = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  HemicubeBackend classical(8);
  const double eighth = 0.125;
  EXPECT_NEAR(single(classical, up, rectangle({-eighth, -eighth, 1}, {0, 2 * eighth, 0}, {2 * eighth, 0, 0})),
              howell_b3(0.25, 0.25, 1.0), 1e-15);
  // Twice as wide, u in [-1/8, 3/8]: the centre 5.5 on its right edge, inside the right task, is not taken either.
  EXPECT_NEAR(single(classical, up, rectangle({-eighth, -eighth, 1}, {0, 2 * eighth, 0}, {4 * eighth, 0, 0})),
              2.0 * howell_b3(0.25, 0.25, 1.0), 1e-15);
  EXPECT_NEAR(single(classical, up, rectangle({-0.2, -0.2, 1}, {0, 0.4, 0}, {0.4, 0, 0})),
              4.0 * howell_b3(0.25, 0.25, 1.0), 1e-15);
}

// With keep_unoccluded, the classical hemicube adds up for each receiver asked for the delta form factors of every
// pixel it covers, in front or not: the factor it gets with nothing in front. A receiver on the top face's right
// column half (u in [0.1, 0.6]) partly hidden by a plate at height 1/2 gets less than alone, and its unoccluded
// factor is what it gets alone; the plate, not asked for, gets none. (Sampled from the columns of the top face's
// right task, the delta form factors must be read at the face's columns, not at the task's.)
TEST(HemicubeAccuracy, ClassicalHemicubeKeepsTheUnoccludedFactorsOfTheReceiversAskedFor) {
  const Shooter up = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  const Polygon receiver = rectangle({0.1, -0.3, 1}, {0, 0.5, 0}, {0.5, 0, 0});
  HemicubeBackend lone(100);
  const double alone = single(lone, up, receiver);
  ASSERT_GT(alone, 0.0);
  ReceiverView view;
  add(view, receiver, 0, 0);
  add(view, rectangle({0.2, -0.2, 0.5}, {0, 0.2, 0}, {0.2, 0, 0}), 1, 1);
  HemicubeBackend classical(100);
  const std::vector<std::uint8_t> wanted{1, 0};
  ASSERT_TRUE(classical.keep_unoccluded(wanted));
  const std::vector<double> f = run(classical, up, view);
  EXPECT_LT(f[0], alone);  // the plate hides u in [0.4, 0.6], v in [-0.3, 0] of it
  EXPECT_GT(f[0], 0.5 * alone);
  EXPECT_GT(f[1], 0.0);
  std::vector<double> unoccluded(view.size(), 0.0);
  ASSERT_TRUE(classical.add_unoccluded(unoccluded));
  EXPECT_NEAR(unoccluded[0], alone, 1e-15);
  EXPECT_EQ(unoccluded[1], 0.0);
}

TEST(HemicubeAccuracy, PaperFigure1SmallReceiverBetweenPixelCentres) {
  // A square of 0.4 x 0.4 pixels at height 1, inside top-face pixel (61, 57) of N = 100 but away from its
  // centre: the classical hemicube misses it, the AA hemicube gets the analytic value.
  const double px = 2.0 / 100;
  const double x0 = -1 + 61 * px + 0.05 * px, y0 = -1 + 57 * px + 0.55 * px;
  const Polygon tiny = rectangle({x0, y0, 1}, {0, 0.4 * px, 0}, {0.4 * px, 0, 0});
  const Shooter up = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  const double exact = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), tiny);
  HemicubeBackend classical(100);
  AaHemicubeBackend aa(100);
  EXPECT_EQ(single(classical, up, tiny), 0.0);
  EXPECT_LT(relative_error(single(aa, up, tiny), exact), 0.005);
  // A row of such receivers (Figure 2's elements smaller than a cell): the AA total stays right.
  ReceiverView row;
  double exact_row = 0.0;
  for (int k = 0; k < 40; ++k) {
    const Polygon p = rectangle({-0.6 + 0.031 * k, 0.213, 1}, {0, 0.007, 0}, {0.007, 0, 0});
    add(row, p, static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k));
    exact_row += polygon_form_factor(Vec3(0), Vec3(0, 0, 1), p);
  }
  const std::vector<double> f = run(aa, up, row);
  EXPECT_LT(relative_error(std::accumulate(f.begin(), f.end(), 0.0), exact_row), 0.005);
}

TEST(HemicubeAccuracy, CoplanarPiecesGetTheWholeSurfaceTotal) {
  // One surface, whole or cut into 13 x 7 pieces, partly behind an occluder: same AA total to 1e-9. Coplanar pieces
  // have one depth key and spread in every pixel, so the layer rule shares the pixel among them as the surface rule
  // does (a reviewer found the test passing with every piece its own surface id); the list-level test
  // FormfactorCoverageList.SameSurfacePiecesShareTheFractionInFront isolates the surface rule.
  const Vec3 o{-0.8, -0.6, 1.3}, e1{0, 1.7, 0.2}, e2{1.9, 0, 0.1};
  const Polygon occluder = rectangle({-0.3, -0.2, 0.8}, {0, 0.5, 0}, {0.6, 0, 0});
  for (double angle : {0.0, 0.37}) {
    const Shooter s = rotated_shooter(Vec3(0.05, 0.02, 0), glm::normalize(Vec3(0.3, 0.1, 1.0)), angle);
    ReceiverView whole, cut;
    add(whole, occluder, 9, 0);
    add(cut, occluder, 9, 0);
    add(whole, rectangle(o, e1, e2), 4, 1);
    const std::vector<std::uint32_t> ids = add_surface(cut, grid(o, e1, e2, 13, 7), 4, 1);
    AaHemicubeBackend aa(100);
    const double w = run(aa, s, whole)[1];
    const std::vector<double> f = run(aa, s, cut);
    double sum = 0.0;
    for (std::uint32_t i : ids) sum += f[i];
    EXPECT_NEAR(sum, w, 1e-9) << angle;
    EXPECT_GT(w, 0.1);
  }
}

TEST(HemicubeAccuracy, AaHemicubeOcclusionGivesTheVisiblePart) {
  // Receiver [-0.5, 0.5]^2 at height 2; a parallel occluder at height 1 over x in [0.1, 1] hides x >= 0.2.
  const Shooter up = rotated_shooter(Vec3(0), Vec3(0, 0, 1), 0.21);
  ReceiverView view;
  add(view, rectangle({-0.5, -0.5, 2}, {0, 1, 0}, {1, 0, 0}), 0, 0);
  add(view, rectangle({0.1, -1, 1}, {0, 2, 0}, {0.9, 0, 0}), 1, 1);
  const double visible = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), rectangle({-0.5, -0.5, 2}, {0, 1, 0}, {0.7, 0, 0}));
  AaHemicubeBackend aa(100);
  const std::vector<double> f = run(aa, up, view);
  EXPECT_LT(relative_error(f[0], visible), 0.01) << f[0] << " vs " << visible;
  EXPECT_LT(relative_error(f[1], polygon_form_factor(Vec3(0), Vec3(0, 0, 1), rectangle({0.1, -1, 1}, {0, 2, 0}, {0.9, 0, 0}))), 0.005);
  HemicubeBackend classical(100);
  EXPECT_LT(relative_error(run(classical, up, view)[0], visible), 0.02);
}

// A thin plate just above a floor (a picture on a wall, a rug's edge, a seat over a floor), seen at a slant: the
// plate hides part of the floor and nothing hides the plate, whether the two are one face each or cut into pieces.
// The depth key of every piece is taken at the pixel centre, where pieces of one plane agree with each other and
// with the plate above them. Taken at the centre moved into each piece's bounding box, where a floor pixel held
// the border of two pieces their keys came from other points of the pixel, the floor group landed in front of the
// plate and took the pixel: with both cut into 16 x 16 the plate got 0.000442 of its 0.004624.
TEST(HemicubeAccuracy, ThinPlateOverACutFloorKeepsItsFormFactor) {
  const Shooter s = Shooter::from_normal(Vec3(0, -0.5, 0.05), Vec3(0, 1, 0.15));
  const Vec3 plate_corner(-1, 1, 0.01), plate_x(2, 0, 0), plate_y(0, 5, 0);
  AnalyticBackend analytic;
  const double exact = single(analytic, s, rectangle(plate_corner, plate_x, plate_y));
  for (const int cut : {1, 4, 16}) {
    ReceiverView view;
    add_surface(view, grid({-5, 0, 0}, {10, 0, 0}, {0, 10, 0}, cut, cut), 0, 0);
    const std::vector<std::uint32_t> plate = add_surface(view, grid(plate_corner, plate_x, plate_y, cut, cut), 1, 1000);
    AaHemicubeBackend aa(100);
    const std::vector<double> f = run(aa, s, view);
    double sum = 0.0;
    for (const std::uint32_t i : plate) sum += f[i];
    EXPECT_LT(relative_error(sum, exact), 0.005) << "cut " << cut << " x " << cut << ": " << sum << " vs " << exact;
  }
}

// A receiver seen nearly edge-on keeps its factor in front of a surface behind it. Its plane passes close to the
// shooter, so the plane's 1/depth changes across a pixel by as much as its value; where the card covers part of a
// pixel, the ray through the pixel centre meets its plane beyond the card, behind the floor. With that centre value
// as the key, the floor's full entry refused the card's in 30 of its 68 pixels at d = 0.0193 and N = 100 (-33.6 %,
// the floor 4.2e-4 too much; the worst over d was 33 to 35 % at N = 100 to 400, always at d N of about 1.9, and at
// N = 50 a card 0.0022 from the shooter lost all). The key is now kept within the 1/depth its surface can have
// (docs/form-factors.md, "Depth kept per receiver and pixel").
TEST(HemicubeAccuracy, EdgeOnCardInFrontOfAFloorKeepsItsFormFactor) {
  const Shooter s = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  const auto facing = [&](Polygon p) { return plane_of(p).signed_distance(s.centre) < 0.0 ? reversed(p) : p; };
  const Polygon floor = facing(rectangle({-4, -4, 2}, {8, 0, 0}, {0, 8, 0}));
  const Vec3 x(1, 0, 0), n = glm::normalize(Vec3(0, 1, -0.3)), b = glm::cross(n, x);
  const auto card = [&](double d) {  // 0.6 x 0.4, its plane d from the shooter
    return facing(rectangle(Vec3(0, 0.3, 1) + d * n - 0.3 * x - 0.2 * b, 0.6 * x, 0.4 * b));
  };
  for (const int resolution : {50, 100, 200}) {
    AaHemicubeBackend aa(resolution);
    for (int k = 0; k < 30; ++k) {
      const double d = 0.002 * std::pow(100.0, k / 29.0);  // the card's plane 0.002 to 0.2 from the shooter
      ReceiverView view;
      add(view, card(d), 1, 1);
      add(view, floor, 0, 0);
      const double alone = single(aa, s, card(d)), with_floor = run(aa, s, view)[0];
      EXPECT_LT(relative_error(with_floor, alone), 1e-9) << "N = " << resolution << ", d = " << d;
    }
  }
  AnalyticBackend analytic;
  AaHemicubeBackend aa(100);
  ReceiverView view;
  add(view, card(0.0193), 1, 1);
  add(view, floor, 0, 0);
  const std::vector<double> f = run(aa, s, view), exact = run(analytic, s, view);
  EXPECT_LT(relative_error(f[0], exact[0]), 0.005) << f[0] << " vs " << exact[0];
  // The card's shadow lies inside the floor: the floor sees all of itself but the shadow.
  EXPECT_LT(relative_error(f[1], exact[1] - exact[0]), 1e-4) << f[1] << " vs " << exact[1] - exact[0];
}

// A floor that runs on behind a partition standing on it (docs/form-factors.md, "Known limits"): seen from a point
// in front of the partition, a pixel on its foot holds floor in front of the partition, floor behind it and the
// partition's foot. The two floor pieces are one surface and tile the pixel; taken as one group at one depth they
// hid the partition's foot, and the floor behind it took its share: the strip got 6.5e-7, 1.95e-4 and 2.19e-4 of its
// 3.58e-4 (N = 100, 100 turned, 200 turned; 3.586e-4 at N = 200 unturned), the hidden floor 3.7e-4 to 1.2e-3. The foot is a strip 0.004 high (a fifth of a pixel there), the floor
// behind is hidden from the shooter: exact factors from the analytic back end, the strip's unoccluded (nothing stands
// between it and the shooter), the hidden floor's 0. What the hidden floor still gets (1.0e-5 at N = 100, 4.6e-6 at
// N = 200, with the frame turned) lies in the pixels at the partition's two ends, where the floor behind, the
// partition and the empty space beside it add up to less than the pixel and the walk takes them side by side; a
// floor behind 0.2 narrower than the partition gets 4e-10.
// The partition tests' cases: N = 100 and 200, the frame as is and turned by 0.3 about the shooting direction (+x);
// body(resolution, shooter, where). The floor lies `kBelow` under the shooting point, the partition at x = kX0.
constexpr double kBelow = 1.0137, kX0 = 2.0;
template <class Body>
void for_each_partition_case(Body&& body) {
  for (const int resolution : {100, 200})
    for (const double angle : {0.0, 0.3})
      body(resolution, rotated_shooter(Vec3(0), Vec3(1, 0, 0), angle),
           "N = " + std::to_string(resolution) + ", angle " + std::to_string(angle));
}

TEST(HemicubeAccuracy, PartitionFootOverAFloorRunningOnBehindItKeepsItsFormFactor) {
  const double below = kBelow, x0 = kX0, foot = 0.004;
  const Vec3 ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  AnalyticBackend analytic;
  for_each_partition_case([&](int resolution, const Shooter& s, const std::string& where) {
    ReceiverView view;
    const std::uint32_t front = add(view, rectangle({0.0, -1, -below}, x0 * ex, 2.0 * ey), 0, 0);  // faces +z
    const std::uint32_t behind = add(view, rectangle({x0, -1, -below}, 2.0 * ex, 2.0 * ey), 0, 1);
    const std::uint32_t strip = add(view, rectangle({x0, -1, -below}, foot * ez, 2.0 * ey), 1, 2);  // faces -x
    add(view, rectangle({x0, -1, -below + foot}, (1.5 - foot) * ez, 2.0 * ey), 1, 2);
    AaHemicubeBackend aa(resolution);
    const std::vector<double> f = run(aa, s, view);
    // Nothing stands between the shooter and the strip or the floor in front.
    const std::vector<double> exact = run(analytic, s, view);
    const double exact_strip = exact[strip];
    EXPECT_LT(relative_error(f[strip], exact_strip), 0.02) << where << ": " << f[strip] << " vs " << exact_strip;
    EXPECT_LT(f[behind], 0.05 * exact_strip) << where;
    EXPECT_LT(relative_error(f[front], exact[front]), 0.005) << where << ": " << f[front] << " vs " << exact[front];
    std::printf("%s: strip %.6g (exact %.6g), floor behind %.3g, floor in front %.6g (exact %.6g)\n", where.c_str(),
                f[strip], exact_strip, f[behind], f[front], exact[front]);
  });
}

// The partition of the test above with the floor behind it running on past its end, cut into pieces of 0.005
// round the end's foot (one surface with the floor in front). From the shooting point the partition hides the
// floor behind it where |y| <= x / 2 and leaves the triangle (2, 1), (4, 2), (2, 2) of it in view. At the partition's end, a pixel holds
// floor in front, the partition's end, floor behind it and floor past it; the walk takes the part of each piece
// behind the partition's plane that the partition does not cover in the image beside the others, and the rest
// after them (docs/form-factors.md, "Overfilled layers ordered by planes"). Taken wholly after them, the hidden
// pieces and those past the end shared what the first round left by their coverages.
TEST(HemicubeAccuracy, FloorPastAPartitionsEndIsSeenAndTheFloorBehindItIsNot) {
  const double below = kBelow, x0 = kX0;
  const Vec3 ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  AnalyticBackend analytic;
  for_each_partition_case([&](int resolution, const Shooter& s, const std::string& where) {
    ReceiverView view;
    add(view, rectangle({0.0, -1, -below}, x0 * ex, 3.0 * ey), 0, 0);  // faces +z
    // The floor behind: a corner of 0.1 x 0.2 round the partition's end cut into pieces of 0.005, the rest in
    // three rectangles.
    const std::vector<Polygon> behind = grid({x0, 0.9, -below}, 0.1 * ex, 0.2 * ey, 20, 40);
    std::vector<std::uint32_t> ids;
    for (std::size_t k = 0; k < behind.size(); ++k)
      ids.push_back(add(view, behind[k], 0, 1 + static_cast<std::uint32_t>(k)));
    add(view, rectangle({x0 + 0.1, -1, -below}, 1.9 * ex, 3.0 * ey), 0, 5000);
    add(view, rectangle({x0, -1, -below}, 0.1 * ex, 1.9 * ey), 0, 5001);
    add(view, rectangle({x0, 1.1, -below}, 0.1 * ex, 0.9 * ey), 0, 5002);
    add(view, rectangle({x0, -1, -below}, 1.5 * ez, 2.0 * ey), 1, 9000);  // faces -x
    AaHemicubeBackend aa(resolution);
    const std::vector<double> f = run(aa, s, view), exact = run(analytic, s, view);
    double hidden = 0.0, seen = 0.0, seen_exact = 0.0;
    for (std::size_t k = 0; k < behind.size(); ++k) {
      double lowest = 1e30, highest = -1e30;  // of y - x / 2 over the piece's corners
      for (const Vec3& c : behind[k]) {
        lowest = std::min(lowest, c.y - 0.5 * c.x);
        highest = std::max(highest, c.y - 0.5 * c.x);
      }
      if (highest < 0.0) hidden += f[ids[k]];
      if (lowest > 0.0) {
        seen += f[ids[k]];
        seen_exact += exact[ids[k]];
      }
    }
    // The corner's part in view: the triangle (2, 1), (2.1, 1.05), (2, 1.1) past the partition's shadow.
    const double in_view = polygon_form_factor(s.centre, s.normal,
                                               Polygon{{x0, 1, -below}, {x0 + 0.1, 1.05, -below}, {x0 + 0.1, 1.1, -below},
                                                       {x0, 1.1, -below}});
    std::printf("%s: the corner's floor hidden behind the partition %.3g, its pieces in view %.6g (exact %.6g), "
                "its part in view %.6g\n", where.c_str(), hidden, seen, seen_exact, in_view);
    // Measured: in view within 4.1 % (N = 100 turned; 0.2 % unturned, 2.2 % at N = 200 turned), hidden at most
    // 4.9 % of the part in view. Taken wholly after the others, 10.2 % short and 10.0 % (N = 100 turned), 2.3 % and
    // 1.5 % (N = 200 turned).
    EXPECT_LT(relative_error(seen, seen_exact), 0.05) << where;
    EXPECT_LT(hidden, 0.055 * in_view) << where;
  });
}

// The same in a room: a 1 x 1 table top 1 to 2 from a wall, seen from a point of the wall a little above the table's
// plane, with the opposite wall behind it. It lost 22 % at N = 100 (0.031 above) and N = 200 (0.0156 above). The
// table top alone is also held to its exact factor (the analytic back end, checked against Howell's closed forms),
// so that an error at these grazing angles shared by both runs would not pass.
TEST(HemicubeAccuracy, TableTopSeenFromJustAboveItsPlaneKeepsItsFormFactor) {
  const Polygon wall = rectangle({-3, 3, -1}, {6, 0, 0}, {0, 0, 4});  // y = 3, facing -y
  const Polygon top = rectangle({-0.5, 1, 0.75}, {1, 0, 0}, {0, 1, 0});  // faces +z
  AnalyticBackend analytic;
  double worst = 0.0;
  for (const int resolution : {100, 200}) {
    AaHemicubeBackend aa(resolution);
    for (int k = 0; k < 40; ++k) {
      const double above = 0.001 * std::pow(100.0, k / 39.0);
      const Shooter s = Shooter::from_normal(Vec3(0, 0, 0.75 + above), Vec3(0, 1, 0));
      ReceiverView view;
      add(view, top, 1, 1);
      add(view, wall, 0, 0);
      const double alone = single(aa, s, top), with_wall = run(aa, s, view)[0];
      EXPECT_LT(relative_error(with_wall, alone), 1e-9) << "N = " << resolution << ", " << above << " above";
      const double exact = single(analytic, s, top);
      worst = std::max(worst, relative_error(alone, exact));
      EXPECT_LT(relative_error(alone, exact), 0.005) << "N = " << resolution << ", " << above << " above: " << alone
                                                     << " vs " << exact;
    }
  }
  std::printf("table top seen from 0.001 to 0.1 above its plane: worst relative error %.2e\n", worst);
}

// The receivers' order does not change the AA hemicube's values, also for a surface close to the shooter that
// crosses its plane: there pixels hold pieces of the plane where the ray through the pixel centre meets the plane
// behind the shooter, and the depth key taken there must be the plane's in that pixel, not each piece's own
// (docs/form-factors.md, "Depth kept per receiver and pixel"). A randomised program's case (mode E, seed 3, case
// 540) shrunk to three receivers, scaled by 1e4 and rounded: a wall 2.5 from the shooter and a plane 0.01 from it
// cut into a triangle and a quad (one surface). Before, keys came from each piece's own box: the triangle got
// 0.0048400 or 0.0048363 and the quad 4.08e-5 or 3.23e-5 (26 %), by order (N = 3000: 0.0049353, 4.94e-5).
TEST(HemicubeAccuracy, AaHemicubeGivesTheSameValuesInAnyOrderOfReceiversCrossingTheShootersPlane) {
  const Shooter s = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  const Vec3 n = glm::normalize(Vec3(-0.59, 0.68, 0.43));
  const Plane cut_plane{n, 0.01};
  const auto on = [&](double x, double y) { return Vec3(x, y, -(cut_plane.d + n.x * x + n.y * y) / n.z); };
  const Vec3 a = on(1.2, 1.07), b = on(-1.8, -2.54), c = on(1.86, 0.98), d = on(3.09, 3.32), e = on(3.02, 2.09);
  const std::vector<Polygon> polygons = {rectangle({2.5, -10, -1}, {0, 0, 7}, {0, 22, 0}), {a, b, c}, {d, a, c, e}};
  const std::vector<Plane> planes = {plane_of(polygons[0]), cut_plane, cut_plane};
  const std::uint32_t surfaces[] = {0, 1, 1};
  AaHemicubeBackend aa(100);
  std::vector<std::uint32_t> order = {0, 1, 2};
  std::vector<double> first;
  do {
    ReceiverView view;
    for (const std::uint32_t k : order) view.add(polygons[k], planes[k], surfaces[k], k);
    const std::vector<double> f = run(aa, s, view);
    std::vector<double> by_receiver(f.size());
    for (std::size_t k = 0; k < f.size(); ++k) by_receiver[order[k]] = f[k];
    if (first.empty()) {
      first = by_receiver;
      ASSERT_GT(first[2], 0.0);
      continue;
    }
    for (std::size_t k = 0; k < f.size(); ++k)
      EXPECT_NEAR(by_receiver[k], first[k], 1e-12 * first[k])
          << "receiver " << k << ", order " << order[0] << order[1] << order[2];
  } while (std::next_permutation(order.begin(), order.end()));
}

// Coplanar surfaces sharing edges (one plane, several materials: Scene makes each its own physical surface) get the
// total of one surface cut the same way, also where something else's depth range overlaps theirs and the pixel
// overfills, so that the walk takes the recurrence: there the surfaces share the f in front of them (the paper's
// identical-z exception) instead of hiding A_1 A_2 of each other. Before: a checkerboard floor with a block standing
// on it lost 2.8e-4 (0.04 %) to the block's base edges, and a floor seen at a grazing angle behind a plate lost 0.18 %.
TEST(HemicubeAccuracy, CoplanarSurfacesSharingEdgesGetOneSurfacesTotal) {
  AaHemicubeBackend aa(100);
  const Plane floor_plane{{0, 1, 0}, 0};
  {  // A 32 x 32 checkerboard of two surfaces, a block standing on it (no bottom face), seen from above one corner.
    const Shooter s = Shooter::from_normal(Vec3(1.3, 0.9, 1.1), glm::normalize(Vec3(-0.5, -1, -0.4)));
    double floor_total[2] = {0, 0}, block_total[2] = {0, 0};
    for (int checker = 0; checker < 2; ++checker) {
      ReceiverView view;
      const int n = 32;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const double x0 = -2 + 4.0 * i / n, z0 = -2 + 4.0 * j / n, d = 4.0 / n;
          view.add(Polygon{{x0, 0, z0}, {x0, 0, z0 + d}, {x0 + d, 0, z0 + d}, {x0 + d, 0, z0}}, floor_plane,
                   checker != 0 ? static_cast<std::uint32_t>((i + j) % 2) : 0u, static_cast<std::uint32_t>(view.size()));
        }
      const std::size_t floor_count = view.size();
      const Vec3 lo(-0.37, 0, -0.29), hi(0.41, 0.5, 0.33), d = hi - lo;
      const std::vector<Polygon> block = {
          rectangle({lo.x, hi.y, lo.z}, {0, 0, d.z}, {d.x, 0, 0}), rectangle(lo, {0, d.y, 0}, {0, 0, d.z}),
          rectangle({hi.x, lo.y, lo.z}, {0, 0, d.z}, {0, d.y, 0}), rectangle(lo, {d.x, 0, 0}, {0, d.y, 0}),
          rectangle({lo.x, lo.y, hi.z}, {0, d.y, 0}, {d.x, 0, 0})};
      for (std::uint32_t k = 0; k < block.size(); ++k) add(view, block[k], 10 + k, 5000 + k);
      const std::vector<double> f = run(aa, s, view);
      for (std::size_t i = 0; i < f.size(); ++i) (i < floor_count ? floor_total : block_total)[checker] += f[i];
    }
    EXPECT_NEAR(floor_total[1], floor_total[0], 1e-12) << "checkerboard floor";
    EXPECT_NEAR(block_total[1], block_total[0], 1e-12) << "block on the checkerboard";
  }
  {  // A floor seen at a grazing angle behind a thin plate, whole and cut into two surfaces across the line of sight.
    const Shooter s = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
    const double h = 0.01, cut = 0.1234;
    const Polygon whole = rectangle({-1, -h, 0.1}, {0, 0, 2.9}, {2, 0, 0});
    const Polygon left = rectangle({-1, -h, 0.1}, {0, 0, 2.9}, {1 + cut, 0, 0});
    const Polygon right = rectangle({cut, -h, 0.1}, {0, 0, 2.9}, {1 - cut, 0, 0});
    const Polygon plate = rectangle({-0.3, -0.0099, 0.3}, {0, 0.0049, 0}, {0.6, 0, 0});
    const Plane plane = plane_of(whole);
    ReceiverView one, two;
    one.add(whole, plane, 0, 0);
    add(one, plate, 5, 5);
    two.add(left, plane, 0, 0);
    two.add(right, plane, 1, 1);
    add(two, plate, 5, 5);
    const std::vector<double> a = run(aa, s, one), b = run(aa, s, two);
    EXPECT_NEAR(b[0] + b[1], a[0], 1e-12 * a[0]) << "grazing floor behind a plate";
    EXPECT_NEAR(b[2], a[1], 1e-15);
  }
}

// Two surfaces lying on one another in one plane (a lamp laid on a ceiling; the import warns of it) have the same key
// in every pixel they share. Which of them a hemicube shows there was the one whose receiver came first: a lamp
// whole, before the ceiling, took its pixels; cut into pieces numbered after the ceiling's, it lost them, and the
// solver shared the lamp's factor among its pieces by the little they got at its edges (a plate under such a lamp
// ended with radiosities from -383 to 366). At equal keys the surface with the lower id is in front, whatever the
// receivers' order and pieces.
TEST(HemicubeAccuracy, SurfacesOnOneAnotherInOnePlaneHideOneAnotherWhateverTheirPieces) {
  const Shooter s = rotated_shooter(Vec3(0.2, -0.1, 0), Vec3(0, 0, 1), 0.3);
  const Plane plane{{0, 0, -1}, 0.5};  // z = 0.5, facing down
  const Polygon ceiling = rectangle({-2, -2, 0.5}, {0, 4, 0}, {4, 0, 0});
  const Polygon lamp = rectangle({-0.3, -0.4, 0.5}, {0, 1, 0}, {1.1, 0, 0});
  const std::vector<Polygon> lamp_pieces = grid({-0.3, -0.4, 0.5}, {0, 1, 0}, {1.1, 0, 0}, 3, 3);
  const auto exact = [&](const Polygon& p) {
    ReceiverView alone;
    alone.add(p, plane, 0, 0);
    return run(*make_backend("analytic"), s, alone)[0];
  };
  const double lamp_exact = exact(lamp), ceiling_exact = exact(ceiling);
  for (const char* name : {"aa-hemicube", "hemicube"}) {
    for (const std::uint32_t lamp_surface : {0u, 2u}) {  // the lamp in front (0), the ceiling in front (2)
      double first_lamp = -1.0, first_ceiling = -1.0;
      for (const bool whole : {true, false}) {
        for (const bool lamp_first : {true, false}) {
          ReceiverView view;
          std::vector<std::uint32_t> lamp_ids;
          const auto add_lamp = [&] {
            for (const Polygon& piece : whole ? std::vector<Polygon>{lamp} : lamp_pieces)
              lamp_ids.push_back(view.add(piece, plane, lamp_surface, 1));
          };
          if (lamp_first) add_lamp();
          const std::uint32_t ceiling_id = view.add(ceiling, plane, 1, 0);
          if (!lamp_first) add_lamp();
          const std::vector<double> f = run(*make_backend(name, {.resolution = 100}), s, view);
          double lamp_total = 0.0;
          for (const std::uint32_t id : lamp_ids) lamp_total += f[id];
          const std::string what = std::string(name) + (lamp_surface == 0 ? ", lamp in front" : ", ceiling in front") +
                                   (whole ? ", lamp whole" : ", lamp in 9 pieces") +
                                   (lamp_first ? ", lamp first" : ", ceiling first");
          if (first_lamp < 0.0) {
            first_lamp = lamp_total;
            first_ceiling = f[ceiling_id];
            // In front, the lamp gets its own factor and hides it from the ceiling; behind, it gets nothing.
            const double tolerance = std::string_view(name) == "hemicube" ? 0.02 : 0.005;
            if (lamp_surface == 0) {
              EXPECT_NEAR(lamp_total, lamp_exact, tolerance * lamp_exact) << what;
              EXPECT_NEAR(f[ceiling_id], ceiling_exact - lamp_exact, tolerance * ceiling_exact) << what;
            } else {
              EXPECT_LT(lamp_total, 1e-3 * lamp_exact) << what;
              EXPECT_NEAR(f[ceiling_id], ceiling_exact, tolerance * ceiling_exact) << what;
            }
            continue;
          }
          // The same in any order, whole or in pieces: the AA hemicube's pieces add up to the whole, the classical
          // hemicube's take the whole's pixel centres.
          EXPECT_NEAR(lamp_total, first_lamp, 1e-6 * lamp_exact) << what;
          EXPECT_NEAR(f[ceiling_id], first_ceiling, 1e-6 * ceiling_exact) << what;
        }
      }
    }
  }
}

TEST(HemicubeAccuracy, SubsetStillOccludes) {
  const Shooter up = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  ReceiverView view;
  add(view, rectangle({-0.5, -0.5, 2}, {0, 1, 0}, {1, 0, 0}), 0, 0);
  add(view, rectangle({0.1, -1, 1}, {0, 2, 0}, {0.9, 0, 0}), 1, 1);
  const std::vector<std::uint32_t> subset = {0};
  for (const char* name : {"aa-hemicube", "hemicube"}) {
    auto backend = make_backend(name, {.resolution = 64});
    std::vector<double> all(2), part = {-1.0, -1.0};
    backend->compute(up, view, {}, all);
    backend->compute(up, view, subset, part);
    EXPECT_EQ(part[0], all[0]) << name;
    EXPECT_EQ(part[1], -1.0) << name;
  }
}

double box_sum(FormFactorBackend& backend, const Shooter& s, const ReceiverView& view) {
  const std::vector<double> f = run(backend, s, view);
  return std::accumulate(f.begin(), f.end(), 0.0);
}

// From every shooter inside a closed scene, at each of `resolutions`: the classical hemicube's form factors sum to
// 1 within 1e-12 (every pixel sample belongs to exactly one receiver and the exact delta form factors sum to 1);
// the AA hemicube's never exceed 1 and sum to 1 within `aa_tolerance`.
void expect_closed_sums(const ReceiverView& view, const std::vector<Shooter>& shooters, double aa_tolerance,
                        const char* label, std::initializer_list<int> resolutions = {50, 100, 151}) {
  for (int n : resolutions) {
    HemicubeBackend classical(n);
    AaHemicubeBackend aa(n);
    for (const Shooter& s : shooters) {
      EXPECT_NEAR(box_sum(classical, s, view), 1.0, 1e-12) << label << " N=" << n;
      const double aa_sum = box_sum(aa, s, view);
      std::printf("%s N=%d: AA sum - 1 = %.3e\n", label, n, aa_sum - 1.0);
      EXPECT_LE(aa_sum, 1.0 + 1e-12) << label << " N=" << n;
      EXPECT_NEAR(aa_sum, 1.0, aa_tolerance) << label << " N=" << n;
    }
  }
}

TEST(HemicubeAccuracy, ClosedBoxSumsToOne) {
  ReceiverView view;
  add_box(view, Vec3(0), Vec3(1.0, 1.3, 0.9), 5);
  const std::vector<Shooter> shooters = {
      Shooter::from_normal({0.5, 0.65, 0.0}, {0, 0, 1}),
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, 1.0)), 0.5),
      rotated_shooter({0.8, 0.2, 0.6}, glm::normalize(Vec3(-1.0, 0.7, -0.2)), 1.1),
  };
  // AA: exact inside the walls. Where walls meet inside a pixel their depth ranges overlap, so they form one
  // layer and share the pixel side by side (coverage_list.h); the paper's plain E = A (1 - f) would lose
  // A_front A_back there (section 3.2.5), 0.2-0.8 % of the hemisphere at these resolutions.
  expect_closed_sums(view, shooters, 1e-12, "box");
}

// The smallest resolutions the back ends accept. Below N = 4 the top face's quarter tasks have no columns, and the
// AA hemicube threw when it gave one of them a rasterizer (`aarad formfactors cornell --from light --resolution 3`:
// "viewport 0 x 3 is out of range").
TEST(HemicubeAccuracy, ClosedBoxSumsToOneAtTheSmallestResolutions) {
  ReceiverView view;
  add_box(view, Vec3(0), Vec3(1.0, 1.3, 0.9), 3);
  const std::vector<Shooter> shooters = {
      Shooter::from_normal({0.5, 0.65, 0.0}, {0, 0, 1}),
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, 1.0)), 0.5),
  };
  expect_closed_sums(view, shooters, 1e-12, "small box", {2, 3, 4, 5, 6, 7});
}

// The same box with one wall a rounding error inside the others' ends, as files written in single precision (what
// Blender stores) or with few decimals put junctions: the wall x = 1 stands at 1 - 1e-7, so the floor, the ceiling
// and the walls y = 0 and y = 1.3 reach 1e-7 behind it. In the pixels along those junctions the coverages add up to
// a little more than 1, and the layer rule (slack 1e-9) took that for receivers overlapping in the pixel: the
// recurrence then took A_front A_back from the one behind, as the paper's walk does at every junction, and the sums
// fell 3.5e-4 to 2.3e-3 short (N = 50 to 151). An overfill this small is rounding, and the layer is side by side
// (kLayerSlack); capped at the pixel, nothing is counted twice.
TEST(HemicubeAccuracy, ClosedBoxWhoseWallsMeetARoundingApartSumsToOne) {
  const double w = 1.0, d = 1.3, h = 0.9, inset = 1e-7;
  const Vec3 ex(w, 0, 0), ey(0, d, 0), ez(0, 0, h);
  ReceiverView view;
  const std::vector<std::vector<Polygon>> faces = {
      grid(Vec3(0), ex, ey, 5, 5),                     // z = 0: normal +z
      grid(ez, ey, ex, 5, 5),                          // z = h: normal -z
      grid(Vec3(0), ey, ez, 5, 5),                     // x = 0: normal +x
      grid(Vec3(w - inset, 0, 0), ez, ey, 5, 5),       // x = w - inset: normal -x
      grid(Vec3(0), ez, ex, 5, 5),                     // y = 0: normal +y
      grid(ey, ex, ez, 5, 5),                          // y = d: normal -y
  };
  std::uint32_t patch = 0;
  for (std::uint32_t s = 0; s < faces.size(); ++s) {
    add_surface(view, faces[s], s, patch);
    patch += static_cast<std::uint32_t>(faces[s].size());
  }
  const std::vector<Shooter> shooters = {
      Shooter::from_normal({0.5, 0.65, 0.0}, {0, 0, 1}),
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, 1.0)), 0.5),
      rotated_shooter({0.8, 0.2, 0.6}, glm::normalize(Vec3(-1.0, 0.7, -0.2)), 1.1),
  };
  for (int n : {50, 100, 151}) {
    AaHemicubeBackend aa(n);
    for (const Shooter& s : shooters) {
      const double sum = box_sum(aa, s, view);
      std::printf("box with a wall 1e-7 in N=%d: AA sum - 1 = %.3e\n", n, sum - 1.0);
      EXPECT_LE(sum, 1.0 + 1e-12) << "N=" << n;
      EXPECT_NEAR(sum, 1.0, 1e-12) << "N=" << n;
    }
  }
}

// A closed room tiled with rectangles of two materials, as a modeller writes it: turned, its coordinates rounded to
// 6 significant digits, each material's tiles of one wall a physical surface of its own with the plane of its first
// tile, the rows of tiles staggered (T-vertices, which the rounding moves off the edges they lie on). The two surfaces
// of one wall seen face on have keys a rounding apart (3e-6 of the key) and spreads of 1e-7, so with kLayerTouch
// relative to the key they were two layers, and the second lost A_1 A_2 of every pixel along their junctions
// (coverage_list.h, KeyRounding): the factors from the floor summed to 1 - 4.8e-3 (N = 50) to 1 - 1.7e-3 (N = 151);
// with its coordinates unrounded, to 1 within 1e-15. Now within 3.1e-4: what is left is the room's corners, where the
// rounded tiles overlap by more than kLayerSlack of a pixel and the recurrence takes A_front A_back from the one
// behind (1.3e-6 at N = 50, the cracks the rounding opens).
TEST(HemicubeAccuracy, TurnedRoomOfTwoMaterialsWrittenWithSixDigitsSumsToOne) {
  const Vec3 size(5.3, 3.1, 3.7);
  const Vec3 axis = glm::normalize(Vec3(0.3, 1.0, -0.4));
  const double angle = 0.7;
  const auto turn = [&](const Vec3& p) {  // by `angle` round `axis` (Rodrigues)
    return std::cos(angle) * p + std::sin(angle) * glm::cross(axis, p) + (1.0 - std::cos(angle)) * glm::dot(axis, p) * axis;
  };
  const auto written = [&](const Vec3& p) {  // turned and printed with %.6g
    const Vec3 q = turn(p);
    Vec3 r;
    for (int i = 0; i < 3; ++i) {
      char text[32];
      std::snprintf(text, sizeof text, "%.6g", q[i]);
      r[i] = std::strtod(text, nullptr);
    }
    return r;
  };
  ReceiverView view;
  std::uint32_t surface = 0, patch = 0;
  // A wall origin + s e1 + t e2 (e1 x e2 its normal, into the room) in `rows` rows, each cut into `cols` tiles
  // offset by half a tile from the row below, the materials alternating.
  const auto wall = [&](const Vec3& origin, const Vec3& e1, const Vec3& e2, int rows, int cols) {
    std::vector<Polygon> pieces[2];
    for (int r = 0; r < rows; ++r) {
      std::vector<double> cuts = {0.0};
      for (int c = 1; c < cols; ++c) cuts.push_back((c - 0.5 * (r % 2)) / cols);
      cuts.push_back(1.0);
      for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
        const Vec3 a = origin + cuts[c] * e1 + (double(r) / rows) * e2;
        const Vec3 b = origin + cuts[c + 1] * e1 + (double(r) / rows) * e2;
        const Vec3 up = e2 / double(rows);
        pieces[(r + c) % 2].push_back(Polygon{written(a), written(b), written(b + up), written(a + up)});
      }
    }
    for (const std::vector<Polygon>& p : pieces) {
      add_surface(view, p, surface++, patch);
      patch += static_cast<std::uint32_t>(p.size());
    }
  };
  const Vec3 ex(size.x, 0, 0), ey(0, size.y, 0), ez(0, 0, size.z);
  wall(Vec3(0), ez, ex, 3, 4);       // floor y = 0, facing +y
  wall(ey, ex, ez, 4, 3);            // ceiling, facing -y
  wall(Vec3(0), ey, ez, 3, 3);       // x = 0, facing +x
  wall(ex, ez, ey, 3, 4);            // x = size.x, facing -x
  wall(Vec3(0), ex, ey, 3, 5);       // z = 0, facing +z
  wall(ez, ey, ex, 4, 3);            // z = size.z, facing -z
  const Vec3 up = glm::normalize(turn(Vec3(0, 1, 0)));
  const std::vector<Shooter> shooters = {
      Shooter::from_normal(turn(Vec3(0.5 * size.x, 0.0, 0.5 * size.z)), up),  // the floor's centre
      Shooter::from_normal(turn(Vec3(1.1, 0.0, 2.9)), up),
  };
  expect_closed_sums(view, shooters, 5e-4, "turned room of two materials, 6 digits");
}

// A closed room with a block standing on its floor: the floor is cut around the block's footprint into
// convex pieces of one surface (as the Cornell box's floor), the block has a top and four sides, each its own
// surface. Junctions of different surfaces now run through the middle of the hemisphere (block sides on the
// floor, block edges), not only along the room's corners.
ReceiverView room_with_block(const Vec3& lo = Vec3(0.3, 0.5, 0.0)) {  // lo: the block's footprint corner
  ReceiverView view;
  const double w = 1.0, d = 1.3, h = 0.9;  // room [0, w] x [0, d] x [0, h]
  const Vec3 size(0.3, 0.3, 0.35);         // block size
  const Vec3 ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  std::vector<Polygon> floor;
  for (const Polygon& piece : {rectangle({0, 0, 0}, lo.x * ex, d * ey),
                               rectangle({lo.x + size.x, 0, 0}, (w - lo.x - size.x) * ex, d * ey),
                               rectangle({lo.x, 0, 0}, size.x * ex, lo.y * ey),
                               rectangle({lo.x, lo.y + size.y, 0}, size.x * ex, (d - lo.y - size.y) * ey)}) {
    const auto cut = grid(piece[0], piece[1] - piece[0], piece[3] - piece[0], 2, 2);
    floor.insert(floor.end(), cut.begin(), cut.end());
  }
  add_surface(view, floor, 0, 0);
  std::uint32_t patch = 100;
  auto wall = [&](const std::vector<Polygon>& pieces, std::uint32_t surface) {
    add_surface(view, pieces, surface, patch);
    patch += static_cast<std::uint32_t>(pieces.size());
  };
  wall(grid(h * ez, d * ey, w * ex, 3, 3), 1);        // ceiling, facing down
  wall(grid(Vec3(0), d * ey, h * ez, 3, 3), 2);       // x = 0, facing +x
  wall(grid(w * ex, h * ez, d * ey, 3, 3), 3);        // x = w, facing -x
  wall(grid(Vec3(0), h * ez, w * ex, 3, 3), 4);       // y = 0, facing +y
  wall(grid(d * ey, w * ex, h * ez, 3, 3), 5);        // y = d, facing -y
  const Vec3 bx = size.x * ex, by = size.y * ey, bz = size.z * ez;
  wall(grid(lo + bz, bx, by, 2, 2), 6);               // block top, facing +z
  wall(grid(lo, bz, by, 2, 2), 7);                    // x = lo.x, facing -x
  wall(grid(lo + bx, by, bz, 2, 2), 8);               // x = lo.x + 0.3, facing +x
  wall(grid(lo, bx, bz, 2, 2), 9);                    // y = lo.y, facing -y
  wall(grid(lo + by, bz, bx, 2, 2), 10);              // y = lo.y + 0.3, facing +y
  return view;
}

TEST(HemicubeAccuracy, RoomWithABlockOnTheFloorSumsToOne) {
  const ReceiverView view = room_with_block();
  const std::vector<Shooter> shooters = {
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, -1.0)), 0.5),   // just above the block
      rotated_shooter({0.15, 0.3, 0.1}, glm::normalize(Vec3(1.0, 1.0, 0.2)), 0.2),      // low, facing the block
      rotated_shooter({0.8, 1.1, 0.6}, glm::normalize(Vec3(-0.7, -1.0, -0.6)), 1.1),    // a far corner
  };
  // AA: where surfaces meet inside a pixel they form a layer, and where the block hides a surface that covers
  // the rest of the pixel the walk is exact. Where a piece of the floor lies partly in front of the block's plane
  // and partly behind it (the floor around the block's base seen past its edge), the walk by planes cuts it there
  // (coverage_list.h, "An overfilled layer ordered by planes"). Measured: |sum - 1| <= 5.6e-16; before the cut,
  // 7.4e-5 (N = 50), the whole piece taken as in front of the block; 7.9e-5 before the walk ordered overfilled
  // layers by planes; the paper's plain walk is 2.4e-3 to 8.5e-3 short here.
  expect_closed_sums(view, shooters, 1e-12, "room with block");
}

// The room with a block at the scales the import accepts (coordinates up to 1e50, sizes down to 1e-50). The AA
// hemicube's depth keys are 1 / depth: scaled by a power of two, the scene must give the same factors bit for bit,
// and at any scale the factors still sum to 1. The keys' spreads are floats: before the shot's keys were scaled to
// the scene's size, a room 1e45 across lost 1.1e-5 of a shot (spreads below a float's range) and one 1e-45
// across 6e-6 and more (spreads beyond it), the receivers behind the block seen through it.
TEST(HemicubeAccuracy, AaHemicubeGivesTheSameFactorsAtEveryScale) {
  const ReceiverView unit = room_with_block();
  const auto scaled = [&unit](double k) {
    ReceiverView view;
    for (std::size_t i = 0; i < unit.size(); ++i) {
      Polygon polygon;
      for (const Vec3& p : unit.polygon(i)) polygon.push_back(p * k);
      Plane plane = unit.plane(i);
      plane.d *= k;
      view.add(polygon, plane, unit.surface(i), unit.patch(i));
    }
    return view;
  };
  const std::vector<Shooter> shooters = {
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, -1.0)), 0.5),
      rotated_shooter({0.15, 0.3, 0.1}, glm::normalize(Vec3(1.0, 1.0, 0.2)), 0.2),
      rotated_shooter({0.8, 1.1, 0.6}, glm::normalize(Vec3(-0.7, -1.0, -0.6)), 1.1),
  };
  AaHemicubeBackend aa(100);
  for (const Shooter& s : shooters) {
    std::vector<double> reference(unit.size(), 0.0);
    aa.compute(s, unit, {}, reference);
    for (const double k : {0x1p-166, 0x1p-133, 0x1p-100, 0x1p-50, 0x1p50, 0x1p100, 0x1p133, 0x1p166, 1e-45, 1e45}) {
      const ReceiverView view = scaled(k);
      Shooter at = s;
      at.centre *= k;
      std::vector<double> out(view.size(), 0.0);
      aa.compute(at, view, {}, out);
      EXPECT_NEAR(std::accumulate(out.begin(), out.end(), 0.0), 1.0, 1e-12) << k;
      int exponent = 0;
      if (std::frexp(k, &exponent) != 0.5) continue;  // not a power of two
      std::size_t differ = 0;
      for (std::size_t i = 0; i < out.size(); ++i) differ += out[i] != reference[i];
      EXPECT_EQ(differ, 0u) << k;
    }
  }
}

// A closed room whose floor runs on past one of its walls, outside: the floor outside is the same surface as the
// floor inside and meets it along the wall's foot. Seen from inside, the wall hides it, so the factors to the room
// sum to 1 and the floor outside gets nothing. At the wall's foot a pixel holds the floor inside, the wall's foot
// and the floor outside (one surface with the floor inside, one key); before the walk ordered such pixels by
// planes, the floor outside took a share of them: here the room's sums fell 1.1e-3 to 3.4e-3 short, 1.1e-3 to
// 3.3e-3 of it into the floor outside. Measured now: the room within 5.8e-5 (N = 50; 2.3e-5 at N = 100; what does
// not go to the floor outside was 1.4e-4 before), the floor outside at most 1.9e-6.
TEST(HemicubeAccuracy, FloorRunningOnPastAWallGetsNothingFromInside) {
  ReceiverView view;
  add_box(view, Vec3(0), Vec3(1.0, 1.3, 0.9), 4);
  const std::uint32_t outside = view.add(rectangle({1, 0, 0}, {1.5, 0, 0}, {0, 1.3, 0}), Plane{{0, 0, 1}, 0}, 0, 999);
  const std::vector<Shooter> shooters = {
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, -0.6)), 0.3),
      rotated_shooter({0.2, 0.5, 0.7}, glm::normalize(Vec3(1.0, 0.1, -0.5)), 0.3),
      rotated_shooter({0.5, 0.65, 0.05}, glm::normalize(Vec3(1.0, 0.2, 0.1)), 1.1),
  };
  for (const int n : {50, 100}) {
    AaHemicubeBackend aa(n);
    for (const Shooter& s : shooters) {
      std::vector<double> f(view.size(), 0.0);
      aa.compute(s, view, {}, f);
      double room = 0.0;
      for (std::uint32_t i = 0; i < view.size(); ++i)
        if (i != outside) room += f[i];
      std::printf("floor running on past a wall, N=%d: room sum - 1 = %.3e, floor outside %.3e\n", n, room - 1.0,
                  f[outside]);
      EXPECT_NEAR(room, 1.0, 1e-4) << "N = " << n;
      EXPECT_LT(f[outside], 5e-6) << "N = " << n;
    }
  }
}

// A subset's compute() skips the receivers that share no pixel with the subset (TileMask); what the subset gets
// must not change. Subsets: the block and the floor pieces next to it (hidden behind one another from every
// shooter here), two floor pieces alone, and every fifth receiver. The classical hemicube's item buffer is the same
// at every pixel the subset covers, so its sums are bit-identical; the AA hemicube adds a receiver's pixels in runs
// that skipped receivers no longer interrupt, so its sums may differ in the last bits.
TEST(HemicubeAccuracy, SubsetGetsWhatTheWholeShotGives) {
  const ReceiverView view = room_with_block();
  std::vector<std::uint32_t> block_and_floor, two_floor_pieces, every_fifth;
  for (std::uint32_t i = 0; i < view.size(); ++i) {
    if (view.surface(i) >= 6 || (view.surface(i) == 0 && i >= 8)) block_and_floor.push_back(i);
    if (i % 5 == 0) every_fifth.push_back(i);
  }
  two_floor_pieces = {9, 13};
  const std::vector<Shooter> shooters = {
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, -1.0)), 0.5),
      rotated_shooter({0.15, 0.3, 0.1}, glm::normalize(Vec3(1.0, 1.0, 0.2)), 0.2),
      rotated_shooter({0.8, 1.1, 0.6}, glm::normalize(Vec3(-0.7, -1.0, -0.6)), 1.1),
      rotated_shooter({0.45, 0.65, 0.9}, Vec3(0, 0, -1), 0.3),  // on the ceiling, above the block
  };
  for (const char* name : {"aa-hemicube", "hemicube"}) {
    for (int n : {50, 101}) {
      auto backend = make_backend(name, {.resolution = n});
      for (const Shooter& s : shooters) {
        std::vector<double> whole(view.size());
        backend->compute(s, view, {}, whole);
        for (const auto* subset : {&block_and_floor, &two_floor_pieces, &every_fifth}) {
          std::vector<double> part(view.size(), -1.0);
          backend->compute(s, view, *subset, part);
          for (std::uint32_t i = 0; i < view.size(); ++i) {
            if (std::find(subset->begin(), subset->end(), i) == subset->end()) {
              EXPECT_EQ(part[i], -1.0) << name << " N=" << n << " receiver " << i;
            } else if (std::string_view(name) == "hemicube") {
              EXPECT_EQ(part[i], whole[i]) << name << " N=" << n << " receiver " << i;
            } else {
              EXPECT_NEAR(part[i], whole[i], 1e-14 + 1e-12 * whole[i]) << name << " N=" << n << " receiver " << i;
            }
          }
        }
      }
    }
  }
}

// room_with_block with every receiver cut into cuts x cuts pieces of its patch, the patch ids spread out by
// `stride` (a stride past 16 receivers per id makes them sparse, and prepare_subset then prepares every receiver).
ReceiverView room_with_block_cut(std::uint32_t stride, int cuts = 3, const Vec3& block = Vec3(0.3, 0.5, 0.0)) {
  const ReceiverView coarse = room_with_block(block);
  ReceiverView view;
  for (std::uint32_t i = 0; i < coarse.size(); ++i) {
    const std::span<const Vec3> q = coarse.polygon(i);
    for (const Polygon& piece : grid(q[0], q[1] - q[0], q[3] - q[0], cuts, cuts))
      view.add(piece, coarse.plane(i), coarse.surface(i), coarse.patch(i) * stride);
  }
  return view;
}

// Every subset's factors from `dense` (whose patches prepare_subset may skip) equal those from `sparse` (the same
// receivers with sparse patch ids: every receiver prepared), bit for bit, for both hemicubes at N = 50 and 101.
void expect_subsets_get_the_same(const ReceiverView& dense, const ReceiverView& sparse,
                                 std::span<const Shooter> shooters,
                                 std::span<const std::vector<std::uint32_t>* const> subsets) {
  ASSERT_EQ(dense.size(), sparse.size());
  for (const char* name : {"aa-hemicube", "hemicube"}) {
    for (int n : {50, 101}) {
      auto skipping = make_backend(name, {.resolution = n}), preparing_all = make_backend(name, {.resolution = n});
      for (const Shooter& s : shooters) {
        for (const std::vector<std::uint32_t>* subset : subsets) {
          std::vector<double> skipped(dense.size(), -1.0), all(dense.size(), -1.0);
          skipping->compute(s, dense, *subset, skipped);
          preparing_all->compute(s, sparse, *subset, all);
          for (const std::uint32_t i : *subset)
            EXPECT_EQ(skipped[i], all[i]) << name << " N=" << n << " receiver " << i;
        }
      }
    }
  }
}

// How many receivers prepare_subset prepares for `subset` of `dense`, summed over the shooters at N = 50 and 101; and
// that with sparse patch ids it prepares every receiver.
std::size_t prepared_for(const ReceiverView& dense, const ReceiverView& sparse, std::span<const Shooter> shooters,
                         std::span<const std::uint32_t> subset) {
  std::size_t prepared = 0;
  for (int n : {50, 101}) {
    for (const Shooter& s : shooters) {
      PreparedReceivers p;
      p.prepare_subset(s, dense, subset, HemicubeGeometry(n));
      prepared += p.prepared_count();
      p.prepare_subset(s, sparse, subset, HemicubeGeometry(n));
      EXPECT_EQ(p.prepared_count(), sparse.size());
    }
  }
  return prepared;
}

// prepare_subset prepares only the patches whose ball may reach a tile of the subset, and skips the rest before
// transforming their points. The subset must get exactly what it gets with every receiver prepared (sparse patch
// ids), for both hemicubes, from shooters that have patches on all sides, across face seams, and next to them
// (a ball reaching behind the shooter's plane).
TEST(HemicubeAccuracy, SubsetSkipsWholePatchesAndGetsTheSameNumbers) {
  const ReceiverView dense = room_with_block_cut(1), sparse = room_with_block_cut(1000);
  ASSERT_EQ(dense.size(), sparse.size());
  std::vector<std::uint32_t> one_patch, block, every_seventh;
  for (std::uint32_t i = 0; i < dense.size(); ++i) {
    if (dense.patch(i) == dense.patch(100)) one_patch.push_back(i);
    if (dense.surface(i) >= 6) block.push_back(i);
    if (i % 7 == 3) every_seventh.push_back(i);
  }
  const std::vector<Shooter> shooters = {
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, -1.0)), 0.5),
      rotated_shooter({0.15, 0.3, 0.1}, glm::normalize(Vec3(1.0, 1.0, 0.2)), 0.2),
      rotated_shooter({0.45, 0.65, 0.9}, Vec3(0, 0, -1), 0.3),    // on the ceiling, above the block
      rotated_shooter({0.45, 0.65, 0.3501}, Vec3(0, 0, 1), 0.7),  // just above the block's top
      rotated_shooter({0.6001, 0.62, 0.2}, Vec3(1, 0, 0), 0.1),   // on a side of the block
  };
  const std::vector<std::uint32_t>* const subsets[] = {&one_patch, &block, &every_seventh};
  expect_subsets_get_the_same(dense, sparse, shooters, subsets);
  const std::size_t prepared = prepared_for(dense, sparse, shooters, one_patch);
  const std::size_t offered = 2 * shooters.size() * dense.size();
  // The pieces of one wall patch lie in a small part of every hemicube here: most patches are skipped, also those
  // reaching behind a face's apex plane (whose part on the face is bounded by the frustum: 1 467 of 7 290 receivers
  // were prepared when such a patch was taken to reach every tile, 639 now).
  EXPECT_LT(prepared, offered / 8) << prepared << " of " << offered;
}

// With a patch per piece (729 patches: 46 clusters of 16 in 6 groups of 8 clusters), prepare_subset skips whole groups
// and clusters of patches as well as single patches; the subset still gets exactly what it gets with every receiver
// prepared (sparse patch ids).
TEST(HemicubeAccuracy, SubsetSkipsGroupsOfPatchesAndGetsTheSameNumbers) {
  const ReceiverView coarse = room_with_block();
  const auto pieces_as_patches = [&](std::uint32_t stride) {
    ReceiverView view;
    std::uint32_t patch = 0;
    for (std::uint32_t i = 0; i < coarse.size(); ++i) {
      const std::span<const Vec3> q = coarse.polygon(i);
      for (const Polygon& piece : grid(q[0], q[1] - q[0], q[3] - q[0], 3, 3))
        view.add(piece, coarse.plane(i), coarse.surface(i), stride * patch++);
    }
    return view;
  };
  const ReceiverView dense = pieces_as_patches(1), sparse = pieces_as_patches(1000);
  ASSERT_GT(dense.size(), 2 * 16 * 8);  // more than two groups
  std::vector<std::uint32_t> corner, block, every_eleventh;
  for (std::uint32_t i = 0; i < dense.size(); ++i) {
    if (i / 9 == 40) corner.push_back(i);  // the pieces of one coarse receiver
    if (dense.surface(i) >= 6) block.push_back(i);
    if (i % 11 == 5) every_eleventh.push_back(i);
  }
  ASSERT_EQ(corner.size(), 9u);
  const std::vector<Shooter> shooters = {
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, -1.0)), 0.5),
      rotated_shooter({0.45, 0.65, 0.9}, Vec3(0, 0, -1), 0.3),
      rotated_shooter({0.6001, 0.62, 0.2}, Vec3(1, 0, 0), 0.1),
  };
  const std::vector<std::uint32_t>* const subsets[] = {&corner, &block, &every_eleventh};
  expect_subsets_get_the_same(dense, sparse, shooters, subsets);
  const std::size_t prepared = prepared_for(dense, sparse, shooters, corner);
  const std::size_t offered = 2 * shooters.size() * dense.size();
  // One coarse receiver's pieces lie in a small part of each hemicube: 203 of 4 374 receivers were prepared.
  EXPECT_LT(prepared, offered / 10) << prepared << " of " << offered;
}

// A view marked as a refinement of the last one a back end saw (ReceiverView::mark_refinement_of: the solver's view
// after splits) keeps that view's patch balls and boxes; its subsets must still get what a back end that found them
// afresh gives. A view that is not marked, or marked as refining another view than the last one seen, has its balls
// found again: here its block stands elsewhere, under patches with the same ids.
TEST(HemicubeAccuracy, RefinedViewKeepsPatchBallsAndGetsTheSameNumbers) {
  const ReceiverView coarse = room_with_block_cut(1, 3), moved = room_with_block_cut(1, 3, Vec3(0.55, 0.2, 0.0));
  ReceiverView fine = room_with_block_cut(1, 6), fine_again = room_with_block_cut(1, 6);
  fine.mark_refinement_of(coarse.revision());
  fine_again.mark_refinement_of(coarse.revision());  // not of `moved`, the view seen just before it below
  const std::vector<Shooter> shooters = {
      rotated_shooter({0.31, 0.72, 0.4}, glm::normalize(Vec3(0.4, -0.3, -1.0)), 0.5),
      rotated_shooter({0.15, 0.3, 0.1}, glm::normalize(Vec3(1.0, 1.0, 0.2)), 0.2),
      rotated_shooter({0.45, 0.65, 0.9}, Vec3(0, 0, -1), 0.3),
  };
  // The floor's receivers: the block, listed through its patches' balls, hides part of the floor from every shooter.
  const auto floor = [](const ReceiverView& view) {
    std::vector<std::uint32_t> subset;
    for (std::uint32_t i = 0; i < view.size(); ++i)
      if (view.surface(i) == 0) subset.push_back(i);
    return subset;
  };
  for (const char* name : {"aa-hemicube", "hemicube"}) {
    for (const Shooter& s : shooters) {
      auto kept = make_backend(name, {.resolution = 50});
      for (const ReceiverView* view : std::array<const ReceiverView*, 4>{&coarse, &fine, &moved, &fine_again}) {
        const std::vector<std::uint32_t> subset = floor(*view);
        std::vector<double> with_kept(view->size(), -1.0), afresh(view->size(), -1.0);
        kept->compute(s, *view, subset, with_kept);
        make_backend(name, {.resolution = 50})->compute(s, *view, subset, afresh);
        for (const std::uint32_t i : subset) EXPECT_EQ(with_kept[i], afresh[i]) << name << " receiver " << i;
      }
    }
  }
}

TEST(HemicubeAccuracy, SeparatedOccluderStillOccludes) {
  // A card floating 0.2 above a receiver hides part of it from the point below: their depth ranges in every
  // pixel are far apart, so the layer rule does not apply and the walk is the paper's E = A (1 - f).
  // Both are cut into pieces that meet inside pixels, so the pieces of each form layers of their own.
  ReceiverView view;
  add_surface(view, grid({-0.5, -0.5, 1.0}, {0, 1, 0}, {1, 0, 0}, 7, 7), 0, 0);           // receiver at z = 1
  add_surface(view, grid({-0.5, -0.5, 0.8}, {0, 0.6, 0}, {0.45, 0, 0}, 5, 5), 1, 100);    // occluder at z = 0.8
  const Shooter up = Shooter::from_normal(Vec3(0), Vec3(0, 0, 1));
  // The visible part of the receiver: the unit square at z = 1 minus the occluder's shadow from the origin,
  // x in [-0.5, -0.05] and y in [-0.5, 0.1] scaled by 1 / 0.8, clipped to the square: [-0.5, -0.0625] x [-0.5, 0.125].
  const double whole = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), rectangle({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0}));
  const double shadow =
      polygon_form_factor(Vec3(0), Vec3(0, 0, 1), rectangle({-0.5, -0.5, 1}, {0, 0.625, 0}, {0.4375, 0, 0}));
  const double card = polygon_form_factor(Vec3(0), Vec3(0, 0, 1), rectangle({-0.5, -0.5, 0.8}, {0, 0.6, 0}, {0.45, 0, 0}));
  AaHemicubeBackend aa(100);
  const std::vector<double> f = run(aa, up, view);
  double receiver = 0.0, occluder = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i) (view.surface(i) == 0 ? receiver : occluder) += f[i];
  EXPECT_LT(relative_error(receiver, whole - shadow), 0.01) << receiver << " " << whole - shadow;
  EXPECT_LT(relative_error(occluder, card), 0.005) << occluder << " " << card;
}

TEST(HemicubeAccuracy, SameNumbersWithOneAndTwoThreads) {
  ReceiverView view;
  add_box(view, Vec3(0), Vec3(1.0, 1.3, 0.9), 6);
  add(view, rectangle({0.2, 0.3, 0.5}, {0, 0.4, 0}, {0.5, 0, 0}), 6, 1000);   // a floating two-sided card
  add(view, rectangle({0.2, 0.3, 0.5}, {0.5, 0, 0}, {0, 0.4, 0}), 7, 1001);
  const Shooter s = rotated_shooter({0.4, 0.6, 0.05}, glm::normalize(Vec3(0.1, 0.2, 1.0)), 0.3);
  for (const char* name : {"aa-hemicube", "hemicube", "analytic"}) {
    std::vector<double> one(view.size()), two(view.size());
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
      make_backend(name, {.resolution = 120})->compute(s, view, {}, one);
    }
    {
      // global_control only caps the threads; an arena of two slots makes two of them available even on a
      // one-CPU runner, where the default arena would have one.
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
      tbb::task_arena arena(2);
      arena.execute([&] {
        EXPECT_EQ(tbb::this_task_arena::max_concurrency(), 2);
        make_backend(name, {.resolution = 120})->compute(s, view, {}, two);
      });
    }
    EXPECT_EQ(one, two) << name;
  }
}

// The closed unit cube cut 4 x 4 on each face, its leaves split in a checkerboard and half of the pieces again: leaves
// of up to 4 + 8 vertices, the hanging vertices on their edges. Shooters inside, with axis-aligned frames.
mesh::Hierarchy cube_with_t_vertices() {
  mesh::Hierarchy hierarchy(aarad::test::unit_cube(), {.patch_size = 0.5, .element_size = 0.25});
  // Leaves of `level` whose cell of a grid of `cells` per unit has an even index sum are split.
  const auto split_checkerboard = [&](int level, double cells) {
    for (const mesh::NodeId leaf : hierarchy.leaves()) {
      const Vec3 c = glm::floor(hierarchy.centroid(leaf) * cells);
      if (hierarchy.level(leaf) == level && static_cast<int>(c.x + c.y + c.z) % 2 == 0) {
        EXPECT_TRUE(hierarchy.split(leaf).ok);
      }
    }
  };
  split_checkerboard(1, 4.0);
  split_checkerboard(2, 8.0);
  return hierarchy;
}

std::vector<Shooter> cube_shooters() {
  return {Shooter::from_normal({0.5, 0.125, 0.5}, {0, 1, 0}), Shooter::from_normal({0.375, 0.5, 0.625}, {-1, 0, 0}),
          Shooter::from_normal({0.5, 1e-9, 0.5}, {0, 1, 0})};
}

// T-vertices of the adaptive mesh: a leaf whose neighbour was split has the pieces' corners on its edge as hanging
// vertices. The solver's receivers are leaf loops (refine/receiver_cache.h), so the leaf's edge and the pieces' edges
// are the same segments between the same points, and the classical hemicube's fill rule gives every pixel centre
// on them to exactly one side. In the cube above, edges project onto lines through pixel centres at odd N. In a
// closed scene every pixel centre belongs to a receiver, so the factors add up to the delta table's own sum. With the
// corners only, the leaf's edge ran a rounding off the pieces' edges where the projection divides, and the pixel
// centres between the two belonged to neither: 12 of these 21 shots (all at odd N) fell short, by 1.1e-5 to 1.9e-3
// (shooter 2, N = 51).
TEST(HemicubeAccuracy, ClassicalHemicubeGivesEveryPixelCentreAcrossTVerticesToOneReceiver) {
  const mesh::Hierarchy hierarchy = cube_with_t_vertices();
  refine::ReceiverCache cache;
  cache.update(hierarchy);
  EXPECT_EQ(cache.view().max_polygon_size(), 4u + 8u);
  const std::vector<Shooter> shooters = cube_shooters();
  double worst = 0.0;
  for (const int n : {49, 50, 51, 99, 100, 101, 151}) {
    HemicubeBackend classical(n);
    const double total = HemicubeGeometry(n).total();
    for (std::size_t k = 0; k < shooters.size(); ++k) {
      const double sum = box_sum(classical, shooters[k], cache.view());
      worst = std::max(worst, std::abs(sum - total));
      EXPECT_NEAR(sum, total, 1e-12) << "shooter " << k << ", N = " << n;
    }
  }
  std::printf("cube with T-vertices: worst |sum - table| %.3g\n", worst);
}

// The AA hemicube and the analytic back end over the same receivers of up to twelve vertices, some collinear: in the
// closed cube each shot's factors add up to 1.
TEST(HemicubeAccuracy, AaHemicubeAndAnalyticSumToOneOverReceiversWithTVertices) {
  const mesh::Hierarchy hierarchy = cube_with_t_vertices();
  refine::ReceiverCache cache;
  cache.update(hierarchy);
  const std::vector<Shooter> shooters = cube_shooters();
  AnalyticBackend analytic;
  for (const int n : {51, 100}) {
    AaHemicubeBackend aa(n);
    for (std::size_t k = 0; k < shooters.size(); ++k) {
      const double aa_sum = box_sum(aa, shooters[k], cache.view());
      const double analytic_sum = box_sum(analytic, shooters[k], cache.view());
      std::printf("cube with T-vertices, shooter %zu N=%d: AA sum - 1 = %.3g, analytic sum - 1 = %.3g\n", k, n,
                  aa_sum - 1.0, analytic_sum - 1.0);
      EXPECT_NEAR(aa_sum, 1.0, 1e-12) << "shooter " << k << ", N = " << n;
      EXPECT_NEAR(analytic_sum, 1.0, 1e-12) << "shooter " << k;
    }
  }
}

}  // namespace
}  // namespace aarad::formfactor
