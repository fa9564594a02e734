// The receivers a form-factor back end sees, built from the leaf elements of the hierarchy and rebuilt only
// when the leaf set changes (Hierarchy::revision()). Receiver i is leaf leaf(i); a leaf's receiver index is
// receiver(node). Receivers follow the hierarchy's deterministic leaf order (by node id).
#pragma once

#include "formfactor/receiver_view.h"
#include "mesh/hierarchy.h"

#include <cstdint>
#include <span>
#include <vector>

namespace aarad::refine {

inline constexpr std::uint32_t kNoReceiver = 0xffffffffu;

class ReceiverCache {
 public:
  // Rebuilds the view when the hierarchy's revision differs from the cached one (or on first use);
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

 private:
  formfactor::ReceiverView view_;
  std::vector<mesh::NodeId> leaves_;
  std::vector<std::uint32_t> receiver_of_node_;
  std::uint64_t revision_ = 0;
  std::uint64_t rebuilds_ = 0;
  bool built_ = false;
};

}  // namespace aarad::refine
