// Initial meshing of physical surfaces into patches and elements.
// Substructuring after Cohen, Greenberg, Immel and Brock 1986 ("An efficient radiosity approach for
// realistic image synthesis", section 3): patches are the shooters, elements the receivers. A surface that is
// one convex quadrilateral or one triangle (one face, or faces tiling one) gets a grid of patches; others are
// triangulated with CGAL's constrained Delaunay mesher (Shewchuk's / Ruppert's refinement, CGAL 2D Conforming
// Triangulations and Meshes, Delaunay_mesher_2).
#include "aarad/mesh/initial_meshing.h"

#include "aarad/core/error.h"
#include "aarad/core/face_check.h"
#include "aarad/core/polygon.h"
#include "aarad/core/predicates.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>

namespace aarad::mesh {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Delaunay_mesh_vertex_base_2<Kernel>;
using FaceBase = CGAL::Delaunay_mesh_face_base_2<Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::Exact_predicates_tag>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<Cdt>;
using Point2 = Kernel::Point_2;

// An orthonormal frame (u, v) in the plane with u x v = n: counter-clockwise in 2D is counter-clockwise
// seen from the front.
struct Frame {
  Vec3 origin, u, v;
  Vec2 to_2d(const Vec3& p) const { return {glm::dot(p - origin, u), glm::dot(p - origin, v)}; }
  Vec3 to_3d(const Vec2& p) const { return origin + p.x * u + p.y * v; }
};

Frame frame_of(const Plane& plane, const Vec3& origin) {
  const Vec3 n = plane.normal;
  const Vec3 axis = std::abs(n.x) < 0.6 ? Vec3(1, 0, 0) : (std::abs(n.y) < 0.6 ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
  const Vec3 u = glm::normalize(glm::cross(axis, n));
  return {origin, u, glm::cross(n, u)};
}

// Pieces of at most `size` along `length`, as a double (it is checked against the budget before it becomes an int).
double divisions(double length, double size) { return std::max(1.0, std::ceil(length / size - 1e-9)); }

// The point k / n of the way from p to q, 0 <= k <= n. Two surfaces meeting along an edge are meshed apart, and
// where both grids put a point at the same place on it the two points must be bit-identical: a hemicube pixel
// centre on the edge's projection would otherwise fall in a gap a rounding wide that no receiver claims
// (formfactor/hemicube.cpp's fill rule covers shared edges, not edges a rounding apart). So the point is computed
// from the lexicographically smaller end, whichever way round the caller walks the edge, and the parameter is a
// correctly rounded quotient, equal for equal fractions (2 / 6 and 1 / 3 alike).
Vec3 point_along(const Vec3& p, const Vec3& q, int k, int n) {
  if (k == 0) return p;
  if (k == n) return q;
  const bool flipped = std::tie(q.x, q.y, q.z) < std::tie(p.x, p.y, p.z);
  const Vec3& from = flipped ? q : p;
  const Vec3& to = flipped ? p : q;
  return from + (static_cast<double>(flipped ? n - k : k) / n) * (to - from);
}

// The count limit of one surface's meshing: what MeshingOptions::max_initial_elements leaves after the surfaces
// meshed before it. Counts are checked, in doubles, before anything is allocated.
struct Budget {
  const Scene& scene;
  const Surface& surface;
  double remaining = 0.0;
  double limit = 0.0;     // of the whole scene
  double diagonal = 0.0;  // the scene's
  double patch_size = 0.0, element_size = 0.0;

  void check(double count, const char* items, const char* option, double size) const {
    if (count <= remaining) return;
    // A size of 1e-300 squares to 0 and the count to inf, which is no number to show.
    char counted[64];
    if (std::isfinite(count)) {
      std::snprintf(counted, sizeof counted, "%.3g", count);
    } else {
      std::snprintf(counted, sizeof counted, "more than %.3g", std::numeric_limits<double>::max());
    }
    char text[600];
    const double before = limit - remaining;  // the initial elements of the surfaces meshed before this one
    if (count <= limit && before > 0.0) {
      // This surface alone would fit: the surfaces before it took the budget, by both sizes, and the size this
      // check is about is not the one to blame (a reviewer's floor of tiny elements made a wall's patches fail).
      std::snprintf(text, sizeof text,
                    "meshing: with patch size %g and element size %g the surfaces meshed before group '%s' make "
                    "%.3g initial elements, and with its %s initial %s the scene makes more than the limit of "
                    "%.3g (MeshingOptions::max_initial_elements); choose a larger element size or patch size",
                    patch_size, element_size, scene.groups[surface.group].name.c_str(), before, counted, items,
                    limit);
    } else {
      std::snprintf(text, sizeof text,
                    "meshing: with %s %g the surface of group '%s' makes %s initial %s, and the scene more than "
                    "the limit of %.3g (MeshingOptions::max_initial_elements); choose a larger %s",
                    option, size, scene.groups[surface.group].name.c_str(), counted, items, limit, option);
    }
    throw Error(text);
  }
};

bool strictly_convex_quad(std::span<const Vec3> polygon, const Frame& frame) {
  if (polygon.size() != 4) return false;
  std::array<Vec2, 4> p;
  for (int i = 0; i < 4; ++i) p[i] = frame.to_2d(polygon[i]);
  for (int i = 0; i < 4; ++i)
    if (orientation(p[i], p[(i + 1) % 4], p[(i + 2) % 4]) != Sign::kPositive) return false;
  return true;
}

// One convex quadrilateral: a global bilinear grid of (nx ex) x (ny ey) points; patch (i, j) covers
// ex x ey grid cells, each cell an element.
SurfaceMeshing mesh_convex_quad(std::span<const Vec3> c, double patch_size, double element_size,
                                const Budget& budget) {
  const double lu = std::max(glm::length(c[1] - c[0]), glm::length(c[2] - c[3]));
  const double lv = std::max(glm::length(c[3] - c[0]), glm::length(c[2] - c[1]));
  const double patches_u = divisions(lu, patch_size), patches_v = divisions(lv, patch_size);
  budget.check(patches_u * patches_v, "patches", "patch size", patch_size);
  const double elements_u = divisions(lu / patches_u, element_size);
  const double elements_v = divisions(lv / patches_v, element_size);
  budget.check(patches_u * patches_v * elements_u * elements_v, "elements", "element size", element_size);
  const int nx = static_cast<int>(patches_u), ny = static_cast<int>(patches_v);
  const int ex = static_cast<int>(elements_u), ey = static_cast<int>(elements_v);
  const int gx = nx * ex, gy = ny * ey;
  SurfaceMeshing out;
  out.points.reserve(static_cast<std::size_t>(gx + 1) * (gy + 1));
  for (int j = 0; j <= gy; ++j)
    for (int i = 0; i <= gx; ++i) {
      const double s = static_cast<double>(i) / gx, t = static_cast<double>(j) / gy;
      if (j == 0) out.points.push_back(point_along(c[0], c[1], i, gx));
      else if (j == gy) out.points.push_back(point_along(c[3], c[2], i, gx));
      else if (i == 0) out.points.push_back(point_along(c[0], c[3], j, gy));
      else if (i == gx) out.points.push_back(point_along(c[1], c[2], j, gy));
      else out.points.push_back((1 - s) * (1 - t) * c[0] + s * (1 - t) * c[1] + s * t * c[2] + (1 - s) * t * c[3]);
    }
  auto index = [&](int i, int j) { return j * (gx + 1) + i; };
  for (int pj = 0; pj < ny; ++pj)
    for (int pi = 0; pi < nx; ++pi) {
      const int i0 = pi * ex, j0 = pj * ey;
      out.patches.push_back({index(i0, j0), index(i0 + ex, j0), index(i0 + ex, j0 + ey), index(i0, j0 + ey)});
      std::vector<CornerIndices> elements;
      for (int j = j0; j < j0 + ey; ++j)
        for (int i = i0; i < i0 + ex; ++i)
          elements.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)});
      out.elements.push_back(std::move(elements));
    }
  return out;
}

// The outline of a surface whose faces tile one convex polygon, as exporters write a quad as two triangles or
// a fan: an edge two faces share (once each way) cancels, and what is left must be one loop, of the faces' total
// area, that is a triangle or a strictly convex quadrilateral once points exactly on a straight run (exact
// orientation in the surface's plane) are dropped. Such a surface is meshed as that one polygon; every other
// shape returns nullopt and goes to the Delaunay mesher, whose constraints along every face edge (before it took
// the outline of the faces' union) and minimum angle cut a two-triangle square into several times as many patches.
std::optional<std::vector<Vec3>> convex_outline(const Scene& scene, const Surface& surface, const Frame& frame) {
  using Key = std::array<double, 3>;
  const auto key = [](const Vec3& p) { return Key{p.x, p.y, p.z}; };
  std::map<std::pair<Key, Key>, std::pair<Vec3, Vec3>> edges;  // directed edges not (yet) cancelled
  double faces_area = 0.0;
  std::vector<Vec2> face_2d;
  for (const std::uint32_t fi : surface.faces) {
    const std::vector<Vec3>& face = scene.faces[fi].vertices;
    // Edges cancel to the outline of a tiling only for simple faces (import refuses others; a scene built
    // through the library may hold a bow-tie, whose lobes would cover part of the outline twice).
    face_2d.clear();
    for (const Vec3& p : face) face_2d.push_back(frame.to_2d(p));
    if (!is_simple(face_2d)) return std::nullopt;
    faces_area += aarad::area(face);
    for (std::size_t i = 0; i < face.size(); ++i) {
      const Vec3& a = face[i];
      const Vec3& b = face[(i + 1) % face.size()];
      if (edges.erase({key(b), key(a)}) != 0) continue;               // shared with a face before: inside
      if (!edges.try_emplace({key(a), key(b)}, a, b).second) return std::nullopt;  // two faces overlap
    }
  }
  std::map<Key, Vec3> next;  // each loop vertex to the next one
  for (const auto& [ends, points] : edges)
    if (!next.try_emplace(ends.first, points.second).second) return std::nullopt;  // not one simple loop
  if (next.size() < 3) return std::nullopt;
  std::vector<Vec3> loop{edges.begin()->second.first};
  while (loop.size() <= next.size()) {
    const auto following = next.find(key(loop.back()));
    if (following == next.end()) return std::nullopt;  // an open chain
    if (key(following->second) == key(loop.front())) break;
    loop.push_back(following->second);
  }
  if (loop.size() != next.size()) return std::nullopt;  // more than one loop
  std::vector<Vec3> corners;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Vec2 before = frame.to_2d(loop[(i + loop.size() - 1) % loop.size()]);
    const Vec2 here = frame.to_2d(loop[i]);
    const Vec2 after = frame.to_2d(loop[(i + 1) % loop.size()]);
    if (orientation(before, here, after) != Sign::kZero) corners.push_back(loop[i]);
  }
  if (!(std::abs(aarad::area(corners) - faces_area) <= 1e-9 * faces_area)) return std::nullopt;
  if (corners.size() == 3 || strictly_convex_quad(corners, frame)) return corners;
  return std::nullopt;
}

// Divides every triangle patch into m x m similar triangles, m the same over the surface so patches sharing
// an edge conform. Points on a patch edge are made once per edge (keyed by its ends' indices) by point_along, so
// both patches share them, and a neighbouring surface whose patch has the same edge ends gets the same points.
void divide_triangle_patches(SurfaceMeshing& out, double element_size, const Budget& budget) {
  double longest = 0.0;
  for (const CornerIndices& patch : out.patches)
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, glm::length(out.points[static_cast<std::size_t>(patch[(k + 1) % 3])] -
                                              out.points[static_cast<std::size_t>(patch[k])]));
  const double pieces = divisions(longest, element_size);
  budget.check(static_cast<double>(out.patches.size()) * pieces * pieces, "elements", "element size", element_size);
  const int m = static_cast<int>(pieces);

  // Points along patch edges, keyed by the edge's (lower, higher) point index.
  std::map<std::pair<int, int>, std::vector<int>> edge_points;
  auto edge_point = [&](int a, int b, int k) {  // point k of m along a -> b, 0 < k < m
    const bool flipped = a > b;
    const int lo = flipped ? b : a, hi = flipped ? a : b;
    auto [it, inserted] = edge_points.try_emplace({lo, hi});
    if (inserted)
      for (int i = 1; i < m; ++i) {
        it->second.push_back(static_cast<int>(out.points.size()));
        out.points.push_back(point_along(out.points[lo], out.points[hi], i, m));
      }
    return it->second[flipped ? m - k - 1 : k - 1];
  };
  for (const CornerIndices& patch : out.patches) {
    const int a = patch[0], b = patch[1], c = patch[2];
    // Grid point (i, j), i + j <= m: a + i/m (b - a) + j/m (c - a).
    std::vector<int> grid(static_cast<std::size_t>((m + 1) * (m + 1)), -1);
    auto at = [&](int i, int j) -> int& { return grid[static_cast<std::size_t>(j * (m + 1) + i)]; };
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i + j <= m; ++i) {
        int& g = at(i, j);
        if (i == 0 && j == 0) g = a;
        else if (i == m) g = b;
        else if (j == m) g = c;
        else if (j == 0) g = edge_point(a, b, i);
        else if (i == 0) g = edge_point(a, c, j);
        else if (i + j == m) g = edge_point(b, c, j);
        else {
          g = static_cast<int>(out.points.size());
          const double s = static_cast<double>(i) / m, t = static_cast<double>(j) / m;
          out.points.push_back(out.points[a] + s * (out.points[b] - out.points[a]) + t * (out.points[c] - out.points[a]));
        }
      }
    std::vector<CornerIndices> elements;
    for (int j = 0; j < m; ++j)
      for (int i = 0; i + j < m; ++i) {
        elements.push_back({at(i, j), at(i + 1, j), at(i, j + 1), -1});
        if (i + j + 1 < m) elements.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), -1});
      }
    out.elements.push_back(std::move(elements));
  }
}

// One triangle: an n x n grid of similar triangle patches (no edge longer than patch_size), then elements.
SurfaceMeshing mesh_triangle(std::span<const Vec3> c, double patch_size, double element_size, const Budget& budget) {
  const double longest =
      std::max({glm::length(c[1] - c[0]), glm::length(c[2] - c[1]), glm::length(c[0] - c[2])});
  const double rows = divisions(longest, patch_size);
  budget.check(rows * rows, "patches", "patch size", patch_size);
  const int n = static_cast<int>(rows);
  SurfaceMeshing out;
  std::vector<int> row_start;  // grid point (i, j), i + j <= n, is row_start[j] + i
  for (int j = 0; j <= n; ++j) {
    row_start.push_back(static_cast<int>(out.points.size()));
    for (int i = 0; i + j <= n; ++i) {
      const double s = static_cast<double>(i) / n, t = static_cast<double>(j) / n;
      if (j == 0) out.points.push_back(point_along(c[0], c[1], i, n));
      else if (i == 0) out.points.push_back(point_along(c[0], c[2], j, n));
      else if (i + j == n) out.points.push_back(point_along(c[1], c[2], j, n));
      else out.points.push_back(c[0] + s * (c[1] - c[0]) + t * (c[2] - c[0]));
    }
  }
  auto at = [&](int i, int j) { return row_start[static_cast<std::size_t>(j)] + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i + j < n; ++i) {
      out.patches.push_back({at(i, j), at(i + 1, j), at(i, j + 1), -1});
      if (i + j + 1 < n) out.patches.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), -1});
    }
  divide_triangle_patches(out, element_size, budget);
  return out;
}

// How far off its surface's plane a corner may lie and keep its bits (mesh_surface says why): 1e-12 of the scene's
// diagonal, or 16 units in the last place of the largest coordinate of `points`.
double plane_slack(std::span<const Vec3> points, double diagonal) {
  double largest = 0.0;
  for (const Vec3& p : points) largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  return std::max(1e-12 * diagonal, 16.0 * std::numeric_limits<double>::epsilon() * largest);
}

// `p` moved onto `plane` when it lies farther than `slack` off it.
Vec3 onto_plane(const Vec3& p, const Plane& plane, double slack) {
  const double distance = plane.signed_distance(p);
  return std::abs(distance) > slack ? p - distance * plane.normal : p;
}

// Points of a plane within `weld` of an earlier point are that point: the first of a cluster is kept, with what
// came with it (a 3D position, say). Kept points are found through cells of side `weld`, so n points cost n
// lookups of nine cells.
template <class Payload>
class Welder {
 public:
  explicit Welder(double weld) : weld_(weld) {}
  // The kept point within `weld` of p and its payload, or p with `payload`, kept from now on.
  std::pair<Vec2, Payload> operator()(const Vec2& p, const Payload& payload) {
    const double cx = std::floor(p.x / weld_), cy = std::floor(p.y / weld_);
    for (double i = cx - 1.0; i <= cx + 1.0; i += 1.0)
      for (double j = cy - 1.0; j <= cy + 1.0; j += 1.0) {
        const auto cell = cells_.find({i, j});
        if (cell == cells_.end()) continue;
        for (const auto& kept : cell->second)
          if (glm::dot(p - kept.first, p - kept.first) <= weld_ * weld_) return kept;
      }
    cells_[{cx, cy}].emplace_back(p, payload);
    return {p, payload};
  }

 private:
  double weld_;
  std::map<std::pair<double, double>, std::vector<std::pair<Vec2, Payload>>> cells_;
};

// Any other surface: constrained Delaunay mesh of the union of its faces (shared edges and T-junctions
// between its faces become shared triangulation vertices, so the result conforms), then elements.
// Per point, 1 when it lies in one of the polygons (contains). Trying every polygon for every point was quadratic
// in a surface of many faces (a floor of 54 000 faces around 4 096 box footprints: 1.7 s). A polygon contains no
// point outside its bounding box (contains counts crossings of the horizontal line through the point: none there
// when the point is above or below the box, and as many on either side as the polygon crosses that line when it
// is left or right of it, an even number), so only the pairs whose boxes meet are tried, found by intersecting
// boxes (CGAL's box_intersection_d, closed boxes: a point is a box of no extent). The result is the same.
std::vector<std::uint8_t> centres_in_faces(const std::vector<Point2>& points,
                                           const std::vector<std::vector<Vec2>>& polygons) {
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, std::uint32_t>;
  std::vector<Box> point_boxes, polygon_boxes;
  point_boxes.reserve(points.size());
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    double at[2] = {points[i].x(), points[i].y()};
    point_boxes.emplace_back(at, at, i);
  }
  polygon_boxes.reserve(polygons.size());
  for (std::uint32_t k = 0; k < polygons.size(); ++k) {
    Vec2 low = polygons[k].front(), high = low;
    for (const Vec2& p : polygons[k]) {
      low = glm::min(low, p);
      high = glm::max(high, p);
    }
    double lo[2] = {low.x, low.y}, hi[2] = {high.x, high.y};
    polygon_boxes.emplace_back(lo, hi, k);
  }
  std::vector<std::uint8_t> inside(points.size(), 0);
  CGAL::box_intersection_d(point_boxes.begin(), point_boxes.end(), polygon_boxes.begin(), polygon_boxes.end(),
                           [&](const Box& point, const Box& polygon) {
                             std::uint8_t& in = inside[point.info()];
                             const Vec2 at(point.min_coord(0), point.min_coord(1));
                             if (in == 0) in = contains(polygons[polygon.info()], at);
                           });
  return inside;
}

SurfaceMeshing mesh_general(const Scene& scene, const Surface& surface, double patch_size, double element_size,
                            const Budget& budget) {
  // The mesher makes triangles with edges up to patch_size, of area 0.433 patch_size^2 at most (equilateral):
  // refuse a size that cannot stay within the budget before refining.
  budget.check(surface.area / (0.433 * patch_size * patch_size), "patches", "patch size", patch_size);
  // Input vertices keep their 3D positions (a neighbouring surface has the same points), but those that import let
  // off the surface's plane are moved onto it, as mesh_surface moves a grid's corners, and so is the frame's origin,
  // from which the mesher's new points are placed: a wall with a window, rotated and written with six decimals, had
  // corners up to 2.6e-7 off its plane (the invariant allows 1e-9 of the diagonal).
  std::vector<Vec3> surface_points;
  for (const std::uint32_t fi : surface.faces)
    surface_points.insert(surface_points.end(), scene.faces[fi].vertices.begin(), scene.faces[fi].vertices.end());
  const double slack = plane_slack(surface_points, budget.diagonal);
  const Frame frame = frame_of(surface.plane, onto_plane(surface_points.front(), surface.plane, slack));
  std::vector<std::vector<Vec2>> polygons;
  std::map<std::pair<double, double>, Vec3> original;  // 2D position of an input vertex -> its 3D position
  Cdt cdt;
  // Features below `weld`, the import's tolerance for faces joining one plane (kPlaneDistance), are rounding errors
  // of the file: the mesher would refine down to them, until CGAL's inexact constructions break the triangulation
  // (a crash, for vertices or gaps of one ulp to 1e-9). So a vertex within `weld` of an earlier one is that vertex
  // (the first of a cluster, in face order, is kept, with its 3D position), and below, an edge passing within
  // `weld` of another vertex is split there.
  const double weld = kPlaneDistance * budget.diagonal;
  Welder<bool> welded(weld);
  std::vector<Vec2> vertices;  // every face's vertices, sorted by x (with repeats)
  for (const std::uint32_t fi : surface.faces) {
    const Face& face = scene.faces[fi];
    std::vector<Vec2> polygon;
    for (const Vec3& v : face.vertices) {
      polygon.push_back(welded(frame.to_2d(v), true).first);
      original.emplace(std::make_pair(polygon.back().x, polygon.back().y), onto_plane(v, surface.plane, slack));
      vertices.push_back(polygon.back());
    }
    polygons.push_back(std::move(polygon));
  }
  std::sort(vertices.begin(), vertices.end(), [](const Vec2& p, const Vec2& q) { return p.x < q.x; });
  // The outline of the union of the faces is the constraint: its own edges, not the faces'. An edge two faces share
  // (once each way) is no feature of the surface, only of how the file cut it: kept, the mesher refined around it.
  // A plate with a round hole written as 36 thin triangles fanned from its corners, as CAD exporters write it, made
  // 70 469 patches (now 300), and the Cornell floor, cut into slabs around the blocks, 207 patches to the ceiling's
  // 16 (now 91). So every face edge is split at the vertices of the surface that lie on it or within `weld` of it
  // (a T-junction, perhaps written a rounding error off the edge, as exporters do; left as it was, the sliver
  // between the edge and the vertex was a gap, which the mesher refined down to the rounding error, a crash, or
  // left as a hole), and the pieces two faces share, once each way, cancel; the rest are constraints.
  using Point = std::pair<double, double>;
  const auto point = [](const Vec2& p) { return Point{p.x, p.y}; };
  std::map<std::pair<Point, Point>, int> pieces;  // directed pieces of face edges not (yet) cancelled, with counts
  const auto add_piece = [&](const Vec2& from, const Vec2& to) {
    const auto reverse = pieces.find({point(to), point(from)});
    if (reverse != pieces.end() && reverse->second > 0) {
      --reverse->second;
    } else {
      ++pieces[{point(from), point(to)}];
    }
  };
  std::vector<std::pair<double, Vec2>> cuts;  // along an edge: parameter, point
  // The faces as the pieces cut them: every edge split at the vertices it was cut at. Where a T-junction vertex
  // lies a rounding off its neighbour's edge, the faces as written leave a gap a few units in the last place wide
  // between the two (or overlap there); split, they share the pieces bit for bit, and no point falls between them.
  std::vector<std::vector<Vec2>> split_polygons;
  split_polygons.reserve(polygons.size());
  for (const std::vector<Vec2>& polygon : polygons) {
    std::vector<Vec2>& split = split_polygons.emplace_back();
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      const Vec2& a = polygon[i];
      const Vec2& b = polygon[(i + 1) % polygon.size()];
      if (a == b) continue;
      split.push_back(a);
      const Vec2 d = b - a;
      const double length2 = glm::dot(d, d);
      cuts.clear();
      const auto first = std::lower_bound(vertices.begin(), vertices.end(), std::min(a.x, b.x) - weld,
                                          [](const Vec2& p, double x) { return p.x < x; });
      // A vertex within `weld` of the edge lies within `weld` of its y range too: the others are passed over
      // before any arithmetic (with twice the margin, against rounding), which an edge along y, whose x range
      // holds a whole column of a surface's vertices, meets for nearly all of them.
      const double y_low = std::min(a.y, b.y) - 2.0 * weld, y_high = std::max(a.y, b.y) + 2.0 * weld;
      for (auto it = first; it != vertices.end() && it->x <= std::max(a.x, b.x) + weld; ++it) {
        const Vec2& v = *it;
        if (v.y < y_low || v.y > y_high || v == a || v == b) continue;
        const double t = glm::dot(v - a, d) / length2;
        if (!(t > 0.0 && t < 1.0)) continue;
        const Vec2 off = v - (a + t * d);
        if (glm::dot(off, off) <= weld * weld || orientation(a, b, v) == Sign::kZero) cuts.emplace_back(t, v);
      }
      std::sort(cuts.begin(), cuts.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
      Vec2 from = a;
      for (const auto& [t, v] : cuts) {
        if (v == from) continue;  // a vertex of several faces
        add_piece(from, v);
        split.push_back(v);
        from = v;
      }
      add_piece(from, b);
    }
  }
  for (const auto& [ends, count] : pieces) {
    if (count == 0) continue;
    cdt.insert_constraint(Point2(ends.first.first, ends.first.second), Point2(ends.second.first, ends.second.second));
  }
  // The constraints cut the triangulation into regions, each inside the surface or outside it (a hole, a gap
  // between faces) as a whole; the regions outside are not meshed. A region is inside when most of its area is:
  // the area of its triangles whose centres lie in a face (split at its T-junctions as above, so that only the
  // constraints bound their union) against that of the others. No one triangle decides: the centre of a sliver
  // along the outline (three points of a straight run that rounding bent, as where two strips' ends lie on one
  // line) rounds onto one of its vertices or edges, or across a constraint, and a triangle spanning several faces
  // has its centre on an edge between two of them as often as the faces' corners lie on a grid. Marked from any
  // one triangle whose centre was in no face, the whole region was left out: a ceiling of 17 rotated tiles, far
  // from the origin, whose largest triangle had its centre a rounding off a tile edge that ended at a T-junction,
  // in the gap between the tile and its neighbour (the surface was then "all narrower than" the weld). The
  // triangles themselves are marked, not their centres handed to the mesher as seeds, which it would locate again
  // (a sliver's centre, located on its vertex, named a triangle of the neighbouring face, whose region was then
  // left out: two rotated strips 53 wide, one strip-width apart, and a sliver of area 1.1e-11).
  std::vector<Cdt::Face_handle> triangles;
  std::vector<Point2> centres;
  std::map<Cdt::Face_handle, std::size_t> triangle_index;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    triangle_index.emplace(f, triangles.size());
    triangles.push_back(f);
    centres.push_back(CGAL::centroid(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point()));
  }
  const std::vector<std::uint8_t> inside = centres_in_faces(centres, split_polygons);
  if (cdt.dimension() == 2) {  // else no triangle (faces collapsed onto a line by welding): an error below
    for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->set_in_domain(true);
    std::vector<std::uint8_t> seen(triangles.size(), 0);
    std::vector<std::size_t> region;
    for (std::size_t start = 0; start < triangles.size(); ++start) {
      if (seen[start] != 0) continue;
      // The region of triangle `start`: the finite triangles reached from it across edges that are no constraints.
      // One that reaches the unbounded side the mesher marks outside anyway.
      region.assign(1, start);
      seen[start] = 1;
      double in_area = 0.0, out_area = 0.0;
      bool any_out = false;
      for (std::size_t k = 0; k < region.size(); ++k) {
        const Cdt::Face_handle f = triangles[region[k]];
        const double a = std::abs(CGAL::area(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point()));
        (inside[region[k]] != 0 ? in_area : out_area) += a;
        any_out = any_out || inside[region[k]] == 0;
        for (int e = 0; e < 3; ++e) {
          const Cdt::Face_handle g = f->neighbor(e);
          if (f->is_constrained(e) || cdt.is_infinite(g)) continue;
          const std::size_t j = triangle_index.at(g);
          if (seen[j] == 0) {
            seen[j] = 1;
            region.push_back(j);
          }
        }
      }
      // A region of no area (faces welded flat) is inside only when every centre is, as before.
      const bool in = in_area > out_area || (in_area == out_area && !any_out);
      if (!in)
        for (const std::size_t k : region) triangles[k]->set_in_domain(false);
    }
    // With the domain specified, the mesher marks the faces reached from the unbounded side out too, as with seeds.
    CGAL::refine_Delaunay_mesh_2(cdt, Criteria(0.125, patch_size), true);
  }

  SurfaceMeshing out;
  std::map<Cdt::Vertex_handle, int> vertex_index;
  auto index_of = [&](Cdt::Vertex_handle v) {
    auto [it, inserted] = vertex_index.emplace(v, static_cast<int>(out.points.size()));
    if (inserted) {
      const auto found = original.find({v->point().x(), v->point().y()});
      out.points.push_back(found != original.end() ? found->second
                                                   : frame.to_3d({v->point().x(), v->point().y()}));
    }
    return it->second;
  };
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (!f->is_in_domain()) continue;
    const CornerIndices patch{index_of(f->vertex(0)), index_of(f->vertex(1)), index_of(f->vertex(2)), -1};
    out.patches.push_back(patch);
  }
  // Faces narrower everywhere than `weld` (slivers of a scene's tessellation) collapse onto their own edges when
  // their vertices are welded and T-junctions split; where a surface is only such faces, nothing is left. The import
  // passes them (their size is not below kSmallestFace), so the error names the file and line of one, not only the
  // group: it was "initial meshing: surface of group 's' has no area to mesh", where `aarad inspect` saw no problem.
  if (out.patches.empty()) {
    const Face& face = scene.faces[surface.faces.front()];
    char width[32];
    std::snprintf(width, sizeof width, "%g", weld);
    throw InputError(scene.name.empty() ? std::string("scene") : scene.name, face.source_line,
                     "the faces of one surface of group '" + scene.groups[surface.group].name + "' (this one and " +
                         std::to_string(surface.faces.size() - 1) + " more in its plane) are all narrower than " +
                         width + " (1e-6 of the scene's diagonal), which the meshing takes for rounding errors: "
                         "nothing is left to mesh. Make them wider or remove them");
  }
  budget.check(static_cast<double>(out.patches.size()), "patches", "patch size", patch_size);
  divide_triangle_patches(out, element_size, budget);
  return out;
}

// Cuts the meshing along the contact lines of the surface (mesh/contact_lines.h; docs/hierarchy.md, "Contact
// lines"): a patch that a contact segment crosses, or whose outline a segment ends on, is no longer a shooter whose
// one point stands for both sides of the line. The patches so touched (the region) are triangulated again, as one
// constrained Delaunay triangulation (CGAL) of
// - the region's outline: the element edges of its patches that no other patch of the region shares, with every
//   point on them, so the patches around the region keep their element edges and the mesh stays conforming;
// - the element corners inside the region, as plain points, except those within half an element's size of a
//   contact segment (they would make slivers along it);
// - the contact segments, as constraints: ends within `weld` of an outline point taken as that point, ends within
//   `weld` of an outline edge and crossings of the outline put on that edge, and cut at the outline points they
//   pass within `weld` of, so that no two constraints cross on the outline; inside the region, cut into equal
//   pieces no longer than an element's size (the square root of the region's mean element area), which stand for
//   the corners left out along them.
// No Delaunay refinement: it would split the outline's edges, which the patches around the region share. Every
// triangle inside the region becomes a patch of one element. Patches the segments do not touch keep their bits.
void cut_along_contacts(SurfaceMeshing& out, const Frame& frame, const Plane& plane,
                        std::span<const ContactSegment> contacts, double weld) {
  if (contacts.empty() || out.patches.empty()) return;
  const auto count = [](const CornerIndices& c) { return c[3] < 0 ? 3 : 4; };
  std::vector<Vec2> at(out.points.size());
  for (std::size_t i = 0; i < out.points.size(); ++i) at[i] = frame.to_2d(out.points[i]);
  struct Segment {
    Vec2 a, b;
    Vec3 a3, b3;
  };
  // Segment ends within `weld` of an earlier end are that end: the chords of two faces across the plane meet where
  // the faces share an edge, each computed from its own face, a rounding apart (kept apart, they made a sliver).
  Welder<Vec3> welded(weld);
  std::vector<Segment> segments;
  for (const ContactSegment& c : contacts) {
    const auto [a, a3] = welded(frame.to_2d(c.a), c.a);
    const auto [b, b3] = welded(frame.to_2d(c.b), c.b);
    if (glm::length(b - a) > weld) segments.push_back({a, b, a3, b3});
  }
  // Per patch, the points of its elements, each once; made when first asked for (most surfaces meet their contact
  // lines only along their outline, and ask for none).
  const std::size_t patches = out.patches.size();
  std::vector<std::vector<int>> element_points_of(patches);
  const auto element_points = [&](std::size_t p) -> const std::vector<int>& {
    std::vector<int>& points = element_points_of[p];
    if (points.empty()) {
      for (const CornerIndices& e : out.elements[p])
        for (int k = 0; k < count(e); ++k) points.push_back(e[static_cast<std::size_t>(k)]);
      std::sort(points.begin(), points.end());
      points.erase(std::unique(points.begin(), points.end()), points.end());
    }
    return points;
  };
  // Distance from x to the line of the directed edge (c, d), positive on its left (inside a counter-clockwise patch).
  const auto inside_distance = [](const Vec2& c, const Vec2& d, const Vec2& x) {
    const Vec2 e = d - c;
    return (e.x * (x.y - c.y) - e.y * (x.x - c.x)) / glm::length(e);
  };
  // Whether segment s crosses patch p (a piece longer than `weld` inside it, farther than `weld` from its outline),
  // or, with `ends`, has an end within `weld` of it that is none of its points (the patch must then take the end on
  // its outline, for the mesh to stay conforming).
  const auto touches = [&](const Segment& s, std::size_t p, bool ends) {
    const CornerIndices& c = out.patches[p];
    const int n = count(c);
    const auto corner = [&](int k) { return at[static_cast<std::size_t>(c[static_cast<std::size_t>(k % n)])]; };
    const auto depth = [&](const Vec2& x) {  // the least inside distance over the edges
      double least = std::numeric_limits<double>::infinity();
      for (int k = 0; k < n; ++k) least = std::min(least, inside_distance(corner(k), corner(k + 1), x));
      return least;
    };
    double t0 = 0.0, t1 = 1.0;  // the part of the segment inside the patch (Cyrus and Beck)
    for (int k = 0; k < n && t0 <= t1; ++k) {
      const double da = inside_distance(corner(k), corner(k + 1), s.a);
      const double db = inside_distance(corner(k), corner(k + 1), s.b);
      if (da < 0.0 && db < 0.0)
        t1 = -1.0;
      else if (da < 0.0)
        t0 = std::max(t0, da / (da - db));
      else if (db < 0.0)
        t1 = std::min(t1, da / (da - db));
    }
    if (t0 <= t1 && (t1 - t0) * glm::length(s.b - s.a) > weld && depth(s.a + 0.5 * (t0 + t1) * (s.b - s.a)) > weld)
      return true;
    if (!ends) return false;
    for (const Vec2& end : {s.a, s.b}) {
      if (depth(end) < -weld) continue;
      bool known = false;
      for (const int q : element_points(p)) known = known || glm::length(at[static_cast<std::size_t>(q)] - end) <= weld;
      if (!known) return true;
    }
    return false;
  };
  // Pairs whose boxes meet, sorted (CGAL's box_intersection_d reports them in no documented order): every search
  // below is by boxes, so a surface with many contact lines costs what each line's neighbourhood costs.
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, std::uint32_t>;
  const auto box = [](Vec2 low, Vec2 high, double grow, std::uint32_t info) {
    double lo[2] = {low.x - grow, low.y - grow}, hi[2] = {high.x + grow, high.y + grow};
    return Box(lo, hi, info);
  };
  const auto meeting = [](std::vector<Box>& first, std::vector<Box>& second) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    CGAL::box_intersection_d(first.begin(), first.end(), second.begin(), second.end(),
                             [&](const Box& a, const Box& b) { pairs.emplace_back(a.info(), b.info()); });
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  };
  // The segments' boxes grown by `grow`, those of the used ones only when `only_used` is given.
  const auto segment_boxes = [&](double grow, const std::vector<std::uint8_t>* only_used) {
    std::vector<Box> boxes;
    for (std::uint32_t i = 0; i < segments.size(); ++i)
      if (only_used == nullptr || (*only_used)[i] != 0)
        boxes.push_back(box(glm::min(segments[i].a, segments[i].b), glm::max(segments[i].a, segments[i].b), grow, i));
    return boxes;
  };
  std::vector<Box> patch_boxes, all_segments = segment_boxes(0.0, nullptr);
  for (std::uint32_t p = 0; p < patches; ++p) {
    Vec2 low = at[static_cast<std::size_t>(out.patches[p][0])], high = low;
    for (int k = 1; k < count(out.patches[p]); ++k) {
      low = glm::min(low, at[static_cast<std::size_t>(out.patches[p][static_cast<std::size_t>(k)])]);
      high = glm::max(high, at[static_cast<std::size_t>(out.patches[p][static_cast<std::size_t>(k)])]);
    }
    patch_boxes.push_back(box(low, high, weld, p));
  }
  // The segments that cross a patch cut it, and every patch their ends touch. A segment along the outline, or
  // outside the surface, cuts nothing, wherever its ends lie.
  const auto patch_segment = meeting(patch_boxes, all_segments);
  std::vector<std::uint8_t> cut(patches, 0), used(segments.size(), 0);
  for (const auto& [patch, segment] : patch_segment)
    if (touches(segments[segment], patch, false)) used[segment] = 1;
  for (const auto& [patch, segment] : patch_segment)
    if (used[segment] != 0 && touches(segments[segment], patch, true)) cut[patch] = 1;
  if (std::find(cut.begin(), cut.end(), 1) == cut.end()) return;

  // The region's outline: directed element edges whose reverse no element of the region has.
  std::map<std::pair<int, int>, int> edges;
  double element_area = 0.0;
  std::size_t element_count = 0;
  for (std::size_t p = 0; p < patches; ++p) {
    if (cut[p] == 0) continue;
    for (const CornerIndices& e : out.elements[p]) {
      const int n = count(e);
      std::vector<Vec2> corners;
      for (int k = 0; k < n; ++k) {
        const int a = e[static_cast<std::size_t>(k)], b = e[static_cast<std::size_t>((k + 1) % n)];
        corners.push_back(at[static_cast<std::size_t>(a)]);
        if (edges.erase({b, a}) == 0) ++edges[{a, b}];
      }
      element_area += std::abs(signed_area(corners));
      ++element_count;
    }
  }
  // Region points by 2D position: the outline's (kept whatever the segments) and the inside ones.
  std::map<std::pair<double, double>, int> index_of;
  for (const auto& [ends, n] : edges)
    for (const int v : {ends.first, ends.second})
      index_of.emplace(std::make_pair(at[static_cast<std::size_t>(v)].x, at[static_cast<std::size_t>(v)].y), v);
  // Distance from x to segment s.
  const auto distance = [](const Segment& s, const Vec2& x) {
    const Vec2 d = s.b - s.a;
    const double t = std::clamp(glm::dot(x - s.a, d) / glm::dot(d, d), 0.0, 1.0);
    return glm::length(x - (s.a + t * d));
  };
  const double clear = std::max(2.0 * weld, 0.5 * std::sqrt(element_area / static_cast<double>(element_count)));
  std::vector<int> inside_points;  // in the order of the patches and their elements
  std::vector<std::uint8_t> listed(out.points.size(), 0);
  for (std::size_t p = 0; p < patches; ++p) {
    if (cut[p] == 0) continue;
    for (const int v : element_points(p)) {
      const Vec2& x = at[static_cast<std::size_t>(v)];
      if (listed[static_cast<std::size_t>(v)] != 0 || index_of.count({x.x, x.y}) != 0) continue;
      listed[static_cast<std::size_t>(v)] = 1;
      inside_points.push_back(v);
    }
  }
  {
    std::vector<Box> point_boxes, near_segments = segment_boxes(clear, &used);
    for (std::uint32_t k = 0; k < inside_points.size(); ++k) {
      const Vec2& x = at[static_cast<std::size_t>(inside_points[k])];
      point_boxes.push_back(box(x, x, 0.0, k));
    }
    std::vector<std::uint8_t> near(inside_points.size(), 0);
    for (const auto& [k, i] : meeting(point_boxes, near_segments))
      if (distance(segments[i], at[static_cast<std::size_t>(inside_points[k])]) <= clear) near[k] = 1;
    std::size_t kept = 0;
    for (std::size_t k = 0; k < inside_points.size(); ++k) {
      if (near[k] != 0) continue;
      const Vec2& x = at[static_cast<std::size_t>(inside_points[k])];
      index_of.emplace(std::make_pair(x.x, x.y), inside_points[k]);
      inside_points[kept++] = inside_points[k];
    }
    inside_points.resize(kept);
  }

  // The outline's pieces, and where the segments meet them: ends within `weld` of a piece are moved onto it, and
  // crossings are put on it, each computed once from the piece's own ends, so the segment and the outline share
  // the point bit for bit and no constraint crosses another there.
  struct Piece {
    int a, b;
    std::vector<std::pair<double, Vec2>> stops;  // parameter along a -> b, point
  };
  std::vector<Piece> pieces;
  std::vector<Box> piece_boxes;
  for (const auto& [ends, n] : edges) {
    const Vec2 a = at[static_cast<std::size_t>(ends.first)], b = at[static_cast<std::size_t>(ends.second)];
    piece_boxes.push_back(box(glm::min(a, b), glm::max(a, b), weld, static_cast<std::uint32_t>(pieces.size())));
    pieces.push_back({ends.first, ends.second, {}});
  }
  // Per used segment, the pieces within `weld` of it (in the outline's order), and their ends.
  std::vector<std::vector<std::uint32_t>> pieces_near(segments.size());
  {
    std::vector<Box> used_segments = segment_boxes(weld, &used);
    for (const auto& [piece, segment] : meeting(piece_boxes, used_segments)) pieces_near[segment].push_back(piece);
  }
  std::vector<int> points_near;
  const auto cross = [](const Vec2& p, const Vec2& q) { return p.x * q.y - p.y * q.x; };
  std::map<std::pair<double, double>, Vec3> segment_ends;  // new points that are a segment's end, on the plane
  const double slack = plane_slack(out.points, 0.0);
  std::vector<std::pair<Vec2, Vec2>> contact_pieces;
  // The outline points near segment i, each once, in the order the outline lists them.
  const auto outline_points_near = [&](std::size_t i) {
    points_near.clear();
    for (const std::uint32_t k : pieces_near[i])
      for (const int v : {pieces[k].a, pieces[k].b})
        if (std::find(points_near.begin(), points_near.end(), v) == points_near.end()) points_near.push_back(v);
  };
  // Where each used segment's ends go: onto an outline point or piece within `weld`, or where they are.
  std::vector<std::array<Vec2, 2>> end_at(segments.size());
  for (std::size_t i = 0; i < segments.size(); ++i) {
    if (used[i] == 0) continue;
    const Segment& s = segments[i];
    outline_points_near(i);
    for (const auto& [end, end3, k] : {std::tuple{s.a, s.a3, 0}, std::tuple{s.b, s.b3, 1}}) {
      Vec2 moved = end;
      bool placed = false;
      for (const int v : points_near)
        if (!placed && glm::length(at[static_cast<std::size_t>(v)] - end) <= weld) {
          moved = at[static_cast<std::size_t>(v)];
          placed = true;
        }
      for (const std::uint32_t near : pieces_near[i]) {
        if (placed) break;
        Piece& piece = pieces[near];
        const Vec2 a = at[static_cast<std::size_t>(piece.a)], e = at[static_cast<std::size_t>(piece.b)] - a;
        const double u = glm::dot(end - a, e) / glm::dot(e, e);
        if (!(u > 0.0 && u < 1.0) || glm::length(end - (a + u * e)) > weld) continue;
        moved = a + u * e;
        piece.stops.emplace_back(u, moved);
        placed = true;
      }
      if (!placed) segment_ends.emplace(std::make_pair(end.x, end.y), onto_plane(end3, plane, slack));
      end_at[i][static_cast<std::size_t>(k)] = moved;
    }
  }
  // Where two segments meet inside the region. An end of one within `weld` of the other splits the other at that
  // end; a crossing splits both at one point, computed once, and taken as the segment end, outline point or earlier
  // crossing within `weld` of it. Left to the triangulation, a crossing was computed there, a rounding away from a
  // point that is the same where three surfaces meet: two vertices an ulp apart, and a triangle of no area.
  //
  // The ends of two segments within `weld` of each other become one point first (the outline's points before them):
  // two contact lines that start where one surface meets two others (a floor and a face lying in the floor's plane,
  // both cut through by a third) were computed apart, an ulp apart, and the triangulation made a patch of no area
  // between them (a reviewer's fuzzing; the solve then stopped with "receiver runs clockwise").
  std::vector<std::vector<std::pair<double, Vec2>>> met(segments.size());
  {
    Welder<bool> crossings(weld);
    for (const auto& [ends, n] : edges)
      for (const int v : {ends.first, ends.second}) crossings(at[static_cast<std::size_t>(v)], true);
    for (std::size_t i = 0; i < segments.size(); ++i)
      if (used[i] != 0)
        for (Vec2& x : end_at[i]) x = crossings(x, true).first;
    std::vector<Box> first = segment_boxes(weld, &used), second = first;
    const auto parameter = [&](std::size_t i, const Vec2& x) {
      const Vec2 d = segments[i].b - segments[i].a;
      return glm::dot(x - segments[i].a, d) / glm::dot(d, d);
    };
    // An end x of another segment splits segment i when it lies within `weld` of i away from i's ends.
    const auto splits = [&](std::size_t i, const Vec2& x) {
      const double t = parameter(i, x);
      return t > 0.0 && t < 1.0 && distance(segments[i], x) <= weld && glm::length(x - end_at[i][0]) > weld &&
             glm::length(x - end_at[i][1]) > weld;
    };
    for (const auto& [i, j] : meeting(first, second)) {
      if (i >= j) continue;
      bool touched = false;
      for (const auto& [at_end, other] : {std::pair{i, j}, std::pair{j, i}})
        for (const Vec2& x : end_at[at_end])
          if (splits(other, x)) {
            met[other].emplace_back(parameter(other, x), x);
            touched = true;
          }
      if (touched) continue;
      const Vec2 p = end_at[i][0], d = end_at[i][1] - p, q = end_at[j][0], e = end_at[j][1] - q;
      const double denominator = cross(d, e);
      if (denominator == 0.0) continue;
      const double t = cross(q - p, e) / denominator, u = cross(q - p, d) / denominator;
      if (!(t > 0.0 && t < 1.0 && u > 0.0 && u < 1.0)) continue;
      const Vec2 x = crossings(p + t * d, true).first;
      if (std::min({glm::length(x - p), glm::length(x - end_at[i][1]), glm::length(x - q),
                    glm::length(x - end_at[j][1])}) <= weld)
        continue;  // at an end: taken above
      met[i].emplace_back(parameter(i, x), x);
      met[j].emplace_back(parameter(j, x), x);
    }
  }
  for (std::size_t i = 0; i < segments.size(); ++i) {
    if (used[i] == 0) continue;
    const Segment& s = segments[i];
    const Vec2 d = s.b - s.a;
    std::vector<std::pair<double, Vec2>> stops{{0.0, end_at[i][0]}, {1.0, end_at[i][1]}};
    stops.insert(stops.end(), met[i].begin(), met[i].end());
    outline_points_near(i);
    for (const int v : points_near) {
      const Vec2& x = at[static_cast<std::size_t>(v)];
      const double t = glm::dot(x - s.a, d) / glm::dot(d, d);
      if (t > 0.0 && t < 1.0 && distance(s, x) <= weld) stops.emplace_back(t, x);
    }
    for (const std::uint32_t k : pieces_near[i]) {
      Piece& piece = pieces[k];
      const Vec2 a = at[static_cast<std::size_t>(piece.a)], b = at[static_cast<std::size_t>(piece.b)], e = b - a;
      const double denominator = cross(d, e);
      if (denominator == 0.0) continue;
      const double t = cross(a - s.a, e) / denominator, u = cross(a - s.a, d) / denominator;
      if (!(t > 0.0 && t < 1.0 && u > 0.0 && u < 1.0)) continue;
      const Vec2 x = a + u * e;
      if (glm::length(x - a) <= weld || glm::length(x - b) <= weld || glm::length(x - s.a) <= weld ||
          glm::length(x - s.b) <= weld)
        continue;  // at a point already taken
      // A point the piece already stops at within `weld` of the crossing (another segment's crossing or end) is
      // the crossing: segments that overlap along one line (two surfaces standing on one line from either side)
      // cross a piece at one place, but each computed it from its own ends, a few ulps apart, and both points went
      // on the piece; far from the origin they are one 3D point, and the triangle between them had no area.
      const auto taken = std::find_if(piece.stops.begin(), piece.stops.end(),
                                      [&](const auto& stop) { return glm::length(stop.second - x) <= weld; });
      if (taken != piece.stops.end()) {
        stops.emplace_back(glm::dot(taken->second - s.a, d) / glm::dot(d, d), taken->second);
        continue;
      }
      piece.stops.emplace_back(u, x);
      stops.emplace_back(t, x);
    }
    std::sort(stops.begin(), stops.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
    for (std::size_t k = 0; k + 1 < stops.size(); ++k) {
      const Vec2 from = stops[k].second, to = stops[k + 1].second;
      if (glm::length(to - from) <= weld) continue;
      // A piece along the outline needs no cut: the outline is one already.
      const Vec2 middle = 0.5 * (from + to);
      bool along = false;
      for (const std::uint32_t near : pieces_near[i]) {
        const Piece& piece = pieces[near];
        const Segment edge{at[static_cast<std::size_t>(piece.a)], at[static_cast<std::size_t>(piece.b)], {}, {}};
        along = along || distance(edge, middle) <= weld;
      }
      if (along) continue;
      // Cut into pieces no longer than an element, so that the triangles along the line are element-sized: whole,
      // the piece was one edge of a sliver reaching from one end of the line to the other (the element corners near
      // it are left out), whose centroid then shot to the line's far end seen edge on (docs/hierarchy.md).
      // The points are computed from the lower end (by x, then y) whichever way the segment runs: two segments
      // that overlap along a line (where a surface meets two others of one plane) then cut their shared piece at the
      // same points, not at points an ulp apart, between which the triangulation made a patch of no area.
      const auto parts = static_cast<int>(std::ceil(glm::length(to - from) / (2.0 * clear)));
      // The pieces go from `from` to `to` as before (the triangulation's insertion order).
      const bool forward = std::tie(from.x, from.y) < std::tie(to.x, to.y);
      const Vec2 low = forward ? from : to, high = forward ? to : from;
      const auto point = [&](int part) {  // the end of piece `part` (1 .. parts) from `from`
        const int step = forward ? part : parts - part;
        return step == 0 ? low : step == parts ? high : low + (static_cast<double>(step) / parts) * (high - low);
      };
      Vec2 start = from;
      for (int part = 1; part <= parts; ++part) {
        const Vec2 stop = point(part);
        contact_pieces.emplace_back(start, stop);
        start = stop;
      }
    }
  }

  Cdt cdt;
  using Key2 = std::pair<double, double>;
  const auto key2 = [](const Vec2& p) { return Key2{p.x, p.y}; };
  std::set<std::pair<Key2, Key2>> outline;  // the outline's constraint pieces, both ways round
  for (Piece& piece : pieces) {
    std::sort(piece.stops.begin(), piece.stops.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
    Vec2 from = at[static_cast<std::size_t>(piece.a)];
    piece.stops.emplace_back(1.0, at[static_cast<std::size_t>(piece.b)]);
    for (const auto& [u, to] : piece.stops) {
      if (to == from) continue;
      cdt.insert_constraint(Point2(from.x, from.y), Point2(to.x, to.y));
      outline.insert({key2(from), key2(to)});
      outline.insert({key2(to), key2(from)});
      from = to;
    }
  }
  for (const int v : inside_points)
    cdt.insert(Point2(at[static_cast<std::size_t>(v)].x, at[static_cast<std::size_t>(v)].y));
  for (const auto& [from, to] : contact_pieces) cdt.insert_constraint(Point2(from.x, from.y), Point2(to.x, to.y));

  // Inside the region: faces reached from the unbounded side across an odd number of the outline's edges (the
  // segments' own edges are crossed freely).
  std::map<Cdt::Face_handle, int> depth_of;
  std::vector<std::pair<Cdt::Face_handle, int>> stack{{cdt.infinite_face(), 0}};
  std::vector<Cdt::Face_handle> next_level;
  int level = 0;
  while (!stack.empty()) {
    while (!stack.empty()) {
      const auto [f, depth] = stack.back();
      stack.pop_back();
      if (!depth_of.emplace(f, depth).second) continue;
      for (int k = 0; k < 3; ++k) {
        const Cdt::Face_handle g = f->neighbor(k);
        if (depth_of.count(g) != 0) continue;
        const Point2& p = f->vertex(Cdt::cw(k))->point();
        const Point2& q = f->vertex(Cdt::ccw(k))->point();
        if (f->is_constrained(k) && outline.count({{p.x(), p.y()}, {q.x(), q.y()}}) != 0) {
          next_level.push_back(g);
        } else {
          stack.emplace_back(g, depth);
        }
      }
    }
    ++level;
    for (const Cdt::Face_handle g : next_level)
      if (depth_of.count(g) == 0) stack.emplace_back(g, level);
    next_level.clear();
  }
  std::vector<Cdt::Face_handle> faces;
  std::vector<std::uint8_t> inside;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    faces.push_back(f);
    inside.push_back(static_cast<std::uint8_t>(depth_of[f] % 2));
  }
  SurfaceMeshing result;
  result.points = std::move(out.points);
  for (std::size_t p = 0; p < patches; ++p) {
    if (cut[p] != 0) continue;
    result.patches.push_back(out.patches[p]);
    result.elements.push_back(std::move(out.elements[p]));
  }
  const auto vertex = [&](Cdt::Vertex_handle h) {
    const std::pair<double, double> key{h->point().x(), h->point().y()};
    auto [it, added] = index_of.emplace(key, static_cast<int>(result.points.size()));
    if (added) {
      const auto end = segment_ends.find(key);
      result.points.push_back(
          end != segment_ends.end() ? end->second : onto_plane(frame.to_3d({key.first, key.second}), plane, slack));
    }
    return it->second;
  };
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (inside[i] == 0) continue;
    const CornerIndices triangle{vertex(faces[i]->vertex(0)), vertex(faces[i]->vertex(1)), vertex(faces[i]->vertex(2)),
                                 -1};
    result.patches.push_back(triangle);
    result.elements.push_back({triangle});
  }
  // The element corners left out of the region are no longer used: the points are renumbered without them.
  std::vector<int> renumbered(result.points.size(), -1);
  std::vector<Vec3> points;
  for (std::vector<CornerIndices>& elements : result.elements)
    for (CornerIndices& e : elements)
      for (int k = 0; k < count(e); ++k) {
        int& v = renumbered[static_cast<std::size_t>(e[static_cast<std::size_t>(k)])];
        if (v < 0) {
          v = static_cast<int>(points.size());
          points.push_back(result.points[static_cast<std::size_t>(e[static_cast<std::size_t>(k)])]);
        }
        e[static_cast<std::size_t>(k)] = v;
      }
  for (CornerIndices& c : result.patches)
    for (int k = 0; k < count(c); ++k)
      c[static_cast<std::size_t>(k)] = renumbered[static_cast<std::size_t>(c[static_cast<std::size_t>(k)])];
  result.points = std::move(points);
  out = std::move(result);
}

}  // namespace

MeshingOptions resolve_options(const Scene& scene, const MeshingOptions& options) {
  MeshingOptions resolved = options;
  const double d = scene.diagonal();
  if (!(d > 0.0)) throw Error("meshing: the scene has no extent (diagonal " + std::to_string(d) + ")");
  const auto valid = [](double size) { return std::isfinite(size) && size >= 0.0; };
  if (!valid(options.patch_size) || !valid(options.element_size) || !valid(options.min_area))
    throw Error("meshing: patch_size, element_size and min_area must be finite and >= 0 (0 picks a default)");
  if (options.max_level < 1 || options.max_level > 60)
    throw Error("meshing: max_level must lie in [1, 60], got " + std::to_string(options.max_level));
  if (!(options.max_initial_elements >= 1.0 && options.max_initial_elements <= kMostInitialElements))
    throw Error("meshing: max_initial_elements must lie in [1, 1e9], got " + std::to_string(options.max_initial_elements));
  if (resolved.patch_size == 0.0) resolved.patch_size = d / 8.0;
  if (resolved.element_size == 0.0) resolved.element_size = resolved.patch_size / 2.0;
  if (resolved.min_area == 0.0) resolved.min_area = 1e-7 * d * d;
  return resolved;
}

SurfaceMeshing mesh_surface(const Scene& scene, std::uint32_t surface_id, double patch_size, double element_size,
                            double max_elements, double scene_limit, double diagonal,
                            std::span<const ContactSegment> contacts) {
  const Surface& surface = scene.surfaces.at(surface_id);
  const Budget budget{scene, surface, max_elements, scene_limit, diagonal, patch_size, element_size};
  const std::vector<Vec3>& first = scene.faces[surface.faces.front()].vertices;
  const Frame frame = frame_of(surface.plane, first.front());
  std::optional<std::vector<Vec3>> outline =
      surface.faces.size() == 1 ? std::optional<std::vector<Vec3>>(first) : convex_outline(scene, surface, frame);
  std::optional<SurfaceMeshing> meshing;
  // An outline narrower than the weld distance (a sliver: its corners all within that of one line) has no plane the
  // grids could keep their points on (a triangle 7e-11 wide made children 6.7e-8 off their parents' planes): the
  // Delaunay path takes it, which welds it flat and refuses a surface of nothing but such faces, naming a line.
  if (outline && width_across(*outline) <= kPlaneDistance * diagonal) outline.reset();
  if (outline) {
    // The grids interpolate between the corners, so a corner that import let off the surface's plane (faces
    // within 1e-6 of the diagonal join a surface) would take whole rows of patches off it: such corners are
    // moved onto the plane. Corners within 1e-12 of the diagonal, or within 16 units in the last place of their
    // largest coordinate, keep their bits: far from the origin a corner on the plane is only known to be within a
    // few such units of it, and moved by that rounding, the corners of two surfaces meeting along an edge were no
    // longer one point (a closed cube of side 0.7 at (1e5, 3e4, 0) had 78 distinct grid points instead of 56, and
    // its AA hemicube factors summed to 1 - 2.2e-3, taking each overlap for one surface in front of another).
    const double off = plane_slack(*outline, diagonal);
    for (Vec3& p : *outline) p = onto_plane(p, surface.plane, off);
    if (strictly_convex_quad(*outline, frame)) meshing = mesh_convex_quad(*outline, patch_size, element_size, budget);
    else if (outline->size() == 3 && aarad::area(*outline) > 0.0)
      meshing = mesh_triangle(*outline, patch_size, element_size, budget);
  }
  if (!meshing) meshing = mesh_general(scene, surface, patch_size, element_size, budget);
  cut_along_contacts(*meshing, frame, surface.plane, contacts, kPlaneDistance * diagonal);
  return std::move(*meshing);
}

}  // namespace aarad::mesh
