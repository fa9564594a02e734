// Display reconstruction of element radiosities: vertex values as area-weighted means of the surrounding
// leaves (Cohen and Wallace, "Radiosity and Realistic Image Synthesis", 1993, section 9.3.1 "nodal averaging"),
// hanging vertices interpolated along their host edge so no seam appears (Baum, Mann, Smith and Winget 1991,
// section 4.3, "T-vertices"), and a crack-free triangulation that anchors the T-vertices.
#include "aarad/mesh/display.h"

#include "aarad/mesh/leaf_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <tuple>
#include <unordered_map>
#include <utility>

namespace aarad::mesh {
namespace {

using VertexHandle = LeafMesh::VertexHandle;
using FaceHandle = LeafMesh::FaceHandle;

// The leaf's face loop starting at its first corner.
void loop_from_first_corner(const Hierarchy::Impl& m, NodeId leaf, std::vector<int>& loop) {
  loop.clear();
  for (auto v : m.mesh.fv_range(FaceHandle(m.face[leaf]))) loop.push_back(v.idx());
  const auto first = std::find(loop.begin(), loop.end(), m.corners[leaf][0]);
  std::rotate(loop.begin(), first, loop.end());
}

// A hanging vertex lies on the edge between two corners of a leaf (its host edge), at parameter t; a corner
// of every leaf around it has a = -1.
struct Host {
  int a = -1, b = -1;
  double t = 0.0;
};

// Whether two surfaces of one smoothing group show one curved surface across their shared edge: their fronts turn
// less than a right angle apart. The two faces of a wall modelled with both sides (faces are one-sided), back to
// back in one smoothing group (Blender writes `s 1` for every smooth-shaded object), are not: the lit side's
// radiosity showed on the dark side.
bool facing_alike(const Scene& scene, std::uint32_t a, std::uint32_t b) {
  return glm::dot(scene.surfaces[a].plane.normal, scene.surfaces[b].plane.normal) > 0.0;
}

// Smoothing groups (Scene's Face::smoothing): corner vertices of different surfaces of one scene group, one
// nonzero smoothing group and one material, facing alike, that lie at one point, within the distance at which the
// initial meshing joins vertices, pool their leaves' areas and values, so that each of them takes the area-weighted
// mean of all the leaves around the point and the display is continuous across the edges between those surfaces.
// Radiosity is reflectance times what arrives, so it steps where the material changes, smooth or not. Hanging
// vertices keep their host edge's interpolation (a surface's outer boundary has none); hang_smoothed_vertices then
// handles the boundary vertices that the other side of such an edge lacks.
void pool_smoothed_vertices(const Hierarchy::Impl& m, std::span<const std::uint32_t> vertex_surface,
                            std::span<const Host> host, std::vector<Rgb>& weighted, std::vector<double>& weight) {
  const double tolerance = kPlaneDistance * m.scene().diagonal();
  // Candidates by cell of side `tolerance` (as the initial meshing welds vertices): two within the tolerance lie in
  // the same cell or in neighbouring ones.
  struct Candidate {
    std::uint32_t group, smoothing, material;
    std::array<double, 3> cell;
    Vec3 p;
    int vertex;
    auto key() const { return std::tie(group, smoothing, material, cell); }
  };
  std::vector<Candidate> candidates;
  for (std::size_t v = 0; v < vertex_surface.size(); ++v) {
    if (!(weight[v] > 0.0) || host[v].a >= 0) continue;
    const Surface& surface = m.scene().surfaces[vertex_surface[v]];
    if (surface.smoothing == 0) continue;
    const Vec3 p = m.point(static_cast<int>(v));
    candidates.push_back({surface.group, surface.smoothing, surface.material,
                          {std::floor(p.x / tolerance), std::floor(p.y / tolerance), std::floor(p.z / tolerance)}, p,
                          static_cast<int>(v)});
  }
  if (candidates.empty()) return;
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tuple_cat(a.key(), std::tie(a.vertex)) < std::tuple_cat(b.key(), std::tie(b.vertex));
  });
  // Union-find over the candidates.
  std::vector<std::size_t> root(candidates.size());
  std::iota(root.begin(), root.end(), std::size_t{0});
  const auto find = [&](std::size_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  const auto unite_close = [&](std::size_t i, std::size_t j) {
    const Candidate &a = candidates[i], &b = candidates[j];
    if (std::abs(b.p.x - a.p.x) <= tolerance && std::abs(b.p.y - a.p.y) <= tolerance &&
        std::abs(b.p.z - a.p.z) <= tolerance &&
        vertex_surface[static_cast<std::size_t>(a.vertex)] != vertex_surface[static_cast<std::size_t>(b.vertex)] &&
        facing_alike(m.scene(), vertex_surface[static_cast<std::size_t>(a.vertex)],
                     vertex_surface[static_cast<std::size_t>(b.vertex)]))
      root[find(j)] = find(i);
  };
  const auto by_key = [](const Candidate& c, const Candidate& d) { return c.key() < d.key(); };
  // Cell by cell: pairs within the cell, and with the 13 neighbouring cells that sort after it.
  for (std::size_t begin = 0; begin < candidates.size();) {
    std::size_t end = begin + 1;
    while (end < candidates.size() && candidates[end].key() == candidates[begin].key()) ++end;
    for (std::size_t i = begin; i < end; ++i)
      for (std::size_t j = i + 1; j < end; ++j) unite_close(i, j);
    for (int dx = 0; dx <= 1; ++dx)
      for (int dy = dx == 0 ? 0 : -1; dy <= 1; ++dy)
        for (int dz = dx == 0 && dy == 0 ? 1 : -1; dz <= 1; ++dz) {
          Candidate probe = candidates[begin];
          probe.cell = {probe.cell[0] + dx, probe.cell[1] + dy, probe.cell[2] + dz};
          const auto [first, last] = std::equal_range(candidates.begin() + static_cast<std::ptrdiff_t>(end),
                                                      candidates.end(), probe, by_key);
          for (auto j = first; j != last; ++j)
            for (std::size_t i = begin; i < end; ++i) unite_close(i, static_cast<std::size_t>(j - candidates.begin()));
        }
    begin = end;
  }
  // Sums per class, in candidate order (deterministic), then given to every member.
  std::vector<Rgb> class_weighted(candidates.size());
  std::vector<double> class_weight(candidates.size(), 0.0);
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const auto v = static_cast<std::size_t>(candidates[i].vertex);
    class_weighted[find(i)] += weighted[v];
    class_weight[find(i)] += weight[v];
  }
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const auto v = static_cast<std::size_t>(candidates[i].vertex);
    weighted[v] = class_weighted[find(i)];
    weight[v] = class_weight[find(i)];
  }
}

// Smoothing groups, after the pooling: where the two sides of an edge between surfaces of one scene group, one nonzero
// smoothing group and one material, facing alike, are split differently, a boundary vertex of one side lies strictly
// inside a boundary edge of the other, which shows the linear interpolation of its ends there. Such a vertex hangs
// across the surfaces: it takes that interpolation too, as a T-vertex inside a surface does, so both sides show one
// line. Its host edge's ends may hang across themselves when the two sides' vertices interleave (an edge cut in three
// on one side and in two on the other): then only one line through the nearest vertices that hang on no edge is
// continuous on both sides, so the host becomes that pair, found by walking along the line away from the vertex.
// "Strictly inside" and "on the edge" mean farther than the pooling tolerance from both ends and within it of the
// segment.
void hang_smoothed_vertices(const Hierarchy::Impl& m, std::span<const std::uint32_t> vertex_surface,
                            std::span<const double> weight, std::vector<Host>& host) {
  const double tolerance = kPlaneDistance * m.scene().diagonal();
  const auto surface_of = [&](int v) -> const Surface& {
    return m.scene().surfaces[vertex_surface[static_cast<std::size_t>(v)]];
  };
  // Boundary edges of smoothing surfaces, entered in a grid at points along them no farther apart than a quarter of
  // the cell side: a point on the segment lies within an eighth of a side of one of them, so a vertex within the
  // tolerance of the segment (at most an eighth of a side) lies less than half a side from one, which is in the
  // vertex's cell or in one of the 8 around it on the side of its nearer cell walls. The side is the median length
  // of the edges, so a cell holds a few edges and an edge a few cells; cells are found through a hash table.
  struct CellKey {
    std::uint32_t group, smoothing, material;
    std::array<double, 3> cell;
    bool operator==(const CellKey&) const = default;
    auto tied() const { return std::tie(group, smoothing, material, cell); }
  };
  struct CellHash {
    std::size_t operator()(const CellKey& k) const {
      std::size_t h = std::hash<std::uint64_t>()((std::uint64_t{k.group} << 32) ^ k.smoothing);
      h = h * 0x9E3779B97F4A7C15ull ^ k.material;
      for (const double x : k.cell) h = h * 0x9E3779B97F4A7C15ull ^ std::hash<double>()(x);
      return h;
    }
  };
  struct Entry {
    CellKey key;
    int a, b;
  };
  std::vector<std::array<int, 2>> edges;
  std::vector<double> lengths;
  for (const auto h : m.mesh.halfedges()) {
    if (!h.is_boundary()) continue;
    const int a = h.from().idx(), b = h.to().idx();
    if (!(weight[static_cast<std::size_t>(a)] > 0.0) || host[static_cast<std::size_t>(a)].a >= 0 ||
        surface_of(a).smoothing == 0)
      continue;
    edges.push_back({a, b});
    lengths.push_back(glm::length(m.point(b) - m.point(a)));
  }
  if (edges.empty()) return;
  std::nth_element(lengths.begin(), lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2), lengths.end());
  const double side = std::max(lengths[lengths.size() / 2], 8.0 * tolerance);
  const auto cell_of = [&](const Vec3& p) {
    return std::array<double, 3>{std::floor(p.x / side), std::floor(p.y / side), std::floor(p.z / side)};
  };
  std::vector<Entry> entries;
  for (const auto& [a, b] : edges) {
    const Surface& surface = surface_of(a);
    const Vec3 pa = m.point(a), d = m.point(b) - pa;
    const double pieces = std::ceil(4.0 * glm::length(d) / side);
    for (double i = 0.0; i <= pieces; ++i)
      entries.push_back({{surface.group, surface.smoothing, surface.material, cell_of(pa + (i / pieces) * d)}, a, b});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& c, const Entry& d) {
    return std::tuple_cat(c.key.tied(), std::tie(c.a)) < std::tuple_cat(d.key.tied(), std::tie(d.a));
  });
  entries.erase(std::unique(entries.begin(), entries.end(),
                            [](const Entry& c, const Entry& d) { return c.key == d.key && c.a == d.a; }),
                entries.end());
  std::unordered_map<CellKey, std::pair<std::size_t, std::size_t>, CellHash> cells;
  for (std::size_t begin = 0; begin < entries.size();) {
    std::size_t end = begin + 1;
    while (end < entries.size() && entries[end].key == entries[begin].key) ++end;
    cells.emplace(entries[begin].key, std::pair{begin, end});
    begin = end;
  }
  std::vector<int> boundary_vertices;  // every boundary vertex starts one boundary halfedge
  for (const auto& edge : edges) boundary_vertices.push_back(edge[0]);
  std::sort(boundary_vertices.begin(), boundary_vertices.end());

  // The edge each boundary vertex hangs on across surfaces (the first found), a = -1 for none.
  std::vector<Host> across(host.size());
  const auto hang_across = [&](int v, const Entry& e) {
    const Vec3 p = m.point(v), pa = m.point(e.a), d = m.point(e.b) - pa;
    const double t = glm::dot(p - pa, d) / glm::dot(d, d);
    if (vertex_surface[static_cast<std::size_t>(e.a)] == vertex_surface[static_cast<std::size_t>(v)] ||
        !facing_alike(m.scene(), vertex_surface[static_cast<std::size_t>(e.a)],
                      vertex_surface[static_cast<std::size_t>(v)]) ||
        !(t > 0.0 && t < 1.0) || glm::length(p - pa) <= tolerance || glm::length(p - m.point(e.b)) <= tolerance ||
        glm::length(pa + t * d - p) > tolerance)
      return false;
    across[static_cast<std::size_t>(v)] = {e.a, e.b, t};
    return true;
  };
  for (const int v : boundary_vertices) {
    const Surface& surface = surface_of(v);
    const Vec3 p = m.point(v);
    const std::array<double, 3> own = cell_of(p);
    std::array<double, 3> toward;  // the neighbouring cell on the side of the nearer cell wall, per axis
    for (int axis = 0; axis < 3; ++axis) {
      const auto i = static_cast<std::size_t>(axis);
      toward[i] = own[i] + (p[axis] / side - own[i] < 0.5 ? -1.0 : 1.0);
    }
    bool found = false;
    for (int corner = 0; corner < 8 && !found; ++corner) {
      const CellKey key{surface.group, surface.smoothing, surface.material,
                        {(corner & 1) ? toward[0] : own[0], (corner & 2) ? toward[1] : own[1],
                         (corner & 4) ? toward[2] : own[2]}};
      const auto cell = cells.find(key);
      if (cell == cells.end()) continue;
      const auto [first, last] = cell->second;
      for (std::size_t e = first; e < last && !found; ++e) found = hang_across(v, entries[e]);
    }
  }

  // Walks from `end` along the line from v through it, as long as the vertex reached hangs across on an edge of that
  // line, to the first one that does not; each step goes farther from v, and the walk is capped for a corrupted mesh.
  const auto walk = [&](int v, int end) {
    const Vec3 p = m.point(v);
    for (std::size_t steps = 0; steps < boundary_vertices.size(); ++steps) {
      const Host& next = across[static_cast<std::size_t>(end)];
      if (next.a < 0) break;
      const Vec3 direction = m.point(end) - p;
      const int far = glm::dot(m.point(next.b) - m.point(next.a), direction) > 0.0 ? next.b : next.a;
      const Vec3 q = m.point(far) - p;
      if (glm::length(q - direction * (glm::dot(q, direction) / glm::dot(direction, direction))) > tolerance) break;
      end = far;
    }
    return end;
  };
  for (const int v : boundary_vertices) {
    const Host& edge = across[static_cast<std::size_t>(v)];
    if (edge.a < 0) continue;
    const int a = walk(v, edge.a), b = walk(v, edge.b);
    const Vec3 pa = m.point(a), d = m.point(b) - pa;
    host[static_cast<std::size_t>(v)] = {a, b, glm::dot(m.point(v) - pa, d) / glm::dot(d, d)};
  }
}

}  // namespace

DisplayMesh build_display_mesh(const Hierarchy& hierarchy, std::span<const Rgb> node_values) {
  const Hierarchy::Impl& m = hierarchy.impl();
  const std::size_t vertex_count = m.mesh.n_vertices();
  const std::vector<NodeId> leaves = hierarchy.leaves();

  // Hanging vertices: a loop vertex that is not a corner of the leaf lies on the edge between the corners
  // around it (its host edge).
  std::vector<Host> host(vertex_count);
  std::vector<std::uint32_t> vertex_surface(vertex_count);
  std::vector<Rgb> weighted(vertex_count);
  std::vector<double> weight(vertex_count, 0.0);
  std::vector<int> loop;
  for (NodeId leaf : leaves) {
    loop_from_first_corner(m, leaf, loop);
    const int corners = m.corner_count(leaf);
    int k = 0;
    for (std::size_t i = 1; i < loop.size(); ++i) {
      const int next = m.corners[leaf][static_cast<std::size_t>((k + 1) % corners)];
      if (loop[i] == next) {
        k = (k + 1) % corners;
        continue;
      }
      const int a = m.corners[leaf][static_cast<std::size_t>(k)];
      const Vec3 pa = m.point(a), d = m.point(next) - pa;
      host[static_cast<std::size_t>(loop[i])] = {a, next, glm::dot(m.point(loop[i]) - pa, d) / glm::dot(d, d)};
    }
    for (int c = 0; c < corners; ++c) {
      const auto v = static_cast<std::size_t>(m.corners[leaf][static_cast<std::size_t>(c)]);
      weighted[v] += node_values[leaf] * m.area[leaf];
      weight[v] += m.area[leaf];
      vertex_surface[v] = m.surface[leaf];
    }
  }
  // Smoothing groups: nothing of it runs for a scene without one.
  const auto smoothing = [](const Surface& surface) { return surface.smoothing != 0; };
  if (std::any_of(m.scene().surfaces.begin(), m.scene().surfaces.end(), smoothing)) {
    pool_smoothed_vertices(m, vertex_surface, host, weighted, weight);
    hang_smoothed_vertices(m, vertex_surface, weight, host);
  }

  // Resolve values; a hanging vertex's host corners may hang on a coarser leaf themselves (nested), so
  // resolve depth first. Host edges belong to strictly larger leaves, so the recursion ends; a vertex hanging
  // across surfaces is hosted by vertices that hang on no edge of another surface (hang_smoothed_vertices).
  DisplayMesh out;
  out.positions.reserve(vertex_count);
  for (std::size_t v = 0; v < vertex_count; ++v) out.positions.push_back(m.point(static_cast<int>(v)));
  out.vertex_values.assign(vertex_count, Rgb());
  std::vector<char> state(vertex_count, 0);  // 0 unresolved, 1 in progress, 2 done
  std::vector<int> stack;
  for (std::size_t start = 0; start < vertex_count; ++start) {
    if (state[start] == 2) continue;
    stack.push_back(static_cast<int>(start));
    while (!stack.empty()) {
      const auto v = static_cast<std::size_t>(stack.back());
      const Host& hv = host[v];
      if (hv.a < 0) {
        out.vertex_values[v] = weight[v] > 0.0 ? weighted[v] / weight[v] : Rgb();
        state[v] = 2;
        stack.pop_back();
        continue;
      }
      const auto a = static_cast<std::size_t>(hv.a), b = static_cast<std::size_t>(hv.b);
      if (state[a] == 2 && state[b] == 2) {
        out.vertex_values[v] = out.vertex_values[a] * (1.0 - hv.t) + out.vertex_values[b] * hv.t;
        state[v] = 2;
        stack.pop_back();
        continue;
      }
      if (state[v] == 1) {  // a cycle of hosts: only a corrupted mesh gets here; fall back to the mean
        out.vertex_values[v] = weight[v] > 0.0 ? weighted[v] / weight[v] : Rgb();
        state[v] = 2;
        stack.pop_back();
        continue;
      }
      state[v] = 1;
      if (state[a] != 2) stack.push_back(hv.a);
      if (state[b] != 2) stack.push_back(hv.b);
    }
  }

  // Triangulation. A leaf without hanging vertices is one triangle or two (along the shorter diagonal); a leaf
  // with hanging vertices is a fan from its centre over every piece of its loop, which keeps each T-vertex an
  // actual vertex of the triangulation (no crack) and every triangle non-degenerate for a convex leaf.
  out.triangles.reserve(leaves.size() * 2);
  out.triangle_leaf.reserve(leaves.size() * 2);
  for (NodeId leaf : leaves) {
    loop_from_first_corner(m, leaf, loop);
    const int corners = m.corner_count(leaf);
    auto add = [&](int a, int b, int c) {
      out.triangles.push_back({static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(c)});
      out.triangle_leaf.push_back(leaf);
    };
    if (static_cast<int>(loop.size()) == corners) {
      if (corners == 3) {
        add(loop[0], loop[1], loop[2]);
      } else if (glm::length(m.point(loop[2]) - m.point(loop[0])) <= glm::length(m.point(loop[3]) - m.point(loop[1]))) {
        add(loop[0], loop[1], loop[2]);
        add(loop[0], loop[2], loop[3]);
      } else {
        add(loop[0], loop[1], loop[3]);
        add(loop[1], loop[2], loop[3]);
      }
      continue;
    }
    Vec3 centre(0.0);
    Rgb value;
    for (int c = 0; c < corners; ++c) {
      const int v = m.corners[leaf][static_cast<std::size_t>(c)];
      centre += m.point(v);
      value += out.vertex_values[static_cast<std::size_t>(v)];
    }
    const auto centre_index = static_cast<int>(out.positions.size());
    out.positions.push_back(centre / static_cast<double>(corners));
    out.vertex_values.push_back(value / static_cast<double>(corners));
    for (std::size_t i = 0; i < loop.size(); ++i) add(centre_index, loop[i], loop[(i + 1) % loop.size()]);
  }
  return out;
}

}  // namespace aarad::mesh
