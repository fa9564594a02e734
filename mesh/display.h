// Display reconstruction: vertex radiosities and a crack-free triangulation of the leaf elements.
#pragma once

#include "aarad/mesh/hierarchy.h"

#include <array>
#include <span>
#include <vector>

namespace aarad::mesh {

struct DisplayMesh {
  std::vector<Vec3> positions;
  std::vector<Rgb> vertex_values;                      // interpolated value per vertex
  std::vector<std::array<std::uint32_t, 3>> triangles; // counter-clockwise seen from the front
  std::vector<NodeId> triangle_leaf;                   // the leaf element each triangle belongs to
};

// node_values is indexed by NodeId (node_count() entries; only leaves are read). A vertex takes the
// area-weighted mean of the leaves around it on the same surface, or on every surface of its scene group and
// smoothing group (Face::smoothing) that has a corner at that point; a hanging vertex takes the linear
// interpolation along its host edge, so no shading seam appears. A boundary vertex of such a surface that lies
// strictly inside a boundary edge of another one of its smoothing group hangs across: it takes the interpolation
// that edge shows (between the nearest vertices along it that hang on no edge, when the two sides interleave).
// Leaves with hanging vertices on their boundary are triangulated with those vertices (T-vertex anchoring), so the
// triangulation has no crack.
DisplayMesh build_display_mesh(const Hierarchy& hierarchy, std::span<const Rgb> node_values);

}  // namespace aarad::mesh
