// The subdivision-invariant checker (../shared/design.md, "Subdivision invariants"; docs/hierarchy.md lists
// each invariant with its tolerance). Every loop over the half-edge structure is capped, so a corrupted mesh
// is reported, never walked forever.
#include "aarad/mesh/invariants.h"

#include "aarad/core/polygon.h"
#include "aarad/mesh/leaf_mesh.h"

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <sstream>

namespace aarad::mesh {
namespace {

using VertexHandle = LeafMesh::VertexHandle;
using HalfedgeHandle = LeafMesh::HalfedgeHandle;
using FaceHandle = LeafMesh::FaceHandle;

constexpr double kAreaTolerance = 1e-12;       // children areas sum to the parent's, relative
constexpr double kLengthTolerance = 1e-9;      // positions, relative to the scene diagonal
constexpr double kRadiosityTolerance = 1e-9;   // area-weighted mean, relative to the radiosity
// A point computed from the scene's coordinates (a midpoint, a grid point) is only known to a few units in the
// last place of the largest coordinate: 16 of them. Far from the origin (a building in georeferenced metres,
// 1e6 away) that exceeds the tolerances above, and bounds them from below.
constexpr double kPositionUlps = 16.0;

class Checker {
 public:
  explicit Checker(const Hierarchy& h) : h_(h), m_(h.impl()), mesh_(m_.mesh) {
    double largest = 0.0;
    for (const Face& face : m_.scene().faces)
      for (const Vec3& p : face.vertices) largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    position_error_ = kPositionUlps * std::numeric_limits<double>::epsilon() * largest;
    length_tolerance_ = std::max(kLengthTolerance * m_.scene().diagonal(), position_error_);
  }

  static double perimeter(std::span<const Vec3> corners) {
    double sum = 0.0;
    for (std::size_t i = 0; i < corners.size(); ++i) sum += glm::length(corners[(i + 1) % corners.size()] - corners[i]);
    return sum;
  }

  // How far computed areas may be from one another: kAreaTolerance relative, or what moving the corners of the
  // polygons involved by the position error changes (at most their perimeters times that error).
  double area_tolerance(double area, double perimeters) const {
    return std::max(kAreaTolerance * area, perimeters * position_error_);
  }

  std::vector<Violation> run() {
    check_finite();
    check_tree();
    check_face_map();
    const bool mesh_ok = check_half_edges();
    if (mesh_ok) {
      check_boundary();
      check_hanging_vertices();
      if (m_.options.balance) check_balance();
    }
    check_tiling();
    check_surface_areas();
    check_surface_planes();
    check_radiosity();
    return std::move(violations_);
  }

  std::vector<Violation> run_display(const DisplayMesh& display) {
    if (check_display_positions(display)) {
      check_display_hanging_vertices(display);
      check_display_triangles(display);
    }
    return std::move(violations_);
  }

 private:
  template <typename... Parts>
  void report(const char* invariant, NodeId node, const Parts&... parts) {
    std::ostringstream message;
    message.precision(17);
    (message << ... << parts);
    violations_.push_back({invariant, node, message.str()});
  }

  bool face_deleted(FaceHandle f) const { return mesh_.has_face_status() && mesh_.status(f).deleted(); }
  bool halfedge_deleted(HalfedgeHandle h) const {
    return mesh_.has_edge_status() && mesh_.status(mesh_.edge_handle(h)).deleted();
  }
  bool valid_node(NodeId n) const { return n < m_.parent.size(); }
  Vec3 point(VertexHandle v) const { return to_vec3(mesh_.point(v)); }

  // The vertices of face f's loop from its halfedge, or false when the loop does not close within the cap.
  bool loop_of(FaceHandle f, std::vector<VertexHandle>& out) const {
    out.clear();
    const HalfedgeHandle start = mesh_.halfedge_handle(f);
    if (!start.is_valid() || start.idx() >= static_cast<int>(mesh_.n_halfedges())) return false;
    HalfedgeHandle h = start;
    for (std::size_t i = 0; i <= mesh_.n_halfedges(); ++i) {
      out.push_back(mesh_.from_vertex_handle(h));
      h = mesh_.next_halfedge_handle(h);
      if (h == start) return true;
      if (!h.is_valid() || mesh_.face_handle(h) != f) return false;
    }
    return false;
  }

  // Every position, area and radiosity is a finite number (and every area positive). The other checks compare
  // with tolerances, which a NaN passes.
  void check_finite() {
    for (VertexHandle v : mesh_.vertices()) {
      const Vec3 p = point(v);
      if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
        report("finite-values", kNoNode, "vertex ", v.idx(), " is at (", p.x, ", ", p.y, ", ", p.z, ")");
    }
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      if (!(std::isfinite(m_.area[n]) && m_.area[n] > 0.0))
        report("finite-values", n, "node ", n, " has area ", m_.area[n]);
      const Rgb& b = m_.radiosity[n];
      if (!(std::isfinite(b.r) && std::isfinite(b.g) && std::isfinite(b.b)))
        report("finite-values", n, "node ", n, " has radiosity (", b.r, ", ", b.g, ", ", b.b, ")");
    }
  }

  // The patches of each surface cover its area. The crack and boundary checks compare the leaf mesh with the
  // outline it had when the hierarchy was built; this compares it with the scene, so a piece the initial
  // meshing left out is a violation, not a hole in the outline. The meshing moves the faces' corners by up to
  // kPlaneDistance x the diagonal (onto the surface's plane, onto one another, onto a neighbour's edge), which
  // changes the area by at most the faces' perimeters times that; both sums also round once per term.
  void check_surface_areas() {
    const auto& surfaces = m_.scene().surfaces;
    const double moved = kPlaneDistance * m_.scene().diagonal();
    std::vector<double> covered(surfaces.size(), 0.0), perimeters(surfaces.size(), 0.0);
    std::vector<std::size_t> terms(surfaces.size(), 0);
    std::vector<Vec3> corners;
    for (const NodeId p : m_.patch_ids) {
      if (!valid_node(p) || m_.surface[p] >= surfaces.size()) continue;  // reported by check_tree
      h_.corners(p, corners);
      covered[m_.surface[p]] += m_.area[p];
      perimeters[m_.surface[p]] += perimeter(corners);
      ++terms[m_.surface[p]];
    }
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
      const double area = surfaces[s].area;
      double outline = 0.0;
      for (const std::uint32_t f : surfaces[s].faces) outline += perimeter(m_.scene().faces[f].vertices);
      const double rounding = 4.0 * std::numeric_limits<double>::epsilon() *
                              static_cast<double>(terms[s] + surfaces[s].faces.size()) * area;
      const double tolerance = std::max({area_tolerance(area, perimeters[s]), rounding, outline * moved});
      if (!(std::abs(covered[s] - area) <= tolerance))
        report("surface-covered", kNoNode, "the patches of surface ", s, " cover ", covered[s], " of its area ", area,
               " (", terms[s], " patches)");
    }
  }

  // The corners of every node lie in the plane of its surface. (check_tiling holds children to their parent's
  // plane; this holds the patches, and so the whole tree, to the surface's.)
  void check_surface_planes() {
    std::vector<Vec3> corners;
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      if (m_.surface[n] >= m_.scene().surfaces.size()) continue;  // reported by check_tree
      const Plane& plane = h_.plane(n);
      h_.corners(n, corners);
      for (const Vec3& p : corners) {
        const double distance = plane.signed_distance(p);
        if (!(std::abs(distance) <= length_tolerance_))
          report("surface-plane", n, "a corner of node ", n, " lies ", distance, " off the plane of surface ",
                 m_.surface[n]);
      }
    }
  }

  void check_tree() {
    std::size_t roots = 0;
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      if (m_.surface[n] >= m_.scene().surfaces.size())
        report("levels-parents", n, "node ", n, " names surface ", m_.surface[n], ", which does not exist");
      const NodeId p = m_.parent[n];
      if (p == kNoNode) {
        ++roots;
        if (m_.level[n] != 0) report("levels-parents", n, "patch ", n, " has level ", int(m_.level[n]), ", not 0");
        if (m_.patch_of[n] != n) report("levels-parents", n, "patch ", n, " names patch ", m_.patch_of[n]);
        continue;
      }
      if (!valid_node(p)) {
        report("levels-parents", n, "node ", n, " has parent ", p, ", which does not exist");
        continue;
      }
      // Bottom-up passes (Hierarchy::update_inner_radiosity, check_radiosity) visit ids in decreasing order.
      if (p >= n) report("levels-parents", n, "node ", n, " has parent ", p, ", whose id is not smaller");
      const auto siblings = h_.children(p);
      if (std::find(siblings.begin(), siblings.end(), n) == siblings.end())
        report("levels-parents", n, "node ", n, " names parent ", p, ", which does not list it as a child");
      if (m_.level[n] != m_.level[p] + 1)
        report("levels-parents", n, "node ", n, " has level ", int(m_.level[n]), " under parent ", p, " of level ",
               int(m_.level[p]));
      if (m_.patch_of[n] != m_.patch_of[p] || m_.surface[n] != m_.surface[p])
        report("levels-parents", n, "node ", n, " has patch ", m_.patch_of[n], " and surface ", m_.surface[n],
               ", its parent patch ", m_.patch_of[p], " and surface ", m_.surface[p]);
      if (m_.level[n] > m_.options.max_level)
        report("levels-parents", n, "node ", n, " has level ", int(m_.level[n]), " above max_level ", m_.options.max_level);
    }
    for (NodeId n = 0; n < m_.parent.size(); ++n)
      for (NodeId c : h_.children(n))
        if (!valid_node(c) || m_.parent[c] != n)
          report("levels-parents", n, "node ", n, " lists child ", c, ", whose parent is not ", n);
    if (roots != m_.patch_ids.size())
      report("levels-parents", kNoNode, roots, " nodes without a parent but ", m_.patch_ids.size(), " patches");
    std::vector<std::uint8_t> listed(m_.parent.size(), 0);
    for (const NodeId p : m_.patch_ids) {
      if (!valid_node(p) || m_.parent[p] != kNoNode)
        report("levels-parents", valid_node(p) ? p : kNoNode, "the patch list names node ", p, ", which is not a root");
      else if (listed[p]++ != 0)
        report("levels-parents", p, "the patch list names node ", p, " twice");
    }
  }

  void check_face_map() {
    std::size_t leaves = 0;
    std::vector<VertexHandle> loop;
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      const int fi = m_.face[n];
      if (!h_.is_leaf(n)) {
        if (fi != -1) report("face-node-map", n, "inner node ", n, " still names face ", fi);
        continue;
      }
      ++leaves;
      if (fi < 0 || fi >= static_cast<int>(mesh_.n_faces()) || face_deleted(FaceHandle(fi))) {
        report("face-node-map", n, "leaf ", n, " has no face (face index ", fi, ")");
        continue;
      }
      if (mesh_.property(m_.face_node, FaceHandle(fi)) != n)
        report("face-node-map", n, "leaf ", n, " names face ", fi, ", which maps to node ",
               mesh_.property(m_.face_node, FaceHandle(fi)));
      // Its corners lie on its face loop, in counter-clockwise order.
      if (!loop_of(FaceHandle(fi), loop)) continue;  // reported by check_half_edges
      std::vector<std::size_t> at;
      for (int k = 0; k < m_.corner_count(n); ++k) {
        const auto it = std::find(loop.begin(), loop.end(), VertexHandle(m_.corners[n][static_cast<std::size_t>(k)]));
        if (it == loop.end()) break;
        at.push_back(static_cast<std::size_t>(it - loop.begin()));
      }
      std::size_t rotations = 0;
      for (std::size_t k = 0; k < at.size(); ++k) rotations += at[(k + 1) % at.size()] < at[k];
      if (at.size() != static_cast<std::size_t>(m_.corner_count(n)) || rotations != 1)
        report("face-node-map", n, "the corners of leaf ", n, " are not on its face loop in order");
    }
    for (auto f : mesh_.faces()) {
      const NodeId n = mesh_.property(m_.face_node, f);
      if (!valid_node(n) || !h_.is_leaf(n) || m_.face[n] != f.idx())
        report("face-node-map", valid_node(n) ? n : kNoNode, "face ", f.idx(), " maps to node ", n,
               ", which is not a leaf owning that face");
    }
    if (leaves != m_.leaf_count || leaves != mesh_.n_faces() - count_deleted_faces())
      report("face-node-map", kNoNode, leaves, " leaves, leaf_count ", m_.leaf_count, ", ",
             mesh_.n_faces() - count_deleted_faces(), " faces");
  }

  std::size_t count_deleted_faces() const {
    if (!mesh_.has_face_status()) return 0;
    std::size_t deleted = 0;
    for (std::size_t i = 0; i < mesh_.n_faces(); ++i) deleted += mesh_.status(FaceHandle(static_cast<int>(i))).deleted();
    return deleted;
  }

  // A valid manifold half-edge structure: links agree, loops close, vertices are manifold.
  bool check_half_edges() {
    bool ok = true;
    const int nh = static_cast<int>(mesh_.n_halfedges());
    for (int i = 0; i < nh; ++i) {
      const HalfedgeHandle h(i);
      if (halfedge_deleted(h)) continue;
      const HalfedgeHandle next = mesh_.next_halfedge_handle(h), prev = mesh_.prev_halfedge_handle(h);
      if (!next.is_valid() || next.idx() >= nh || !prev.is_valid() || prev.idx() >= nh ||
          mesh_.prev_halfedge_handle(next) != h || mesh_.next_halfedge_handle(prev) != h ||
          mesh_.from_vertex_handle(next) != mesh_.to_vertex_handle(h) ||
          mesh_.face_handle(next) != mesh_.face_handle(h)) {
        const FaceHandle f = mesh_.face_handle(h);
        report("leaf-mesh-manifold", f.is_valid() ? mesh_.property(m_.face_node, f) : kNoNode, "halfedge ", i,
               ": next/prev links or faces disagree");
        ok = false;
      }
      if (mesh_.to_vertex_handle(h) == mesh_.from_vertex_handle(h)) {
        const FaceHandle f = mesh_.face_handle(h);
        report("leaf-mesh-manifold", f.is_valid() ? mesh_.property(m_.face_node, f) : kNoNode, "halfedge ", i,
               " starts and ends at vertex ", mesh_.to_vertex_handle(h).idx());
        ok = false;
      }
    }
    if (!ok) return false;
    std::vector<VertexHandle> loop;
    for (auto f : mesh_.faces()) {
      const NodeId n = mesh_.property(m_.face_node, f);
      if (!loop_of(f, loop) || loop.size() < 3) {
        report("leaf-mesh-manifold", n, "face ", f.idx(), " has no closed loop of at least 3 vertices");
        ok = false;
        continue;
      }
      std::sort(loop.begin(), loop.end());
      if (std::adjacent_find(loop.begin(), loop.end()) != loop.end()) {
        report("leaf-mesh-manifold", n, "face ", f.idx(), " visits a vertex twice");
        ok = false;
      }
    }
    if (!ok) return false;
    for (auto v : mesh_.vertices()) {
      // The circulator starts from the vertex's own link: it must leave v, or the fan walked is another vertex's.
      const HalfedgeHandle link = mesh_.halfedge_handle(v);
      if (link.is_valid() && (link.idx() >= nh || halfedge_deleted(link) || mesh_.from_vertex_handle(link) != v)) {
        report("leaf-mesh-manifold", kNoNode, "vertex ", v.idx(), " links halfedge ", link.idx(),
               ", which does not leave it");
        ok = false;
        continue;
      }
      std::size_t boundary_out = 0, out = 0;
      for (auto h : mesh_.voh_range(v)) {
        boundary_out += h.is_boundary();
        if (++out > mesh_.n_halfedges()) break;
      }
      if (boundary_out > 1 || out == 0) {
        report("leaf-mesh-manifold", kNoNode, "vertex ", v.idx(), out == 0 ? " is isolated" : " is not manifold (",
               boundary_out, out == 0 ? "" : " boundary gaps)");
        ok = false;
      } else if (boundary_out == 1 && !mesh_.is_boundary(link)) {
        // OpenMesh's is_boundary(v) and its boundary walks read only this link.
        report("leaf-mesh-manifold", kNoNode, "boundary vertex ", v.idx(), " links inner halfedge ", link.idx(),
               ", not its boundary halfedge");
        ok = false;
      }
    }
    return ok;
  }

  // No crack: every boundary halfedge lies on the initial outer boundary of its surface, and that boundary's
  // length is unchanged. Across every inner edge both faces belong to one surface.
  void check_boundary() {
    const std::vector<std::uint8_t> on_boundary = boundary_halfedges_on_segments();
    std::vector<double> length(m_.boundaries.size(), 0.0);
    for (auto h : mesh_.halfedges()) {
      if (halfedge_deleted(h)) continue;
      const FaceHandle inner = mesh_.face_handle(h.opp());
      if (!h.is_boundary()) {
        if (inner.is_valid()) {
          const NodeId a = mesh_.property(m_.face_node, h.face()), b = mesh_.property(m_.face_node, inner);
          if (valid_node(a) && valid_node(b) && m_.surface[a] != m_.surface[b])
            report("surface-component", a, "leaves ", a, " and ", b, " share an edge but lie on surfaces ",
                   m_.surface[a], " and ", m_.surface[b]);
        }
        continue;
      }
      if (!inner.is_valid()) {
        report("no-crack", kNoNode, "edge ", h.edge().idx(), " has no face on either side");
        continue;
      }
      const NodeId n = mesh_.property(m_.face_node, inner);
      if (!valid_node(n) || m_.surface[n] >= m_.boundaries.size()) continue;
      const std::uint32_t s = m_.surface[n];
      const Vec3 a = point(h.from()), b = point(h.to());
      length[s] += glm::length(b - a);
      if (on_boundary[static_cast<std::size_t>(h.idx())] == 0)
        report("no-crack", n, "leaf ", n, " has an open edge (", a.x, ", ", a.y, ", ", a.z, ") - (", b.x, ", ", b.y,
               ", ", b.z, ") inside surface ", s, ": a crack");
    }
    for (std::size_t s = 0; s < length.size(); ++s)
      if (std::abs(length[s] - m_.boundaries[s].length) > 1e-9 * m_.boundaries[s].length)
        report("outer-boundary", kNoNode, "surface ", s, " has outer boundary length ", length[s], ", initially ",
               m_.boundaries[s].length);
  }

  // Per halfedge, 1 when it is a boundary halfedge of a leaf whose ends lie on one segment of its surface's initial
  // boundary (on_segment). Trying every segment of the surface for every boundary halfedge was quadratic in a
  // surface with many holes (a floor meshed around 4 096 box footprints: 16 000 segments, 0.7 s). The pairs are
  // found by intersecting boxes instead (CGAL's box_intersection_d, as Scene::coplanar_overlaps): both ends of a
  // halfedge on a segment lie within twice the length tolerance of the segment's bounding box (within the
  // tolerance of a point of the segment extended by the tolerance at each end), so the halfedge's box meets the
  // segment's grown by four times the tolerance, far more than the rounding of on_segment. The fourth dimension
  // keeps surfaces apart. Halfedges and segments with a coordinate that is not finite are tried one by one, as
  // before (on_segment is false for them, but a box of them is not a box). So are the halfedges of a surface of
  // at most kFewSegments segments, the usual case: at two boxes of 80 bytes and CGAL's copies per halfedge, boxing
  // them took 219 MB for a 298 765-face sphere (a surface per pair of faces, heaptrack) and was slower.
  std::vector<std::uint8_t> boundary_halfedges_on_segments() const {
    constexpr std::size_t kFewSegments = 16;
    using SegmentBox = CGAL::Box_intersection_d::Box_with_info_d<double, 4, std::uint32_t>;
    std::vector<std::uint8_t> on(mesh_.n_halfedges(), 0);
    const auto finite = [](const Vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); };
    const auto box = [](const Vec3& low, const Vec3& high, std::uint32_t surface, std::uint32_t info) {
      double lo[4] = {low.x, low.y, low.z, surface - 0.25};
      double hi[4] = {high.x, high.y, high.z, surface + 0.25};
      return SegmentBox(lo, hi, info);
    };
    struct SegmentRef {
      std::uint32_t surface, index;
    };
    std::vector<SegmentRef> segments;
    std::vector<SegmentBox> segment_boxes;
    std::vector<std::uint8_t> unboxed_segments(m_.boundaries.size(), 0);  // per surface: few, or one not finite
    const double margin = 4.0 * length_tolerance_;
    for (std::uint32_t s = 0; s < m_.boundaries.size(); ++s) {
      if (m_.boundaries[s].segments.size() <= kFewSegments) unboxed_segments[s] = 1;
      for (std::uint32_t k = 0; k < m_.boundaries[s].segments.size() && unboxed_segments[s] == 0; ++k) {
        const auto& seg = m_.boundaries[s].segments[k];
        if (!finite(seg[0]) || !finite(seg[1])) {
          unboxed_segments[s] = 1;
          continue;
        }
        segment_boxes.push_back(box(glm::min(seg[0], seg[1]) - Vec3(margin), glm::max(seg[0], seg[1]) + Vec3(margin),
                                    s, static_cast<std::uint32_t>(segments.size())));
        segments.push_back({s, k});
      }
    }
    std::vector<SegmentBox> halfedge_boxes;
    const auto try_every_segment = [&](HalfedgeHandle h, std::uint32_t s) {
      const Vec3 a = point(mesh_.from_vertex_handle(h)), b = point(mesh_.to_vertex_handle(h));
      on[static_cast<std::size_t>(h.idx())] =
          std::any_of(m_.boundaries[s].segments.begin(), m_.boundaries[s].segments.end(),
                      [&](const auto& seg) { return on_segment(a, seg) && on_segment(b, seg); });
    };
    for (auto h : mesh_.halfedges()) {
      if (halfedge_deleted(h) || !h.is_boundary()) continue;
      const FaceHandle inner = mesh_.face_handle(h.opp());
      if (!inner.is_valid()) continue;
      const NodeId n = mesh_.property(m_.face_node, inner);
      if (!valid_node(n) || m_.surface[n] >= m_.boundaries.size()) continue;
      const std::uint32_t s = m_.surface[n];
      const Vec3 a = point(h.from()), b = point(h.to());
      if (!finite(a) || !finite(b) || unboxed_segments[s] != 0) {
        try_every_segment(h, s);
        continue;
      }
      halfedge_boxes.push_back(box(glm::min(a, b), glm::max(a, b), s, static_cast<std::uint32_t>(h.idx())));
    }
    CGAL::box_intersection_d(segment_boxes.begin(), segment_boxes.end(), halfedge_boxes.begin(), halfedge_boxes.end(),
                             [&](const SegmentBox& segment, const SegmentBox& halfedge) {
                               std::uint8_t& flag = on[halfedge.info()];
                               if (flag != 0) return;
                               const SegmentRef ref = segments[segment.info()];
                               const auto& seg = m_.boundaries[ref.surface].segments[ref.index];
                               const HalfedgeHandle h(static_cast<int>(halfedge.info()));
                               flag = on_segment(point(mesh_.from_vertex_handle(h)), seg) &&
                                      on_segment(point(mesh_.to_vertex_handle(h)), seg);
                             });
    return on;
  }

  bool on_segment(const Vec3& p, const std::array<Vec3, 2>& seg) const {
    const Vec3 d = seg[1] - seg[0];
    const double t = glm::dot(p - seg[0], d) / glm::dot(d, d);
    const double slack = length_tolerance_ / glm::length(d);
    return t >= -slack && t <= 1.0 + slack && glm::length(seg[0] + t * d - p) <= length_tolerance_;
  }

  // Calls visit(leaf, vertex, k, a, b) for every vertex on the face loop of every leaf that is not one of its
  // corners: a hanging vertex, between corners k and k + 1, vertex indices a and b (its host edge).
  template <class Visit>
  void for_each_hanging_vertex(Visit&& visit) const {
    std::vector<VertexHandle> loop;
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      if (!h_.is_leaf(n) || m_.face[n] < 0 || !loop_of(FaceHandle(m_.face[n]), loop)) continue;
      const int corners = m_.corner_count(n);
      const auto first = std::find(loop.begin(), loop.end(), VertexHandle(m_.corners[n][0]));
      if (first == loop.end()) continue;  // reported by check_face_map
      std::rotate(loop.begin(), first, loop.end());
      int k = 0;
      for (std::size_t i = 1; i < loop.size(); ++i) {
        const int a = m_.corners[n][static_cast<std::size_t>(k)];
        const int b = m_.corners[n][static_cast<std::size_t>((k + 1) % corners)];
        if (loop[i].idx() == b) {
          k = (k + 1) % corners;
          continue;
        }
        visit(n, loop[i], k, a, b);
      }
    }
  }

  // The parameter of point p along the edge from vertex a to vertex b.
  double edge_parameter(const Vec3& p, int a, int b) const {
    const Vec3 pa = m_.point(a), edge = m_.point(b) - pa;
    return glm::dot(p - pa, edge) / glm::dot(edge, edge);
  }

  // Between two consecutive corners of a leaf, the other loop vertices lie on the straight edge, in order.
  void check_hanging_vertices() {
    NodeId last_leaf = kNoNode;
    int last_edge = -1;
    double last_t = 0.0;
    for_each_hanging_vertex([&](NodeId n, VertexHandle v, int k, int a, int b) {
      if (n != last_leaf || k != last_edge) last_t = 0.0;  // the first on this edge
      last_leaf = n;
      last_edge = k;
      const Vec3 p = point(v);
      const double t = edge_parameter(p, a, b);
      const double off = glm::length(m_.point(a) + t * (m_.point(b) - m_.point(a)) - p);
      if (off > length_tolerance_ || t <= last_t || t >= 1.0)
        report("hanging-vertex-on-edge", n, "vertex ", v.idx(), " of leaf ", n, " lies at parameter ", t,
               " and distance ", off, " from its host edge (corners ", k, " and ", (k + 1) % m_.corner_count(n), ")");
      last_t = t;
    });
  }

  // The display mesh's first vertices are the leaf mesh's, at the same points, each with a value.
  bool check_display_positions(const DisplayMesh& d) {
    const std::size_t vertices = mesh_.n_vertices();
    if (d.positions.size() < vertices || d.vertex_values.size() != d.positions.size() ||
        d.triangle_leaf.size() != d.triangles.size()) {
      report("display-positions", kNoNode, "the display mesh has ", d.positions.size(), " positions, ",
             d.vertex_values.size(), " values and ", d.triangles.size(), " triangles for ", d.triangle_leaf.size(),
             " leaves, for a leaf mesh of ", vertices, " vertices");
      return false;
    }
    for (VertexHandle v : mesh_.vertices())
      if (d.positions[static_cast<std::size_t>(v.idx())] != point(v))
        report("display-positions", kNoNode, "display vertex ", v.idx(), " is not at leaf-mesh vertex ", v.idx());
    for (const auto& triangle : d.triangles)
      for (const std::uint32_t index : triangle)
        if (index >= d.positions.size()) {
          report("display-positions", kNoNode, "a triangle names vertex ", index, " of ", d.positions.size());
          return false;
        }
    return true;
  }

  // Every hanging vertex shows the linear interpolation of its host edge's ends, so no shading seam appears.
  void check_display_hanging_vertices(const DisplayMesh& d) {
    for_each_hanging_vertex([&](NodeId n, VertexHandle v, int, int a, int b) {
      const double t = edge_parameter(point(v), a, b);
      const Rgb& va = d.vertex_values[static_cast<std::size_t>(a)];
      const Rgb& vb = d.vertex_values[static_cast<std::size_t>(b)];
      const Rgb& value = d.vertex_values[static_cast<std::size_t>(v.idx())];
      for (int ch = 0; ch < 3; ++ch) {
        const double expected = va[ch] * (1.0 - t) + vb[ch] * t;
        const double scale = std::max(std::abs(va[ch]), std::abs(vb[ch]));
        if (!(std::abs(value[ch] - expected) <= kRadiosityTolerance * scale))
          report("display-hanging-vertex", n, "hanging vertex ", v.idx(), " of leaf ", n, " shows ", value[ch],
                 " in channel ", ch, ", not ", expected, " between vertices ", a, " and ", b, " (t = ", t, ")");
      }
    });
  }

  // Each leaf's triangles cover its area, and no directed edge appears twice: the triangles tile the leaves with
  // no crack (a crack leaves a leaf's area short) and no overlap (two triangles on one side of an edge).
  void check_display_triangles(const DisplayMesh& d) {
    std::vector<double> covered(m_.parent.size(), 0.0), perimeter(m_.parent.size(), 0.0);
    std::vector<std::array<std::uint32_t, 2>> edges;
    edges.reserve(3 * d.triangles.size());
    for (std::size_t t = 0; t < d.triangles.size(); ++t) {
      const NodeId leaf = d.triangle_leaf[t];
      const auto& tri = d.triangles[t];
      if (!valid_node(leaf) || !h_.is_leaf(leaf)) {
        report("display-crack-free", valid_node(leaf) ? leaf : kNoNode, "triangle ", t, " belongs to node ", leaf,
               ", not a leaf");
        continue;
      }
      const std::array<Vec3, 3> p{d.positions[tri[0]], d.positions[tri[1]], d.positions[tri[2]]};
      covered[leaf] += aarad::area(p);
      perimeter[leaf] += Checker::perimeter(p);
      for (int k = 0; k < 3; ++k) edges.push_back({tri[static_cast<std::size_t>(k)], tri[static_cast<std::size_t>((k + 1) % 3)]});
    }
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      if (!h_.is_leaf(n)) continue;
      if (!(std::abs(covered[n] - m_.area[n]) <= area_tolerance(m_.area[n], perimeter[n])))
        report("display-crack-free", n, "the triangles of leaf ", n, " cover ", covered[n], " of its area ", m_.area[n]);
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 1; i < edges.size(); ++i)
      if (edges[i] == edges[i - 1])
        report("display-crack-free", kNoNode, "display edge ", edges[i][0], " -> ", edges[i][1],
               " belongs to two triangles on the same side");
  }

  void check_balance() {
    std::vector<NodeId> neighbours;
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      if (!h_.is_leaf(n) || m_.face[n] < 0) continue;
      h_.edge_neighbours(n, neighbours);
      for (NodeId nb : neighbours)
        if (valid_node(nb) && m_.level[nb] + 1 < m_.level[n])
          report("balance", n, "leaf ", n, " of level ", int(m_.level[n]), " borders leaf ", nb, " of level ",
                 int(m_.level[nb]));
    }
  }

  // Children tile their parent: areas sum, corners in the parent's plane and inside it, counter-clockwise
  // like it, no two children overlap (separating-axis test on the convex children).
  void check_tiling() {
    allowed_area_error_.assign(m_.parent.size(), 0.0);
    std::vector<Vec3> parent_corners, child_corners;
    std::vector<std::vector<Vec2>> children_2d;
    std::vector<NodeId> child_nodes;  // the node of each entry of children_2d
    std::vector<Vec2> parent_2d;
    for (NodeId n = 0; n < m_.parent.size(); ++n) {
      h_.corners(n, parent_corners);
      const double stored = m_.area[n], actual = aarad::area(parent_corners);
      const double parent_perimeter = perimeter(parent_corners);
      if (std::abs(stored - actual) > area_tolerance(actual, parent_perimeter))
        report("children-tile-parent", n, "node ", n, " stores area ", stored, " but its corners span ", actual);
      const auto children = h_.children(n);
      if (children.empty()) continue;
      const Plane plane = plane_of(parent_corners);
      parent_2d.resize(parent_corners.size());
      project_to_2d(parent_corners, plane.normal, parent_2d);
      double sum = 0.0, perimeters = parent_perimeter;
      children_2d.clear();
      child_nodes.clear();
      for (NodeId c : children) {
        if (!valid_node(c)) continue;
        h_.corners(c, child_corners);
        sum += aarad::area(child_corners);
        perimeters += perimeter(child_corners);
        if (glm::dot(vector_area(child_corners), plane.normal) <= 0.0)
          report("children-tile-parent", c, "child ", c, " of node ", n, " is not counter-clockwise like its parent");
        for (const Vec3& p : child_corners)
          if (std::abs(plane.signed_distance(p)) > length_tolerance_)
            report("children-tile-parent", c, "a corner of child ", c, " lies ", plane.signed_distance(p),
                   " off the plane of node ", n);
        child_nodes.push_back(c);
        children_2d.emplace_back(child_corners.size());
        project_to_2d(child_corners, plane.normal, children_2d.back());
        for (const Vec2& p : children_2d.back())
          if (outside(parent_2d, p))
            report("children-tile-parent", c, "a corner of child ", c, " lies outside node ", n);
      }
      allowed_area_error_[n] = area_tolerance(m_.area[n], perimeters) / m_.area[n];
      if (std::abs(sum - m_.area[n]) > area_tolerance(m_.area[n], perimeters))
        report("children-tile-parent", n, "children of node ", n, " cover ", sum, " of its area ", m_.area[n],
               " (relative ", (sum - m_.area[n]) / m_.area[n], ")");
      check_children_disjoint(n, child_nodes, children_2d);
    }
  }

  // No two of a node's children overlap. Pairs are swept by the left ends of their x ranges (a patch can have
  // thousands of initial elements). A pair that a shift of less than half the tolerance along x or y would pull
  // apart is skipped: the overlap test measures penetration along edge normals, and for convex polygons the least
  // of those is the shortest shift that separates them, in any direction, so it would call the pair separated too.
  void check_children_disjoint(NodeId parent, const std::vector<NodeId>& nodes,
                               const std::vector<std::vector<Vec2>>& polygons) {
    const double slack = 0.5 * length_tolerance_;
    boxes_.clear();
    for (const std::vector<Vec2>& polygon : polygons) {
      Box box{polygon.front(), polygon.front()};
      for (const Vec2& p : polygon) {
        box.low = glm::min(box.low, p);
        box.high = glm::max(box.high, p);
      }
      boxes_.push_back(box);
    }
    order_.resize(polygons.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
    std::sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
      return boxes_[a].low.x < boxes_[b].low.x || (boxes_[a].low.x == boxes_[b].low.x && a < b);
    });
    for (std::size_t a = 0; a < order_.size(); ++a) {
      const Box& first = boxes_[order_[a]];
      for (std::size_t b = a + 1; b < order_.size(); ++b) {
        const Box& second = boxes_[order_[b]];
        if (first.high.x - second.low.x < slack) break;  // nor any later child
        if (std::min(first.high.y - second.low.y, second.high.y - first.low.y) < slack) continue;
        if (overlap(polygons[order_[a]], polygons[order_[b]])) {
          const NodeId x = nodes[order_[a]], y = nodes[order_[b]];
          report("children-tile-parent", std::min(x, y), "children ", std::min(x, y), " and ", std::max(x, y),
                 " of node ", parent, " overlap");
        }
      }
    }
  }

  // Outside a convex counter-clockwise polygon by more than the length tolerance.
  bool outside(const std::vector<Vec2>& polygon, const Vec2& p) const {
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      const Vec2 a = polygon[i], b = polygon[(i + 1) % polygon.size()];
      const Vec2 d = b - a;
      if ((d.x * (p.y - a.y) - d.y * (p.x - a.x)) / glm::length(d) < -length_tolerance_) return true;
    }
    return false;
  }

  // Two convex polygons overlap when no edge normal of either separates them by more than the tolerance.
  bool overlap(const std::vector<Vec2>& a, const std::vector<Vec2>& b) const {
    auto separated_by_edges_of = [&](const std::vector<Vec2>& p, const std::vector<Vec2>& q) {
      for (std::size_t i = 0; i < p.size(); ++i) {
        const Vec2 d = p[(i + 1) % p.size()] - p[i];
        const Vec2 normal = Vec2(d.y, -d.x) / glm::length(d);  // outward for counter-clockwise p
        double p_max = -std::numeric_limits<double>::infinity(), q_min = std::numeric_limits<double>::infinity();
        for (const Vec2& v : p) p_max = std::max(p_max, glm::dot(v, normal));
        for (const Vec2& v : q) q_min = std::min(q_min, glm::dot(v, normal));
        if (q_min >= p_max - length_tolerance_) return true;
      }
      return false;
    };
    return !separated_by_edges_of(a, b) && !separated_by_edges_of(b, a);
  }

  // Every inner node's B is the area-weighted mean of the B of the leaves below it. The hierarchy weighs an
  // inner child by its stored area, which may differ from the sum of its leaves' areas by the position error
  // (check_tiling); `slack` bounds what those differences below a node move its mean, relative to the largest
  // |B| of its leaves (`peak`). A difference is counted up to what check_tiling allows (`allowed`, summed down
  // the levels): a wrong stored area, reported there, does not also hide a wrong mean above it.
  void check_radiosity() {
    const std::size_t count = m_.parent.size();
    std::vector<Rgb> weighted(count);
    std::vector<double> area(count, 0.0), slack(count, 0.0), peak(count, 0.0), allowed(count, 0.0);
    for (std::size_t i = count; i-- > 0;) {  // children have larger ids than their parent
      const auto n = static_cast<NodeId>(i);
      double weight_error = 0.0;  // of n as its parent's child: |stored area - its leaves' area|, relative
      if (h_.is_leaf(n)) {
        weighted[n] = m_.radiosity[n] * m_.area[n];
        area[n] = m_.area[n];
        peak[n] = std::max({std::abs(m_.radiosity[n].r), std::abs(m_.radiosity[n].g), std::abs(m_.radiosity[n].b)});
      } else {
        allowed[n] += allowed_area_error_[n];
        weight_error = std::min(std::abs(m_.area[n] - area[n]) / area[n], allowed[n]);
        // Hierarchy::add_radiosity divides by n's own stored area, not its leaves' sum: that difference moves
        // n's mean too.
        const double tolerance = 2.0 * slack[n] * peak[n] + weight_error * peak[n];
        const Rgb mean = weighted[n] / area[n];
        const Rgb& b = m_.radiosity[n];
        for (int ch = 0; ch < 3; ++ch) {
          const double scale = std::max(std::abs(b[ch]), std::abs(mean[ch]));
          if (!(std::abs(b[ch] - mean[ch]) <= kRadiosityTolerance * scale + tolerance))
            report("radiosity-mean", n, "node ", n, " has B[", ch, "] = ", b[ch], " but its leaves average ", mean[ch],
                   std::isfinite(mean[ch]) ? "" : " (no leaf below it reaches it)");
        }
      }
      const NodeId p = m_.parent[n];
      if (p != kNoNode && valid_node(p) && p < n) {
        weighted[p] += weighted[n];
        area[p] += area[n];
        slack[p] = std::max(slack[p], slack[n] + weight_error);
        allowed[p] = std::max(allowed[p], allowed[n]);
        peak[p] = std::max(peak[p], peak[n]);
      }
    }
  }

  const Hierarchy& h_;
  const Hierarchy::Impl& m_;
  const LeafMesh& mesh_;
  double length_tolerance_ = 0.0;
  double position_error_ = 0.0;
  std::vector<double> allowed_area_error_;  // per node, from check_tiling: relative
  std::vector<Violation> violations_;
  // Scratch of check_tiling: the 2D bounding box of every child of one node, and their sweep order.
  struct Box {
    Vec2 low, high;
  };
  std::vector<Box> boxes_;
  std::vector<std::size_t> order_;
};

}  // namespace

std::vector<Violation> check_invariants(const Hierarchy& hierarchy) { return Checker(hierarchy).run(); }

std::vector<Violation> check_display(const Hierarchy& hierarchy, const DisplayMesh& display) {
  return Checker(hierarchy).run_display(display);
}

}  // namespace aarad::mesh
