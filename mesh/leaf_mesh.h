// Hierarchy::Impl: the leaf mesh (one OpenMesh PolyMesh with double points) and the node tree in plain arrays.
// Included by the mesh/ implementation files and by tests that corrupt the structure on purpose to show that
// check_invariants reports it; everything is public for that reason. Library users stay with hierarchy.h.
//
// Handles and garbage collection: a split never deletes a face, edge or vertex. It reuses the parent's face
// handle for one child and lets OpenMesh's insert_edge create the other three, and split_edge inserts the
// edge midpoints (which become hanging vertices of an unsplit neighbour). Nothing is ever marked deleted, so
// no garbage collection ever runs and every stored handle index (Impl::face, Impl::corners) stays valid for
// the life of the hierarchy.
#pragma once

#include "aarad/mesh/hierarchy.h"

#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace aarad::mesh {

struct LeafMeshTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using LeafMesh = OpenMesh::PolyMesh_ArrayKernelT<LeafMeshTraits>;

inline Vec3 to_vec3(const OpenMesh::Vec3d& p) { return {p[0], p[1], p[2]}; }
inline OpenMesh::Vec3d to_point(const Vec3& p) { return {p.x, p.y, p.z}; }

// The outer boundary of one physical surface as meshed initially: maximal straight segments, and its length.
// Leaf-mesh boundary halfedges must lie on these segments forever (check_invariants, "no-crack").
struct SurfaceBoundary {
  std::vector<std::array<Vec3, 2>> segments;
  double length = 0.0;
};

struct Hierarchy::Impl {
  std::shared_ptr<const Scene> scene_ptr;  // a copy of the scene, or the caller's (Hierarchy's constructors)
  const Scene& scene() const { return *scene_ptr; }
  MeshingOptions options;  // defaults resolved

  LeafMesh mesh;
  OpenMesh::FPropHandleT<NodeId> face_node;  // leaf face -> its node

  // The tree, indexed by NodeId. A node's children are child_ids[child_begin .. child_begin + child_count);
  // children always have larger ids than their parent.
  std::vector<NodeId> parent;
  std::vector<std::uint32_t> child_begin;
  std::vector<std::uint32_t> child_count;
  std::vector<NodeId> child_ids;
  std::vector<std::uint8_t> level;
  std::vector<NodeId> patch_of;
  std::vector<std::uint32_t> surface;
  std::vector<std::array<int, 4>> corners;  // vertex indices, counter-clockwise; [3] = -1 for a triangle
  std::vector<double> area;
  std::vector<Rgb> radiosity;
  std::vector<Rgb> unshot;
  std::vector<int> face;  // face index of a leaf, -1 for an inner node
  std::vector<std::uint64_t> loop_revision;  // the revision at which a leaf's face loop last changed

  std::vector<NodeId> patch_ids;
  std::vector<SurfaceBoundary> boundaries;  // per surface
  std::size_t initial_elements = 0;
  std::size_t leaf_count = 0;
  std::uint64_t revision = 0;
  // The vertices, edges and faces the mesh has room for (LeafMesh::reserve; OpenMesh does not report it).
  std::array<std::size_t, 3> mesh_room{0, 0, 0};

  // Appends a node, made at the current revision; returns its id.
  NodeId add_node(NodeId parent_id, int node_level, NodeId patch_id, std::uint32_t surface_id,
                  const std::array<int, 4>& corner_vertices);
  // Room for one more split in every array it grows (the node arrays, the mesh's elements and properties), reserved
  // ahead in doubling steps: memory that runs out then throws here, before the split has changed anything.
  void make_room_for_split();
  int corner_count(NodeId node) const { return corners[node][3] < 0 ? 3 : 4; }
  Vec3 point(int vertex) const { return to_vec3(mesh.point(LeafMesh::VertexHandle(vertex))); }
  double corner_area(NodeId node) const;
};

}  // namespace aarad::mesh
