// The solver's receiver cache (refine/receiver_cache.h): after splits it copies the receivers of the leaves that
// stayed from its previous view and reads only the new leaves from the hierarchy. That view must be the one a
// fresh build gives: the same receivers in the same order, corner for corner, with shared points that stand for
// the same coordinates.
#include "core/builtin_scenes.h"
#include "mesh/hierarchy.h"
#include "refine/receiver_cache.h"

#include <gtest/gtest.h>

#include <random>

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
  // Every corner's point is the corner itself, and corners of one mesh vertex share a point.
  for (std::size_t v = 0; v < a.vertices().size(); ++v) {
    EXPECT_EQ(a.points()[a.corner_points()[v]], a.vertices()[v]) << "corner " << v;
    EXPECT_EQ(b.points()[b.corner_points()[v]], b.vertices()[v]) << "corner " << v;
  }
}

TEST(SolverReceiverCache, ViewAfterSplitsIsTheViewOfAFreshBuild) {
  for (const bool balance : {false, true}) {
    const Scene scene = make_cornell_box();
    mesh::MeshingOptions options;
    options.balance = balance;
    mesh::Hierarchy hierarchy(scene, options);
    ReceiverCache cache;
    ASSERT_TRUE(cache.update(hierarchy));
    EXPECT_FALSE(cache.update(hierarchy));  // nothing changed
    std::mt19937_64 rng(balance ? 31 : 17);
    for (int round = 0; round < 12; ++round) {
      // A few splits per round, as a round of substructuring makes.
      const std::vector<mesh::NodeId> leaves = hierarchy.leaves();
      for (int k = 0; k < 1 + round % 4; ++k) hierarchy.split(leaves[static_cast<std::size_t>(rng() % leaves.size())]);
      ASSERT_TRUE(cache.update(hierarchy));
      ReceiverCache fresh;
      fresh.update(hierarchy);
      expect_same_view(cache, fresh);
      if (HasFatalFailure()) return;
    }
    EXPECT_EQ(cache.incremental_rebuilds(), 12u) << "balance " << balance;
    EXPECT_GT(cache.size(), hierarchy.initial_element_count());
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
  ReceiverCache fresh;
  fresh.update(second);
  expect_same_view(cache, fresh);
}

}  // namespace
}  // namespace aarad::refine
