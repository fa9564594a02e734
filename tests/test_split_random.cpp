// Property tests: hundreds of seeded random split sequences (quads, triangles, a concave L, the Cornell box;
// with and without balance), every invariant checked after every operation.
#include "aarad/core/builtin_scenes.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/mesh/invariants.h"
#include "test_hierarchy_scenes.h"

#include <gtest/gtest.h>

#include <random>

namespace aarad::mesh {
namespace {

using test::describe;

struct Stats {
  std::size_t splits = 0, refusals = 0, balance_splits = 0;
  int deepest = 0;
};

// One sequence: random radiosities on the leaves, then `operations` random splits (half of them of a child
// of the previous split, to reach deep nesting and nested hanging vertices) and radiosity additions.
void run_sequence(const Scene& scene, const MeshingOptions& options, std::uint64_t seed, int operations, Stats& stats) {
  Hierarchy h(scene, options);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(unit(rng), unit(rng), unit(rng));
  h.update_inner_radiosity();
  auto violations = check_invariants(h);
  ASSERT_TRUE(violations.empty()) << "seed " << seed << " initial\n" << describe(violations);
  std::vector<NodeId> recent;
  for (int op = 0; op < operations; ++op) {
    const std::vector<NodeId> leaves = h.leaves();
    ASSERT_EQ(leaves.size(), h.leaf_count());
    NodeId target;
    if (!recent.empty() && unit(rng) < 0.5) {
      target = recent[static_cast<std::size_t>(rng() % recent.size())];
    } else {
      target = leaves[static_cast<std::size_t>(rng() % leaves.size())];
    }
    const std::size_t leaf_count = h.leaf_count();
    const std::uint64_t revision = h.revision();
    const SplitResult r = h.split(target);
    if (r.ok) {
      ++stats.splits;
      stats.balance_splits += r.also_split.size();
      EXPECT_EQ(h.leaf_count(), leaf_count + 3 * (1 + r.also_split.size()));
      EXPECT_GT(h.revision(), revision);
      for (NodeId c : r.also_split) EXPECT_FALSE(h.is_leaf(c));
      if (!options.balance) {
        EXPECT_TRUE(r.also_split.empty());
      }
      recent = r.children;
      stats.deepest = std::max(stats.deepest, h.level(r.children[0]));
    } else {
      ++stats.refusals;
      EXPECT_FALSE(r.reason.empty());
      EXPECT_EQ(h.leaf_count(), leaf_count);
      EXPECT_EQ(h.revision(), revision);
      recent.clear();
    }
    if (op % 5 == 4) {  // a receive as the solver does it
      const std::vector<NodeId> now = h.leaves();
      h.add_radiosity(now[static_cast<std::size_t>(rng() % now.size())], Rgb(unit(rng), unit(rng), 0.0));
    }
    violations = check_invariants(h);
    ASSERT_TRUE(violations.empty()) << "seed " << seed << " operation " << op << " split " << target << "\n"
                                    << describe(violations);
  }
}

MeshingOptions options_for(double patch, double element, int max_level, bool balance) {
  MeshingOptions o;
  o.patch_size = patch;
  o.element_size = element;
  o.max_level = max_level;
  o.balance = balance;
  return o;
}

void run_many(const Scene& scene, const MeshingOptions& options, int sequences, int operations, std::uint64_t base) {
  Stats stats;
  for (int s = 0; s < sequences; ++s) {
    run_sequence(scene, options, base + static_cast<std::uint64_t>(s), operations, stats);
    if (::testing::Test::HasFatalFailure()) return;
  }
  // The sequences did what they are for: many splits, refusals at the maximum level, deep nesting, and
  // (with balance) forced neighbour splits.
  EXPECT_GT(stats.splits, static_cast<std::size_t>(sequences * operations / 2));
  EXPECT_GT(stats.refusals, 0u);
  EXPECT_EQ(stats.deepest, options.max_level);
  if (options.balance) {
    EXPECT_GT(stats.balance_splits, 0u);
  }
}

TEST(SplitRandom, QuadPatchSequences) { run_many(test::square_scene(), options_for(1.0, 0.5, 6, false), 200, 50, 1000); }
TEST(SplitRandom, QuadPatchSequencesBalanced) { run_many(test::square_scene(), options_for(1.0, 0.5, 6, true), 200, 50, 2000); }
TEST(SplitRandom, TrianglePatchSequences) { run_many(test::triangle_scene(), options_for(2.0, 0.75, 6, false), 200, 50, 3000); }
TEST(SplitRandom, TrianglePatchSequencesBalanced) {
  run_many(test::triangle_scene(), options_for(2.0, 0.75, 6, true), 200, 50, 4000);
}
TEST(SplitRandom, ConcaveLShapeSequences) { run_many(test::l_scene(), options_for(0.8, 0.8, 5, false), 100, 50, 5000); }
TEST(SplitRandom, ConcaveLShapeSequencesBalanced) { run_many(test::l_scene(), options_for(0.8, 0.8, 5, true), 100, 50, 6000); }

TEST(SplitRandom, CornellBoxSequences) {
  const Scene scene = make_cornell_box();
  run_many(scene, options_for(scene.diagonal() / 3.0, scene.diagonal() / 3.0, 5, false), 30, 60, 7000);
}
TEST(SplitRandom, CornellBoxSequencesBalanced) {
  const Scene scene = make_cornell_box();
  run_many(scene, options_for(scene.diagonal() / 3.0, scene.diagonal() / 3.0, 5, true), 30, 60, 8000);
}

}  // namespace
}  // namespace aarad::mesh
