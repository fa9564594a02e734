// Receiver view of the leaf elements (design.md: formfactor/ sees plain polygons, never the mesh).
#include "refine/receiver_cache.h"

namespace aarad::refine {

bool ReceiverCache::update(const mesh::Hierarchy& hierarchy) {
  if (built_ && hierarchy.revision() == revision_) return false;
  leaves_ = hierarchy.leaves();
  view_.clear();
  view_.reserve(leaves_.size(), leaves_.size() * 4);
  receiver_of_node_.assign(hierarchy.node_count(), kNoReceiver);
  std::vector<Vec3> corners;
  for (std::size_t i = 0; i < leaves_.size(); ++i) {
    const mesh::NodeId leaf = leaves_[i];
    hierarchy.corners(leaf, corners);
    // Corners keyed by their mesh vertex, so that the back ends transform a shared vertex once per shot.
    const std::array<std::uint32_t, 4> keys = hierarchy.corner_vertices(leaf);
    view_.add(corners, std::span<const std::uint32_t>(keys.data(), corners.size()), hierarchy.plane(leaf),
              hierarchy.surface(leaf), hierarchy.patch(leaf));
    receiver_of_node_[leaf] = static_cast<std::uint32_t>(i);
  }
  revision_ = hierarchy.revision();
  built_ = true;
  ++rebuilds_;
  return true;
}

}  // namespace aarad::refine
