// The checks a scene face must pass before it is meshed: at least three distinct vertices, a size within the
// range the solver's doubles handle, not all vertices on one line, and a boundary that does not cross or touch
// itself. The OBJ importer (core/obj_import.h) skips or rejects a face that fails them, with its file and line;
// Scene::validate() rejects a scene built in code with such a face. Both ask check_face, so they decide alike.
// CGAL's mesher crashes on a face that fails them (a zero-area or self-intersecting constraint polygon in
// refine_Delaunay_mesh_2).
#pragma once

#include "aarad/core/math.h"

#include <algorithm>
#include <span>
#include <vector>

namespace aarad {

// A face's area is zero when twice its area (the length of its Newell sum) is below this fraction of its squared
// bounding-box diagonal. (Whether it is planar depends on the scene it is in: the importer's planar_pieces.)
inline constexpr double kZeroAreaFraction = 1e-12;
// The range of scales the solver computes in: no coordinate beyond kMaxCoordinate in magnitude, no face smaller
// (bounding-box diagonal) than kMinFaceSize. The solver's products of lengths stay far from the ends of a double's
// range there: the Cornell box (coordinates up to 560) solves as at scale 1 scaled by 1e-64 to 1e58, and fails
// scaled by 1e60 (an arithmetic exception) or 1e-66 (broken invariants; at 1e-70 all light is lost). Radiosity
// does not depend on the scene's scale, so a scene can always be scaled into the range.
inline constexpr double kMaxCoordinate = 1e50;
inline constexpr double kMinFaceSize = 1e-50;

enum class FaceProblem {
  kNone,
  kFewerThanThreeDistinct,  // fewer than three distinct vertices
  kTooLarge,                // a coordinate beyond kMaxCoordinate in magnitude
  kTooSmall,                // a bounding-box diagonal below kMinFaceSize
  kCollinear,               // all vertices on one line (no two edges from a vertex span an area)
  kSelfIntersecting,        // two edges cross or touch (decided exactly on the projection to its plane)
  kZeroArea,                // a simple boundary enclosing no area (twice its area below kZeroAreaFraction x size^2)
};

// What check_face finds. With a problem, the fields after `problem` are valid up to the step that found it.
struct FaceCheck {
  FaceProblem problem = FaceProblem::kNone;
  std::vector<Vec3> vertices;  // the face without repeated consecutive vertices (cyclically)
  double size = 0.0;           // the diagonal of its axis-aligned bounding box
  Vec3 normal{0.0};            // unit; the Newell normal (counter-clockwise seen from its tip)
  std::vector<Vec2> flat;      // `vertices` projected along `normal` (project_to_2d), counter-clockwise
  double deviation = 0.0;      // the largest distance of a vertex from the plane with `normal` through their mean
};

FaceCheck check_face(std::span<const Vec3> vertices);

// How far the vertices of a polygon lie from the line through two of them far apart (the farthest from the first
// vertex, and the farthest from that one): for a triangle, its smallest altitude. A face whose width is below the
// meshing's weld distance (kPlaneDistance x the scene's diagonal, scene.h) collapses there onto its own edges.
inline double width_across(std::span<const Vec3> vertices) {
  if (vertices.size() < 3) return 0.0;
  const auto farthest_from = [&](const Vec3& p) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < vertices.size(); ++i)
      if (glm::dot(vertices[i] - p, vertices[i] - p) > glm::dot(vertices[best] - p, vertices[best] - p)) best = i;
    return vertices[best];
  };
  const Vec3 a = farthest_from(vertices[0]), b = farthest_from(a);
  const Vec3 d = b - a;
  const double length2 = glm::dot(d, d);
  if (!(length2 > 0.0)) return 0.0;
  double width = 0.0;
  for (const Vec3& v : vertices) {
    const Vec3 off = (v - a) - (glm::dot(v - a, d) / length2) * d;
    width = std::max(width, glm::length(off));
  }
  return width;
}

}  // namespace aarad
