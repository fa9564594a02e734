// The staged coverage arena of the AA hemicube (formfactor/coverage_list.h) builds, block by block, the same
// per-pixel lists as the immediate CoverageArena (Chandran, Kiran, Phani and Rai, section 3.2.1: lists sorted on
// insertion, same-surface groups, layers of overlapping depth ranges, full pixels): the same entries in the same
// order give the same walk, value for value, whatever the number of column blocks. The staged arena emits the
// pixels whose entries all belong to one surface before the others of their block, so its output is compared
// after a stable sort by pixel: each pixel's entries in the same order with the same values.
#include "aarad/formfactor/coverage_list.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <vector>

namespace aarad::formfactor {
namespace {

using Emitted = std::vector<std::tuple<std::size_t, std::uint32_t, double>>;

TEST(FormfactorCoverageList, StagedArenaWalksLikeTheImmediateArena) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  // 300 x 200 pixels: blocks of 64 columns (12 800 pixels), five blocks; 100 x 100 and 40 x 30: one block, where
  // pixels of one surface skip their lists. Most pixels of 100 x 100 get one or two entries, so many are of one
  // surface; a pixel of 40 x 30 gets about 17 entries of six surfaces, so hardly any.
  struct Case {
    int width, height;
    bool one_surface_pixels;
  };
  for (const auto& [width, height, one_surface_pixels] : {Case{300, 200, false}, Case{100, 100, true}, Case{40, 30, false}}) {
    CoverageArena immediate;
    StagedCoverageArena staged;
    for (int round = 0; round < 2; ++round) {  // twice: the arenas must come back empty after take_all
      immediate.reset(static_cast<std::size_t>(width) * height);
      staged.reset(width, height);
      staged.describe_receivers(20000);
      for (std::uint32_t r = 0; r < 20000; ++r) {
        const int x = static_cast<int>(u(rng) * width), y = static_cast<int>(u(rng) * height);
        // Few pixels per receiver overlap at low resolution; draw depths from a few planes so ties occur.
        const double depth = std::floor(u(rng) * 8.0) + (u(rng) < 0.5 ? 0.0 : 0.5);
        const double coverage = u(rng) < 0.4 ? 1.0 : (u(rng) < 0.5 ? 0.5 : u(rng));
        // Half the entries with a depth spread that reaches the neighbouring planes: layers in the walk.
        const float spread = u(rng) < 0.5 ? 0.0f : 0.3f;
        const CoverageEntry entry{depth, coverage, r, static_cast<std::uint32_t>(u(rng) * 6), spread};
        staged.describe(r, spread, entry.surface);  // a receiver's spread and surface (here one entry each)
        immediate.insert(static_cast<std::size_t>(x) * height + y, entry);
        staged.insert(x, y, entry);
      }
      Emitted a, b;
      immediate.take_all([&](std::size_t p, std::uint32_t r, double e) { a.emplace_back(p, r, e); });
      staged.take_all([&](std::size_t p, std::uint32_t r, double e) { b.emplace_back(p, r, e); });
      EXPECT_GT(a.size(), static_cast<std::size_t>(width) * height / 4);  // most pixels emit something
      // The pixels of one surface come first: the order differs, so that path ran.
      if (one_surface_pixels) {
        EXPECT_NE(a, b) << width << " x " << height;
      }
      std::stable_sort(b.begin(), b.end(), [](const auto& l, const auto& r) { return std::get<0>(l) < std::get<0>(r); });
      EXPECT_EQ(a, b) << width << " x " << height;
    }
  }
}

}  // namespace
}  // namespace aarad::formfactor
