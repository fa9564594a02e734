// Per-pixel coverage lists of the anti-aliased hemicube (Chandran, Kiran, Phani and Rai, section 3.2.1):
// insertion sort into pooled linked lists. See coverage_list.h for the rules and the layout.
#include "formfactor/coverage_list.h"

namespace aarad::formfactor {

void CoverageArena::reset(std::size_t pixels) {
  if (live_ != 0) std::fill(slots_.begin(), slots_.end(), Slot{});
  if (slots_.size() < pixels) slots_.resize(pixels);
  nodes_.clear();
  live_ = 0;
  entries_ = 0;
}

bool CoverageArena::insert_partial(Slot& slot, const CoverageEntry& entry) {
  ++entries_;
  if (!(entry.depth < slot.depth)) return false;  // behind the nearest full entry
  const bool was_empty = slot.receiver == kNone && slot.head == kNil;
  std::uint32_t prev = kNil, cur = slot.head & kIndexMask, before = kNil;
  std::uint32_t prev_surface = kNoSurface;
  bool placed = false;
  auto link = [&](std::uint32_t after) {
    const auto added = static_cast<std::uint32_t>(nodes_.size());
    const std::uint32_t next = after == kNil ? (slot.head & kIndexMask) : nodes_[after].next;
    nodes_.push_back(Node{entry.depth, entry.coverage, entry.receiver, entry.surface, next});
    if (after == kNil) {
      slot.head = (slot.head & kFullBit) | added;
    } else {
      nodes_[after].next = added;
    }
    return added;
  };
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
      const std::uint32_t added = link(last);
      if (sum >= kFullCoverage) {
        nodes_[added].next = kNil;  // everything behind a covering group is hidden
        slot.head |= kFullBit;
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
    if ((slot.head & kFullBit) != 0) return false;  // behind the covering group
    before = prev;
  }
  if (was_empty) ++live_;
  link(before);
  return true;
}

}  // namespace aarad::formfactor
