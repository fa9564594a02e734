// The public subdivision-invariant checker. What each invariant asks, and its tolerance, is in docs/hierarchy.md
// ("Invariants"); check_invariants reports them by these names: children-tile-parent, leaf-mesh-manifold, no-crack,
// outer-boundary, surface-covered, surface-component, hanging-vertex-on-edge, levels-parents, face-node-map,
// balance (when the hierarchy keeps balance), surface-plane, finite-values, radiosity-mean.
#pragma once

#include "aarad/mesh/display.h"
#include "aarad/mesh/hierarchy.h"

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

// The display reconstruction of `hierarchy` (build_display_mesh): its first vertices are the leaf mesh's, in place;
// every hanging vertex's value is the linear interpolation of its host edge's ends (display-hanging-vertex); the
// triangles of every leaf cover its area, and no edge is used twice the same way round (display-crack-free: no
// crack, no overlap). Empty when the display mesh is sound.
std::vector<Violation> check_display(const Hierarchy& hierarchy, const DisplayMesh& display);

}  // namespace aarad::mesh
