// Running out of memory while a leaf splits: the split either happens whole or not at all (with balance, the
// neighbour splits it forces each happen whole or not at all), and the hierarchy stays sound. A split that ran out of
// memory half-way left a node with four children that were never added, and the solver's finish() crashed on it
// (a reviewer's solve under `ulimit -v`: a segmentation fault instead of exit 3 and the solution so far).
// This program replaces the global operator new with one that fails on request, counted per thread.
#include "aarad/core/builtin_scenes.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/mesh/invariants.h"
#include "test_hierarchy_scenes.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <new>

namespace {
// Allocations this thread may still make before one fails; -1: none fails.
thread_local long g_allocations_left = -1;
}  // namespace

void* operator new(std::size_t size) {
  if (g_allocations_left == 0) throw std::bad_alloc();
  if (g_allocations_left > 0) --g_allocations_left;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace aarad::mesh {
namespace {

TEST(HierarchyOutOfMemory, ASplitThatRunsOutOfMemoryLeavesASoundHierarchy) {
  for (const bool balance : {false, true}) {
    MeshingOptions o;
    o.patch_size = 140.0;
    o.element_size = 70.0;
    o.min_area = 1.0;
    o.balance = balance;
    Hierarchy h(make_cornell_box(), o);
    std::size_t failures = 0;
    NodeId leaf = h.leaves().front();
    for (int split = 0; split < 60; ++split) {
      // The n-th allocation of the split fails, for n = 0, 1, ... until the split needs no more than n.
      for (long allowed = 0;; ++allowed) {
        const std::size_t nodes = h.node_count(), leaves = h.leaf_count();
        SplitResult result;
        bool failed = false;
        g_allocations_left = allowed;
        try {
          result = h.split(leaf);
        } catch (const std::bad_alloc&) {
          failed = true;
        }
        g_allocations_left = -1;
        if (!failed) {
          // Deeper, forcing neighbours to split; elsewhere once refused.
          leaf = result.ok ? result.children[static_cast<std::size_t>(split) % 4]
                           : h.leaves()[static_cast<std::size_t>(split) * 7 % h.leaf_count()];
          break;
        }
        ++failures;
        if (!balance) {
          ASSERT_EQ(h.node_count(), nodes) << "split " << split << ", allocation " << allowed;
          ASSERT_EQ(h.leaf_count(), leaves);
        }
        ASSERT_TRUE(h.is_leaf(leaf));
        const auto violations = check_invariants(h);
        ASSERT_TRUE(violations.empty()) << "split " << split << ", allocation " << allowed << ": "
                                        << test::describe(violations);
      }
    }
    EXPECT_GT(failures, 60u) << "every split allocates at least once";
    h.update_inner_radiosity();  // what the solver's finish() does
  }
}

}  // namespace
}  // namespace aarad::mesh
