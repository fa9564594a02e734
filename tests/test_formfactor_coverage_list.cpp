// The per-pixel coverage lists of the AA hemicube (Chandran et al., section 3.2): the front-to-back walk
// E_k = A_k (1 - f_{k-1}), the same-surface rule, layers of entries whose depth ranges overlap, the full-pixel
// rule, and the error bounds of sections 3.2.5 and 3.2.6 on synthetic pixel lists (entries at distinct depths
// without spread, so the paper's plain walk).
//
// The paper's configurations, worked out (docs/form-factors.md):
// - Pure underestimation (every patch visible): n patches side by side with A_i = 1/n fill the pixel; the walk
//   gives f = 1 - prod(1 - A_i), so the error sum A_i - f = prod(1 - A_i) = (1 - 1/n)^n, the largest value of
//   prod(1 - A_i) under sum A_i = 1 (AM-GM).
// - Pure overestimation (every patch but the first hidden): patch 0 covers A_0; patches 1..n-1 lie entirely
//   behind it, each covering at most A_0, so their true share is 0 and their estimated share is
//   f - A_0 = (1 - A_0)(1 - prod_{i>0}(1 - A_i)), largest when every A_i = A_0: with x = 1 - A_0 the error is
//   x - x^n, maximal at x = (1/n)^(1/(n-1)) with value (1/n)^(1/(n-1)) - (1/n)^(n/(n-1)) (the paper's maximum).
//   The paper writes the maximiser as A_0 = 1 - (1/(n-1))^(1/(n-2)): that is the same expression with n - 1
//   patches in place of n (an index shift; at n = 2 it is undefined). The tests check the value, the maximiser
//   and the shift.
#include "aarad/formfactor/coverage_list.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <span>
#include <vector>

namespace aarad::formfactor {
namespace {

double total_visible(const std::vector<CoverageEntry>& list) {
  double sum = 0.0;
  resolve_front_to_back(list, [&](std::uint32_t, double e) { sum += e; });
  return sum;
}

TEST(FormfactorCoverageList, FrontToBackRecurrence) {
  const std::vector<CoverageEntry> list = {{1.0, 0.5, 0, 0}, {2.0, 0.4, 1, 1}, {3.0, 0.3, 2, 2}};
  std::vector<double> e(3);
  const double f = resolve_front_to_back(list, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.5);
  EXPECT_DOUBLE_EQ(e[1], 0.4 * 0.5);
  EXPECT_DOUBLE_EQ(e[2], 0.3 * (1 - 0.5) * (1 - 0.4));  // section 3.2.3: A_k prod_{i<k} (1 - A_i)
  EXPECT_DOUBLE_EQ(f, 1 - 0.5 * 0.6 * 0.7);
}

TEST(FormfactorCoverageList, SameSurfacePiecesShareTheFractionInFront) {
  // An occluder of 0.5 in front of two pieces of one surface that together fill the pixel.
  const std::vector<CoverageEntry> list = {{1.0, 0.5, 0, 7}, {2.0, 0.25, 1, 3}, {2.0, 0.75, 2, 3}, {3.0, 0.9, 3, 4}};
  std::vector<double> e(4);
  const double f = resolve_front_to_back(list, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[1], 0.25 * 0.5);
  EXPECT_DOUBLE_EQ(e[2], 0.75 * 0.5);  // not 0.75 * (1 - 0.5 - 0.125)
  EXPECT_DOUBLE_EQ(e[3], 0.0);         // behind a full surface
  EXPECT_DOUBLE_EQ(f, 1.0);
  // The same pieces with depth keys apart (2.0 and 2.3, no spread: no layer joins them): only their surface id
  // makes them share the fraction in front (a reviewer's check; at one depth the layer rule alone gave it).
  const std::vector<CoverageEntry> apart = {{1.0, 0.5, 0, 7}, {2.0, 0.25, 1, 3}, {2.3, 0.75, 2, 3}, {3.0, 0.9, 3, 4}};
  std::vector<double> g(4);
  const double f_apart = resolve_front_to_back(apart, [&](std::uint32_t r, double v) { g[r] = v; });
  EXPECT_DOUBLE_EQ(g[1], 0.25 * 0.5);
  EXPECT_DOUBLE_EQ(g[2], 0.75 * 0.5);
  EXPECT_DOUBLE_EQ(g[3], 0.0);
  EXPECT_DOUBLE_EQ(f_apart, 1.0);
}

TEST(FormfactorCoverageList, SurfacesMeetingInThePixelShareItSideBySide) {
  // A floor piece and a wall piece meeting along a line through the pixel: their depth ranges overlap, their
  // coverages add up to 1, so both are visible whole (the paper's walk would give the wall 0.7 x 0.4 = 0.28).
  const std::vector<CoverageEntry> corner = {{2.0, 0.6, 0, 1, 0.1f}, {2.05, 0.4, 1, 2, 0.1f}};
  std::vector<double> e(2);
  double f = resolve_front_to_back(corner, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.6);
  EXPECT_DOUBLE_EQ(e[1], 0.4);
  EXPECT_DOUBLE_EQ(f, 1.0);
  // The same two behind an occluder that covers 0.5: each keeps its share of the uncovered half.
  const std::vector<CoverageEntry> behind = {{1.0, 0.5, 2, 3}, {2.0, 0.6, 0, 1, 0.1f}, {2.05, 0.4, 1, 2, 0.1f}};
  std::vector<double> g(3);
  f = resolve_front_to_back(behind, [&](std::uint32_t r, double v) { g[r] = v; });
  EXPECT_DOUBLE_EQ(g[2], 0.5);
  EXPECT_DOUBLE_EQ(g[0], 0.3);
  EXPECT_DOUBLE_EQ(g[1], 0.2);
  EXPECT_DOUBLE_EQ(f, 1.0);
  // Identical depth without a spread (the paper's identical-z exception) is a layer too.
  const std::vector<CoverageEntry> same_z = {{2.0, 0.6, 0, 1}, {2.0, 0.4, 1, 2}};
  EXPECT_DOUBLE_EQ(total_visible(same_z), 1.0);
}

TEST(FormfactorCoverageList, OverlappingRangesThatOverfillThePixelUseTheRecurrence) {
  // Depth ranges overlap, but the coverages add up to more than the pixel, so the entries overlap in the
  // pixel: the walk falls back to E = A (1 - f), nearest first.
  const std::vector<CoverageEntry> list = {{2.0, 0.7, 0, 1, 0.1f}, {2.05, 0.6, 1, 2, 0.1f}};
  std::vector<double> e(2);
  const double f = resolve_front_to_back(list, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.7);
  EXPECT_DOUBLE_EQ(e[1], 0.6 * 0.3);
  EXPECT_DOUBLE_EQ(f, 1.0 - 0.3 * 0.4);
  // Ranges apart: the recurrence whatever the coverages.
  const std::vector<CoverageEntry> apart = {{2.0, 0.6, 0, 1, 0.01f}, {2.05, 0.4, 1, 2, 0.01f}};
  EXPECT_DOUBLE_EQ(total_visible(apart), 0.6 + 0.4 * 0.4);
}

TEST(FormfactorCoverageList, SurfacesMeetingARoundingApartStillShareThePixel) {
  // The floor and the wall of SurfacesMeetingInThePixelShareItSideBySide, with the wall's edge a rounding of the
  // file's coordinates over the floor's (coverages 0.6 and 0.4 + 1e-6): side by side, the wall keeps the rest of
  // the pixel, 0.4. Taken for an overlap (the slack was 1e-9), the wall got 0.4 x 0.4 = 0.16.
  const std::vector<CoverageEntry> corner = {{2.0, 0.6, 0, 1, 0.1f}, {2.05, 0.4 + 1e-6, 1, 2, 0.1f}};
  std::vector<double> e(2);
  const double f = resolve_front_to_back(corner, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.6);
  EXPECT_DOUBLE_EQ(e[1], 0.4);
  EXPECT_DOUBLE_EQ(f, 1.0);
}

TEST(FormfactorCoverageList, CoplanarSurfacesInAnOverfilledLayerShareTheFractionInFront) {
  // Two surfaces of one plane (two materials of a floor meeting inside the pixel: the same key and spread) and an
  // occluder whose depth range overlaps theirs; the coverages add up to 1.5, so the layer takes the recurrence. The
  // coplanar surfaces lie side by side (the paper's identical-z exception): each gets its share of what the occluder
  // leaves, as one surface cut in two would (before: the second got 0.4 x (1 - 0.5 - 0.3) = 0.08).
  const std::vector<CoverageEntry> list = {{1.0, 0.5, 0, 7, 2.0f}, {2.0, 0.6, 1, 3, 0.5f}, {2.0, 0.4, 2, 4, 0.5f}};
  std::vector<double> e(3);
  const double f = resolve_front_to_back(list, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.5);
  EXPECT_DOUBLE_EQ(e[1], 0.3);
  EXPECT_DOUBLE_EQ(e[2], 0.2);
  EXPECT_DOUBLE_EQ(f, 1.0);
  // Planes that merely meet on the pixel's ray (equal keys, different spreads) keep the recurrence.
  const std::vector<CoverageEntry> meeting = {{1.0, 0.5, 0, 7, 2.0f}, {2.0, 0.6, 1, 3, 0.5f}, {2.0, 0.4, 2, 4, 0.7f}};
  EXPECT_DOUBLE_EQ(total_visible(meeting), 0.5 + 0.3 + 0.4 * (1 - 0.5 - 0.3));
}

TEST(FormfactorCoverageList, LayersChainThroughOverlappingRanges) {
  // Three pieces of three surfaces, each range overlapping the next (a corner of three walls): one layer.
  const std::vector<CoverageEntry> list = {{1.0, 0.2, 0, 1, 0.3f}, {1.5, 0.3, 1, 2, 0.3f}, {2.0, 0.5, 2, 3, 0.3f},
                                           {5.0, 0.9, 3, 4, 0.1f}};
  std::vector<double> e(4);
  const double f = resolve_front_to_back(list, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.2);
  EXPECT_DOUBLE_EQ(e[1], 0.3);
  EXPECT_DOUBLE_EQ(e[2], 0.5);
  EXPECT_DOUBLE_EQ(e[3], 0.0);  // behind a covered pixel
  EXPECT_DOUBLE_EQ(f, 1.0);
}

TEST(FormfactorCoverageList, PureUnderestimationReachesPaperBound) {
  std::mt19937 rng(3);
  for (int n = 2; n <= 50; ++n) {
    std::vector<CoverageEntry> list;
    for (int i = 0; i < n; ++i) list.push_back({1.0 + i, 1.0 / n, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i)});
    const double error = 1.0 - total_visible(list);  // every patch is visible: the truth is sum A_i = 1
    EXPECT_NEAR(error, std::pow(1.0 - 1.0 / n, n), 1e-12) << n;
    // No other split of the pixel among n visible patches does worse.
    std::exponential_distribution<double> g;
    for (int trial = 0; trial < 50; ++trial) {
      std::vector<double> a(n);
      for (double& v : a) v = g(rng);
      const double s = std::accumulate(a.begin(), a.end(), 0.0);
      for (int i = 0; i < n; ++i) list[i].coverage = a[i] / s;
      EXPECT_LE(1.0 - total_visible(list), std::pow(1.0 - 1.0 / n, n) + 1e-12);
    }
  }
  // The bound tends to 1/e: the list code with 10 000 equal visible patches loses (1 - 1e-4)^1e4, which is 1/e less
  // about 1/(2e n) = 1.8e-5.
  const int n = 10000;
  std::vector<CoverageEntry> list;
  for (int i = 0; i < n; ++i) list.push_back({1.0 + i, 1.0 / n, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i)});
  const double error = 1.0 - total_visible(list);
  EXPECT_NEAR(error, std::exp(-1.0), 2e-5);
  EXPECT_LT(error, std::exp(-1.0));
}

double overestimation(int n, double a0) {
  // Patch 0 covers a0; patches 1..n-1 lie behind it inside its projection, each covering a0.
  std::vector<CoverageEntry> list;
  for (int i = 0; i < n; ++i) list.push_back({1.0 + i, a0, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i)});
  return total_visible(list) - a0;  // the truth is a0 (everything else is hidden)
}

TEST(FormfactorCoverageList, PureOverestimationReachesPaperMaximum) {
  for (int n = 2; n <= 50; ++n) {
    const double paper_max = std::pow(1.0 / n, 1.0 / (n - 1)) - std::pow(1.0 / n, double(n) / (n - 1));
    const double a0 = 1.0 - std::pow(1.0 / n, 1.0 / (n - 1));
    EXPECT_NEAR(overestimation(n, a0), paper_max, 1e-12) << n;
    // It is the maximum over A_0.
    for (int k = 0; k <= 1000; ++k) EXPECT_LE(overestimation(n, k / 1000.0), paper_max + 1e-15) << n << " " << k;
    // The paper's A_0 = 1 - (1/(n-1))^(1/(n-2)), as printed, counts one patch more than its maximum does: at
    // m = n + 1 it is the maximiser above, and taken at m = n itself it falls short of the maximum (n >= 3).
    const auto paper_a0 = [](int m) { return 1.0 - std::pow(1.0 / (m - 1), 1.0 / (m - 2)); };
    EXPECT_NEAR(overestimation(n, paper_a0(n + 1)), paper_max, 1e-12) << n;
    if (n >= 3) {
      EXPECT_LT(overestimation(n, paper_a0(n)), paper_max - 1e-6) << n;
    }
    // Occluded patches smaller than A_0 give less.
    std::vector<CoverageEntry> list = {{1.0, a0, 0, 0}};
    for (int i = 1; i < n; ++i) list.push_back({1.0 + i, 0.7 * a0, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i)});
    EXPECT_LT(total_visible(list) - a0, paper_max);
  }
}

TEST(FormfactorCoverageList, ArenaSortsOnInsertionWhateverTheOrder) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<CoverageEntry> entries;
    const int n = 1 + trial % 12;
    for (int i = 0; i < n; ++i)
      entries.push_back({u(rng) * 10, 0.3 * u(rng), static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i)});
    std::vector<CoverageEntry> sorted = entries;
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.depth < b.depth; });
    std::vector<double> expected(n, 0.0), got(n, 0.0);
    resolve_front_to_back(sorted, [&](std::uint32_t r, double e) { expected[r] = e; });
    std::shuffle(entries.begin(), entries.end(), rng);
    CoverageArena arena;
    arena.reset(3);
    for (const CoverageEntry& e : entries) EXPECT_TRUE(arena.insert(1, e));
    arena.resolve(1, [&](std::uint32_t r, double e) { got[r] = e; });
    EXPECT_EQ(got, expected);
    EXPECT_TRUE(arena.empty(0));
    EXPECT_TRUE(arena.empty(2));
  }
}

TEST(FormfactorCoverageList, ArenaGroupsPiecesOfOneSurface) {
  CoverageArena arena;
  arena.reset(1);
  // Pieces of surface 5 at slightly different depths (rounding of their planes), another surface between.
  arena.insert(0, {2.0, 0.2, 0, 5});
  arena.insert(0, {2.5, 0.3, 1, 6});
  arena.insert(0, {2.0 + 1e-15, 0.3, 2, 5});
  arena.insert(0, {1.0, 0.1, 3, 7});
  std::vector<std::uint32_t> order;
  arena.for_each(0, [&](const CoverageEntry& e) { order.push_back(e.receiver); });
  EXPECT_EQ(order, (std::vector<std::uint32_t>{3, 0, 2, 1}));
  std::vector<double> e(4);
  arena.resolve(0, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.2 * 0.9);
  EXPECT_DOUBLE_EQ(e[2], 0.3 * 0.9);
}

TEST(FormfactorCoverageList, ArenaKeepsAGroupWholeWhenAnotherSurfaceLiesBetweenItsDepths) {
  // Two pieces of surface 5 (a tilted plane: 2.0 and 2.2 at their sample points) and a piece of surface 6 at a
  // depth between them. Positions are decided at group heads, so surface 6 goes behind the whole group; the
  // three ranges touch, cover 0.9 together, and each piece is seen whole: E = A = 0.3. Put between the pieces,
  // surface 6 would split the group into two layers: 0.3, then 0.3 x 0.7 = 0.21, then 0.3 x 0.49 = 0.147.
  CoverageArena arena;
  arena.reset(1);
  EXPECT_TRUE(arena.insert(0, {2.0, 0.3, 0, 5}));
  EXPECT_TRUE(arena.insert(0, {2.2, 0.3, 1, 5}));
  EXPECT_TRUE(arena.insert(0, {2.1, 0.3, 2, 6}));
  std::vector<std::uint32_t> order;
  arena.for_each(0, [&](const CoverageEntry& e) { order.push_back(e.receiver); });
  EXPECT_EQ(order, (std::vector<std::uint32_t>{0, 1, 2}));
  std::vector<double> e(3, -1.0);
  const double f = arena.resolve(0, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[0], 0.3);
  EXPECT_DOUBLE_EQ(e[1], 0.3);
  EXPECT_DOUBLE_EQ(e[2], 0.3);
  EXPECT_DOUBLE_EQ(f, 0.9);
}

// The list rules, written out plainly over groups: an entry joins its surface's group (after its last piece),
// or starts a group before the first group whose head lies behind it (or at its depth, of a higher surface); a
// group whose coverages reach the pixel drops the groups behind it, and a covered list refuses new groups behind
// them all. Random arrivals, with runs
// of one surface (the arena's shortcut for the group that took the last entry) and without.
TEST(FormfactorCoverageList, ArenaListsFollowTheGroupRulesWhateverTheArrivals) {
  struct Group {
    std::uint32_t surface;
    double head;
    double sum;
    std::vector<std::uint32_t> receivers;
  };
  std::mt19937 random(12345);
  std::uniform_int_distribution<int> pick_surface(0, 4), pick_depth(0, 5), pick_eighths(1, 4), pick_count(2, 16);
  std::bernoulli_distribution same_as_last(0.6);
  int covered_lists = 0, refused = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    CoverageArena arena;
    arena.reset(1);
    std::vector<Group> groups;
    bool full = false;
    std::uint32_t surface = 0;
    const int count = pick_count(random);
    for (int n = 0; n < count; ++n) {
      if (n == 0 || !same_as_last(random)) surface = static_cast<std::uint32_t>(pick_surface(random));
      // Coverages in eighths add up exactly, so groups reach the pixel.
      const CoverageEntry e{1.0 + pick_depth(random), pick_eighths(random) / 8.0, static_cast<std::uint32_t>(n),
                            surface};
      bool accepted = true;
      auto g = std::find_if(groups.begin(), groups.end(), [&](const Group& x) { return x.surface == surface; });
      if (g != groups.end()) {
        g->receivers.push_back(e.receiver);
        g->sum += e.coverage;
        if (g->sum >= kFullCoverage) {
          groups.erase(g + 1, groups.end());
          full = true;
        }
      } else {
        // At the same depth, the lower surface goes first (the rule of equal keys).
        g = std::find_if(groups.begin(), groups.end(), [&](const Group& x) {
          return x.head > e.depth || (x.head == e.depth && surface < x.surface);
        });
        if (g == groups.end() && full)
          accepted = false;
        else
          groups.insert(g, Group{surface, e.depth, e.coverage, {e.receiver}});
      }
      refused += !accepted;
      ASSERT_EQ(arena.insert(0, e), accepted) << "trial " << trial << ", entry " << n;
    }
    std::vector<std::uint32_t> expected, order;
    for (const Group& g : groups) expected.insert(expected.end(), g.receivers.begin(), g.receivers.end());
    arena.for_each(0, [&](const CoverageEntry& e) { order.push_back(e.receiver); });
    ASSERT_EQ(order, expected) << "trial " << trial;
    ASSERT_EQ(arena.full(0), full) << "trial " << trial;
    covered_lists += full;
  }
  // Both kinds of list, and refusals, occurred.
  EXPECT_GT(covered_lists, 300);
  EXPECT_LT(covered_lists, 2700);
  EXPECT_GT(refused, 100);
}

TEST(FormfactorCoverageList, AFullEntryAtThePartialEntrysDepthHidesItOrNotWhateverTheOrder) {
  // A partial entry at exactly the depth of a full one of another surface is in front of it when its surface is the
  // lower (the rule of equal keys): it takes its coverage and the full receiver the rest, whatever the order. Else it
  // is hidden: offered after the full entry it is refused, offered before it it is dropped, and the full receiver
  // takes the whole pixel either way.
  for (const std::uint32_t partial_surface : {1u, 3u}) {
    for (const bool partial_first : {true, false}) {
      CoverageArena arena;
      arena.reset(1);
      const CoverageEntry partial{2.0, 0.5, 0, partial_surface}, full{2.0, 1.0, 1, 2};
      const bool in_front = partial_surface < full.surface;
      if (partial_first) arena.insert(0, partial);
      EXPECT_TRUE(arena.insert(0, full));
      if (!partial_first) {
        EXPECT_EQ(arena.insert(0, partial), in_front);
      }
      std::vector<double> e(2, -1.0);
      EXPECT_DOUBLE_EQ(arena.resolve(0, [&](std::uint32_t r, double v) { e[r] = v; }), 1.0);
      const std::vector<double> expected = in_front ? std::vector<double>{0.5, 0.5} : std::vector<double>{-1.0, 1.0};
      EXPECT_EQ(e, expected) << partial_first << " " << partial_surface;
      std::vector<double> taken(2, -1.0);
      arena.take_all([&](std::size_t, std::uint32_t r, double v) { taken[r] = v; });
      EXPECT_EQ(taken, e) << partial_first << " " << partial_surface;
    }
  }
}

TEST(FormfactorCoverageList, FullEntriesAtOneDepthGoToTheLowerSurfaceWhateverTheOrder) {
  // Two surfaces lying on one another in one plane: the lower surface takes the pixel, whichever arrives first, in
  // both arenas.
  for (const bool lower_first : {true, false}) {
    const CoverageEntry lower{2.0, 1.0, 0, 4}, higher{2.0, 1.0, 1, 7};
    CoverageArena arena;
    arena.reset(1);
    StagedCoverageArena staged;
    staged.reset(1, 1);
    staged.describe_receivers(2);
    staged.describe(0, 0.0f, lower.surface);
    staged.describe(1, 0.0f, higher.surface);
    const std::vector<CoverageEntry> arrivals = lower_first ? std::vector{lower, higher} : std::vector{higher, lower};
    // The first is taken; the second only when it is the lower.
    EXPECT_TRUE(arena.insert(0, arrivals[0]));
    EXPECT_EQ(arena.insert(0, arrivals[1]), !lower_first);
    for (const CoverageEntry& entry : arrivals) staged.insert(0, 0, entry);
    std::vector<double> e(2, 0.0), taken(2, 0.0);
    arena.take_all([&](std::size_t, std::uint32_t r, double v) { e[r] += v; });
    staged.take_all([&](std::size_t, std::uint32_t r, double v) { taken[r] += v; });
    EXPECT_EQ(e, (std::vector<double>{1.0, 0.0})) << lower_first;
    EXPECT_EQ(taken, e) << lower_first;
  }
}

TEST(FormfactorCoverageList, AFullEntryBetweenTheDepthsOfOneSurfacesPiecesKeepsTheGroupWhole) {
  // A group is placed, and judged in front of or behind a full entry, by its nearest piece (as on insertion):
  // surface 5 starts in front of the full entry at 2.0, so both its pieces are walked, each seen whole (0.3,
  // sum 0.6), and the full receiver takes the rest, 0.4. Cutting the group at its second piece would give the
  // full receiver 0.7.
  CoverageArena arena;
  arena.reset(1);
  EXPECT_TRUE(arena.insert(0, {1.0, 0.3, 0, 5}));
  EXPECT_TRUE(arena.insert(0, {3.0, 0.3, 1, 5}));
  EXPECT_TRUE(arena.insert(0, {2.0, 1.0, 2, 6}));
  std::vector<double> e(3, -1.0);
  EXPECT_DOUBLE_EQ(arena.resolve(0, [&](std::uint32_t r, double v) { e[r] = v; }), 1.0);
  EXPECT_DOUBLE_EQ(e[0], 0.3);
  EXPECT_DOUBLE_EQ(e[1], 0.3);
  EXPECT_DOUBLE_EQ(e[2], 0.4);
}

// A floor running on behind a wall standing on it, in the pixel at the wall's foot (coverage_list.h, "An overfilled
// layer ordered by planes"): the floor in front (receiver 0) covers 0.4 below the foot, the floor behind the wall
// (1) the other 0.6, and the wall's foot (2) the same 0.6 in front of it. One key for the floor's pieces, the wall's
// a little behind it, ranges overlapping. The walk without planes gives the floor the pixel and the wall nothing;
// told that the floor behind lies behind the wall's plane, the floor in front and the wall share the pixel.
struct FloorBehindTheWall {  // receiver 1 lies behind receiver 2's plane
  static constexpr bool kActive = true;
  PlaneSide side(std::uint32_t front, std::uint32_t back) const {
    return front == 2 && back == 1 ? PlaneSide::kBehind : PlaneSide::kNotBehind;
  }
  double cell_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>) const { return 1.0; }
  double hidden_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>,
                     std::span<const CoverageEntry>) const {
    return 1.0;
  }
};
struct EachBehindTheOther {  // faces meeting at a convex edge
  static constexpr bool kActive = true;
  PlaneSide side(std::uint32_t front, std::uint32_t back) const {
    return front != back ? PlaneSide::kBehind : PlaneSide::kNotBehind;
  }
  double cell_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>) const { return 1.0; }
  double hidden_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>,
                     std::span<const CoverageEntry>) const {
    return 1.0;
  }
};
// Receivers 1 and 3 of the floor lie behind the plane of the wall, receiver 2; of 3, two thirds lie past the wall's
// end in the image.
struct FloorPastTheWallsEnd {
  static constexpr bool kActive = true;
  PlaneSide side(std::uint32_t front, std::uint32_t back) const {
    return front == 2 && (back == 1 || back == 3) ? PlaneSide::kBehind : PlaneSide::kNotBehind;
  }
  double cell_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>) const { return 1.0; }
  double hidden_part(std::uint32_t back, std::span<const std::uint32_t>, std::span<const std::uint32_t>,
                     std::span<const CoverageEntry>) const {
    return back == 3 ? 1.0 / 3.0 : 1.0;
  }
};

TEST(FormfactorCoverageList, APlaneOrderPutsTheFloorBehindAWallAfterIt) {
  const std::vector<CoverageEntry> list = {{1.0, 0.4, 0, 0, 0.2f}, {1.0, 0.6, 1, 0, 0.2f}, {1.05, 0.6, 2, 1, 0.0f}};
  std::vector<double> plain(3, -1.0), ordered(3, -1.0);
  CoverageWalk().walk(list, [&](std::uint32_t r, double v) { plain[r] = v; });
  EXPECT_EQ(plain, (std::vector<double>{0.4, 0.6, 0.0}));
  CoverageWalk walk;
  walk.walk(list, [&](std::uint32_t r, double v) { ordered[r] = v; }, FloorBehindTheWall{});
  EXPECT_DOUBLE_EQ(ordered[0], 0.4);
  EXPECT_DOUBLE_EQ(ordered[2], 0.6);
  EXPECT_DOUBLE_EQ(ordered[1], 0.0);
  EXPECT_DOUBLE_EQ(walk.covered(), 1.0);
  // With an empty corner of 0.3 beside the wall (the wall's end in the pixel), the floor behind takes what is left:
  // the layer gives out the whole pixel.
  const std::vector<CoverageEntry> end = {{1.0, 0.4, 0, 0, 0.2f}, {1.0, 0.6, 1, 0, 0.2f}, {1.05, 0.3, 2, 1, 0.0f}};
  CoverageWalk end_walk;
  end_walk.walk(end, [&](std::uint32_t r, double v) { ordered[r] = v; }, FloorBehindTheWall{});
  EXPECT_DOUBLE_EQ(ordered[1], 0.3);
  EXPECT_DOUBLE_EQ(end_walk.covered(), 1.0);
  // Two faces meeting at a convex edge each lie behind the other's plane: neither hides the other, and they lie
  // side by side (here the first two fill the pixel, as in the recurrence).
  CoverageWalk().walk(list, [&](std::uint32_t r, double v) { ordered[r] = v; }, EachBehindTheOther{});
  EXPECT_EQ(ordered, plain);
}

struct NeitherBehind {  // a wall and a ceiling meeting at the room's inner corner
  static constexpr bool kActive = true;
  PlaneSide side(std::uint32_t, std::uint32_t) const { return PlaneSide::kNotBehind; }
  double cell_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>) const { return 1.0; }
  double hidden_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>,
                     std::span<const CoverageEntry>) const {
    return 1.0;
  }
};

// A wall and a ceiling tile meeting in a pixel of a side face's bottom row, seen at grazing incidence from a lamp just
// under the ceiling; the tile's corner, written with 6 digits, lies a little above the wall's long edge, so their
// coverages add up to 1.00012, over the slack (such a pixel at N = 300 had 0.5914 and 0.4087, adding up to 1.000107).
// The recurrence gave the tile 0.4 x 0.40012 of the pixel and lost the rest of it to the hemicube's sky. Told that neither lies behind the
// other's plane (nor, at a convex edge, each behind the other's), the walk puts them side by side: the pixel is
// covered, the tile gets what the wall leaves.
TEST(FormfactorCoverageList, SurfacesHidingNeitherLieSideBySideWhenRoundingOverfillsTheirLayer) {
  const std::vector<CoverageEntry> list = {{1.50, 0.6, 0, 0, 0.01f}, {1.51, 0.40012, 1, 1, 2.7f}};
  std::vector<double> got(2, -1.0);
  CoverageWalk plain;
  plain.walk(list, [&](std::uint32_t r, double v) { got[r] = v; });
  EXPECT_DOUBLE_EQ(got[0], 0.6);
  EXPECT_DOUBLE_EQ(got[1], 0.40012 * 0.4);
  EXPECT_LT(plain.covered(), 0.77);
  for (const bool convex : {false, true}) {
    CoverageWalk walk;
    const auto emit = [&](std::uint32_t r, double v) { got[r] = v; };
    if (convex) {
      walk.walk(list, emit, EachBehindTheOther{});
    } else {
      walk.walk(list, emit, NeitherBehind{});
    }
    EXPECT_DOUBLE_EQ(got[0], 0.6);
    EXPECT_DOUBLE_EQ(got[1], 0.4);
    EXPECT_DOUBLE_EQ(walk.covered(), 1.0);
  }
}

// The wall's end in the pixel: of the floor behind the wall's plane, the part the wall does not cover in the image
// lies side by side with the wall and the floor in front; the part it covers gets what they leave, here nothing.
// Taken together in a later round, the two pieces behind shared what the wall left, 0.15 each: the piece hidden
// behind the wall got light, and the piece past its end too little.
TEST(FormfactorCoverageList, AFloorPiecePastTheWallsEndLiesBesideIt) {
  const std::vector<CoverageEntry> list = {
      {1.0, 0.4, 0, 0, 0.2f}, {1.0, 0.15, 1, 0, 0.2f}, {1.0, 0.45, 3, 0, 0.2f}, {1.05, 0.3, 2, 1, 0.0f}};
  std::vector<double> got(4, 0.0);
  CoverageWalk walk;
  walk.walk(list, [&](std::uint32_t r, double v) { got[r] += v; }, FloorPastTheWallsEnd{});
  EXPECT_DOUBLE_EQ(got[0], 0.4);
  EXPECT_DOUBLE_EQ(got[1], 0.0);
  EXPECT_DOUBLE_EQ(got[2], 0.3);
  EXPECT_DOUBLE_EQ(got[3], 0.3);
  EXPECT_DOUBLE_EQ(walk.covered(), 1.0);
}

// A floor piece across the wall's plane (receiver 1: two thirds of it behind the plane, hidden by the wall, one
// third in front) gets what its two parts would get as pieces of their own, cut at the plane (receivers 3 in front
// and 4 behind): the walk cuts it by Order::cell_part. Taken whole, it was not behind the wall's plane, and the
// walk by planes left the pixel to the recurrence (the wall's foot then got nothing), while its pieces were ordered.
struct FloorAcrossTheWallsPlane {
  static constexpr bool kActive = true;
  PlaneSide side(std::uint32_t front, std::uint32_t back) const {
    if (front != 2) return PlaneSide::kNotBehind;
    return back == 1 ? PlaneSide::kAcross : back == 4 ? PlaneSide::kBehind : PlaneSide::kNotBehind;
  }
  double cell_part(std::uint32_t back, std::span<const std::uint32_t> behind, std::span<const std::uint32_t>) const {
    EXPECT_EQ(back, 1u);
    return behind.empty() ? 1.0 / 3.0 : 2.0 / 3.0;
  }
  double hidden_part(std::uint32_t back, std::span<const std::uint32_t> behind, std::span<const std::uint32_t>,
                     std::span<const CoverageEntry>) const {
    return back == 1 && !behind.empty() ? 2.0 / 3.0 : 1.0;  // of receiver 1, its part behind is all hidden
  }
};

TEST(FormfactorCoverageList, AFloorPieceAcrossTheWallsPlaneIsCutThere) {
  const std::vector<CoverageEntry> across = {{1.0, 0.4, 0, 0, 0.2f}, {1.0, 0.6, 1, 0, 0.2f}, {1.05, 0.4, 2, 1, 0.0f}};
  const std::vector<CoverageEntry> cut = {
      {1.0, 0.4, 0, 0, 0.2f}, {1.0, 0.2, 3, 0, 0.2f}, {1.0, 0.4, 4, 0, 0.2f}, {1.05, 0.4, 2, 1, 0.0f}};
  std::vector<double> whole(5, 0.0), pieces(5, 0.0);
  CoverageWalk walk, cut_walk;
  walk.walk(across, [&](std::uint32_t r, double v) { whole[r] += v; }, FloorAcrossTheWallsPlane{});
  cut_walk.walk(cut, [&](std::uint32_t r, double v) { pieces[r] += v; }, FloorAcrossTheWallsPlane{});
  EXPECT_DOUBLE_EQ(pieces[0], 0.4);
  EXPECT_DOUBLE_EQ(pieces[3], 0.2);
  EXPECT_DOUBLE_EQ(pieces[4], 0.0);
  EXPECT_DOUBLE_EQ(pieces[2], 0.4);
  EXPECT_DOUBLE_EQ(whole[0], pieces[0]);
  EXPECT_DOUBLE_EQ(whole[1], pieces[3] + pieces[4]);
  EXPECT_DOUBLE_EQ(whole[2], pieces[2]);
  EXPECT_DOUBLE_EQ(walk.covered(), 1.0);
}

// A wall whose one leaf covers the pixel (a full entry, kept inline) stands on the floor: the floor in front of it
// (receiver 0) and behind it (1) share one key, in front of the wall's. The full entry is walked among the entries
// whose ranges reach its own, as the wall's pieces would be (receivers 2 and 3, covering the pixel together): the
// floor in front and the wall's foot share the pixel, the floor behind gets nothing. Walked behind the list, the
// wall got nothing and the floor behind the rest of the pixel.
struct FloorBehindTheWallsPieces {
  static constexpr bool kActive = true;
  PlaneSide side(std::uint32_t front, std::uint32_t back) const {
    return (front == 2 || front == 3) && back == 1 ? PlaneSide::kBehind : PlaneSide::kNotBehind;
  }
  double cell_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>) const { return 1.0; }
  double hidden_part(std::uint32_t, std::span<const std::uint32_t>, std::span<const std::uint32_t>,
                     std::span<const CoverageEntry>) const {
    return 1.0;
  }
  FloorBehindTheWallsPieces at(std::size_t) const { return *this; }
};

TEST(FormfactorCoverageList, AFullEntryIsWalkedAsItsPiecesWouldBe) {
  const CoverageEntry front{1.0, 0.4, 0, 0, 0.2f}, behind{1.0, 0.6, 1, 0, 0.2f};
  std::vector<double> whole(4, 0.0), pieces(4, 0.0);
  CoverageArena arena;
  arena.reset(1);
  EXPECT_TRUE(arena.insert(0, {1.05, 1.0, 2, 1, 0.1f}));  // the wall's leaf, covering the pixel
  EXPECT_TRUE(arena.insert(0, front));
  EXPECT_TRUE(arena.insert(0, behind));
  arena.take_all([&](std::size_t, std::uint32_t r, double v) { whole[r] += v; }, FloorBehindTheWallsPieces{});
  arena.reset(1);
  EXPECT_TRUE(arena.insert(0, {1.05, 0.5, 2, 1, 0.1f}));  // the wall's leaf in two pieces
  EXPECT_TRUE(arena.insert(0, {1.05, 0.5, 3, 1, 0.1f}));
  EXPECT_TRUE(arena.insert(0, front));
  EXPECT_TRUE(arena.insert(0, behind));
  arena.take_all([&](std::size_t, std::uint32_t r, double v) { pieces[r] += v; }, FloorBehindTheWallsPieces{});
  EXPECT_DOUBLE_EQ(pieces[0], 0.4);
  EXPECT_DOUBLE_EQ(pieces[1], 0.0);
  EXPECT_DOUBLE_EQ(pieces[2] + pieces[3], 0.6);
  EXPECT_DOUBLE_EQ(whole[0], pieces[0]);
  EXPECT_DOUBLE_EQ(whole[1], pieces[1]);
  EXPECT_DOUBLE_EQ(whole[2], pieces[2] + pieces[3]);
  // A floor entry wholly behind the full entry's range is refused, as behind a covering group.
  arena.reset(1);
  EXPECT_TRUE(arena.insert(0, {1.05, 1.0, 2, 1, 0.1f}));
  EXPECT_FALSE(arena.insert(0, {1.5, 0.5, 4, 2, 0.1f}));
}

// The floor's pieces cover the pixel, yet the wall standing on it keeps its entry: its depth range reaches into the
// floor's, so it may lie in front of the floor's part behind it. A surface whose range lies wholly behind the floor's
// is still refused, and so is a surface in the floor's plane.
TEST(FormfactorCoverageList, AFullGroupKeepsTheEntriesWhoseRangeReachesIntoItsOwn) {
  for (const bool wall_first : {false, true}) {
    CoverageArena arena;
    arena.reset(1);
    const CoverageEntry wall{1.05, 0.6, 2, 1, 0.0f};
    if (wall_first) {
      EXPECT_TRUE(arena.insert(0, wall));
    }
    EXPECT_TRUE(arena.insert(0, {1.0, 0.4, 0, 0, 0.2f}));
    EXPECT_TRUE(arena.insert(0, {1.0, 0.6, 1, 0, 0.2f}));
    EXPECT_TRUE(arena.full(0));
    if (!wall_first) {
      EXPECT_TRUE(arena.insert(0, wall));
    }
    EXPECT_FALSE(arena.insert(0, {1.5, 0.5, 3, 2, 0.1f}));  // wholly behind the floor
    EXPECT_FALSE(arena.insert(0, {1.0, 0.5, 4, 3, 0.2f}));  // a rug in the floor's plane
    std::vector<CoverageEntry> kept;
    arena.for_each(0, [&](const CoverageEntry& e) { kept.push_back(e); });
    ASSERT_EQ(kept.size(), 3u) << (wall_first ? "wall first" : "wall last");
    EXPECT_EQ(kept[2].receiver, 2u);
  }
}

TEST(FormfactorCoverageList, FullEntryTakesItsPlaceByDepth) {
  CoverageArena arena;
  arena.reset(2);
  EXPECT_TRUE(arena.insert(1, {1.0, 0.25, 0, 0}));
  EXPECT_TRUE(arena.insert(1, {3.0, 0.5, 1, 1}));
  EXPECT_TRUE(arena.insert(1, {2.0, 1.0, 2, 2}));   // covers the pixel between the two
  EXPECT_TRUE(arena.full(1));
  EXPECT_FALSE(arena.insert(1, {2.5, 0.5, 3, 3}));  // behind it
  EXPECT_FALSE(arena.insert(1, {4.0, 1.0, 4, 4}));  // a farther full entry
  std::vector<double> e(5, -1.0);
  const double f = arena.resolve(1, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_EQ(e, (std::vector<double>{0.25, -1.0, 0.75, -1.0, -1.0}));
  EXPECT_DOUBLE_EQ(f, 1.0);
  std::vector<double> taken(5, -1.0);
  arena.take_all([&](std::size_t pixel, std::uint32_t r, double v) {
    EXPECT_EQ(pixel, 1u);
    taken[r] = v;
  });
  EXPECT_EQ(taken, e);
  EXPECT_TRUE(arena.empty(1));  // taken
  // Through the same walk as a sorted synthetic list.
  const std::vector<CoverageEntry> sorted = {{1.0, 0.25, 0, 0}, {2.0, 1.0, 2, 2}, {3.0, 0.5, 1, 1}};
  std::vector<double> s(3, -1.0);
  resolve_front_to_back(sorted, [&](std::uint32_t r, double v) { s[r] = v; });
  EXPECT_EQ(s, (std::vector<double>{0.25, 0.0, 0.75}));
  EXPECT_EQ(arena.entries(), 5u);
}

TEST(FormfactorCoverageList, FullPixelTakesNothingBehind) {
  CoverageArena arena;
  arena.reset(1);
  EXPECT_TRUE(arena.insert(0, {3.0, 0.5, 0, 1}));   // a surface behind
  EXPECT_TRUE(arena.insert(0, {2.0, 0.6, 1, 2}));   // piece of surface 2
  EXPECT_FALSE(arena.full(0));
  EXPECT_TRUE(arena.insert(0, {2.0, 0.4, 2, 2}));   // surface 2 now covers the pixel: drops surface 1
  EXPECT_TRUE(arena.full(0));
  EXPECT_FALSE(arena.insert(0, {4.0, 0.9, 3, 3}));  // behind the full surface: refused
  EXPECT_TRUE(arena.insert(0, {2.0, 1e-14, 4, 2})); // a crumb of the full surface itself joins it
  EXPECT_TRUE(arena.insert(0, {1.0, 0.25, 5, 4}));  // in front: accepted, the pixel stays full
  EXPECT_TRUE(arena.full(0));
  std::vector<double> e(6, -1.0);
  const double f = arena.resolve(0, [&](std::uint32_t r, double v) { e[r] = v; });
  EXPECT_DOUBLE_EQ(e[5], 0.25);
  EXPECT_DOUBLE_EQ(e[1], 0.6 * 0.75);
  EXPECT_DOUBLE_EQ(e[2], 0.4 * 0.75);
  EXPECT_EQ(e[0], -1.0);  // dropped
  EXPECT_EQ(e[3], -1.0);  // refused
  EXPECT_LE(f, 1.0);
  EXPECT_NEAR(f, 1.0, 1e-15);
  // A full entry (one receiver covering the pixel) in front hides the list behind it; partial entries behind
  // it are refused.
  EXPECT_TRUE(arena.insert(0, {0.5, 1.0, 6, 8}));
  EXPECT_FALSE(arena.insert(0, {0.7, 0.3, 7, 9}));
  std::vector<double> hidden(8, -1.0);
  EXPECT_DOUBLE_EQ(arena.resolve(0, [&](std::uint32_t r, double v) { hidden[r] = v; }), 1.0);
  EXPECT_DOUBLE_EQ(hidden[6], 1.0);
  EXPECT_EQ(hidden[5], -1.0);
  EXPECT_EQ(hidden[7], -1.0);
  // Resetting keeps the pool but empties the lists.
  arena.reset(1);
  EXPECT_TRUE(arena.empty(0));
  EXPECT_FALSE(arena.full(0));
}

}  // namespace
}  // namespace aarad::formfactor
