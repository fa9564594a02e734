// Edge-neighbour table of the receivers (see neighbour_table.h).
#include "aarad/refine/neighbour_table.h"

#include <utility>

namespace aarad::refine {

void NeighbourTable::update(const mesh::Hierarchy& hierarchy, const ReceiverCache& cache) {
  if (revision_ == cache.revision() && source_ == &hierarchy.impl()) return;
  const bool same_hierarchy = source_ == &hierarchy.impl();
  next_offsets_.assign(1, 0);
  next_neighbours_.clear();
  std::size_t old = 0;  // walks leaves_ alongside the cache's leaves: both are sorted by node id
  for (std::size_t i = 0; i < cache.size(); ++i) {
    const mesh::NodeId leaf = cache.leaf(i);
    while (same_hierarchy && old < leaves_.size() && leaves_[old] < leaf) ++old;
    bool copied = same_hierarchy && old < leaves_.size() && leaves_[old] == leaf;
    if (copied) {
      const std::size_t mark = next_neighbours_.size();
      for (std::uint32_t k = offsets_[old]; k < offsets_[old + 1]; ++k) {
        const std::uint32_t receiver = cache.receiver(leaves_[neighbours_[k]]);
        if (receiver == kNoReceiver) {  // that neighbour was split
          next_neighbours_.resize(mark);
          copied = false;
          break;
        }
        next_neighbours_.push_back(receiver);
      }
    }
    if (copied) {
      ++copied_lists_;
    } else {
      hierarchy.edge_neighbours(leaf, around_);
      for (mesh::NodeId neighbour : around_) next_neighbours_.push_back(cache.receiver(neighbour));
    }
    next_offsets_.push_back(static_cast<std::uint32_t>(next_neighbours_.size()));
  }
  std::swap(offsets_, next_offsets_);
  std::swap(neighbours_, next_neighbours_);
  leaves_.assign(cache.leaves().begin(), cache.leaves().end());
  revision_ = cache.revision();
  source_ = &hierarchy.impl();
}

}  // namespace aarad::refine
