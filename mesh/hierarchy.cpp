// The patch/element hierarchy: initial meshing into one OpenMesh PolyMesh, 1-to-4 splits with hanging (T-)
// vertices, optional 2:1 balance, and neighbour queries.
// Substructuring after Cohen, Greenberg, Immel and Brock 1986 ("An efficient radiosity approach for realistic
// image synthesis", section 3); T-vertex handling as in Baum, Mann, Smith and Winget 1991 ("Making radiosity
// usable: automatic preprocessing and meshing techniques for the generation of accurate radiosity solutions",
// section 4: an unrefined neighbour keeps the new vertex on its edge; balanced subdivision keeps neighbours
// within one level). The choices (no deletion, child order, defaults) are in docs/hierarchy.md.
#include "aarad/mesh/hierarchy.h"

#include "aarad/core/error.h"
#include "aarad/core/polygon.h"
#include "aarad/mesh/initial_meshing.h"
#include "aarad/mesh/leaf_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <string>
#include <utility>

namespace aarad::mesh {
namespace {

using VertexHandle = LeafMesh::VertexHandle;
using HalfedgeHandle = LeafMesh::HalfedgeHandle;
using FaceHandle = LeafMesh::FaceHandle;

// The boundary of a freshly meshed surface as maximal straight segments. The surface's vertices are
// [first_vertex, end_vertex) and its halfedges [first_halfedge, n_halfedges()): both were added last, so `visited`
// covers this surface's halfedges only (one array as long as the whole mesh, per surface, made a million-face
// scene quadratic).
SurfaceBoundary boundary_of(const LeafMesh& mesh, int first_vertex, int end_vertex, int first_halfedge) {
  SurfaceBoundary boundary;
  std::vector<char> visited(mesh.n_halfedges() - static_cast<std::size_t>(first_halfedge), 0);
  auto seen = [&](HalfedgeHandle e) -> char& { return visited[static_cast<std::size_t>(e.idx() - first_halfedge)]; };
  for (int vi = first_vertex; vi < end_vertex; ++vi)
    for (auto h : mesh.voh_range(VertexHandle(vi))) {
      if (!h.is_boundary() || seen(h)) continue;
      // Walk the loop, starting right after a corner (a direction change) so segments are maximal.
      auto direction = [&](HalfedgeHandle e) {
        return to_vec3(mesh.point(mesh.to_vertex_handle(e)) - mesh.point(mesh.from_vertex_handle(e)));
      };
      auto straight = [&](HalfedgeHandle a, HalfedgeHandle b) {
        const Vec3 da = direction(a), db = direction(b);
        return glm::dot(da, db) > 0.0 &&
               glm::length(glm::cross(da, db)) <= 1e-12 * glm::length(da) * glm::length(db);
      };
      HalfedgeHandle start = h;
      for (HalfedgeHandle e = mesh.prev_halfedge_handle(start); e != h; e = mesh.prev_halfedge_handle(e)) {
        if (!straight(e, start)) break;
        start = e;
      }
      HalfedgeHandle e = start;
      Vec3 segment_start = to_vec3(mesh.point(mesh.from_vertex_handle(start)));
      do {
        seen(e) = 1;
        boundary.length += glm::length(direction(e));
        const HalfedgeHandle next = mesh.next_halfedge_handle(e);
        if (!straight(e, next) || next == start) {
          const Vec3 end = to_vec3(mesh.point(mesh.to_vertex_handle(e)));
          boundary.segments.push_back({segment_start, end});
          segment_start = end;
        }
        e = next;
      } while (e != start);
    }
  return boundary;
}

// The halfedge of face f's loop that ends at v (in) or starts at v (out).
HalfedgeHandle halfedge_into(const LeafMesh& mesh, FaceHandle f, VertexHandle v) {
  for (auto h : mesh.fh_range(f))
    if (h.to() == v) return h;
  return HalfedgeHandle();
}
HalfedgeHandle halfedge_out_of(const LeafMesh& mesh, FaceHandle f, VertexHandle v) {
  for (auto h : mesh.fh_range(f))
    if (h.from() == v) return h;
  return HalfedgeHandle();
}

// Calls visit(v) for every vertex v of the leaf's face loop, counter-clockwise from its first corner.
template <class Visit>
void walk_leaf_loop(const Hierarchy::Impl& m, NodeId leaf, Visit&& visit) {
  const LeafMesh& mesh = m.mesh;
  const HalfedgeHandle first = halfedge_out_of(mesh, FaceHandle(m.face[leaf]), VertexHandle(m.corners[leaf][0]));
  HalfedgeHandle h = first;
  do {
    visit(mesh.from_vertex_handle(h));
    h = mesh.next_halfedge_handle(h);
  } while (h != first);
}

// Splits face f along a new edge a -> b (both on its loop); the new face holds a -> b and the old loop from b
// back to a, f keeps b -> a and the old loop from a to b. Returns the halfedge a -> b.
HalfedgeHandle connect(LeafMesh& mesh, FaceHandle f, VertexHandle a, VertexHandle b) {
  return mesh.insert_edge(halfedge_into(mesh, f, a), halfedge_out_of(mesh, f, b));
}

// The midpoint of the edge from corner a (the loop halfedge `out_of_a` leaves it) to corner b of one face:
// reused when a neighbour already put it on the loop (the same expression 0.5 (a + b) gives the same bits
// from both sides), else a new vertex inserted into the loop piece that contains it, which makes it a
// hanging vertex of the face across that piece: `gained` is that face (invalid when the midpoint was reused or
// the piece lies on the boundary).
VertexHandle midpoint_on_chain(LeafMesh& mesh, HalfedgeHandle out_of_a, VertexHandle b, FaceHandle& gained) {
  gained = FaceHandle();
  const VertexHandle a = mesh.from_vertex_handle(out_of_a);
  const OpenMesh::Vec3d pa = mesh.point(a), pb = mesh.point(b);
  const OpenMesh::Vec3d mid = 0.5 * (pa + pb);
  for (HalfedgeHandle h = out_of_a; mesh.to_vertex_handle(h) != b; h = mesh.next_halfedge_handle(h))
    if (mesh.point(mesh.to_vertex_handle(h)) == mid) return mesh.to_vertex_handle(h);
  const OpenMesh::Vec3d d = pb - pa;
  const double dd = OpenMesh::dot(d, d);
  HalfedgeHandle h = out_of_a;
  while (mesh.to_vertex_handle(h) != b &&
         OpenMesh::dot(mesh.point(mesh.to_vertex_handle(h)) - pa, d) / dd < 0.5)
    h = mesh.next_halfedge_handle(h);
  gained = mesh.opposite_face_handle(h);
  const VertexHandle m = mesh.add_vertex(mid);
  mesh.split_edge(mesh.edge_handle(h), m);
  return m;
}

// Faces of one surface that touch at a single point (two tiles of a checkerboard's colour meeting at a corner) share
// that point as one vertex, and OpenMesh links their fans into a complex vertex: a vertex with two boundary gaps,
// which the leaf mesh's invariant (leaf-mesh-manifold) forbids. Each fan of elements around such a point after the
// first gets a copy of the point instead, as the two fans share no edge. A patch's corner follows its elements.
void separate_pinched_fans(SurfaceMeshing& meshing) {
  // Incidences (element, corner slot) joined across every edge two elements share, at both of its ends.
  std::vector<std::pair<std::size_t, std::size_t>> element_of;  // flat element index -> (patch, element)
  for (std::size_t p = 0; p < meshing.elements.size(); ++p)
    for (std::size_t e = 0; e < meshing.elements[p].size(); ++e) element_of.emplace_back(p, e);
  const auto corners_of = [&](std::size_t flat) -> CornerIndices& {
    return meshing.elements[element_of[flat].first][element_of[flat].second];
  };
  const auto count = [](const CornerIndices& c) { return c[3] < 0 ? 3 : 4; };
  std::vector<std::size_t> root(element_of.size() * 4);
  for (std::size_t i = 0; i < root.size(); ++i) root[i] = i;
  const auto find = [&](std::size_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  const auto join = [&](std::size_t a, std::size_t b) { root[find(a)] = find(b); };
  // Every directed edge a -> b with its incidence at a and at b; an undirected edge's two faces meet by its key.
  struct EdgeEnd {
    std::uint64_t key;
    std::size_t at_low, at_high;  // the incidences at the edge's lower and higher point index
  };
  std::vector<EdgeEnd> edges;
  for (std::size_t f = 0; f < element_of.size(); ++f) {
    const CornerIndices& c = corners_of(f);
    const int n = count(c);
    for (int k = 0; k < n; ++k) {
      const int a = c[static_cast<std::size_t>(k)], b = c[static_cast<std::size_t>((k + 1) % n)];
      const std::size_t ia = f * 4 + static_cast<std::size_t>(k), ib = f * 4 + static_cast<std::size_t>((k + 1) % n);
      const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
      edges.push_back({lo << 32 | hi, a < b ? ia : ib, a < b ? ib : ia});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const EdgeEnd& x, const EdgeEnd& y) { return x.key < y.key; });
  for (std::size_t i = 1; i < edges.size(); ++i) {
    if (edges[i].key != edges[i - 1].key) continue;
    join(edges[i].at_low, edges[i - 1].at_low);
    join(edges[i].at_high, edges[i - 1].at_high);
  }
  // The first fan of each point keeps it; each further fan gets a copy.
  std::vector<std::size_t> first_fan(meshing.points.size(), root.size());
  std::vector<std::pair<std::size_t, int>> copy_of_fan;  // (fan root, new point index), few
  for (std::size_t f = 0; f < element_of.size(); ++f) {
    CornerIndices& c = corners_of(f);
    for (int k = 0; k < count(c); ++k) {
      int& v = c[static_cast<std::size_t>(k)];
      const std::size_t fan = find(f * 4 + static_cast<std::size_t>(k));
      std::size_t& first = first_fan[static_cast<std::size_t>(v)];
      if (first == root.size()) first = fan;
      if (first == fan) continue;
      auto it = std::find_if(copy_of_fan.begin(), copy_of_fan.end(), [&](const auto& x) { return x.first == fan; });
      if (it == copy_of_fan.end()) {
        meshing.points.push_back(meshing.points[static_cast<std::size_t>(v)]);
        it = copy_of_fan.insert(copy_of_fan.end(), {fan, static_cast<int>(meshing.points.size() - 1)});
      }
      v = it->second;
    }
  }
  if (copy_of_fan.empty()) return;
  // A patch's corners are corners of its elements: each takes the index its elements use at that point.
  for (std::size_t p = 0; p < meshing.patches.size(); ++p) {
    CornerIndices& corners = meshing.patches[p];
    for (int k = 0; k < count(corners); ++k) {
      int& v = corners[static_cast<std::size_t>(k)];
      const Vec3 at = meshing.points[static_cast<std::size_t>(v)];
      for (const CornerIndices& e : meshing.elements[p])
        for (int j = 0; j < count(e); ++j) {
          const int corner = e[static_cast<std::size_t>(j)];
          if (meshing.points[static_cast<std::size_t>(corner)] == at) v = corner;
        }
    }
  }
}

}  // namespace

// --- Impl ---------------------------------------------------------------------------------------------------

NodeId Hierarchy::Impl::add_node(NodeId parent_id, int node_level, NodeId patch_id, std::uint32_t surface_id,
                                 const std::array<int, 4>& corner_vertices) {
  const auto id = static_cast<NodeId>(parent.size());
  parent.push_back(parent_id);
  child_begin.push_back(0);
  child_count.push_back(0);
  level.push_back(static_cast<std::uint8_t>(node_level));
  patch_of.push_back(patch_id == kNoNode ? id : patch_id);
  surface.push_back(surface_id);
  corners.push_back(corner_vertices);
  area.push_back(0.0);
  area.back() = corner_area(id);
  radiosity.emplace_back();
  unshot.emplace_back();
  face.push_back(-1);
  loop_revision.push_back(revision);
  return id;
}

namespace {

// Room for `extra` more elements in `v`, doubling as push_back would.
template <class T>
void make_room(std::vector<T>& v, std::size_t extra) {
  if (v.size() + extra > v.capacity()) v.reserve(std::max(v.size() + extra, 2 * v.capacity()));
}

}  // namespace

void Hierarchy::Impl::make_room_for_split() {
  make_room(parent, 4);
  make_room(child_begin, 4);
  make_room(child_count, 4);
  make_room(child_ids, 4);
  make_room(patch_of, 4);
  make_room(surface, 4);
  make_room(level, 4);
  make_room(corners, 4);
  make_room(area, 4);
  make_room(radiosity, 4);
  make_room(unshot, 4);
  make_room(face, 4);
  make_room(loop_revision, 4);
  // A split adds at most 5 vertices (4 edge midpoints and a quad's centre), 8 edges (4 edge halves and 4 cuts
  // inside the leaf) and 3 faces.
  const std::array<std::size_t, 3> needed{mesh.n_vertices() + 5, mesh.n_edges() + 8, mesh.n_faces() + 3};
  if (needed[0] > mesh_room[0] || needed[1] > mesh_room[1] || needed[2] > mesh_room[2]) {
    std::array<std::size_t, 3> room;
    for (std::size_t k = 0; k < 3; ++k) room[k] = std::max(needed[k], 2 * mesh_room[k]);
    mesh.reserve(room[0], room[1], room[2]);
    mesh_room = room;
  }
}

double Hierarchy::Impl::corner_area(NodeId node) const {
  std::array<Vec3, 4> p;
  const int n = corner_count(node);
  for (int k = 0; k < n; ++k) p[static_cast<std::size_t>(k)] = point(corners[node][static_cast<std::size_t>(k)]);
  return aarad::area(std::span<const Vec3>(p.data(), static_cast<std::size_t>(n)));
}

// --- Construction ---------------------------------------------------------------------------------------------

Hierarchy::Hierarchy(const Scene& scene, const MeshingOptions& options)
    : Hierarchy(std::make_shared<const Scene>(scene), options) {}

Hierarchy::Hierarchy(std::shared_ptr<const Scene> scene_ptr, const MeshingOptions& options)
    : impl_(std::make_unique<Impl>()) {
  if (!scene_ptr) throw Error("Hierarchy: no scene (a null pointer)");
  const Scene& scene = *scene_ptr;
  // Importers and built-ins validate their scenes; one built in code may not have been, and the initial meshing
  // crashes (in CGAL's mesher) on a face that validate() refuses, and meshes nothing without build_surfaces().
  scene.validate();
  Impl& m = *impl_;
  m.scene_ptr = std::move(scene_ptr);
  m.options = resolve_options(scene, options);
  m.mesh.add_property(m.face_node, "node");
  m.boundaries.resize(scene.surfaces.size());
  m.revision = 1;  // the initial leaves' loop_revision
  double made = 0.0;  // initial elements so far, against max_initial_elements
  const double diagonal = scene.diagonal();
  const std::vector<std::vector<ContactSegment>> contacts = find_contact_lines(scene, diagonal);
  for (std::uint32_t s = 0; s < scene.surfaces.size(); ++s) {
    const double limit = m.options.max_initial_elements;
    SurfaceMeshing meshing = mesh_surface(scene, s, m.options.patch_size, m.options.element_size, limit - made,
                                          limit, diagonal, contacts[s]);
    separate_pinched_fans(meshing);
    for (const auto& elements : meshing.elements) made += static_cast<double>(elements.size());
    const int base = static_cast<int>(m.mesh.n_vertices());
    const int first_halfedge = static_cast<int>(m.mesh.n_halfedges());
    for (const Vec3& p : meshing.points) m.mesh.add_vertex(to_point(p));
    auto shifted = [base](CornerIndices c) {
      for (int& i : c)
        if (i >= 0) i += base;
      return c;
    };
    for (std::size_t p = 0; p < meshing.patches.size(); ++p) {
      const NodeId patch = m.add_node(kNoNode, 0, kNoNode, s, shifted(meshing.patches[p]));
      m.patch_ids.push_back(patch);
      m.child_begin[patch] = static_cast<std::uint32_t>(m.child_ids.size());
      m.child_count[patch] = static_cast<std::uint32_t>(meshing.elements[p].size());
      for (const CornerIndices& element : meshing.elements[p]) {
        const CornerIndices c = shifted(element);
        const NodeId node = m.add_node(patch, 1, patch, s, c);
        m.child_ids.push_back(node);
        std::vector<VertexHandle> loop;
        for (int i : c)
          if (i >= 0) loop.emplace_back(i);
        const FaceHandle f = m.mesh.add_face(loop);
        if (!f.is_valid())
          throw Error("initial meshing: OpenMesh refused an element of surface " + std::to_string(s) + " (group '" +
                      scene.groups[scene.surfaces[s].group].name + "'): the surface overlaps itself");
        m.face[node] = f.idx();
        m.mesh.property(m.face_node, f) = node;
        ++m.leaf_count;
        ++m.initial_elements;
      }
    }
    m.boundaries[s] = boundary_of(m.mesh, base, static_cast<int>(m.mesh.n_vertices()), first_halfedge);
  }
}

Hierarchy::~Hierarchy() = default;
Hierarchy::Hierarchy(Hierarchy&&) noexcept = default;
Hierarchy& Hierarchy::operator=(Hierarchy&&) noexcept = default;

// --- Queries ----------------------------------------------------------------------------------------------------

// Only leaves have a face in the leaf mesh; an inner node's face index is -1.
void Hierarchy::require_leaf(NodeId node, const char* query) const {
  if (node >= impl_->parent.size() || impl_->face[node] < 0)
    throw Error(std::string("Hierarchy::") + query + ": node " + std::to_string(node) + " is not a leaf");
}

const Scene& Hierarchy::scene() const { return impl_->scene(); }
const MeshingOptions& Hierarchy::options() const { return impl_->options; }
std::size_t Hierarchy::node_count() const { return impl_->parent.size(); }
std::span<const NodeId> Hierarchy::patches() const { return impl_->patch_ids; }
NodeId Hierarchy::parent(NodeId node) const { return impl_->parent[node]; }
std::span<const NodeId> Hierarchy::children(NodeId node) const {
  return {impl_->child_ids.data() + impl_->child_begin[node], impl_->child_count[node]};
}
bool Hierarchy::is_leaf(NodeId node) const { return impl_->child_count[node] == 0; }
int Hierarchy::level(NodeId node) const { return impl_->level[node]; }
NodeId Hierarchy::patch(NodeId node) const { return impl_->patch_of[node]; }
std::uint32_t Hierarchy::surface(NodeId node) const { return impl_->surface[node]; }
double Hierarchy::area(NodeId node) const { return impl_->area[node]; }
const Plane& Hierarchy::plane(NodeId node) const { return impl_->scene().surfaces[impl_->surface[node]].plane; }
int Hierarchy::corner_count(NodeId node) const { return impl_->corner_count(node); }

void Hierarchy::corners(NodeId node, std::vector<Vec3>& out) const {
  out.clear();
  const int n = impl_->corner_count(node);
  for (int k = 0; k < n; ++k) out.push_back(impl_->point(impl_->corners[node][static_cast<std::size_t>(k)]));
}
std::array<std::uint32_t, 4> Hierarchy::corner_vertices(NodeId node) const {
  std::array<std::uint32_t, 4> ids{};
  const int n = impl_->corner_count(node);
  for (int k = 0; k < n; ++k) ids[static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(impl_->corners[node][static_cast<std::size_t>(k)]);
  return ids;
}
std::vector<Vec3> Hierarchy::corners(NodeId node) const {
  std::vector<Vec3> out;
  corners(node, out);
  return out;
}
Vec3 Hierarchy::centroid(NodeId node) const {
  std::array<Vec3, 4> p;
  const int n = impl_->corner_count(node);
  for (int k = 0; k < n; ++k) p[static_cast<std::size_t>(k)] = impl_->point(impl_->corners[node][static_cast<std::size_t>(k)]);
  return aarad::centroid(std::span<const Vec3>(p.data(), static_cast<std::size_t>(n)));
}
void Hierarchy::leaf_polygon(NodeId leaf, std::vector<Vec3>& out) const {
  require_leaf(leaf, "leaf_polygon");
  out.clear();
  walk_leaf_loop(*impl_, leaf, [&](VertexHandle v) { out.push_back(to_vec3(impl_->mesh.point(v))); });
}
void Hierarchy::leaf_polygon(NodeId leaf, std::vector<Vec3>& out, std::vector<std::uint32_t>& vertices) const {
  require_leaf(leaf, "leaf_polygon");
  out.clear();
  vertices.clear();
  walk_leaf_loop(*impl_, leaf, [&](VertexHandle v) {
    out.push_back(to_vec3(impl_->mesh.point(v)));
    vertices.push_back(static_cast<std::uint32_t>(v.idx()));
  });
}
std::uint64_t Hierarchy::loop_revision(NodeId leaf) const {
  require_leaf(leaf, "loop_revision");
  return impl_->loop_revision[leaf];
}

Rgb& Hierarchy::radiosity(NodeId node) { return impl_->radiosity[node]; }
const Rgb& Hierarchy::radiosity(NodeId node) const { return impl_->radiosity[node]; }
Rgb& Hierarchy::unshot(NodeId node) { return impl_->unshot[node]; }
const Rgb& Hierarchy::unshot(NodeId node) const { return impl_->unshot[node]; }
std::span<Rgb> Hierarchy::radiosities() { return impl_->radiosity; }
std::span<Rgb> Hierarchy::unshots() { return impl_->unshot; }
std::span<const Rgb> Hierarchy::radiosities() const { return impl_->radiosity; }
std::span<const Rgb> Hierarchy::unshots() const { return impl_->unshot; }

void Hierarchy::add_radiosity(NodeId leaf, const Rgb& delta) {
  require_leaf(leaf, "add_radiosity");
  Impl& m = *impl_;
  m.radiosity[leaf] += delta;
  for (NodeId a = m.parent[leaf]; a != kNoNode; a = m.parent[a]) m.radiosity[a] += delta * (m.area[leaf] / m.area[a]);
}

void Hierarchy::update_inner_radiosity() { average_inner_nodes(impl_->radiosity); }

void Hierarchy::average_inner_nodes(std::span<Rgb> values) const {
  const Impl& m = *impl_;
  for (std::size_t i = m.parent.size(); i-- > 0;) {  // children have larger ids than their parent
    const auto node = static_cast<NodeId>(i);
    if (m.child_count[node] == 0) continue;
    Rgb sum;
    double area = 0.0;
    for (NodeId c : children(node)) {
      sum += values[c] * m.area[c];
      area += m.area[c];
    }
    if (area > 0.0) values[node] = sum / area;
  }
}

std::vector<NodeId> Hierarchy::leaves() const {
  std::vector<NodeId> out;
  out.reserve(impl_->leaf_count);
  for (NodeId n = 0; n < impl_->parent.size(); ++n)
    if (impl_->child_count[n] == 0) out.push_back(n);
  return out;
}
std::size_t Hierarchy::leaf_count() const { return impl_->leaf_count; }

std::vector<NodeId> Hierarchy::leaves_under(NodeId node) const {
  std::vector<NodeId> out, stack;
  leaves_under(node, out, stack);
  return out;
}

void Hierarchy::leaves_under(NodeId node, std::vector<NodeId>& out, std::vector<NodeId>& stack) const {
  const std::size_t first = out.size();
  stack.assign(1, node);
  while (!stack.empty()) {
    const NodeId n = stack.back();
    stack.pop_back();
    if (is_leaf(n)) {
      out.push_back(n);
      continue;
    }
    const auto c = children(n);
    stack.insert(stack.end(), c.rbegin(), c.rend());
  }
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
}

std::uint64_t Hierarchy::revision() const { return impl_->revision; }
std::size_t Hierarchy::initial_element_count() const { return impl_->initial_elements; }

std::size_t Hierarchy::memory_bytes() const {
  const Impl& m = *impl_;
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  std::size_t total = bytes(m.parent) + bytes(m.child_begin) + bytes(m.child_count) + bytes(m.child_ids) +
                      bytes(m.level) + bytes(m.patch_of) + bytes(m.surface) + bytes(m.corners) + bytes(m.area) +
                      bytes(m.radiosity) + bytes(m.unshot) + bytes(m.face) + bytes(m.loop_revision) +
                      bytes(m.patch_ids);
  total += m.mesh.n_vertices() * (sizeof(LeafMesh::Vertex) + sizeof(LeafMesh::Point)) +
           m.mesh.n_edges() * sizeof(LeafMesh::Edge) + m.mesh.n_faces() * (sizeof(LeafMesh::Face) + sizeof(NodeId));
  return total;
}

void Hierarchy::edge_neighbours(NodeId node, std::vector<NodeId>& out) const {
  require_leaf(node, "edge_neighbours");
  out.clear();
  const LeafMesh& mesh = impl_->mesh;
  for (auto h : mesh.fh_range(FaceHandle(impl_->face[node]))) {
    const FaceHandle g = mesh.opposite_face_handle(h);
    if (!g.is_valid()) continue;
    const NodeId n = mesh.property(impl_->face_node, g);
    if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
  }
}
std::vector<NodeId> Hierarchy::edge_neighbours(NodeId node) const {
  std::vector<NodeId> out;
  edge_neighbours(node, out);
  return out;
}

// --- Splitting -----------------------------------------------------------------------------------------------

std::array<NodeId, 4> Hierarchy::split_leaf(NodeId node) {
  Impl& m = *impl_;
  // Every allocation first: out of memory in the middle of a split (the mesh cut, a node with four children not yet
  // added) left a hierarchy that crashed the solver's finish() (Solver::run keeps the solution so far readable).
  m.make_room_for_split();
  LeafMesh& mesh = m.mesh;
  ++m.revision;  // the children's and the neighbours' loop_revision
  const FaceHandle f(m.face[node]);
  const int n = m.corner_count(node);
  std::array<VertexHandle, 4> c, mid;
  for (int k = 0; k < n; ++k) c[static_cast<std::size_t>(k)] = VertexHandle(m.corners[node][static_cast<std::size_t>(k)]);
  for (int k = 0; k < n; ++k) {
    FaceHandle gained;
    mid[static_cast<std::size_t>(k)] = midpoint_on_chain(mesh, halfedge_out_of(mesh, f, c[static_cast<std::size_t>(k)]),
                                                         c[static_cast<std::size_t>((k + 1) % n)], gained);
    if (gained.is_valid()) m.loop_revision[mesh.property(m.face_node, gained)] = m.revision;
  }
  // The loop halfedge leaving each corner stays with the child at that corner through the edge insertions.
  std::array<HalfedgeHandle, 4> out_of_corner;
  for (int k = 0; k < n; ++k) out_of_corner[static_cast<std::size_t>(k)] = halfedge_out_of(mesh, f, c[static_cast<std::size_t>(k)]);

  std::array<std::array<int, 4>, 4> child_corners;
  std::array<FaceHandle, 4> child_face;
  if (n == 4) {
    const OpenMesh::Vec3d centre_point =
        0.25 * (mesh.point(c[0]) + mesh.point(c[1]) + mesh.point(c[2]) + mesh.point(c[3]));
    const VertexHandle centre = mesh.add_vertex(centre_point);
    const HalfedgeHandle across = connect(mesh, f, mid[0], mid[2]);  // f keeps the c1, c2 half
    const FaceHandle other = mesh.face_handle(across);               // the c3, c0 half
    mesh.split_edge(mesh.edge_handle(across), centre);
    connect(mesh, f, mid[1], centre);
    connect(mesh, other, mid[3], centre);
    for (int k = 0; k < 4; ++k) {
      child_corners[static_cast<std::size_t>(k)] = {c[static_cast<std::size_t>(k)].idx(), mid[static_cast<std::size_t>(k)].idx(),
                                                    centre.idx(), mid[static_cast<std::size_t>((k + 3) % 4)].idx()};
      child_face[static_cast<std::size_t>(k)] = mesh.face_handle(out_of_corner[static_cast<std::size_t>(k)]);
    }
  } else {
    const HalfedgeHandle h01 = connect(mesh, f, mid[0], mid[1]);  // f keeps corner 1
    const FaceHandle rest = mesh.face_handle(h01);
    const HalfedgeHandle h12 = connect(mesh, rest, mid[1], mid[2]);  // rest keeps corner 2
    const HalfedgeHandle h20 = connect(mesh, mesh.face_handle(h12), mid[2], mid[0]);
    for (int k = 0; k < 3; ++k) {
      child_corners[static_cast<std::size_t>(k)] = {c[static_cast<std::size_t>(k)].idx(), mid[static_cast<std::size_t>(k)].idx(),
                                                    mid[static_cast<std::size_t>((k + 2) % 3)].idx(), -1};
      child_face[static_cast<std::size_t>(k)] = mesh.face_handle(out_of_corner[static_cast<std::size_t>(k)]);
    }
    child_corners[3] = {mid[0].idx(), mid[1].idx(), mid[2].idx(), -1};
    child_face[3] = mesh.face_handle(h20);
  }

  std::array<NodeId, 4> ids;
  m.child_begin[node] = static_cast<std::uint32_t>(m.child_ids.size());
  m.child_count[node] = 4;
  m.face[node] = -1;
  for (int k = 0; k < 4; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    ids[ku] = m.add_node(node, m.level[node] + 1, m.patch_of[node], m.surface[node], child_corners[ku]);
    m.child_ids.push_back(ids[ku]);
    m.radiosity[ids[ku]] = m.radiosity[node];
    m.face[ids[ku]] = child_face[ku].idx();
    mesh.property(m.face_node, child_face[ku]) = ids[ku];
  }
  m.leaf_count += 3;
  return ids;
}

void Hierarchy::split_coarser_neighbours(NodeId node, std::vector<NodeId>& also_split) {
  std::vector<NodeId> neighbours;
  for (bool again = true; again;) {
    again = false;
    edge_neighbours(node, neighbours);
    for (NodeId nb : neighbours)
      if (impl_->level[nb] < impl_->level[node]) {
        split_coarser_neighbours(nb, also_split);
        split_leaf(nb);
        also_split.push_back(nb);
        again = true;
        break;
      }
  }
}

// In a balanced mesh a leaf's coarser edge-neighbours are one level coarser, and splitting one of them makes no
// new coarser neighbour for the leaf: the leaves split_coarser_neighbours splits are the coarser neighbours of the
// leaf, theirs, and so on, as the mesh stands before it starts.
void Hierarchy::forced_splits(NodeId node, std::vector<NodeId>& out) const {
  out.clear();
  if (!impl_->options.balance) return;
  std::vector<NodeId> neighbours;
  std::set<NodeId> seen{node};
  std::vector<NodeId> pending{node};
  while (!pending.empty()) {
    const NodeId at = pending.back();
    pending.pop_back();
    edge_neighbours(at, neighbours);
    for (const NodeId nb : neighbours) {
      if (impl_->level[nb] >= impl_->level[at] || !seen.insert(nb).second) continue;
      out.push_back(nb);
      pending.push_back(nb);
    }
  }
}

NodeId Hierarchy::balance_blocker(NodeId node, Refusal& why) const {
  std::vector<NodeId> forced;
  forced_splits(node, forced);
  for (const NodeId nb : forced) {
    double smallest = 0.0;
    why = refusal(nb, smallest);
    if (why != Refusal::kNone) return nb;
  }
  return kNoNode;
}

Hierarchy::Refusal Hierarchy::refusal(NodeId node, double& smallest) const {
  const Impl& m = *impl_;
  if (node >= node_count()) return Refusal::kMissing;
  if (!is_leaf(node)) return Refusal::kInner;
  if (m.level[node] >= m.options.max_level) return Refusal::kMaxLevel;
  // Children's areas from the corner positions the split will create (the same expressions).
  const int n = m.corner_count(node);
  std::array<Vec3, 4> c, mid;
  for (int k = 0; k < n; ++k) c[static_cast<std::size_t>(k)] = m.point(m.corners[node][static_cast<std::size_t>(k)]);
  for (int k = 0; k < n; ++k) mid[static_cast<std::size_t>(k)] = 0.5 * (c[static_cast<std::size_t>(k)] + c[static_cast<std::size_t>((k + 1) % n)]);
  // A leaf a few ulps across has children that floating point cannot hold: an edge midpoint rounds onto an end of
  // its edge (or the centre onto a midpoint), and a child gets two corners at one point and no area. With a tiny
  // min_area and max_level 60, splitting one corner's child over and over reached that at level 51 (zero-area
  // nodes, a hanging vertex on top of a corner, children turned clockwise: check_invariants found all three).
  bool degenerate = false;
  for (int k = 0; k < n; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    degenerate |= mid[ku] == c[ku] || mid[ku] == c[static_cast<std::size_t>((k + 1) % n)];
  }
  // The least child area as split() would make it, counted along the surface's normal: a child turned clockwise
  // by rounding counts as negative.
  const Vec3 normal = plane(node).normal;
  const auto made_area = [&](std::span<const Vec3> child) { return glm::dot(aarad::vector_area(child), normal); };
  double smallest_made = std::numeric_limits<double>::infinity();
  if (n == 4) {
    const Vec3 centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    smallest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 4; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      degenerate |= centre == mid[ku];
      const std::array<Vec3, 4> q{c[ku], mid[ku], centre, mid[static_cast<std::size_t>((k + 3) % 4)]};
      smallest = std::min(smallest, aarad::area(q));
      smallest_made = std::min(smallest_made, made_area(q));
    }
  } else {
    for (int k = 0; k < 3; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      const std::array<Vec3, 3> t{c[ku], mid[ku], mid[static_cast<std::size_t>((k + 2) % 3)]};
      smallest_made = std::min(smallest_made, made_area(t));
    }
    smallest_made = std::min(smallest_made, made_area(std::array<Vec3, 3>{mid[0], mid[1], mid[2]}));
    smallest = m.area[node] / 4.0;  // the four children of a triangle are congruent up to rounding
  }
  if (degenerate || !(smallest_made > 0.0)) return Refusal::kDegenerate;
  return smallest < m.options.min_area ? Refusal::kMinArea : Refusal::kNone;
}

bool Hierarchy::can_split(NodeId node) const {
  double smallest = 0.0;
  if (refusal(node, smallest) != Refusal::kNone) return false;
  Refusal why = Refusal::kNone;
  return !impl_->options.balance || balance_blocker(node, why) == kNoNode;
}

SplitResult Hierarchy::split(NodeId node) {
  SplitResult result;
  const Impl& m = *impl_;
  double smallest = 0.0;
  switch (refusal(node, smallest)) {
    case Refusal::kNone: break;
    case Refusal::kMissing:
      result.reason = "node " + std::to_string(node) + " does not exist (" + std::to_string(node_count()) + " nodes)";
      return result;
    case Refusal::kInner:
      result.reason = "node " + std::to_string(node) + " is not a leaf";
      return result;
    case Refusal::kMaxLevel:
      result.reason = "node " + std::to_string(node) + " is at the maximum level " + std::to_string(m.options.max_level);
      return result;
    case Refusal::kMinArea:
      result.reason = "node " + std::to_string(node) + ": a child would have area " + std::to_string(smallest) +
                      ", below min_area " + std::to_string(m.options.min_area);
      return result;
    case Refusal::kDegenerate:
      result.reason = "node " + std::to_string(node) + " is too small to split in floating point: a child would have "
                      "two corners at one point";
      return result;
  }
  if (m.options.balance) {
    // Balancing splits coarser neighbours first, and theirs in turn: each must take its split, or this one is
    // refused. Split regardless, they went below min_area, and at the deepest levels into children of no area,
    // turned clockwise (a reviewer's --balance solves).
    Refusal why = Refusal::kNone;
    const NodeId blocker = balance_blocker(node, why);
    if (blocker != kNoNode) {
      static constexpr const char* kWhy[] = {"", "is missing", "is not a leaf", "is at the maximum level",
                                             "would have a child below min_area", "is too small to split in "
                                             "floating point"};
      result.reason = "node " + std::to_string(node) + ": balancing would split node " + std::to_string(blocker) +
                      ", which " + kWhy[static_cast<int>(why)];
      return result;
    }
    split_coarser_neighbours(node, result.also_split);
  }
  result.children.reserve(4);  // before the split, which then allocates nothing after it has begun
  const std::array<NodeId, 4> ids = split_leaf(node);
  result.children.assign(ids.begin(), ids.end());
  result.ok = true;
  return result;
}

}  // namespace aarad::mesh
