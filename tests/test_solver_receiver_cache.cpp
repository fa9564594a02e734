// The solver's receiver cache (refine/receiver_cache.h): a receiver is its leaf's loop, hanging vertices included.
// After splits the cache copies the receivers of the leaves that stayed from its previous view and reads from the
// hierarchy only the new leaves and those whose loops gained a hanging vertex. That view must be the one a fresh
// build gives: the same receivers in the same order, vertex for vertex, with one shared point per distinct vertex
// position. The neighbour table (refine/neighbour_table.h) copies lists the same way and must equal the
// hierarchy's edge-neighbours.
#include "aarad/core/builtin_scenes.h"
#include "aarad/formfactor/backend.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/refine/neighbour_table.h"
#include "aarad/refine/receiver_cache.h"
#include "solver_test_scenes.h"
#include "test_hierarchy_scenes.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <tuple>

namespace aarad::refine {
namespace {

void expect_same_view(const ReceiverCache& updated, const ReceiverCache& fresh) {
  ASSERT_EQ(updated.size(), fresh.size());
  const formfactor::ReceiverView& a = updated.view();
  const formfactor::ReceiverView& b = fresh.view();
  EXPECT_EQ(a.max_polygon_size(), b.max_polygon_size());
  ASSERT_EQ(a.vertices().size(), b.vertices().size());
  for (std::size_t i = 0; i < updated.size(); ++i) {
    ASSERT_EQ(updated.leaf(i), fresh.leaf(i)) << "receiver " << i;
    EXPECT_EQ(updated.receiver(updated.leaf(i)), i);
    const auto pa = a.polygon(i), pb = b.polygon(i);
    ASSERT_EQ(pa.size(), pb.size()) << "receiver " << i;
    for (std::size_t k = 0; k < pa.size(); ++k) EXPECT_EQ(pa[k], pb[k]) << "receiver " << i << " corner " << k;
    EXPECT_EQ(a.plane(i).normal, b.plane(i).normal);
    EXPECT_EQ(a.plane(i).d, b.plane(i).d);
    EXPECT_EQ(a.surface(i), b.surface(i));
    EXPECT_EQ(a.patch(i), b.patch(i));
  }
  // Every corner's point is the corner itself, and the corners at one position of one surface (one mesh vertex)
  // share a point.
  for (const formfactor::ReceiverView* view : {&a, &b}) {
    std::map<std::tuple<std::uint32_t, double, double, double>, std::uint32_t> point_at;
    for (std::size_t i = 0; i < view->size(); ++i) {
      for (std::uint32_t v = view->offsets()[i]; v < view->offsets()[i + 1]; ++v) {
        const Vec3 p = view->vertices()[v];
        const std::uint32_t point = view->corner_points()[v];
        EXPECT_EQ(view->points()[point], p) << "corner " << v;
        const auto [it, added] = point_at.try_emplace({view->surface(i), p.x, p.y, p.z}, point);
        EXPECT_EQ(it->second, point) << "corner " << v;
      }
    }
  }
}

// Splits a few random leaves (at least one split succeeds), as a round of substructuring does.
void split_some(mesh::Hierarchy& hierarchy, std::mt19937_64& rng, int count) {
  int done = 0;
  for (int attempt = 0; done < count && attempt < 1000; ++attempt) {
    const std::vector<mesh::NodeId> leaves = hierarchy.leaves();
    done += hierarchy.split(leaves[static_cast<std::size_t>(rng() % leaves.size())]).ok ? 1 : 0;
  }
  ASSERT_EQ(done, count);
}

mesh::MeshingOptions meshing(bool balance) {
  mesh::MeshingOptions options;
  options.balance = balance;
  return options;
}

TEST(SolverReceiverCache, ViewAfterSplitsIsTheViewOfAFreshBuild) {
  for (const bool balance : {false, true}) {
    const Scene scene = make_cornell_box();
    mesh::Hierarchy hierarchy(scene, meshing(balance));
    ReceiverCache cache;
    ASSERT_TRUE(cache.update(hierarchy));
    EXPECT_FALSE(cache.update(hierarchy));  // nothing changed
    std::mt19937_64 rng(balance ? 31 : 17);
    for (int round = 0; round < 12; ++round) {
      split_some(hierarchy, rng, 1 + round % 4);
      const formfactor::ReceiverView before = cache.view();
      ASSERT_TRUE(cache.update(hierarchy));
      ReceiverCache fresh;
      fresh.update(hierarchy);
      expect_same_view(cache, fresh);
      if (HasFatalFailure()) return;
      // Marked as a refinement of the view before (ReceiverView::mark_refinement_of), which it is: every point of a
      // patch's receivers lies in the box of that patch's points before (the convex hull's box), and every patch
      // keeps receivers. A fresh build is not marked.
      EXPECT_EQ(cache.view().refines(), before.revision());
      EXPECT_EQ(fresh.view().refines(), 0u);
      std::map<std::uint32_t, std::pair<Vec3, Vec3>> box;  // per patch: lowest and highest point before
      for (std::size_t i = 0; i < before.size(); ++i) {
        auto [it, added] = box.try_emplace(before.patch(i), Vec3(1e300), Vec3(-1e300));
        for (const Vec3& p : before.polygon(i)) {
          it->second.first = glm::min(it->second.first, p);
          it->second.second = glm::max(it->second.second, p);
        }
      }
      std::set<std::uint32_t> patches;
      for (std::size_t i = 0; i < cache.view().size(); ++i) {
        const auto it = box.find(cache.view().patch(i));
        ASSERT_NE(it, box.end()) << "receiver " << i;
        patches.insert(it->first);
        for (const Vec3& p : cache.view().polygon(i)) {
          const Vec3 slack = 1e-12 * (glm::abs(it->second.first) + glm::abs(it->second.second) + Vec3(1.0));
          EXPECT_TRUE(glm::all(glm::greaterThanEqual(p, it->second.first - slack)) &&
                      glm::all(glm::lessThanEqual(p, it->second.second + slack)))
              << "receiver " << i << " of patch " << it->first;
        }
      }
      EXPECT_EQ(patches.size(), box.size());
    }
    EXPECT_EQ(cache.incremental_rebuilds(), 12u) << "balance " << balance;
    EXPECT_GT(cache.size(), hierarchy.initial_element_count());
    // Leaves that stayed gained hanging vertices, and were read again.
    EXPECT_GT(cache.view().max_polygon_size(), 4u) << "balance " << balance;
    EXPECT_GT(cache.reread_leaves(), 0u) << "balance " << balance;
  }
}

// The rectangle [0, 2] x [0, 1] cut into 4 x 2 leaves of 0.5, and the leaf [0.5, 1] x [0, 0.5] split: its three
// neighbours, which stay, gain the midpoints of the edges they share with it. The cache reads those three again (each
// is five points now, the midpoint keyed to the same point as the pieces' corner there) and copies the other four.
TEST(SolverReceiverCache, LeavesThatGainedAHangingVertexAreReadAgain) {
  mesh::Hierarchy hierarchy(test::rectangle_scene(), {.patch_size = 2.0, .element_size = 0.5});
  ASSERT_EQ(hierarchy.leaf_count(), 8u);
  ReceiverCache cache;
  cache.update(hierarchy);
  mesh::NodeId split = mesh::kNoNode;
  for (const mesh::NodeId leaf : hierarchy.leaves())
    if (hierarchy.centroid(leaf) == Vec3(0.75, 0.25, 0.0)) split = leaf;
  ASSERT_NE(split, mesh::kNoNode);
  const std::uint64_t before = hierarchy.revision();
  const std::size_t first_new = hierarchy.node_count();
  ASSERT_TRUE(hierarchy.split(split).ok);
  ASSERT_TRUE(cache.update(hierarchy));
  EXPECT_EQ(cache.incremental_rebuilds(), 1u);
  EXPECT_EQ(cache.reread_leaves(), 3u);
  std::size_t gained = 0;
  for (const mesh::NodeId leaf : hierarchy.leaves()) {
    const auto polygon = cache.view().polygon(cache.receiver(leaf));
    if (leaf < first_new) {  // the leaves that stayed
      EXPECT_EQ(polygon.size() > 4u, hierarchy.loop_revision(leaf) > before) << "leaf " << leaf;
      gained += polygon.size() == 5u ? 1u : 0u;
    }
  }
  EXPECT_EQ(gained, 3u);
  ReceiverCache fresh;
  fresh.update(hierarchy);
  expect_same_view(cache, fresh);
}

TEST(SolverReceiverCache, NeighbourTableAfterSplitsIsTheHierarchysAdjacency) {
  for (const bool balance : {false, true}) {
    const Scene scene = make_cornell_box();
    mesh::Hierarchy hierarchy(scene, meshing(balance));
    ReceiverCache cache;
    NeighbourTable table;
    std::mt19937_64 rng(balance ? 43 : 41);
    std::vector<mesh::NodeId> around;
    for (int round = 0; round < 40; ++round) {
      // Splits clustered in a few places, so that neighbours of neighbours split too.
      split_some(hierarchy, rng, 1 + round % 3);
      if (HasFatalFailure()) return;
      cache.update(hierarchy);
      table.update(hierarchy, cache);
      for (std::size_t i = 0; i < cache.size(); ++i) {
        hierarchy.edge_neighbours(cache.leaf(i), around);
        std::vector<std::uint32_t> expected;
        for (mesh::NodeId n : around) expected.push_back(cache.receiver(n));
        const auto got = table.of(i);
        ASSERT_EQ(std::vector<std::uint32_t>(got.begin(), got.end()), expected) << "round " << round << " receiver " << i;
      }
    }
    // Most lists were copied, not asked of the hierarchy: the copying was tested.
    EXPECT_GT(table.copied_lists(), 30u * hierarchy.initial_element_count()) << "balance " << balance;
  }
}

TEST(SolverReceiverCache, AnotherHierarchyIsBuiltAfresh) {
  const Scene scene = make_cornell_box();
  mesh::Hierarchy first(scene, {}), second(scene, {});
  ReceiverCache cache;
  cache.update(first);
  EXPECT_TRUE(cache.update(second));  // the same revision, but another hierarchy
  second.split(second.leaves().front());
  cache.update(first);
  cache.update(second);
  EXPECT_EQ(cache.incremental_rebuilds(), 0u);
  EXPECT_EQ(cache.view().refines(), 0u);  // built afresh: a refinement of nothing
  ReceiverCache fresh;
  fresh.update(second);
  expect_same_view(cache, fresh);
}

// A table (and a cache) handed another hierarchy at the same revision is built afresh: two hierarchies of the Cornell
// box, each split once at a different leaf, give their new leaves the same node ids.
TEST(SolverReceiverCache, NeighbourTableOfAnotherHierarchyIsBuiltAfresh) {
  const Scene scene = make_cornell_box();
  mesh::Hierarchy first(scene, {}), second(scene, {});
  ASSERT_TRUE(first.split(first.leaves().front()).ok);
  ASSERT_TRUE(second.split(second.leaves().back()).ok);
  ASSERT_EQ(first.revision(), second.revision());
  ASSERT_EQ(first.node_count(), second.node_count());
  ReceiverCache cache;
  NeighbourTable table;
  EXPECT_TRUE(cache.update(first));
  table.update(first, cache);
  EXPECT_TRUE(cache.update(second));
  EXPECT_FALSE(cache.update(second));
  EXPECT_EQ(cache.rebuilds(), 2u);
  table.update(second, cache);
  std::vector<mesh::NodeId> around;
  for (std::size_t i = 0; i < cache.size(); ++i) {
    second.edge_neighbours(cache.leaf(i), around);
    std::vector<std::uint32_t> expected;
    for (mesh::NodeId n : around) expected.push_back(cache.receiver(n));
    const auto got = table.of(i);
    ASSERT_EQ(std::vector<std::uint32_t>(got.begin(), got.end()), expected) << "receiver " << i;
  }
}

// Two surfaces meeting along an edge are meshed apart. Where their grids put points at the same places along the
// edge, those points must be bit-identical, or a hemicube pixel centre exactly on the edge's projection falls in a
// gap a rounding wide that neither receiver claims. From the centre patch of a closed cube's floor, cut 3 x 3, the
// walls' vertical edges project onto pixel centres of the top face at some resolutions: with each wall's points
// computed from its own corners, the classical hemicube's factors in a cube of side 0.7 summed to 1 - 1.43e-4 at
// N = 60 (1 - 2.75e-5 at N = 90, 1 - 1.89e-5 at N = 150). The cell tables sum to 1 (kExactCell), so every shot
// from inside the closed cube must too.
TEST(SolverReceiverCache, MeshedClosedCubeSumsToOneThroughTheClassicalHemicube) {
  for (const double side : {1.0, 0.7, 3.0}) {
    const Scene scene = test::unit_cube(1.0, 0.5, side);
    const mesh::Hierarchy hierarchy(scene, {.patch_size = 0.34 * side, .element_size = 0.34 * side});
    ReceiverCache cache;
    cache.update(hierarchy);
    ASSERT_EQ(cache.size(), 6u * 9u);
    mesh::NodeId centre = mesh::kNoNode;
    for (const mesh::NodeId patch : hierarchy.patches())
      if (glm::length(hierarchy.centroid(patch) - side * Vec3(0.5, 0.0, 0.5)) < 1e-9 * side) centre = patch;
    ASSERT_NE(centre, mesh::kNoNode);
    const formfactor::Shooter shooter =
        formfactor::Shooter::from_normal(hierarchy.centroid(centre), hierarchy.plane(centre).normal);
    for (const int resolution : {30, 60, 90, 100, 150, 300}) {
      const auto backend = formfactor::make_backend("hemicube", {.resolution = resolution});
      std::vector<double> factors(cache.size(), 0.0);
      backend->compute(shooter, cache.view(), {}, factors);
      double sum = 0.0;
      for (const double f : factors) sum += f;
      EXPECT_NEAR(sum, 1.0, 1e-12) << "side " << side << ", N = " << resolution;
    }
  }
}

// The same cube far from the origin (a building in georeferenced metres) through the AA hemicube: every patch's
// factors add up to 1. Its corners are known to a few ulps of their coordinates; moved onto their planes by that
// rounding, the surfaces met a rounding apart, and the AA hemicube's layer rule (1e-9 of a pixel) took the overlap
// for one surface in front of another: at (1e5, 3e4, 0) the worst patch summed to 1 - 2.21e-3, at (1e8, 3e7, 0)
// to 1 - 2.87e-3.
TEST(SolverReceiverCache, MeshedClosedCubeFarFromTheOriginSumsToOneThroughTheAaHemicube) {
  const double side = 0.7;
  for (const Vec3 origin : {Vec3(1e5, 3e4, 0.0), Vec3(1e8, 3e7, 0.0)}) {
    const Scene scene = test::unit_cube(1.0, 0.5, side, origin);
    const mesh::Hierarchy hierarchy(scene, {.patch_size = 0.34 * side, .element_size = 0.34 * side});
    ReceiverCache cache;
    cache.update(hierarchy);
    ASSERT_EQ(cache.size(), 6u * 9u);
    const auto backend = formfactor::make_backend("aa-hemicube", {.resolution = 100});
    double worst = 0.0;
    for (const mesh::NodeId patch : hierarchy.patches()) {
      // Lifted off its surface well beyond the rounding of its coordinates, as the solver does.
      const Vec3 normal = hierarchy.plane(patch).normal;
      const formfactor::Shooter shooter = formfactor::Shooter::from_normal(hierarchy.centroid(patch) + 1e-6 * normal,
                                                                           normal);
      std::vector<double> factors(cache.size(), 0.0);
      backend->compute(shooter, cache.view(), {}, factors);
      double sum = 0.0;
      for (std::size_t i = 0; i < factors.size(); ++i)
        if (cache.view().surface(i) != hierarchy.surface(patch)) sum += factors[i];
      worst = std::max(worst, std::abs(sum - 1.0));
    }
    EXPECT_LT(worst, 1e-12) << "origin " << origin.x << " worst " << worst;
  }
}

}  // namespace
}  // namespace aarad::refine
