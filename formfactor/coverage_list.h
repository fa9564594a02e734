// The per-pixel coverage lists of the anti-aliased hemicube: Chandran, Kiran, Phani and Rai, "Anti-aliased
// hemicubes for radiosity", section 3.2.1.
//
// Every pixel keeps the receivers that cover part of it, sorted front to back on insertion (insertion sort, as
// the paper does). Walking a list front to back, receiver k gets the visible fraction
//     E_k = A_k (1 - f_{k-1}),   f_k = f_{k-1} + E_k,   f_{-1} = 0,
// where A_k is the fraction of the pixel's area the receiver covers. Pieces of one physical surface never
// occlude one another (the paper's identical-z exception): consecutive entries of one surface form a group and
// all use the f in front of the group; f grows by the group's total after it.
//
// A full pixel. A group whose coverages add up to 1 (within kFullCoverage) hides everything behind it: the
// walk gives E = A (1 - 1) = 0 there. The arena then drops the entries behind that group and refuses new
// entries that would go behind it, so a covered pixel stops growing (the paper: "when the entire pixel area is
// consumed, no items are inserted"). Two kinds of entries are still accepted by a full pixel: entries in front
// of the full group (they occlude part of it; it stays full, since the group's own sum does not change), and
// entries of the full group's own surface, which join the group (for a surface tiled by its pieces they are
// rounding crumbs; the walk caps the group so that f never exceeds 1). Fullness is decided from a group's own
// coverage sum, not from f, because the product form of f only reaches 1 through a single full group.
//
// Memory: one pooled arena per face (nodes with next indices, per-pixel heads), reset per face without
// freeing; no heap allocation per entry once the pool has grown to the largest face seen.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace aarad::formfactor {

inline constexpr std::uint32_t kNoSurface = 0xFFFFFFFFu;
// A group whose coverage sum reaches this hides what lies behind it.
inline constexpr double kFullCoverage = 1.0 - 1e-12;

struct CoverageEntry {
  double depth = 0.0;     // any key that grows with the distance along the pixel's ray; smaller is nearer
  double coverage = 0.0;  // A: fraction of the pixel's area covered by the receiver, in [0, 1]
  std::uint32_t receiver = 0;
  std::uint32_t surface = 0;  // physical-surface id: entries of one surface do not occlude each other
};

// The front-to-back recurrence of section 3.2.1 with the same-surface rule, one entry at a time.
class CoverageWalk {
 public:
  // The visible fraction E of the next entry (front to back) of `surface` with coverage A.
  double visible(std::uint32_t surface, double coverage) {
    if (surface != surface_) {
      surface_ = surface;
      in_front_ = covered_;
    }
    double e = coverage * (1.0 - in_front_);
    // Pieces of one surface that overlap (rounding crumbs, or bad input) cannot cover more than the pixel.
    e = std::min(e, 1.0 - covered_);
    if (e < 0.0) e = 0.0;
    covered_ += e;
    return e;
  }
  // f after the entries walked so far.
  double covered() const { return covered_; }

 private:
  double covered_ = 0.0;
  double in_front_ = 0.0;
  std::uint32_t surface_ = kNoSurface;
};

// Walks a list already sorted front to back, calling emit(receiver, E) for every entry; returns the final f.
// Entries of one surface must be consecutive (the arena keeps them so).
template <class Emit>
double resolve_front_to_back(std::span<const CoverageEntry> front_to_back, Emit&& emit) {
  CoverageWalk walk;
  for (const CoverageEntry& e : front_to_back) emit(e.receiver, walk.visible(e.surface, e.coverage));
  return walk.covered();
}

// Per-pixel sorted lists in one pooled arena.
//
// Layout. An entry that covers its whole pixel (A >= kFullCoverage: the interior pixels of a receiver, most of
// the entries at high resolution) hides everything behind it, so only the nearest one matters: every pixel keeps
// it inline, as a z-buffer would (16-byte slot: depth, receiver, list head). Partially covering entries go into
// the pixel's sorted list: nodes of one pool with next indices. The walk merges the two: the inline entry takes
// its place by depth, and everything behind it gets E = 0. A partial entry behind the inline one is refused at
// insertion; list entries that a nearer full entry hides later are skipped by the walk. Slots are cleared as
// take() reads them, so starting a face costs nothing.
class CoverageArena {
 public:
  // Makes room for `pixels` pixels; every list must be empty (all taken) or the slots are cleared.
  void reset(std::size_t pixels);

  // Inserts an entry into the list of `pixel` at its depth (behind entries at the same depth), or into the
  // group of its surface when the list has one. Returns false when the pixel is full in front of it.
  bool insert(std::size_t pixel, const CoverageEntry& entry) {
    Slot& slot = slots_[pixel];
    if (entry.coverage >= kFullCoverage) {
      if (slot.receiver == kNone && slot.head == kNil) ++live_;
      ++entries_;
      if (!(entry.depth < slot.depth)) return false;  // behind the inline entry
      slot.depth = entry.depth;
      slot.receiver = entry.receiver;
      return true;
    }
    return insert_partial(slot, entry);
  }

  // Walks the list of `pixel` front to back, calling emit(receiver, E); returns the final f.
  template <class Emit>
  double resolve(std::size_t pixel, Emit&& emit) const {
    const Slot& slot = slots_[pixel];
    CoverageWalk walk;
    std::uint32_t prev_surface = kNoSurface;
    for (std::uint32_t n = slot.head & kIndexMask; n != kNil; n = nodes_[n].next) {
      const Node& node = nodes_[n];
      if (node.surface != prev_surface && !(node.depth < slot.depth)) break;  // a group behind the full entry
      prev_surface = node.surface;
      emit(node.receiver, walk.visible(node.surface, node.coverage));
    }
    if (slot.receiver != kNone) emit(slot.receiver, walk.visible(kNoSurface, 1.0));
    return walk.covered();
  }

  // resolve(), then empties the pixel.
  template <class Emit>
  double take(std::size_t pixel, Emit&& emit) {
    Slot& slot = slots_[pixel];
    if (slot.receiver == kNone && slot.head == kNil) return 0.0;
    const double f = resolve(pixel, emit);
    slot = Slot{};
    --live_;
    return f;
  }

  // Calls visit(const CoverageEntry&) for the entries of `pixel` that the walk reaches, front to back (the
  // inline full entry with surface kNoSurface).
  template <class Visit>
  void for_each(std::size_t pixel, Visit&& visit) const {
    resolve_entries(pixel, visit);
  }

  // Hints the memory of the list of `pixel` into the cache (a walk in pixel order reads pool nodes that were
  // allocated in receiver order).
  void prefetch(std::size_t pixel) const {
    if (pixel >= slots_.size()) return;
    const std::uint32_t n = slots_[pixel].head & kIndexMask;
    if (n != kNil) __builtin_prefetch(&nodes_[n]);
  }

  bool empty(std::size_t pixel) const { return slots_[pixel].receiver == kNone && slots_[pixel].head == kNil; }
  // Whether the pixel is covered: by a full entry, or by a group of the list.
  bool full(std::size_t pixel) const {
    return slots_[pixel].receiver != kNone || (slots_[pixel].head & kFullBit) != 0;
  }
  // Entries offered since the last reset (accepted or not).
  std::size_t entries() const { return entries_; }

 private:
  static constexpr std::uint32_t kNil = 0x7FFFFFFFu;
  static constexpr std::uint32_t kFullBit = 0x80000000u;  // in Slot::head: the list's last group covers
  static constexpr std::uint32_t kIndexMask = 0x7FFFFFFFu;
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  struct Slot {
    double depth = std::numeric_limits<double>::infinity();  // of the nearest full entry
    std::uint32_t receiver = kNone;                           // the nearest full entry
    std::uint32_t head = kNil;                                // partial list, plus kFullBit
  };
  struct Node {
    double depth;
    double coverage;
    std::uint32_t receiver;
    std::uint32_t surface;
    std::uint32_t next;
  };
  bool insert_partial(Slot& slot, const CoverageEntry& entry);
  template <class Visit>
  void resolve_entries(std::size_t pixel, Visit& visit) const {
    const Slot& slot = slots_[pixel];
    std::uint32_t prev_surface = kNoSurface;
    for (std::uint32_t n = slot.head & kIndexMask; n != kNil; n = nodes_[n].next) {
      const Node& node = nodes_[n];
      if (node.surface != prev_surface && !(node.depth < slot.depth)) break;
      prev_surface = node.surface;
      visit(CoverageEntry{node.depth, node.coverage, node.receiver, node.surface});
    }
    if (slot.receiver != kNone) visit(CoverageEntry{slot.depth, 1.0, slot.receiver, kNoSurface});
  }

  std::vector<Slot> slots_;
  std::vector<Node> nodes_;
  std::size_t live_ = 0;  // pixels not empty
  std::size_t entries_ = 0;
};

}  // namespace aarad::formfactor
