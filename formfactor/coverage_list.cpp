// Per-pixel coverage lists of the anti-aliased hemicube (Chandran, Kiran, Phani and Rai, section 3.2.1):
// insertion sort into pooled linked lists. See coverage_list.h for the rules.
#include "formfactor/coverage_list.h"

namespace aarad::formfactor {

void CoverageArena::reset(std::size_t pixels) {
  heads_.assign(pixels, Head{});
  nodes_.clear();
}

std::uint32_t CoverageArena::allocate(const CoverageEntry& entry, std::uint32_t next) {
  nodes_.push_back(Node{entry.depth, entry.coverage, entry.receiver, entry.surface, next});
  return static_cast<std::uint32_t>(nodes_.size() - 1);
}

bool CoverageArena::insert(std::size_t pixel, const CoverageEntry& entry) {
  std::uint32_t prev = kNil, cur = heads_[pixel].head, before = kNil;
  std::uint32_t prev_surface = kNoSurface;
  bool placed = false;
  while (cur != kNil) {
    const Node& node = nodes_[cur];
    if (node.surface == entry.surface) {
      // Join the group of this surface: append after its last node.
      double sum = entry.coverage;
      std::uint32_t last = cur;
      for (std::uint32_t m = cur; m != kNil && nodes_[m].surface == entry.surface; m = nodes_[m].next) {
        sum += nodes_[m].coverage;
        last = m;
      }
      const std::uint32_t added = allocate(entry, nodes_[last].next);
      nodes_[last].next = added;
      if (sum >= kFullCoverage) {
        nodes_[added].next = kNil;  // everything behind a covering group is hidden
        heads_[pixel].full = 1;
      }
      return true;
    }
    // Depth order is decided at group heads only, so groups stay contiguous.
    if (!placed && node.surface != prev_surface && node.depth > entry.depth) {
      placed = true;
      before = prev;
    }
    prev_surface = node.surface;
    prev = cur;
    cur = node.next;
  }
  if (!placed) {
    if (heads_[pixel].full != 0) return false;  // behind the covering group
    before = prev;
  }
  const std::uint32_t next = before == kNil ? heads_[pixel].head : nodes_[before].next;
  const std::uint32_t added = allocate(entry, next);
  if (before == kNil) {
    heads_[pixel].head = added;
  } else {
    nodes_[before].next = added;
  }
  if (entry.coverage >= kFullCoverage) {
    nodes_[added].next = kNil;
    heads_[pixel].full = 1;
  }
  return true;
}

}  // namespace aarad::formfactor
