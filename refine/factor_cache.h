// The form factors of each patch's last shot, kept so that its next shot need not compute them all again.
//
// A patch's factors depend only on the patch and the leaf elements (the receiver view), and between two shots of
// one patch the mesh changes only by splits (docs/solver.md, "Reusing a patch's form factors"). A row holds, for
// every leaf that received from the patch's last whole shot, the back end's factor; a leaf split since is shot again
// (a subset of the receivers, all occluding), and its pieces share the factor it had, as substructuring's pieces do
// within one shot. Rows are kept within a memory budget, the least recently used given up first.
#pragma once

#include "aarad/mesh/hierarchy.h"

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace aarad::refine {

// The back end's factors of a patch's whole shot, before the near-field correction (refine/near_field.h), which is
// made again from them with the leaves of the moment.
struct FactorRow {
  std::vector<mesh::NodeId> nodes;  // the leaves that got a factor > 0, when the row was stored
  std::vector<double> factors;      // one per node
  // The near-field candidates among them, and the factors they would have had with nothing occluding
  // (FormFactorBackend::add_unoccluded); empty when the back end does not keep those.
  std::vector<mesh::NodeId> near_nodes;
  std::vector<double> near_unoccluded;
  std::size_t node_count = 0;  // the hierarchy's node count then: nodes made since have larger ids
  int samples = 1;             // the shot's points per side (Solver::compute_form_factors)
  std::uint64_t last_use = 0;
};

class FactorCache {
 public:
  explicit FactorCache(std::size_t budget_bytes) : budget_(budget_bytes) {}

  bool enabled() const { return budget_ > 0; }
  // The row of `patch` for hierarchy state `source`, marked used; nullptr when it has none or the rows are of
  // another state (which store() then drops).
  const FactorRow* find(mesh::NodeId patch, const void* source);
  // Takes the patch's row out (an empty one when it has none), for its memory to be filled again and stored.
  FactorRow take(mesh::NodeId patch);
  // Keeps `row` as the patch's, then drops the least recently used rows until the budget holds (a row larger than
  // the whole budget is not kept).
  void store(mesh::NodeId patch, const void* source, FactorRow row);

  std::size_t bytes() const { return bytes_; }

  static std::size_t bytes_of(const FactorRow& row) {
    return sizeof(FactorRow) + (row.nodes.capacity() + row.near_nodes.capacity()) * sizeof(mesh::NodeId) +
           (row.factors.capacity() + row.near_unoccluded.capacity()) * sizeof(double);
  }

 private:
  void clear();
  void drop(std::unordered_map<mesh::NodeId, FactorRow>::iterator row);

  std::size_t budget_;
  std::size_t bytes_ = 0;
  std::uint64_t clock_ = 0;
  const void* source_ = nullptr;
  std::unordered_map<mesh::NodeId, FactorRow> rows_;
};

}  // namespace aarad::refine
