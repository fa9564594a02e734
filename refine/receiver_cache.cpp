// Receiver view of the leaf elements (design.md: formfactor/ sees plain polygons, never the mesh).
#include "aarad/refine/receiver_cache.h"

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
  // The loop keyed by mesh vertex: the back ends transform a shared vertex once per shot, and the leaves on either
  // side of an edge project its hanging vertices to the same pixel coordinates.
  hierarchy.leaf_polygon(leaf, loop_, loop_vertices_);
  view.add(loop_, loop_vertices_, hierarchy.plane(leaf), hierarchy.surface(leaf), hierarchy.patch(leaf));
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
  // Old receivers in runs of consecutive indices; a leaf whose loop changed after the old view was built (a
  // neighbour's split gave it a hanging vertex) is read again in its place.
  const auto unchanged = [&](mesh::NodeId leaf) { return hierarchy.loop_revision(leaf) <= revision_; };
  std::size_t i = 0;
  while (i < kept) {
    if (!unchanged(leaves[i])) {
      add_leaf(next_, hierarchy, leaves[i++]);
      ++reread_leaves_;
      continue;
    }
    const std::uint32_t first = receiver_of_node_[leaves[i]];
    std::uint32_t last = first + 1;
    for (++i; i < kept && receiver_of_node_[leaves[i]] == last && unchanged(leaves[i]); ++i) ++last;
    next_.append_from(view_, first, last);
  }
  for (; i < leaves.size(); ++i) add_leaf(next_, hierarchy, leaves[i]);
  next_.mark_refinement_of(view_.revision());
  return true;
}

}  // namespace aarad::refine
