// The public subdivision-invariant checker (see docs/ and ../shared/design.md for the list).
#pragma once

#include "mesh/hierarchy.h"

#include <string>
#include <vector>

namespace aarad::mesh {

struct Violation {
  std::string invariant;  // short stable name, e.g. "children-tile-parent", "hanging-vertex-on-edge"
  NodeId node = kNoNode;  // the node concerned, when there is one
  std::string message;    // what is wrong, with the numbers
};

// Every violated invariant; empty when the hierarchy is sound.
std::vector<Violation> check_invariants(const Hierarchy& hierarchy);

}  // namespace aarad::mesh
