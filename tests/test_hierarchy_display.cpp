// Display reconstruction (vertex values, hanging-vertex interpolation, crack-free triangulation) and the PLY
// export read back by OpenMesh.
// OpenMesh's PropertyT<VectorT<unsigned char, 3>>::push_back appends a default-constructed colour, whose
// components VectorT leaves uninitialized until they are set; GCC 12 reports that as -Wmaybe-uninitialized
// from a system header. Here every colour is filled by reading a PLY file back.
#if defined(__GNUC__) && !defined(__clang__)  // a GCC warning; Clang has no such group
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/IO/MeshIO.hh>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

#include "aarad/core/builtin_scenes.h"
#include "aarad/mesh/display.h"
#include "aarad/mesh/export_ply.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/mesh/invariants.h"
#include "aarad/mesh/leaf_mesh.h"
#include "test_hierarchy_scenes.h"

#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <utility>

namespace aarad::mesh {
namespace {

MeshingOptions sizes(double patch, double element) {
  MeshingOptions o;
  o.patch_size = patch;
  o.element_size = element;
  return o;
}

std::vector<Rgb> values_of(const Hierarchy& h) {
  std::vector<Rgb> v(h.node_count());
  for (NodeId n = 0; n < h.node_count(); ++n) v[n] = h.radiosity(n);
  return v;
}

std::size_t index_of(const DisplayMesh& d, const Vec3& p) {
  return static_cast<std::size_t>(std::find(d.positions.begin(), d.positions.end(), p) - d.positions.begin());
}

// Crack-free: every triangle edge inside a surface is shared by exactly two triangles with opposite
// directions; the rest lie on the outer boundary; the triangles cover each surface's area, none degenerate.
void expect_crack_free(const Hierarchy& h, const DisplayMesh& d) {
  const std::vector<Violation> violations = check_display(h, d);
  EXPECT_TRUE(violations.empty()) << violations.size() << " display violations, the first: "
                                  << (violations.empty() ? "" : violations.front().message);
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  std::vector<double> area(h.scene().surfaces.size(), 0.0);
  for (std::size_t t = 0; t < d.triangles.size(); ++t) {
    const auto& tri = d.triangles[t];
    const Vec3 a = d.positions[tri[0]], b = d.positions[tri[1]], c = d.positions[tri[2]];
    const Vec3 n = glm::cross(b - a, c - a);
    EXPECT_GT(glm::dot(n, h.plane(d.triangle_leaf[t]).normal), 1e-14 * glm::dot(b - a, b - a)) << "triangle " << t;
    area[h.surface(d.triangle_leaf[t])] += 0.5 * glm::length(n);
    for (int k = 0; k < 3; ++k) ++directed[{tri[static_cast<std::size_t>(k)], tri[static_cast<std::size_t>((k + 1) % 3)]}];
  }
  double boundary = 0.0;
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    if (!directed.count({edge.second, edge.first})) boundary += glm::length(d.positions[edge.second] - d.positions[edge.first]);
  }
  double initial_boundary = 0.0;
  for (const auto& b : h.impl().boundaries) initial_boundary += b.length;
  EXPECT_NEAR(boundary, initial_boundary, 1e-9 * initial_boundary);  // open edges only on the outer boundary
  for (std::size_t s = 0; s < area.size(); ++s) EXPECT_NEAR(area[s], h.scene().surfaces[s].area, 1e-9 * h.scene().surfaces[s].area);
}

TEST(HierarchyDisplay, HangingVertexTakesTheInterpolationAlongItsHostEdge) {
  // L = [0,1]^2 with B = 1; R = [1,2]x[0,1] split into quarters with B = 3, 5, 7, 9 (children 0..3 at R's
  // corners (1,0), (2,0), (2,1), (1,1)). Vertex (1,0) is a corner of L (area 1) and of child 0 (area 1/4):
  // (1 + 3/4) / 1.25 = 1.4. Vertex (1,1): (1 + 9/4) / 1.25 = 2.6. The hanging vertex (1, 0.5) on L's edge
  // takes (1.4 + 2.6) / 2 = 2, not its own average over L, child 0 and child 3 ((1 + 0.75 + 2.25) / 1.5).
  Hierarchy h(test::rectangle_scene(), sizes(2.0, 1.0));
  const NodeId left = h.leaves()[0], right = h.leaves()[1];
  const SplitResult r = h.split(right);
  ASSERT_TRUE(r.ok);
  h.radiosity(left) = Rgb(1.0);
  for (int k = 0; k < 4; ++k) h.radiosity(r.children[static_cast<std::size_t>(k)]) = Rgb(3.0 + 2.0 * k);
  const DisplayMesh d = build_display_mesh(h, values_of(h));
  // Every vertex looked up exists (index_of returns positions.size() for a missing point).
  const std::size_t n = d.positions.size();
  ASSERT_EQ(d.vertex_values.size(), n);
  const std::size_t c10 = index_of(d, {1, 0, 0}), c11 = index_of(d, {1, 1, 0}), hanging = index_of(d, {1, 0.5, 0}),
                    origin = index_of(d, {0, 0, 0}), centre = index_of(d, {1.5, 0.5, 0});
  ASSERT_LT(c10, n);
  ASSERT_LT(c11, n);
  ASSERT_LT(hanging, n);
  ASSERT_LT(origin, n);
  ASSERT_LT(centre, n);
  EXPECT_DOUBLE_EQ(d.vertex_values[c10].r, 1.4);
  EXPECT_DOUBLE_EQ(d.vertex_values[c11].r, 2.6);
  EXPECT_DOUBLE_EQ(d.vertex_values[hanging].r, 2.0);
  EXPECT_DOUBLE_EQ(d.vertex_values[origin].r, 1.0);
  EXPECT_DOUBLE_EQ(d.vertex_values[centre].r, 6.0);  // R's centre: mean of its four children
  // L has five loop vertices: a fan of five triangles from its centre; R's children two each.
  EXPECT_EQ(d.triangles.size(), 5u + 4u * 2u);
  // The fan's centre lies at L's centre, with the mean of L's four corners: (1 + 1.4 + 2.6 + 1) / 4 = 1.5.
  const std::size_t fan = index_of(d, {0.5, 0.5, 0});
  ASSERT_LT(fan, n);
  EXPECT_DOUBLE_EQ(d.vertex_values[fan].r, 1.5);
  expect_crack_free(h, d);
}

// Two unit squares bent along their shared edge x = 1: A in z = 0 with B = 1, B rising to z = 0.3 with B = 3
// (area sqrt(1.09)). With one smoothing group in one scene group the two copies of each shared corner take the
// area-weighted mean of both leaves, (1 + 3 sqrt(1.09)) / (1 + sqrt(1.09)); the outer corners keep 1 and 3.
// Without smoothing, with two smoothing groups, or with the squares in two scene groups, each copy keeps its
// own surface's value.
// Nor with two materials (radiosity steps where the reflectance does: a reviewer's floor of a red and a white quad in
// one smoothing group showed pink beside the seam), nor where the second square turns its back to the first (a wall
// modelled as two faces back to back in one smoothing group showed the lit side's radiosity on the dark side).
TEST(HierarchyDisplay, SmoothingGroupsPoolTheCornersSharedAcrossSurfaces) {
  struct Case {
    const char* what;
    std::uint32_t smoothing_a, smoothing_b;
    bool two_groups;
    bool pooled;
    bool two_materials = false;
    bool back_to_back = false;
  };
  for (const Case c : {Case{"one smoothing group", 1, 1, false, true}, Case{"no smoothing", 0, 0, false, false},
                       Case{"two smoothing groups", 1, 2, false, false}, Case{"two scene groups", 1, 1, true, false},
                       Case{"two materials", 1, 1, false, false, true},
                       Case{"back to back", 1, 1, false, false, false, true}}) {
    SCOPED_TRACE(c.what);
    Scene scene;
    scene.name = "bent";
    const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
    const std::uint32_t red = scene.add_material(Material{"red", Rgb(0.7, 0.05, 0.05), Rgb(0.0)});
    const std::uint32_t first = scene.add_group("a"), second = c.two_groups ? scene.add_group("b") : first;
    scene.add_face(first, grey, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, 0, c.smoothing_a);
    // Bent up by 0.3 over its width; back to back, the same square wound the other way, facing down (its normal
    // . a's < 0).
    const std::vector<Vec3> b_corners =
        c.back_to_back ? std::vector<Vec3>{{1, 0, 0}, {1, 1, 0}, {2, 1, 0.3}, {2, 0, 0.3}}
                       : std::vector<Vec3>{{1, 0, 0}, {2, 0, 0.3}, {2, 1, 0.3}, {1, 1, 0}};
    scene.add_face(second, c.two_materials ? red : grey, b_corners, 0, c.smoothing_b);
    scene.build_surfaces();
    ASSERT_EQ(scene.surfaces.size(), 2u);
    const Hierarchy h(scene, sizes(2.0, 2.0));
    ASSERT_EQ(h.leaves().size(), 2u);  // each square one element
    std::vector<Rgb> values(h.node_count());
    for (const NodeId leaf : h.leaves()) values[leaf] = Rgb(h.surface(leaf) == 0 ? 1.0 : 3.0);
    const DisplayMesh d = build_display_mesh(h, values);
    const double b_area = std::sqrt(1.09), pooled = (1.0 + 3.0 * b_area) / (1.0 + b_area);
    std::vector<double> own(d.positions.size(), 0.0);  // each vertex's own surface's value, from its triangles
    for (std::size_t t = 0; t < d.triangles.size(); ++t)
      for (const std::uint32_t v : d.triangles[t]) own[v] = values[d.triangle_leaf[t]].r;
    int shared_copies = 0;
    for (std::size_t v = 0; v < d.positions.size(); ++v) {
      const Vec3& p = d.positions[v];
      ASSERT_NE(own[v], 0.0) << "vertex " << v << " in no triangle";
      if (p.x == 1.0) {
        ++shared_copies;
        EXPECT_NEAR(d.vertex_values[v].r, c.pooled ? pooled : own[v], 1e-15) << "vertex " << v;
      } else {
        EXPECT_EQ(d.vertex_values[v].r, own[v]) << "vertex " << v;
      }
    }
    EXPECT_EQ(shared_copies, 4);  // (1, 0, 0) and (1, 1, 0), once per surface
    expect_crack_free(h, d);
  }
}

// Two faces of one smoothing group meeting along the edge x = 1, z = 0 from (1, 0, 0) to (1, 1, 0): the unit square in
// z = 0 and the quadrilateral `other` (counter-clockwise, its first and last corners on that edge).
Scene smoothed_pair(const std::vector<Vec3>& other) {
  Scene scene;
  scene.name = "smoothed pair";
  const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
  const std::uint32_t group = scene.add_group("pair");
  scene.add_face(group, grey, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, 0, 1);
  scene.add_face(group, grey, other, 0, 1);
  scene.build_surfaces();
  return scene;
}

// The leaf whose centroid is nearest to `point`.
NodeId leaf_nearest(const Hierarchy& h, const Vec3& point) {
  const std::vector<NodeId> leaves = h.leaves();
  return *std::min_element(leaves.begin(), leaves.end(), [&](NodeId a, NodeId b) {
    return glm::length(h.centroid(a) - point) < glm::length(h.centroid(b) - point);
  });
}

// Along the edge x = 1, z = 0 every display vertex of one surface shows what the other surface's triangles show at
// its point: the value of a vertex there, or the linear interpolation along a triangle edge through it. Returns the
// number of comparisons.
int expect_continuous_along_the_shared_edge(const Hierarchy& h, const DisplayMesh& d) {
  const auto on_edge = [](const Vec3& p) { return std::abs(p.x - 1.0) < 1e-12 && std::abs(p.z) < 1e-12; };
  std::vector<std::uint32_t> surface(d.positions.size());
  for (std::size_t t = 0; t < d.triangles.size(); ++t)
    for (const std::uint32_t v : d.triangles[t]) surface[v] = h.surface(d.triangle_leaf[t]);
  int comparisons = 0;
  for (std::size_t t = 0; t < d.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = d.triangles[t][static_cast<std::size_t>(k)];
      const std::uint32_t b = d.triangles[t][static_cast<std::size_t>((k + 1) % 3)];
      const Vec3 pa = d.positions[a], pb = d.positions[b];
      if (!on_edge(pa) || !on_edge(pb)) continue;
      for (std::size_t v = 0; v < d.positions.size(); ++v) {
        const double along = (d.positions[v].y - pa.y) / (pb.y - pa.y);
        if (surface[v] == h.surface(d.triangle_leaf[t]) || !on_edge(d.positions[v]) || along < 0.0 || along > 1.0)
          continue;
        const Rgb shown = d.vertex_values[a] * (1.0 - along) + d.vertex_values[b] * along;
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(d.vertex_values[v][c], shown[c], 1e-12) << "vertex at y = " << d.positions[v].y;
        ++comparisons;
      }
    }
  return comparisons;
}

// The square and a bent square, one element each, then refined differently next to their shared edge: the square's
// element quartered and its quarter at (1, 0) quartered again (edge vertices at y = 0, 0.25, 0.5, 1), the bent
// square's quartered and its quarter at (1, 1) quartered again (y = 0, 0.5, 0.75, 1). Each side's vertex at y = 0.25
// or 0.75 lies inside an edge of the other side; it shows that edge's interpolation, so the two sides agree all along
// the edge (each keeping its own area-weighted mean, the two sides differed by up to 0.30 at y = 0.25 and 0.75).
TEST(HierarchyDisplay, SmoothingGroupIsContinuousAlongAnEdgeItsSurfacesSplitDifferently) {
  Hierarchy h(smoothed_pair({{1, 0, 0}, {2, 0, 0.3}, {2, 1, 0.3}, {1, 1, 0}}), sizes(2.0, 2.0));
  ASSERT_EQ(h.leaf_count(), 2u);
  ASSERT_TRUE(h.split(leaf_nearest(h, {0.5, 0.5, 0})).ok);
  ASSERT_TRUE(h.split(leaf_nearest(h, {0.75, 0.25, 0})).ok);
  ASSERT_TRUE(h.split(leaf_nearest(h, {1.5, 0.5, 0.15})).ok);
  ASSERT_TRUE(h.split(leaf_nearest(h, {1.25, 0.75, 0.075})).ok);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Rgb> values(h.node_count());
  for (const NodeId leaf : h.leaves()) values[leaf] = Rgb(unit(rng), unit(rng), unit(rng));
  const DisplayMesh d = build_display_mesh(h, values);
  // Each side's 3 triangle edges along the shared edge hold 5 vertices of the other side, ends included.
  EXPECT_EQ(expect_continuous_along_the_shared_edge(h, d), 10);
  expect_crack_free(h, d);
  EXPECT_TRUE(check_invariants(h).empty()) << test::describe(check_invariants(h));
}

// The sides cut the shared edge into different numbers of pieces that interleave: at patch size 0.4 the unit square
// has 3 rows of patches, the trapezoid beside it, 1.5 long on its far side, 4. No vertex inside the edge is on both
// sides, so only one line is continuous on both: every vertex along the edge shows the interpolation between its
// ends.
TEST(HierarchyDisplay, SmoothingGroupIsContinuousWhereTheSidesCutAnEdgeIntoInterleavingPieces) {
  const Hierarchy h(smoothed_pair({{1, 0, 0}, {2, -0.25, 0.3}, {2, 1.25, 0.3}, {1, 1, 0}}), sizes(0.4, 0.4));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Rgb> values(h.node_count());
  for (const NodeId leaf : h.leaves()) values[leaf] = Rgb(unit(rng), unit(rng), unit(rng));
  const DisplayMesh d = build_display_mesh(h, values);
  std::map<std::uint32_t, std::set<double>> cuts;  // per surface, the y of its vertices along the edge
  for (std::size_t t = 0; t < d.triangles.size(); ++t)
    for (const std::uint32_t v : d.triangles[t])
      if (d.positions[v].x == 1.0 && d.positions[v].z == 0.0)
        cuts[h.surface(d.triangle_leaf[t])].insert(d.positions[v].y);
  ASSERT_EQ(cuts.size(), 2u);
  EXPECT_EQ(cuts.begin()->second.size(), 4u);   // 0, 1/3, 2/3, 1
  EXPECT_EQ(cuts.rbegin()->second.size(), 5u);  // 0, 1/4, 1/2, 3/4, 1
  // The square's 3 triangle edges along the shared edge hold 5 of the trapezoid's vertices; its 4, 4 of the square's.
  EXPECT_EQ(expect_continuous_along_the_shared_edge(h, d), 9);
  expect_crack_free(h, d);
  EXPECT_TRUE(check_invariants(h).empty()) << test::describe(check_invariants(h));
}

// A leaf without hanging vertices is cut along its shorter diagonal, so that its two triangles are as little
// stretched as they can be and smooth shading follows the nearer corners. In the parallelogram (0,0) (2,0) (3,1)
// (1,1) the diagonal from (2,0) to (1,1) (length sqrt 2) is the shorter one; (0,0) to (3,1) is sqrt 10.
TEST(HierarchyDisplay, AQuadLeafIsCutAlongItsShorterDiagonal) {
  const Hierarchy h(test::polygon_scene({{0, 0}, {2, 0}, {3, 1}, {1, 1}}, "parallelogram"), sizes(4.0, 4.0));
  ASSERT_EQ(h.leaf_count(), 1u);
  std::vector<Rgb> values(h.node_count(), Rgb(1.0));
  const DisplayMesh display = build_display_mesh(h, values);
  ASSERT_EQ(display.triangles.size(), 2u);
  for (const auto& triangle : display.triangles) {
    std::set<std::pair<double, double>> corners;
    for (const std::uint32_t v : triangle) corners.insert({display.positions[v].x, display.positions[v].y});
    EXPECT_TRUE(corners.contains({2.0, 0.0}) && corners.contains({1.0, 1.0}));
  }
}

TEST(HierarchyDisplay, NestedHangingVerticesInterpolateRecursively) {
  // Split R, then its child 3 (upper-left quarter [1, 1.5] x [0.5, 1], touching L), then that child's child 0
  // (its corner (1, 1): [1, 1.25] x [0.75, 1], touching L): L carries hanging vertices at y = 0.5, 0.75 and
  // 0.875; (1, 0.875) hangs between (1, 0.75), itself hanging, and (1, 1), and every value is the linear
  // interpolation of L's edge ends.
  Hierarchy h(test::rectangle_scene(), sizes(2.0, 1.0));
  const NodeId left = h.leaves()[0], right = h.leaves()[1];
  const SplitResult r = h.split(right);
  const SplitResult r3 = h.split(r.children[3]);
  ASSERT_TRUE(h.split(r3.children[0]).ok);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(unit(rng), unit(rng), unit(rng));
  (void)left;
  const DisplayMesh d = build_display_mesh(h, values_of(h));
  ASSERT_LT(index_of(d, {1, 0, 0}), d.positions.size());
  ASSERT_LT(index_of(d, {1, 1, 0}), d.positions.size());
  ASSERT_EQ(d.vertex_values.size(), d.positions.size());
  const Rgb lo = d.vertex_values[index_of(d, {1, 0, 0})], hi = d.vertex_values[index_of(d, {1, 1, 0})];
  for (double y : {0.5, 0.75, 0.875}) {
    ASSERT_LT(index_of(d, {1, y, 0}), d.positions.size());
    const Rgb v = d.vertex_values[index_of(d, {1, y, 0})];
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], lo[c] * (1 - y) + hi[c] * y, 1e-15) << "y = " << y;
  }
  expect_crack_free(h, d);
}

TEST(HierarchyDisplay, RandomRefinementsOfTheCornellBoxTriangulateWithoutCracks) {
  const Scene scene = make_cornell_box();
  MeshingOptions o = sizes(scene.diagonal() / 4.0, scene.diagonal() / 8.0);
  Hierarchy h(scene, o);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 300; ++i) {
    const auto leaves = h.leaves();
    h.split(leaves[static_cast<std::size_t>(rng() % leaves.size())]);
  }
  for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(static_cast<double>(n % 7));
  expect_crack_free(h, build_display_mesh(h, values_of(h)));
}

TEST(HierarchyExport, PlyIsBinaryAndReadsBackWithFaceProperties) {
  Hierarchy h(test::rectangle_scene(), sizes(2.0, 1.0));
  const SplitResult r = h.split(h.leaves()[1]);
  ASSERT_TRUE(r.ok);
  for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(0.25 * n, 0.5, 1.0 + n);
  const auto dir = std::filesystem::path(AARAD_BINARY_DIR) / "test_hierarchy_export";
  std::filesystem::create_directories(dir);
  const auto path = dir / "mesh.ply";
  std::filesystem::remove(path);
  const VertexColour grey = [](const Rgb& b) {
    const auto v = static_cast<std::uint8_t>(std::clamp(b.r * 40.0, 0.0, 255.0));
    return std::array<std::uint8_t, 3>{v, v, v};
  };
  write_ply(h, values_of(h), grey, path);
  ASSERT_TRUE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(dir / "mesh.ply.tmp"));
  std::ifstream header(path, std::ios::binary);
  std::string line;
  std::string text;
  while (std::getline(header, line) && line != "end_header") text += line + "\n";
  EXPECT_NE(text.find("format binary_little_endian"), std::string::npos) << text;
  for (const char* name : {"radiosity_r", "radiosity_g", "radiosity_b", "level", "patch", "red"})
    EXPECT_NE(text.find(name), std::string::npos) << name << "\n" << text;

  using ReadMesh = OpenMesh::PolyMesh_ArrayKernelT<>;
  ReadMesh mesh;
  mesh.request_vertex_colors();
  OpenMesh::IO::Options options = OpenMesh::IO::Options::Binary | OpenMesh::IO::Options::VertexColor |
                                  OpenMesh::IO::Options::Custom;
  ASSERT_TRUE(OpenMesh::IO::read_mesh(mesh, path.string(), options));
  EXPECT_EQ(mesh.n_faces(), h.leaf_count());
  EXPECT_EQ(mesh.n_vertices(), h.impl().mesh.n_vertices());
  OpenMesh::FPropHandleT<float> radiosity_r, radiosity_b, level, patch;
  ASSERT_TRUE(mesh.get_property_handle(radiosity_r, "radiosity_r"));
  ASSERT_TRUE(mesh.get_property_handle(radiosity_b, "radiosity_b"));
  ASSERT_TRUE(mesh.get_property_handle(level, "level"));
  ASSERT_TRUE(mesh.get_property_handle(patch, "patch"));
  const auto leaves = h.leaves();  // faces are written in leaf order
  for (auto f : mesh.faces()) {
    const NodeId n = leaves[static_cast<std::size_t>(f.idx())];
    EXPECT_FLOAT_EQ(mesh.property(radiosity_r, f), static_cast<float>(0.25 * n));
    EXPECT_FLOAT_EQ(mesh.property(radiosity_b, f), static_cast<float>(1.0 + n));
    EXPECT_FLOAT_EQ(mesh.property(level, f), static_cast<float>(h.level(n)));
    EXPECT_FLOAT_EQ(mesh.property(patch, f), static_cast<float>(h.patch(n)));
  }
  // The left square keeps its hanging vertex: a pentagon in the file.
  EXPECT_EQ(mesh.valence(ReadMesh::FaceHandle(0)), 5u);
  // Vertex (0,0,0) belongs only to L (B.r = 0.25 x its id): colour through the tone map.
  const auto c = mesh.color(ReadMesh::VertexHandle(0));
  EXPECT_EQ(c[0], grey(h.radiosity(leaves[0]))[0]);
}

// An element left whole while its neighbours are split to the deepest level has more than 255 vertices on its loop
// (here 4 corners and 2 x 127 hanging vertices at the default max level 8). OpenMesh's PLY writer gives a face's
// vertex count one byte: the file said 2 for this face, and every face and vertex after it was read as garbage
// (1 521 faces and 206 216 vertices read back from a 1 537-leaf hierarchy at max level 12). The count is written
// in 4 bytes when a face needs it, and in 1 byte otherwise, as before.
TEST(HierarchyExport, PlyKeepsAFaceOfMoreThan255Vertices) {
  Hierarchy h(test::square_scene(), sizes(1.0, 0.5));  // one patch, 2 x 2 elements of level 1
  const NodeId whole = h.leaves().front();
  for (bool split = true; split;) {
    split = false;
    for (const NodeId n : h.edge_neighbours(whole)) split = h.split(n).ok || split;
  }
  std::vector<Vec3> loop;
  h.leaf_polygon(whole, loop);
  ASSERT_EQ(loop.size(), 258u);
  for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(0.25, 0.5, static_cast<double>(n));
  const auto dir = std::filesystem::path(AARAD_BINARY_DIR) / "test_hierarchy_export_258";
  std::filesystem::create_directories(dir);
  const auto path = dir / "mesh.ply";
  write_ply(h, values_of(h), [](const Rgb&) { return std::array<std::uint8_t, 3>{10, 20, 30}; }, path);

  using ReadMesh = OpenMesh::PolyMesh_ArrayKernelT<>;
  ReadMesh mesh;
  mesh.request_vertex_colors();
  OpenMesh::IO::Options options = OpenMesh::IO::Options::Binary | OpenMesh::IO::Options::VertexColor |
                                  OpenMesh::IO::Options::Custom;
  ASSERT_TRUE(OpenMesh::IO::read_mesh(mesh, path.string(), options));
  ASSERT_EQ(mesh.n_faces(), h.leaf_count());
  EXPECT_EQ(mesh.n_vertices(), h.impl().mesh.n_vertices());
  OpenMesh::FPropHandleT<float> radiosity_b;
  ASSERT_TRUE(mesh.get_property_handle(radiosity_b, "radiosity_b"));
  const auto leaves = h.leaves();
  for (auto f : mesh.faces()) {
    const NodeId n = leaves[static_cast<std::size_t>(f.idx())];
    EXPECT_EQ(mesh.property(radiosity_b, f), static_cast<float>(n));
    h.leaf_polygon(n, loop);
    EXPECT_EQ(mesh.valence(f), loop.size());
  }
  EXPECT_EQ(mesh.color(ReadMesh::VertexHandle(0))[2], 30);
}

// Scenes may be scaled far beyond single precision (core/face_check.h: coordinates up to 1e50) and lights made
// as bright or as faint (Ke up to 1e100, or down to what a double holds), but the PLY's float coordinates and
// radiosities turned into inf or 0 there (a reviewer's fuzzing: a scene 1e39 across, Ke 1e39), and a scene 1 across
// and 1e6 from the origin had its points rounded onto a grid of 0.0625, collapsing half its faces (another
// reviewer's). Where single precision would lose them, they are written as doubles.
TEST(HierarchyExport, PlyWritesDoublesWhereFloatsWouldLoseThem) {
  using ReadMesh = OpenMesh::PolyMesh_ArrayKernelT<>;
  const auto dir = std::filesystem::path(AARAD_BINARY_DIR) / "test_hierarchy_export_wide";
  std::filesystem::create_directories(dir);
  struct Case {
    double scale, offset, radiosity;
    bool wide_points, wide_values;
  };
  // Offsets of a third: points off the grids of floats.
  const Case cases[] = {{1.0, 0.0, 0.5, false, false},          // what viewers expect
                        {1.0, 1e3 / 3, 1e-30, false, false},    // floats within 3e-5 of an edge of 0.5
                        {1e45, 0.0, 1e39, true, true},          // beyond the largest float
                        {1.0, 1e6 / 3, 1e-300, true, true},     // floats up to 0.016 off; below the smallest float
                        {1e-3, 1e6 / 3, 0.5, true, false}};
  int index = 0;
  for (const Case& c : cases) {
    Scene scene = test::square_scene();
    for (Face& f : scene.faces)
      for (Vec3& v : f.vertices) v = v * c.scale + Vec3(c.offset);
    scene.build_surfaces();
    Hierarchy h(scene, sizes(c.scale, 0.5 * c.scale));
    for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(c.radiosity, 0.5, 0.25);
    const auto path = dir / ("mesh_" + std::to_string(index++) + ".ply");
    write_ply(h, values_of(h), [](const Rgb&) { return std::array<std::uint8_t, 3>{10, 20, 30}; }, path);
    std::ifstream header(path, std::ios::binary);
    std::string line, text;
    while (std::getline(header, line) && line != "end_header") text += line + "\n";
    const std::string point = c.wide_points ? "double" : "float", value = c.wide_values ? "double" : "float";
    EXPECT_NE(text.find("property " + point + " x\n"), std::string::npos) << text;
    EXPECT_NE(text.find("property " + value + " radiosity_r\n"), std::string::npos) << text;
    EXPECT_NE(text.find("property float level\n"), std::string::npos) << text;

    // The vertices as written (OpenMesh's reader keeps its points in single precision whatever the file holds).
    const DisplayMesh display = build_display_mesh(h, values_of(h));
    for (std::size_t v = 0; v < h.impl().mesh.n_vertices(); ++v) {
      const Vec3& p = display.positions[v];
      for (int k = 0; k < 3; ++k) {
        double x;
        if (c.wide_points) {
          header.read(reinterpret_cast<char*>(&x), sizeof x);  // little-endian, as this machine
        } else {
          float f;
          header.read(reinterpret_cast<char*>(&f), sizeof f);
          x = f;
        }
        // Within a thousandth of the square's smallest edge (0.5 scale), and exactly where written as doubles.
        EXPECT_NEAR(x, p[k], c.wide_points ? 0.0 : 5e-4 * c.scale) << index << " " << v;
      }
      header.ignore(3);  // the colour
    }
    ASSERT_TRUE(header.good());

    ReadMesh mesh;
    OpenMesh::IO::Options options = OpenMesh::IO::Options::Binary | OpenMesh::IO::Options::Custom;
    ASSERT_TRUE(OpenMesh::IO::read_mesh(mesh, path.string(), options)) << index;
    ASSERT_EQ(mesh.n_faces(), h.leaf_count());
    if (!c.wide_values) continue;
    OpenMesh::FPropHandleT<double> radiosity_r;
    ASSERT_TRUE(mesh.get_property_handle(radiosity_r, "radiosity_r"));
    for (auto f : mesh.faces()) EXPECT_EQ(mesh.property(radiosity_r, f), c.radiosity);
  }
}

}  // namespace
}  // namespace aarad::mesh
