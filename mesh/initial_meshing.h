// Initial meshing of the physical surfaces of a scene into patches and elements (Cohen, Greenberg, Immel and
// Brock 1986: patches shoot, elements receive). See docs/hierarchy.md for the choices.
#pragma once

#include "aarad/core/scene.h"
#include "aarad/mesh/contact_lines.h"
#include "aarad/mesh/hierarchy.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace aarad::mesh {

// Defaults relative to the scene diagonal d: patch_size = d / 8, element_size = patch_size / 2,
// min_area = 1e-7 d^2. Fields that are not zero are kept. Throws aarad::Error for negative or non-finite sizes
// or a max_level outside [1, 60].
MeshingOptions resolve_options(const Scene& scene, const MeshingOptions& options);

// A polygon of 3 or 4 point indices, counter-clockwise seen from the surface's front; [3] = -1 for a triangle.
using CornerIndices = std::array<int, 4>;

// The conforming initial meshing of one physical surface: elements touching along an edge share its points.
struct SurfaceMeshing {
  std::vector<Vec3> points;
  std::vector<CornerIndices> patches;
  std::vector<std::vector<CornerIndices>> elements;  // per patch; they tile it
};

// A surface that is one strictly convex quadrilateral (one face, or faces that tile one, as two triangles or a
// fan) becomes a bilinear grid of quad patches (no edge longer than patch_size), each patch an equal grid of quad
// elements (no edge longer than element_size). A surface that is one triangle of positive area (or faces tiling
// one) becomes an n x n grid of similar triangle patches (no edge longer than patch_size). Any other surface
// (concave faces, several faces, holes) is the union of its faces, triangulated by a constrained Delaunay mesher
// (CGAL), with the outline of the union as the constraint, into triangle patches with edges no longer than
// patch_size. Triangle patches are divided into m x m similar triangles (m the same over the surface, so
// patches conform).
// Throws aarad::Error naming the surface's group when it would make more than max_elements patches or
// elements: what the scene's limit (MeshingOptions::max_initial_elements, named in the message) leaves after
// the surfaces meshed before it. Counts are exact and checked before allocating, except the patches of a
// Delaunay-meshed surface: bounded by its area before the mesher runs, counted exactly after it.
// `diagonal` is scene.diagonal(), given by the caller: computing it reads every face, and a scene of n faces has
// up to n surfaces.
// `contacts` are the surface's contact lines (find_contact_lines): the patches they cross are cut along them
// (docs/hierarchy.md, "Contact lines").
SurfaceMeshing mesh_surface(const Scene& scene, std::uint32_t surface, double patch_size, double element_size,
                            double max_elements, double scene_limit, double diagonal,
                            std::span<const ContactSegment> contacts = {});

}  // namespace aarad::mesh
