// Receiver view of the leaf elements (design.md: formfactor/ sees plain polygons, never the mesh).
#include "refine/receiver_cache.h"

#include <utility>

namespace aarad::refine {

bool ReceiverCache::update(const mesh::Hierarchy& hierarchy) {
  if (built_ && &hierarchy.impl() == source_ && hierarchy.revision() == revision_) return false;
  std::vector<mesh::NodeId> leaves = hierarchy.leaves();
  if (built_ && update_after_splits(hierarchy, leaves)) {
    std::swap(view_, next_);
    ++incremental_rebuilds_;
  } else {
    view_.clear();
    view_.reserve(leaves.size(), leaves.size() * 4);
    for (mesh::NodeId leaf : leaves) add_leaf(view_, hierarchy, leaf);
  }
  leaves_ = std::move(leaves);
  receiver_of_node_.assign(hierarchy.node_count(), kNoReceiver);
  for (std::size_t i = 0; i < leaves_.size(); ++i) receiver_of_node_[leaves_[i]] = static_cast<std::uint32_t>(i);
  source_ = &hierarchy.impl();
  node_count_ = hierarchy.node_count();
  revision_ = hierarchy.revision();
  built_ = true;
  ++rebuilds_;
  return true;
}

void ReceiverCache::add_leaf(formfactor::ReceiverView& view, const mesh::Hierarchy& hierarchy, mesh::NodeId leaf) {
  hierarchy.corners(leaf, corners_);
  // Corners keyed by their mesh vertex, so that the back ends transform a shared vertex once per shot.
  const std::array<std::uint32_t, 4> keys = hierarchy.corner_vertices(leaf);
  view.add(corners_, std::span<const std::uint32_t>(keys.data(), corners_.size()), hierarchy.plane(leaf),
           hierarchy.surface(leaf), hierarchy.patch(leaf));
}

bool ReceiverCache::update_after_splits(const mesh::Hierarchy& hierarchy, const std::vector<mesh::NodeId>& leaves) {
  if (&hierarchy.impl() != source_ || hierarchy.node_count() < node_count_) return false;
  // Every leaf among the old nodes must have been a leaf before (a split only turns leaves into inner nodes), and
  // those come first, in the old order.
  std::size_t kept = 0;
  while (kept < leaves.size() && leaves[kept] < node_count_) {
    if (receiver_of_node_[leaves[kept]] == kNoReceiver) return false;
    ++kept;
  }
  next_.start_from_points_of(view_);
  next_.reserve(leaves.size(), leaves.size() * 4);
  // Old receivers in runs of consecutive indices.
  std::size_t i = 0;
  while (i < kept) {
    const std::uint32_t first = receiver_of_node_[leaves[i]];
    std::uint32_t last = first + 1;
    for (++i; i < kept && receiver_of_node_[leaves[i]] == last; ++i) ++last;
    next_.append_from(view_, first, last);
  }
  for (; i < leaves.size(); ++i) add_leaf(next_, hierarchy, leaves[i]);
  return true;
}

}  // namespace aarad::refine
