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
#include <span>
#include <vector>

namespace aarad::formfactor {

inline constexpr std::uint32_t kNoSurface = 0xFFFFFFFFu;
// A group whose coverage sum reaches this hides what lies behind it.
inline constexpr double kFullCoverage = 1.0 - 1e-12;

struct CoverageEntry {
  double depth = 0.0;     // distance along the pixel's ray (axis coordinate); smaller is nearer
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
class CoverageArena {
 public:
  // Empties every list and sizes the arena for `pixels` pixels; keeps the pool's memory.
  void reset(std::size_t pixels);

  // Inserts an entry into the list of `pixel` at its depth (behind entries at the same depth), or into the
  // group of its surface when the list has one. Returns false when the pixel is full in front of it.
  bool insert(std::size_t pixel, const CoverageEntry& entry);

  // Walks the list of `pixel` front to back, calling emit(receiver, E); returns the final f.
  template <class Emit>
  double resolve(std::size_t pixel, Emit&& emit) const {
    CoverageWalk walk;
    for (std::uint32_t n = heads_[pixel].head; n != kNil; n = nodes_[n].next) {
      const Node& node = nodes_[n];
      emit(node.receiver, walk.visible(node.surface, node.coverage));
    }
    return walk.covered();
  }

  // Calls visit(const CoverageEntry&) for the entries of `pixel`, front to back.
  template <class Visit>
  void for_each(std::size_t pixel, Visit&& visit) const {
    for (std::uint32_t n = heads_[pixel].head; n != kNil; n = nodes_[n].next) {
      const Node& node = nodes_[n];
      visit(CoverageEntry{node.depth, node.coverage, node.receiver, node.surface});
    }
  }

  bool full(std::size_t pixel) const { return heads_[pixel].full != 0; }
  std::size_t pixels() const { return heads_.size(); }
  // Nodes allocated since the last reset (including dropped ones).
  std::size_t nodes_used() const { return nodes_.size(); }
  bool empty(std::size_t pixel) const { return heads_[pixel].head == kNil; }

 private:
  static constexpr std::uint32_t kNil = 0xFFFFFFFFu;
  struct Node {
    double depth;
    double coverage;
    std::uint32_t receiver;
    std::uint32_t surface;
    std::uint32_t next;
  };
  struct Head {
    std::uint32_t head = kNil;
    std::uint32_t full = 0;  // 1 when the last group of the list covers the pixel
  };
  std::uint32_t allocate(const CoverageEntry& entry, std::uint32_t next);

  std::vector<Head> heads_;
  std::vector<Node> nodes_;
};

}  // namespace aarad::formfactor
