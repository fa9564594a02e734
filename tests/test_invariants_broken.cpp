// Every invariant broken on purpose (through Hierarchy::Impl, mesh/leaf_mesh.h) and reported by
// check_invariants under its name; the intact structure reports nothing.
#include "aarad/core/polygon.h"
#include "aarad/mesh/display.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/mesh/invariants.h"
#include "aarad/mesh/leaf_mesh.h"
#include "test_hierarchy_scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace aarad::mesh {
namespace {

using test::describe;
using test::reports;

// Two unit squares L and R; R split into four, so L carries a hanging vertex at (1, 0.5); child 0 of R
// split again. Radiosities set and pushed up.
Hierarchy refined(bool balance = false) {
  MeshingOptions o;
  o.patch_size = 2.0;
  o.element_size = 1.0;
  o.balance = balance;
  Hierarchy h(test::rectangle_scene(), o);
  const NodeId right = h.leaves()[1];
  const SplitResult r = h.split(right);
  EXPECT_TRUE(r.ok);
  EXPECT_TRUE(h.split(r.children[0]).ok);
  Rgb value(0.1, 0.2, 0.3);
  for (NodeId n : h.leaves()) h.radiosity(n) = (value += Rgb(0.1));
  h.update_inner_radiosity();
  const auto violations = check_invariants(h);
  EXPECT_TRUE(violations.empty()) << describe(violations);
  return h;
}

NodeId left_leaf(const Hierarchy& h) { return h.leaves()[0]; }
NodeId right_node(const Hierarchy& h) { return h.children(h.patches()[0])[1]; }

// Whether some violation of `invariant` carries `text` in its message.
bool reports_message(const std::vector<Violation>& violations, const std::string& invariant, const std::string& text) {
  for (const auto& v : violations)
    if (v.invariant == invariant && v.message.find(text) != std::string::npos) return true;
  return false;
}

// The vertex of the leaf mesh at `p` exactly (-1 when there is none).
int vertex_at(const Hierarchy& h, const Vec3& p) {
  for (auto v : h.impl().mesh.vertices())
    if (to_vec3(h.impl().mesh.point(v)) == p) return v.idx();
  return -1;
}

// Every node's stored area set to the area its corners span, so the stored-area check stays quiet.
void store_corner_areas(Hierarchy& h) {
  std::vector<Vec3> corners;
  for (NodeId n = 0; n < h.node_count(); ++n) {
    h.corners(n, corners);
    h.impl().area[n] = aarad::area(corners);
  }
}

// The midpoint (1, 0.5) of R's left edge (a hanging vertex of L) moved by dx into R: R's four children then
// leave a sliver of area dx / 2 uncovered, while every node's stored area agrees with its corners and nothing
// leaves its parent. R has area 1, so the children cover 1 - dx / 2 of it.
std::vector<Violation> with_gap(double dx) {
  Hierarchy h = refined();
  const int v = vertex_at(h, Vec3(1, 0.5, 0));
  EXPECT_GE(v, 0);
  if (v < 0) return {};
  h.impl().mesh.point(LeafMesh::VertexHandle(v))[0] += dx;
  store_corner_areas(h);
  return check_invariants(h);
}

TEST(InvariantBroken, ChildAreasNoLongerSumToParent) {
  // The checker's tolerance is 1e-12 relative (docs/hierarchy.md); a gap of 1e-11 of R's area is reported
  // as the children's sum, a gap of 1e-13 is not.
  const std::vector<Violation> gap = with_gap(2e-11);
  EXPECT_TRUE(reports_message(gap, "children-tile-parent", "cover")) << describe(gap);
  EXPECT_FALSE(reports_message(gap, "children-tile-parent", "stores area")) << describe(gap);
  EXPECT_FALSE(reports_message(gap, "children-tile-parent", "outside")) << describe(gap);
  const std::vector<Violation> within = with_gap(2e-13);
  EXPECT_FALSE(reports_message(within, "children-tile-parent", "cover")) << describe(within);
}

TEST(InvariantBroken, ChildOutsideItsParentInItsPlane) {
  // The same midpoint moved out of R into L, within the plane, by 10x the length tolerance (1e-9 of the scene
  // diagonal): child corners outside R are reported; at a tenth of the tolerance they are not.
  auto moved = [](double factor) {
    Hierarchy h = refined();
    const double tolerance = 1e-9 * h.scene().diagonal();
    const int v = vertex_at(h, Vec3(1, 0.5, 0));
    EXPECT_GE(v, 0);
    if (v < 0) return std::vector<Violation>{};
    h.impl().mesh.point(LeafMesh::VertexHandle(v))[0] -= factor * tolerance;
    store_corner_areas(h);
    return check_invariants(h);
  };
  const std::vector<Violation> outside = moved(10.0);
  EXPECT_TRUE(reports_message(outside, "children-tile-parent", "lies outside node")) << describe(outside);
  EXPECT_FALSE(reports_message(outside, "children-tile-parent", "off the plane")) << describe(outside);
  const std::vector<Violation> within = moved(0.1);
  EXPECT_FALSE(reports_message(within, "children-tile-parent", "lies outside node")) << describe(within);
}

TEST(InvariantBroken, ChildNotCounterClockwise) {
  Hierarchy h = refined();
  const NodeId child = h.children(right_node(h))[3];
  ASSERT_EQ(h.corner_count(child), 4);
  std::array<int, 4>& c = h.impl().corners[child];
  std::reverse(c.begin(), c.end());  // same corners, same area, clockwise
  const auto violations = check_invariants(h);
  EXPECT_TRUE(reports_message(violations, "children-tile-parent",
                              "child " + std::to_string(child) + " of node " + std::to_string(right_node(h)) +
                                  " is not counter-clockwise"))
      << describe(violations);
  EXPECT_FALSE(reports_message(violations, "children-tile-parent", "stores area")) << describe(violations);
}

TEST(InvariantBroken, ChildrenOverlap) {
  Hierarchy h = refined();
  const auto children = h.children(right_node(h));
  // Child 2 claims child 1's corners: same area in total, but two children overlap and one quarter is bare.
  Hierarchy::Impl& m = h.impl();
  m.corners[children[2]] = m.corners[children[1]];
  const auto violations = check_invariants(h);
  bool overlap = false;
  for (const auto& v : violations) overlap |= v.invariant == "children-tile-parent" && v.message.find("overlap") != std::string::npos;
  EXPECT_TRUE(overlap) << describe(violations);
}

TEST(InvariantBroken, ChildrenOverlapAmongManyInitialElements) {
  // One patch of 20 x 10 initial elements (the sweep over their x ranges, not the four children of a split);
  // its last element claims the corners of its first, so two children far apart in index order overlap.
  MeshingOptions o;
  o.patch_size = 2.0;
  o.element_size = 0.1;
  Hierarchy h(test::rectangle_scene(), o);
  EXPECT_TRUE(check_invariants(h).empty()) << describe(check_invariants(h));
  const NodeId patch = h.patches()[0];
  const auto children = h.children(patch);
  ASSERT_GE(children.size(), 100u);
  Hierarchy::Impl& m = h.impl();
  m.corners[children.back()] = m.corners[children.front()];
  const auto violations = check_invariants(h);
  bool named = false;
  for (const auto& v : violations)
    named |= v.invariant == "children-tile-parent" && v.node == children.front() &&
             v.message.find("children " + std::to_string(children.front()) + " and " +
                            std::to_string(children.back()) + " of node " + std::to_string(patch) + " overlap") !=
                 std::string::npos;
  EXPECT_TRUE(named) << describe(violations);
}

TEST(InvariantBroken, ChildOutsideItsParentOrPlane) {
  Hierarchy h = refined();
  const NodeId grandchild = h.children(h.children(right_node(h))[0])[2];  // its corner 0 is R's centre
  Hierarchy::Impl& m = h.impl();
  const auto v = LeafMesh::VertexHandle(m.corners[grandchild][0]);
  m.mesh.point(v)[2] += 1e-3;  // lift the centre of R off the plane
  const auto violations = check_invariants(h);
  bool off_plane = false;
  for (const auto& x : violations) off_plane |= x.invariant == "children-tile-parent" && x.message.find("off the plane") != std::string::npos;
  EXPECT_TRUE(off_plane) << describe(violations);
}

TEST(InvariantBroken, HalfEdgeLinksCorrupted) {
  Hierarchy h = refined();
  LeafMesh& mesh = h.impl().mesh;
  const auto f = LeafMesh::FaceHandle(h.impl().face[left_leaf(h)]);
  const auto first = mesh.halfedge_handle(f);
  mesh.set_next_halfedge_handle(first, mesh.next_halfedge_handle(mesh.next_halfedge_handle(first)));
  EXPECT_TRUE(reports(check_invariants(h), "leaf-mesh-manifold")) << describe(check_invariants(h));
}

// OpenMesh walks a vertex's fan from the one halfedge the vertex links: linked to a halfedge of another vertex,
// the fan walked is that vertex's; linked to an inner halfedge, a boundary vertex reads as inner (is_boundary).
TEST(InvariantBroken, VertexLinksAHalfedgeThatDoesNotLeaveItOrIsNotItsBoundary) {
  Hierarchy h = refined();
  LeafMesh& mesh = h.impl().mesh;
  const auto corner = LeafMesh::VertexHandle(vertex_at(h, Vec3(1, 0, 0)));  // on the outer boundary
  const auto inner = LeafMesh::VertexHandle(vertex_at(h, Vec3(1.5, 0.5, 0)));  // inside R
  ASSERT_TRUE(corner.is_valid() && inner.is_valid());
  ASSERT_TRUE(mesh.is_boundary(corner));
  const auto own = mesh.halfedge_handle(corner);
  mesh.set_halfedge_handle(corner, mesh.halfedge_handle(inner));
  EXPECT_TRUE(reports_message(check_invariants(h), "leaf-mesh-manifold", "which does not leave it"))
      << describe(check_invariants(h));
  mesh.set_halfedge_handle(corner, own);
  EXPECT_TRUE(check_invariants(h).empty()) << describe(check_invariants(h));
  for (auto out : mesh.voh_range(corner))
    if (!mesh.is_boundary(out)) {
      mesh.set_halfedge_handle(corner, out);
      break;
    }
  ASSERT_FALSE(mesh.is_boundary(corner));
  EXPECT_TRUE(reports_message(check_invariants(h), "leaf-mesh-manifold", "not its boundary halfedge"))
      << describe(check_invariants(h));
}

// The leaf mesh is compared with the scene, not only with the outline taken when it was built: a unit square's
// mesh, given the 2 x 1 rectangle of the same plane as its scene, leaves half of the surface uncovered.
TEST(InvariantBroken, PatchesThatDoNotCoverTheirSurface) {
  MeshingOptions o;
  o.patch_size = 2.0;
  o.element_size = 1.0;
  Hierarchy rectangle(test::rectangle_scene(), o), half(test::square_scene(), o);
  ASSERT_TRUE(check_invariants(half).empty()) << describe(check_invariants(half));
  half.impl().scene_ptr = rectangle.impl().scene_ptr;
  EXPECT_TRUE(reports_message(check_invariants(half), "surface-covered", "cover 1 of its area 2"))
      << describe(check_invariants(half));
}

// Node ids 3 and 10 swapped with every link kept: parent 10 now has children 3, 7, 8 and 9 of smaller ids, which
// the bottom-up passes (update_inner_radiosity, the mean check) would visit before it. A patch list that names a
// leaf instead of a root is reported too.
TEST(InvariantBroken, ChildWithASmallerIdThanItsParentOrAPatchListNamingALeaf) {
  Hierarchy h = refined();
  Hierarchy::Impl& m = h.impl();
  const NodeId a = 3, b = 10;
  ASSERT_EQ(m.parent[a], 2u);
  ASSERT_EQ(m.child_count[b], 0u);
  const auto swap = [&](auto& values) { std::swap(values[a], values[b]); };
  swap(m.parent), swap(m.child_begin), swap(m.child_count), swap(m.level), swap(m.patch_of), swap(m.surface);
  swap(m.corners), swap(m.area), swap(m.radiosity), swap(m.unshot), swap(m.face), swap(m.loop_revision);
  const auto renamed = [&](NodeId& n) { n = n == a ? b : n == b ? a : n; };
  for (NodeId& n : m.parent) renamed(n);
  for (NodeId& n : m.child_ids) renamed(n);
  for (auto f : m.mesh.faces()) renamed(m.mesh.property(m.face_node, f));
  const auto violations = check_invariants(h);
  EXPECT_TRUE(reports_message(violations, "levels-parents", "whose id is not smaller")) << describe(violations);
  EXPECT_TRUE(reports_message(violations, "radiosity-mean", "no leaf below it reaches it")) << describe(violations);

  Hierarchy g = refined();
  g.impl().patch_ids[0] = left_leaf(g);
  EXPECT_TRUE(reports_message(check_invariants(g), "levels-parents", "which is not a root"))
      << describe(check_invariants(g));
}

TEST(InvariantBroken, HoleInTheLeafMeshIsACrack) {
  Hierarchy h = refined();
  LeafMesh& mesh = h.impl().mesh;
  mesh.request_face_status();
  mesh.request_edge_status();
  mesh.request_vertex_status();
  // Remove the face of one grandchild in the middle of R: its edges become open inside the surface.
  const NodeId grandchild = h.children(h.children(right_node(h))[0])[2];
  mesh.delete_face(LeafMesh::FaceHandle(h.impl().face[grandchild]), false);
  const auto violations = check_invariants(h);
  EXPECT_TRUE(reports(violations, "no-crack")) << describe(violations);
  EXPECT_TRUE(reports(violations, "face-node-map")) << describe(violations);
}

TEST(InvariantBroken, OuterBoundaryMoved) {
  Hierarchy h = refined();
  LeafMesh& mesh = h.impl().mesh;
  // Corner (0, 0) of L, on the outer boundary, moved outwards within the plane.
  const auto v = LeafMesh::VertexHandle(h.impl().corners[left_leaf(h)][0]);
  ASSERT_EQ(to_vec3(mesh.point(v)), Vec3(0, 0, 0));
  mesh.point(v) = OpenMesh::Vec3d(-0.1, -0.1, 0.0);
  const auto violations = check_invariants(h);
  EXPECT_TRUE(reports(violations, "outer-boundary")) << describe(violations);
  EXPECT_TRUE(reports(violations, "no-crack")) << describe(violations);
}

TEST(InvariantBroken, HangingVertexOffItsHostEdge) {
  Hierarchy h = refined();
  LeafMesh& mesh = h.impl().mesh;
  // The hanging vertex (1, 0.5) on L's right edge, pushed into R.
  for (auto v : mesh.fv_range(LeafMesh::FaceHandle(h.impl().face[left_leaf(h)])))
    if (to_vec3(mesh.point(v)) == Vec3(1, 0.5, 0)) mesh.point(v)[0] += 1e-6;
  EXPECT_TRUE(reports(check_invariants(h), "hanging-vertex-on-edge")) << describe(check_invariants(h));
}

TEST(InvariantBroken, LevelDisagreesWithParent) {
  Hierarchy h = refined();
  h.impl().level[h.children(right_node(h))[3]] = 3;
  EXPECT_TRUE(reports(check_invariants(h), "levels-parents")) << describe(check_invariants(h));
}

TEST(InvariantBroken, ParentLinkDisagrees) {
  Hierarchy h = refined();
  h.impl().parent[h.children(right_node(h))[3]] = left_leaf(h);
  EXPECT_TRUE(reports(check_invariants(h), "levels-parents")) << describe(check_invariants(h));
}

TEST(InvariantBroken, FaceMapsToTheWrongNode) {
  Hierarchy h = refined();
  Hierarchy::Impl& m = h.impl();
  m.mesh.property(m.face_node, LeafMesh::FaceHandle(m.face[left_leaf(h)])) = right_node(h);
  EXPECT_TRUE(reports(check_invariants(h), "face-node-map")) << describe(check_invariants(h));
}

TEST(InvariantBroken, LeafWithoutFace) {
  Hierarchy h = refined();
  h.impl().face[left_leaf(h)] = -1;
  EXPECT_TRUE(reports(check_invariants(h), "face-node-map")) << describe(check_invariants(h));
}

TEST(InvariantBroken, LeavesOfTwoSurfacesShareAnEdge) {
  Scene scene = test::rectangle_scene();
  const std::uint32_t group = scene.add_group("lid");
  scene.add_face(group, 0, {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}});  // a second surface above
  scene.build_surfaces();
  ASSERT_EQ(scene.surfaces.size(), 2u);
  MeshingOptions o;
  o.patch_size = 2.0;
  o.element_size = 1.0;
  Hierarchy h(scene, o);
  ASSERT_TRUE(check_invariants(h).empty()) << describe(check_invariants(h));
  h.impl().surface[h.leaves()[0]] = 1;  // as if L belonged to the lid
  EXPECT_TRUE(reports(check_invariants(h), "surface-component")) << describe(check_invariants(h));
  h.impl().surface[h.leaves()[0]] = 7;  // a surface that does not exist
  EXPECT_TRUE(reports(check_invariants(h), "levels-parents")) << describe(check_invariants(h));
}

TEST(InvariantBroken, BalanceViolatedWhenBalanceIsOn) {
  // Child 0 of R is its lower-left quarter: its level-3 children border L (level 1), fine without balance.
  Hierarchy h = refined(false);
  EXPECT_TRUE(check_invariants(h).empty());
  h.impl().options.balance = true;
  EXPECT_TRUE(reports(check_invariants(h), "balance")) << describe(check_invariants(h));
}

TEST(InvariantBroken, InnerRadiosityIsNotTheMeanOfItsLeaves) {
  Hierarchy h = refined();
  h.radiosity(h.children(right_node(h))[2]).g += 1e-6;  // a leaf changed without its ancestors
  EXPECT_TRUE(reports(check_invariants(h), "radiosity-mean")) << describe(check_invariants(h));
  Hierarchy g = refined();
  g.radiosity(g.patches()[0]).r *= 2.0;
  EXPECT_TRUE(reports(check_invariants(g), "radiosity-mean")) << describe(check_invariants(g));
}

// Values that are not numbers pass every comparison with a tolerance; they are reported by name.
TEST(InvariantBroken, NotANumberOrInfinityIsReported) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  Hierarchy inner = refined();
  inner.radiosity(inner.patches()[0]).g = nan;
  EXPECT_TRUE(reports(check_invariants(inner), "finite-values")) << describe(check_invariants(inner));
  Hierarchy leaf = refined();
  leaf.radiosity(left_leaf(leaf)).b = inf;
  leaf.update_inner_radiosity();
  EXPECT_TRUE(reports(check_invariants(leaf), "finite-values")) << describe(check_invariants(leaf));
  Hierarchy area = refined();
  area.impl().area[left_leaf(area)] = nan;
  EXPECT_TRUE(reports(check_invariants(area), "finite-values")) << describe(check_invariants(area));
  Hierarchy vertex = refined();
  const auto v = LeafMesh::VertexHandle(vertex.impl().corners[left_leaf(vertex)][0]);
  vertex.impl().mesh.point(v)[1] = nan;
  EXPECT_TRUE(reports(check_invariants(vertex), "finite-values")) << describe(check_invariants(vertex));
}

// The whole surface moved off its plane: every child still lies in its parent's plane, but not in the surface's.
TEST(InvariantBroken, SurfaceMovedOffItsPlane) {
  Hierarchy h = refined();
  for (auto v : h.impl().mesh.vertices()) h.impl().mesh.point(v)[2] += 1e-6;
  const auto violations = check_invariants(h);
  EXPECT_TRUE(reports(violations, "surface-plane")) << describe(violations);
  EXPECT_FALSE(reports(violations, "children-tile-parent")) << describe(violations);
}

// The display reconstruction of refined(): sound as built; a hanging vertex showing its own value instead of the
// interpolation along its host edge is a shading seam; a triangle left out is a crack, one repeated an overlap.
TEST(InvariantBroken, DisplayHangingVertexNotInterpolatedOrTrianglesNotTilingTheLeaf) {
  const Hierarchy h = refined();
  std::vector<Rgb> values(h.node_count());
  for (NodeId n = 0; n < h.node_count(); ++n) values[n] = h.radiosity(n);
  const DisplayMesh sound = build_display_mesh(h, values);
  EXPECT_TRUE(check_display(h, sound).empty()) << describe(check_display(h, sound));

  DisplayMesh seam = sound;
  const int hanging = vertex_at(h, Vec3(1, 0.5, 0));  // on L's right edge, a corner of R's children
  ASSERT_GE(hanging, 0);
  seam.vertex_values[static_cast<std::size_t>(hanging)].g += 1e-6;
  EXPECT_TRUE(reports(check_display(h, seam), "display-hanging-vertex")) << describe(check_display(h, seam));

  DisplayMesh crack = sound;
  crack.triangles.pop_back();
  crack.triangle_leaf.pop_back();
  EXPECT_TRUE(reports(check_display(h, crack), "display-crack-free")) << describe(check_display(h, crack));

  DisplayMesh overlap = sound;
  overlap.triangles.push_back(sound.triangles.front());
  overlap.triangle_leaf.push_back(sound.triangle_leaf.front());
  EXPECT_TRUE(reports(check_display(h, overlap), "display-crack-free")) << describe(check_display(h, overlap));

  DisplayMesh moved = sound;
  moved.positions[0].x += 0.25;
  EXPECT_TRUE(reports(check_display(h, moved), "display-positions")) << describe(check_display(h, moved));
}

// Damage that only one check sees. Two copies of one triangle of a square leaf (its diagonal halves have equal
// areas) cover the leaf's area exactly but overlap: only the directed-edge check reports it. A triangle handed to
// an inner node is reported at that node.
TEST(InvariantBroken, DisplayTrianglesThatOverlapWithTheRightAreaOrBelongToAnInnerNode) {
  const Hierarchy h = refined();
  std::vector<Rgb> values(h.node_count());
  for (NodeId n = 0; n < h.node_count(); ++n) values[n] = h.radiosity(n);
  const DisplayMesh sound = build_display_mesh(h, values);
  std::size_t pair = sound.triangles.size();
  for (std::size_t t = 0; t + 1 < sound.triangles.size() && pair == sound.triangles.size(); ++t) {
    const NodeId leaf = sound.triangle_leaf[t];
    const auto count = std::count(sound.triangle_leaf.begin(), sound.triangle_leaf.end(), leaf);
    if (count == 2 && sound.triangle_leaf[t + 1] == leaf) pair = t;
  }
  ASSERT_LT(pair, sound.triangles.size()) << "no leaf of two triangles";
  DisplayMesh folded = sound;
  folded.triangles[pair + 1] = folded.triangles[pair];
  EXPECT_TRUE(reports_message(check_display(h, folded), "display-crack-free", "two triangles on the same side"))
      << describe(check_display(h, folded));

  DisplayMesh foreign = sound;
  const NodeId inner = h.patches()[0];
  ASSERT_FALSE(h.is_leaf(inner));
  foreign.triangle_leaf.back() = inner;
  EXPECT_TRUE(reports_message(check_display(h, foreign), "display-crack-free", "not a leaf"))
      << describe(check_display(h, foreign));
}

// A patch not at level 0 is reported at the patch itself (its children's levels disagree with it too).
TEST(InvariantBroken, PatchLevelNotZeroIsReportedAtThePatch) {
  Hierarchy h = refined();
  const NodeId patch = h.patches()[0];
  h.impl().level[patch] = 1;
  bool at_patch = false;
  for (const Violation& v : check_invariants(h)) at_patch = at_patch || (v.invariant == "levels-parents" && v.node == patch);
  EXPECT_TRUE(at_patch) << describe(check_invariants(h));
}

// A 2 x 1 rectangle a million units from the origin (a building in georeferenced metres), every leaf split
// three times: its points are known to about 1e-10 there, which is above the tolerances relative to its size,
// so those follow the position error instead. The intact mesh reports nothing; real damage still shows.
TEST(InvariantBroken, FarFromTheOriginTolerancesFollowThePositionError) {
  const double x = 1e6, y = 1e6;
  MeshingOptions o;
  o.patch_size = 0.7;
  o.element_size = 0.3;
  o.min_area = 1e-9;
  Hierarchy h(test::polygon_scene({{x, y}, {x + 2, y}, {x + 2, y + 1}, {x, y + 1}}), o);
  for (int round = 0; round < 3; ++round)
    for (NodeId leaf : h.leaves()) EXPECT_TRUE(h.split(leaf).ok);
  double value = 0.1;
  for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(value += 0.01);
  h.update_inner_radiosity();
  const auto violations = check_invariants(h);
  EXPECT_TRUE(violations.empty()) << violations.size() << " violations, the first: " << describe(violations).substr(0, 300);

  const NodeId leaf = h.leaves()[7];
  h.radiosity(leaf).g *= 1.0 + 1e-5;  // a leaf changed without its ancestors
  EXPECT_TRUE(reports(check_invariants(h), "radiosity-mean"));
  h.radiosity(leaf).g /= 1.0 + 1e-5;
  h.impl().area[leaf] *= 1.0 + 1e-4;  // far more than the position error moves an area
  EXPECT_TRUE(reports_message(check_invariants(h), "children-tile-parent", "stores area"));
}

// Hierarchy::add_radiosity divides by a node's stored area, which far from the origin may differ from the sum of its
// leaves' areas by what check_tiling allows (1.3e-8 relative here): the mean it keeps is not a violation. A 2 x 1
// rectangle turned by 30 degrees a million units from the origin, split at random and lit leaf by leaf.
TEST(InvariantBroken, FarFromTheOriginLeavesLitOneByOneKeepTheirMean) {
  const double x = 1e6, y = 1e6, c = std::cos(0.5236), s = std::sin(0.5236);
  const auto at = [&](double u, double v) { return Vec2(x + c * u - s * v, y + s * u + c * v); };
  MeshingOptions o;
  o.patch_size = 0.7;
  o.element_size = 0.3;
  Hierarchy h(test::polygon_scene({at(0, 0), at(2, 0), at(2, 1), at(0, 1)}), o);
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (NodeId n : h.leaves()) h.radiosity(n) = Rgb(unit(random));
  h.update_inner_radiosity();
  std::vector<NodeId> recent;
  for (int step = 0; step < 300; ++step) {
    const auto leaves = h.leaves();
    const NodeId target = !recent.empty() && unit(random) < 0.85 ? recent[random() % recent.size()]
                                                                   : leaves[random() % leaves.size()];
    const SplitResult split = h.split(target);
    recent = split.ok ? split.children : std::vector<NodeId>{};
    if (step % 3 == 0) h.add_radiosity(h.leaves()[random() % h.leaf_count()], Rgb(unit(random)));
  }
  EXPECT_GT(h.leaf_count(), 500u);
  const auto violations = check_invariants(h);
  EXPECT_TRUE(violations.empty()) << violations.size() << " violations, the first: " << describe(violations).substr(0, 300);
  const NodeId leaf = h.leaves()[11];
  h.radiosity(leaf).g *= 1.0 + 1e-5;  // a leaf changed without its ancestors
  EXPECT_TRUE(reports(check_invariants(h), "radiosity-mean"));
}

TEST(InvariantBroken, StoredAreaWrong) {
  Hierarchy h = refined();
  h.impl().area[left_leaf(h)] = 0.5;
  EXPECT_TRUE(reports_message(check_invariants(h), "children-tile-parent", "stores area 0.5"))
      << describe(check_invariants(h));
  // 10x the 1e-12 relative tolerance on one child's stored area is reported, 0.1x is not.
  Hierarchy g = refined();
  const NodeId child = g.children(right_node(g))[1];
  const double area = g.impl().area[child];
  g.impl().area[child] = area * (1.0 + 1e-11);
  EXPECT_TRUE(reports_message(check_invariants(g), "children-tile-parent", "node " + std::to_string(child) + " stores area"))
      << describe(check_invariants(g));
  g.impl().area[child] = area * (1.0 + 1e-13);
  EXPECT_FALSE(reports_message(check_invariants(g), "children-tile-parent", "stores area"))
      << describe(check_invariants(g));
}

}  // namespace
}  // namespace aarad::mesh
