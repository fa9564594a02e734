// Reusing a patch's form factors when it shoots again (SolverOptions::factor_cache_mib, refine/factor_cache.h): the
// leaves that stayed keep their factors, the pieces of leaves split since are shot again and share their leaf's
// factor. Without the near-field correction, whose scale belongs to the whole shot, that is the solve with every
// shot computed afresh, to rounding.
#include "aarad/core/builtin_scenes.h"
#include "aarad/core/error.h"
#include "aarad/core/obj_import.h"
#include "aarad/formfactor/aa_hemicube.h"
#include "aarad/refine/receiver_cache.h"
#include "aarad/refine/solver.h"
#include "solver_test_scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>

namespace aarad::refine {
namespace {

const Scene& cornell() {
  static const Scene scene = make_cornell_box();
  return scene;
}

SolverOptions cornell_options(std::int64_t factor_cache_mib, double near_field) {
  SolverOptions options;
  options.meshing = default_meshing(cornell());
  options.factor_cache_mib = factor_cache_mib;
  options.near_field = near_field;
  return options;
}

// The same shots, splits and leaves, and radiosities equal to rounding: a split leaf's pieces are scaled to its
// factor by the ratio of two sums of the same coverage, taken over the leaf's pixels and over its pieces'.
void expect_same_solution(const Solver& fresh, const Solver& reusing) {
  EXPECT_EQ(fresh.shots(), reusing.shots());
  EXPECT_EQ(fresh.splits(), reusing.splits());
  ASSERT_EQ(fresh.hierarchy().leaves(), reusing.hierarchy().leaves());
  const std::vector<Rgb> a = fresh.radiosity(), b = reusing.radiosity();
  ASSERT_EQ(a.size(), b.size());
  double worst = 0.0;
  std::size_t different = 0;
  for (std::size_t node = 0; node < a.size(); ++node) {
    different += !(a[node] == b[node]);
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(b[node][c] - a[node][c]) / std::abs(a[node][c]));
  }
  std::printf("  %zu of %zu nodes differ, by at most %.3g relative\n", different, a.size(), worst);
  EXPECT_LT(worst, 1e-12);
  const Rgb absorbed_a = fresh.absorbed_flux(), absorbed_b = reusing.absorbed_flux();
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(absorbed_b[c], absorbed_a[c], 1e-12 * absorbed_a[c]);
}

// The scene solved with every shot computed afresh and with the factor cache on, the options otherwise the same.
std::pair<std::unique_ptr<Solver>, std::unique_ptr<Solver>> solve_afresh_and_reusing(const Scene& scene,
                                                                                    SolverOptions options) {
  options.factor_cache_mib = 0;
  auto fresh = std::make_unique<Solver>(scene, options);
  fresh->run();
  options.factor_cache_mib = 2048;
  auto reusing = std::make_unique<Solver>(scene, options);
  reusing->run();
  return {std::move(fresh), std::move(reusing)};
}

// With the near-field correction (the default) and without.
TEST(SolverFactorCache, ReusedFactorsSolveTheCornellBoxAsFreshOnes) {
  for (const double near_field : {4.0, 0.0}) {
    Solver fresh(cornell(), cornell_options(0, near_field));
    fresh.run();
    Solver reusing(cornell(), cornell_options(2048, near_field));
    reusing.run();
    std::printf("Cornell box, near field %g: %lld shots, %lld reusing, %lld splits, %zu leaves, %.0f KiB kept\n",
                near_field, static_cast<long long>(reusing.shots()), static_cast<long long>(reusing.reused_shots()),
                static_cast<long long>(reusing.splits()), reusing.hierarchy().leaf_count(),
                static_cast<double>(reusing.factor_cache_bytes()) / 1024.0);
    EXPECT_TRUE(fresh.converged());
    EXPECT_EQ(fresh.reused_shots(), 0);
    EXPECT_EQ(fresh.factor_cache_bytes(), 0u);
    // Most shots come from a patch that shot before, after the mesh changed under it (the splits).
    EXPECT_GT(reusing.reused_shots(), reusing.shots() / 2);
    EXPECT_GT(reusing.splits(), 0);
    EXPECT_GT(reusing.factor_cache_bytes(), std::size_t{1} << 20);  // more than the next test's budget
    expect_same_solution(fresh, reusing);
  }
}

// A patch that shoots from points over its area (Solver::area_shooters) keeps the points in its row, and a row from
// other points is not reused. In data/limits/box_under_lamp.obj two patches do: the lamp, whose first shot is made
// again from 3 x 3 and then 5 x 5 points, and the ceiling patch beside it, over the box's top; the box's top, 0.01
// under the ceiling, tries 3 x 3 and stays with its centroid.
TEST(SolverFactorCache, ReusedFactorsOfPatchesShootingFromMorePointsSolveAsFreshOnes) {
  const Scene scene = import_obj(std::string(AARAD_SOURCE_DIR) + "/data/limits/box_under_lamp.obj");
  SolverOptions options;
  options.max_shots = 300;
  const auto [fresh_solver, reusing_solver] = solve_afresh_and_reusing(scene, options);
  const Solver &fresh = *fresh_solver, &reusing = *reusing_solver;
  EXPECT_EQ(reusing.area_shooters(), 2);
  EXPECT_EQ(fresh.area_shooters(), reusing.area_shooters());
  EXPECT_GT(reusing.reused_shots(), 0);
  expect_same_solution(fresh, reusing);
}

// A patch whose first shots were made from its centroid, and a later one is refused and made again from more points
// (Solver::choose_area_points), keeps those points from then on: its row from the centroid is not reused, and its
// earlier shots move among the pieces of leaves split since by the new points' factors. In
// data/limits/lamp_over_plate.obj a lamp patch's near field is shaped within the far field's bounds while the plate
// under it is 35 leaves, and beyond them once it is 1 163 (the far field 0.018 of the shot, scaled by 1.14 and then
// by 1.32); from 3 x 3 points the far field takes the change. Stepped through its shots, the solve must reach that
// case, solve with the cache as without it, keep every flux accounted for, and leave no leaf below its emission.
TEST(SolverFactorCache, APatchWhosePointsChangeLateSolvesAsWithoutReuse) {
  const Scene scene = import_obj(std::string(AARAD_SOURCE_DIR) + "/data/limits/lamp_over_plate.obj");
  SolverOptions options;
  options.max_shots = 40;
  options.factor_cache_mib = 0;
  Solver fresh(scene, options);
  fresh.run();
  options.factor_cache_mib = 2048;
  Solver reusing(scene, options);
  std::vector<bool> shot_before(reusing.hierarchy().node_count(), false);
  std::int64_t area_shooters = 0, late_changes = 0;
  reusing.run([&](const Progress&) {
    const mesh::NodeId shooter = reusing.last_shooter();
    if (reusing.area_shooters() > area_shooters && shot_before[shooter]) ++late_changes;
    area_shooters = reusing.area_shooters();
    shot_before[shooter] = true;
    return true;
  });
  std::printf("%lld shots, %lld reusing, %lld patches from more points, %lld of them after their first shots\n",
              static_cast<long long>(reusing.shots()), static_cast<long long>(reusing.reused_shots()),
              static_cast<long long>(reusing.area_shooters()), static_cast<long long>(late_changes));
  EXPECT_GE(late_changes, 1);
  EXPECT_GT(reusing.reused_shots(), 0);
  expect_same_solution(fresh, reusing);
  const Rgb emitted = reusing.emitted_flux(), absorbed = reusing.absorbed_flux(), unshot = reusing.unshot_flux(),
            escaped = reusing.escaped_flux();
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(absorbed[c] + unshot[c] + escaped[c], emitted[c], 1e-9 * emitted[c]);
  const mesh::Hierarchy& h = reusing.hierarchy();
  double lowest = 0.0;
  for (const mesh::NodeId leaf : h.leaves()) {
    const Rgb above = h.radiosity(leaf) - scene.material_of_surface(h.surface(leaf)).emission;
    lowest = std::min({lowest, above.r, above.g, above.b});
  }
  EXPECT_EQ(lowest, 0.0) << "a leaf ends below its emission";
}

// What reuse rests on: from any point, a leaf's factor is the sum of its pieces' factors, and a leaf's factor does
// not change when other leaves split. The Cornell box, meshed as aarad solve meshes it, from the centroids of every
// seventh patch (37 shooters), at N = 100: every floor leaf split once, then every other leaf split once. Where the
// blocks stand on the floor and the walls meet it, a pixel holds a floor leaf across a block side's plane, or a
// side's leaf covering the pixel alone (a full entry) beside the floor's pieces; before the AA hemicube's walk cut
// entries across planes and walked full entries among the entries whose ranges reach their own, the leaves there
// and their pieces were hidden differently: 2.3e-6 (floor leaves against their pieces), 6.2e-7 (the other leaves,
// not split), 1.7e-5 and 3.0e-6 (the other way round). Solves with --gradient 0.05 then differed with reused rows
// and without by 0.42 of a node's radiosity (2.6e-6 now; docs/form-factors.md).
TEST(SolverFactorCache, ALeafOfTheCornellBoxGetsWhatItsPiecesGet) {
  const SolverOptions options = cornell_options(0, 4.0);
  Solver whole(cornell(), options), floor_cut(cornell(), options), others_cut(cornell(), options);
  const mesh::Hierarchy& h = whole.hierarchy();
  const auto initial = h.leaves();
  const std::vector<mesh::NodeId> leaves(initial.begin(), initial.end());
  for (const mesh::NodeId leaf : leaves) (h.surface(leaf) == 0 ? floor_cut : others_cut).hierarchy().split(leaf);
  formfactor::AaHemicubeBackend aa(100);
  // Per node of `hierarchy`: the factors of its leaves, added up the tree by one level.
  const auto factors_by_node = [&](const mesh::Hierarchy& hierarchy, const formfactor::Shooter& shooter) {
    ReceiverCache cache;
    cache.update(hierarchy);
    std::vector<double> ff(cache.size(), 0.0);
    aa.compute(shooter, cache.view(), {}, ff);
    std::vector<double> by_node(hierarchy.node_count(), 0.0);
    for (std::uint32_t i = 0; i < ff.size(); ++i) {
      by_node[cache.leaf(i)] += ff[i];
      if (cache.leaf(i) >= h.node_count()) by_node[hierarchy.parent(cache.leaf(i))] += ff[i];
    }
    return by_node;
  };
  double floor_split = 0.0, others_kept = 0.0, others_split = 0.0, floor_kept = 0.0, largest = 0.0;
  for (std::size_t k = 0; k < h.patches().size(); k += 7) {
    const mesh::NodeId patch = h.patches()[k];
    const Vec3 normal = h.plane(patch).normal;
    const formfactor::Shooter shooter = formfactor::Shooter::from_normal(h.centroid(patch) + 1e-6 * normal, normal);
    const std::vector<double> a = factors_by_node(h, shooter), b = factors_by_node(floor_cut.hierarchy(), shooter),
                              c = factors_by_node(others_cut.hierarchy(), shooter);
    for (const mesh::NodeId leaf : leaves) {
      largest = std::max(largest, a[leaf]);
      const bool floor = h.surface(leaf) == 0;
      (floor ? floor_split : others_kept) = std::max(floor ? floor_split : others_kept, std::abs(b[leaf] - a[leaf]));
      (floor ? floor_kept : others_split) = std::max(floor ? floor_kept : others_split, std::abs(c[leaf] - a[leaf]));
    }
  }
  std::printf("Cornell box, 37 shooters: floor leaves against their pieces %.3g, the rest then %.3g; the other leaves "
              "against their pieces %.3g, the floor then %.3g (largest factor %.3g)\n",
              floor_split, others_kept, others_split, floor_kept, largest);
  for (const double difference : {floor_split, others_kept, others_split, floor_kept}) EXPECT_LT(difference, 1e-14);
}

// A budget of 1 MiB holds the factors of a few dozen of the box's patches: the least recently used are given up and
// shot afresh, and the solution is the same.
TEST(SolverFactorCache, ASmallBudgetGivesUpRowsAndKeepsTheSolution) {
  Solver fresh(cornell(), cornell_options(0, 0.0));
  fresh.run();
  Solver reusing(cornell(), cornell_options(1, 0.0));
  std::size_t largest = 0;
  reusing.run([&](const Progress&) {
    largest = std::max(largest, reusing.factor_cache_bytes());
    return true;
  });
  std::printf("Cornell box, 1 MiB: %lld of %lld shots reusing, at most %.0f KiB kept\n",
              static_cast<long long>(reusing.reused_shots()), static_cast<long long>(reusing.shots()),
              static_cast<double>(largest) / 1024.0);
  EXPECT_LE(largest, std::size_t{1} << 20);
  EXPECT_GT(largest, std::size_t{1} << 19);
  EXPECT_GT(reusing.reused_shots(), 0);
  expect_same_solution(fresh, reusing);
}

// A closed room with the AA hemicube (with 2 x 2 shooting points too) and the analytic back end: the same solution,
// and balanced. (The classical hemicube loses pixel centres where a surface was split along its junction with
// another, docs/form-factors.md, "Known limits": there a leaf's pieces do not get its pixel centres, and the cube's
// radiosities differ by up to 3.9e-4 between reused and fresh shots.)
TEST(SolverFactorCache, AClosedRoomSolvedWithReusedFactorsIsTheSameAndBalanced) {
  const Scene scene = test::unit_cube(1.0, 0.5, 1.0);
  struct Case {
    const char* backend;
    int samples;
    double converge;
  };
  for (const Case& c : {Case{"aa-hemicube", 1, 1e-2}, Case{"aa-hemicube", 2, 5e-2}, Case{"analytic", 1, 1e-2}}) {
    SolverOptions options;
    options.backend = c.backend;
    options.shooter_samples = c.samples;
    options.converge = c.converge;
    options.meshing.patch_size = 0.25;
    options.meshing.element_size = 0.125;
    const auto [fresh_solver, reusing_solver] = solve_afresh_and_reusing(scene, options);
    const Solver &fresh = *fresh_solver, &reusing = *reusing_solver;
    const double escaped = reusing.escaped_flux().sum() / reusing.emitted_flux().sum();
    std::printf("unit cube, %s, %d x %d points: %lld shots (%lld reusing), %lld splits, %zu leaves, escaped %.3g "
                "(afresh %.3g)\n",
                c.backend, c.samples, c.samples, static_cast<long long>(reusing.shots()),
                static_cast<long long>(reusing.reused_shots()), static_cast<long long>(reusing.splits()),
                reusing.hierarchy().leaf_count(), escaped, fresh.escaped_flux().sum() / fresh.emitted_flux().sum());
    EXPECT_TRUE(reusing.converged()) << c.backend;
    EXPECT_GT(reusing.reused_shots(), 0) << c.backend;
    EXPECT_GT(reusing.splits(), 0) << c.backend;
    EXPECT_LT(std::abs(escaped), 1e-6) << c.backend;
    expect_same_solution(fresh, reusing);
  }
}

// Leaves split by hand between two shots (Hierarchy::split) are pieces of leaves a row holds like any others.
TEST(SolverFactorCache, LeavesSplitByTheCallerBetweenShotsAreShotAgain) {
  const Scene scene = test::unit_cube(1.0, 0.5, 1.0);
  SolverOptions options;
  options.meshing.patch_size = 0.5;
  options.meshing.element_size = 0.25;
  options.adaptive = false;
  options.near_field = 0.0;
  const auto drive = [&](std::int64_t factor_cache_mib) {
    options.factor_cache_mib = factor_cache_mib;
    auto solver = std::make_unique<Solver>(scene, options);
    for (int shot = 0; shot < 40; ++shot) {
      if (!solver->shoot_once()) break;
      // A leaf on a wall, different every shot, split after the shot; then its first piece.
      const std::vector<mesh::NodeId> leaves = solver->hierarchy().leaves();
      const mesh::NodeId leaf = leaves[(static_cast<std::size_t>(shot) * 7919) % leaves.size()];
      if (solver->hierarchy().can_split(leaf)) solver->hierarchy().split(leaf);
    }
    solver->pull_up();
    return solver;
  };
  const std::unique_ptr<Solver> fresh = drive(0), reusing = drive(2048);
  EXPECT_EQ(reusing->shots(), 40);
  EXPECT_GT(reusing->reused_shots(), 10);
  expect_same_solution(*fresh, *reusing);
}

TEST(SolverFactorCache, ANegativeBudgetIsRefusedByName) {
  SolverOptions options;
  options.factor_cache_mib = -1;
  try {
    Solver solver(cornell(), options);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("SolverOptions::factor_cache_mib (--factor-cache)"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace aarad::refine
