// The receivers a form-factor back end sees, built from the leaf elements of the hierarchy and rebuilt only
// when the leaf set changes (Hierarchy::revision()). Receiver i is leaf leaf(i); a leaf's receiver index is
// receiver(node). Receivers follow the hierarchy's deterministic leaf order (by node id).
//
// A receiver is its leaf's whole face loop (Hierarchy::leaf_polygon): the corners and the hanging vertices on its
// edges, keyed by mesh vertex. Where a neighbour was split, the leaf's edge and the pieces' edges are then the same
// segments between the same points, and the back ends cover complementary areas across them: with the corners
// only, the leaf's edge ran a rounding off the pieces' edges, and a classical-hemicube pixel centre between the two
// belonged to neither (docs/form-factors.md).
//
// After splits, the view is not built again from the mesh: leaves only split and new nodes get larger ids, so
// the new leaf order is the old one without the split leaves, followed by the new leaves. The receivers of the
// leaves that stayed are copied from the old view in runs; the new leaves, and the leaves that stayed but gained a
// hanging vertex since (Hierarchy::loop_revision), are read from the hierarchy. The result is the same view as a
// fresh build (the points may be numbered differently).
#pragma once

#include "aarad/formfactor/receiver_view.h"
#include "aarad/mesh/hierarchy.h"

#include <cstdint>
#include <span>
#include <vector>

namespace aarad::refine {

inline constexpr std::uint32_t kNoReceiver = 0xffffffffu;

class ReceiverCache {
 public:
  // Rebuilds the view when the hierarchy or its revision differs from the cached one (or on first use);
  // returns true when it rebuilt.
  bool update(const mesh::Hierarchy& hierarchy);

  const formfactor::ReceiverView& view() const { return view_; }
  std::size_t size() const { return leaves_.size(); }
  mesh::NodeId leaf(std::size_t receiver) const { return leaves_[receiver]; }
  std::span<const mesh::NodeId> leaves() const { return leaves_; }
  // kNoReceiver for nodes that are not leaves.
  std::uint32_t receiver(mesh::NodeId node) const {
    return node < receiver_of_node_.size() ? receiver_of_node_[node] : kNoReceiver;
  }
  std::uint64_t revision() const { return revision_; }
  std::uint64_t rebuilds() const { return rebuilds_; }
  // How many of those rebuilds copied the receivers that stayed from the previous view (after splits).
  std::uint64_t incremental_rebuilds() const { return incremental_rebuilds_; }
  // Leaves that stayed but were read again by those rebuilds, as their loops had gained hanging vertices.
  std::uint64_t reread_leaves() const { return reread_leaves_; }

 private:
  // Builds next_ from view_ after splits; false when the hierarchy did not change by splits alone.
  bool update_after_splits(const mesh::Hierarchy& hierarchy, const std::vector<mesh::NodeId>& leaves);
  void add_leaf(formfactor::ReceiverView& view, const mesh::Hierarchy& hierarchy, mesh::NodeId leaf);

  formfactor::ReceiverView view_, next_;
  std::vector<Vec3> loop_;
  std::vector<std::uint32_t> loop_vertices_;
  const mesh::Hierarchy::Impl* source_ = nullptr;  // the hierarchy view_ was built from (its state, which a
                                                   // move-assignment replaces)
  std::size_t node_count_ = 0;               // its node count then
  std::vector<mesh::NodeId> leaves_;
  std::vector<std::uint32_t> receiver_of_node_;
  std::uint64_t revision_ = 0;
  std::uint64_t rebuilds_ = 0;
  std::uint64_t incremental_rebuilds_ = 0;
  std::uint64_t reread_leaves_ = 0;
  bool built_ = false;
};

}  // namespace aarad::refine
