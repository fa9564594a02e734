// Edge-neighbours of every receiver of a ReceiverCache, as receiver indices (the adjacency the gradient test of
// adaptive substructuring reads; Cohen, Greenberg, Immel and Brock 1986). Rebuilt when the cache changes, and then
// only in part: leaves only split, so a leaf that was in the previous table has the same edge-neighbours unless
// one of them was split since (a split is the only thing that changes a face loop outside the split face, and
// only the loop of the face across the split edge, which is a neighbour). Such a leaf's list is copied and
// renumbered; new leaves and leaves next to a split are asked of the hierarchy.
#pragma once

#include "aarad/mesh/hierarchy.h"
#include "aarad/refine/receiver_cache.h"

#include <cstdint>
#include <span>
#include <vector>

namespace aarad::refine {

class NeighbourTable {
 public:
  // Brings the table up to date with `cache`, which must be up to date with `hierarchy`.
  void update(const mesh::Hierarchy& hierarchy, const ReceiverCache& cache);

  // The edge-neighbours of receiver i (Hierarchy::edge_neighbours of its leaf, as receiver indices, in order).
  std::span<const std::uint32_t> of(std::size_t i) const {
    return {neighbours_.data() + offsets_[i], neighbours_.data() + offsets_[i + 1]};
  }
  // How many lists the updates so far copied instead of asking the hierarchy (for tests).
  std::uint64_t copied_lists() const { return copied_lists_; }

 private:
  std::vector<std::uint32_t> offsets_{0}, neighbours_;  // CSR by receiver
  std::vector<mesh::NodeId> leaves_;                    // the leaves the table is for, by receiver
  std::uint64_t revision_ = ~std::uint64_t{0};
  const mesh::Hierarchy::Impl* source_ = nullptr;
  std::vector<std::uint32_t> next_offsets_, next_neighbours_;
  std::vector<mesh::NodeId> around_;
  std::uint64_t copied_lists_ = 0;
};

}  // namespace aarad::refine
