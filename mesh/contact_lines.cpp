// Contact lines between surfaces (see contact_lines.h): the D0 discontinuities of Heckbert 1992, section 3, and
// Lischinski, Tampieri and Greenberg 1992, section 3.1.
#include "aarad/mesh/contact_lines.h"

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

namespace aarad::mesh {
namespace {

using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

// Planes closer to parallel than this (1 - |cos|) meet nowhere a meshing could resolve.
constexpr double kParallel = 1e-9;

Box box_of(const std::vector<Vec3>& points, double grow, std::uint32_t info) {
  Vec3 low = points.front(), high = low;
  for (const Vec3& p : points) {
    low = glm::min(low, p);
    high = glm::max(high, p);
  }
  double lo[3] = {low.x - grow, low.y - grow, low.z - grow};
  double hi[3] = {high.x + grow, high.y + grow, high.z + grow};
  return Box(lo, hi, info);
}

// An edge whichever way round: its ends' coordinates, the smaller end first.
using EdgeKey = std::array<double, 6>;
EdgeKey edge_key(const Vec3& p, const Vec3& q) {
  const std::array<double, 3> a{p.x, p.y, p.z}, b{q.x, q.y, q.z};
  return a < b ? EdgeKey{a[0], a[1], a[2], b[0], b[1], b[2]} : EdgeKey{b[0], b[1], b[2], a[0], a[1], a[2]};
}

// The segments where `face` meets `plane` (contact_lines.h), appended to `out`. An edge in the plane for which
// `own(a, b)` holds (an edge of the surface itself, which a neighbouring surface shares) is left out.
template <class Own>
void meet_plane(const std::vector<Vec3>& face, const Plane& plane, double tolerance, Own&& own,
                std::vector<ContactSegment>& out) {
  const std::size_t n = face.size();
  std::array<double, 64> small;
  std::vector<double> large;
  double* distance = small.data();
  if (n > small.size()) {
    large.resize(n);
    distance = large.data();
  }
  bool above = false, below = false;
  for (std::size_t i = 0; i < n; ++i) {
    distance[i] = plane.signed_distance(face[i]);
    above = above || distance[i] > tolerance;
    below = below || distance[i] < -tolerance;
  }
  const auto on = [&](std::size_t i) { return std::abs(distance[i]) <= tolerance; };
  const auto onto = [&](std::size_t i) { return face[i] - distance[i] * plane.normal; };
  if (!(above && below)) {  // on one side: its edges that lie in the plane
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      if (on(i) && on(j) && !own(face[i], face[j])) out.push_back({onto(i), onto(j)});
    }
    return;
  }
  // Across the plane: the points where the outline meets it (at most n).
  std::array<Vec3, 16> few;
  std::vector<Vec3> many;
  std::span<Vec3> room(few);
  if (n > few.size()) {
    many.resize(n);
    room = many;
  }
  std::size_t found = 0;
  bool vertex_on_plane = false;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    if (on(i)) {
      vertex_on_plane = true;
      room[found++] = onto(i);
    } else if (!on(j) && (distance[i] > 0.0) != (distance[j] > 0.0)) {
      const double t = distance[i] / (distance[i] - distance[j]);
      const Vec3 p = face[i] + t * (face[j] - face[i]);
      room[found++] = p - plane.signed_distance(p) * plane.normal;
    }
  }
  const std::span<Vec3> points = room.first(found);
  if (points.size() == 2) {
    out.push_back({points[0], points[1]});
    return;
  }
  if (vertex_on_plane || points.size() % 2 != 0) return;
  // A concave face: its outline enters and leaves the plane's other side alternately along the line.
  const Vec3 along = points.back() - points.front();
  std::sort(points.begin(), points.end(),
            [&](const Vec3& p, const Vec3& q) { return glm::dot(p, along) < glm::dot(q, along); });
  for (std::size_t k = 0; k + 1 < points.size(); k += 2) out.push_back({points[k], points[k + 1]});
}

}  // namespace

std::vector<std::vector<ContactSegment>> find_contact_lines(const Scene& scene, double diagonal) {
  const double tolerance = kPlaneDistance * diagonal;
  std::vector<std::vector<ContactSegment>> contacts(scene.surfaces.size());
  std::vector<Box> surface_boxes, face_boxes;
  surface_boxes.reserve(scene.surfaces.size());
  std::vector<Vec3> points;
  for (std::uint32_t s = 0; s < scene.surfaces.size(); ++s) {
    points.clear();
    for (const std::uint32_t f : scene.surfaces[s].faces)
      points.insert(points.end(), scene.faces[f].vertices.begin(), scene.faces[f].vertices.end());
    if (!points.empty()) surface_boxes.push_back(box_of(points, tolerance, s));
  }
  face_boxes.reserve(scene.faces.size());
  for (std::uint32_t f = 0; f < scene.faces.size(); ++f)
    if (!scene.faces[f].vertices.empty()) face_boxes.push_back(box_of(scene.faces[f].vertices, 0.0, f));
  // Each surface's outline edges (its face edges that no other face of it shares), sorted, made when the surface
  // first meets an edge in its plane: neighbouring surfaces share them (the walls of a room, the triangles of a
  // terrain), and a contact along one cuts nothing. An edge two of its faces share is inside the surface, which
  // the meshing does not follow (docs/hierarchy.md): a surface standing there is a contact line like any other.
  std::vector<std::vector<EdgeKey>> edges_of(scene.surfaces.size());
  const auto own_edges = [&](std::uint32_t s) -> const std::vector<EdgeKey>& {
    std::vector<EdgeKey>& edges = edges_of[s];
    if (edges.empty()) {
      for (const std::uint32_t f : scene.surfaces[s].faces) {
        const std::vector<Vec3>& v = scene.faces[f].vertices;
        for (std::size_t i = 0; i < v.size(); ++i) edges.push_back(edge_key(v[i], v[(i + 1) % v.size()]));
      }
      std::sort(edges.begin(), edges.end());
      std::vector<EdgeKey> once;
      for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) once.push_back(edges[i]);
        i = j;
      }
      edges = std::move(once);
    }
    return edges;
  };
  CGAL::box_intersection_d(surface_boxes.begin(), surface_boxes.end(), face_boxes.begin(), face_boxes.end(),
                           [&](const Box& surface_box, const Box& face_box) {
                             const std::uint32_t s = surface_box.info();
                             const Face& face = scene.faces[face_box.info()];
                             if (face.surface == s) return;
                             const Plane& plane = scene.surfaces[s].plane;
                             const Vec3& normal = scene.surfaces[face.surface].plane.normal;
                             if (1.0 - std::abs(glm::dot(normal, plane.normal)) < kParallel) return;
                             const auto own = [&](const Vec3& a, const Vec3& b) {
                               return std::binary_search(own_edges(s).begin(), own_edges(s).end(), edge_key(a, b));
                             };
                             meet_plane(face.vertices, plane, tolerance, own, contacts[s]);
                           });
  // One segment per line piece, in a fixed order (the boxes' callbacks come in no documented order).
  const auto key = [](const ContactSegment& c) { return edge_key(c.a, c.b); };
  for (std::vector<ContactSegment>& list : contacts) {
    std::erase_if(list, [](const ContactSegment& c) { return c.a == c.b; });
    std::sort(list.begin(), list.end(),
              [&](const ContactSegment& p, const ContactSegment& q) { return key(p) < key(q); });
    list.erase(std::unique(list.begin(), list.end(),
                           [&](const ContactSegment& p, const ContactSegment& q) { return key(p) == key(q); }),
               list.end());
  }
  return contacts;
}

}  // namespace aarad::mesh
