// The patch/element hierarchy: leaf elements of every physical surface in one OpenMesh PolyMesh, the tree
// of patches and elements in plain arrays (Cohen, Greenberg, Immel and Brock 1986, "An efficient radiosity
// approach for realistic image synthesis": patches shoot, elements receive).
//
// API contract shared by the solver (refine/), the display/export code and the invariant checker.
// The implementation may add members; it must not change the meaning of these.
#pragma once

#include "aarad/core/math.h"
#include "aarad/core/rgb.h"
#include "aarad/core/scene.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace aarad::mesh {

using NodeId = std::uint32_t;
inline constexpr NodeId kNoNode = 0xffffffffu;

struct MeshingOptions {
  double patch_size = 0.0;    // longest patch edge, scene units; 0 picks a default from the scene's size
  double element_size = 0.0;  // longest initial element edge; 0 picks a default from the scene's size
  int max_level = 8;          // deepest node level; patches are level 0
  double min_area = 0.0;      // smallest element a split may create; 0 picks a default from the scene's size
  bool balance = false;       // keep edge-neighbours within one level of each other
  // Refuse sizes that would make more initial patches or elements than this, counted per surface before
  // meshing it (each element costs about a kilobyte through a solve). At most kMostInitialElements.
  double max_initial_elements = 2e6;
};

// The largest max_initial_elements (a terabyte of elements; grid indices stay within an int).
inline constexpr double kMostInitialElements = 1e9;

struct SplitResult {
  bool ok = false;
  std::string reason;                // why the split was refused, empty when ok
  std::vector<NodeId> children;      // the four children when ok
  std::vector<NodeId> also_split;    // nodes split by balancing, each now an inner node
};

class Hierarchy {
 public:
  // Meshes a copy of `scene`. Throws what Scene::validate() throws first (a scene built in code whose surfaces are
  // not built, or with a face the initial meshing cannot take), and aarad::Error for bad options.
  Hierarchy(const Scene& scene, const MeshingOptions& options);
  // Meshes `*scene` and reads it through the pointer for the hierarchy's life, without a copy (a million-face scene
  // is some 200 MB). A pointer that owns nothing (std::shared_ptr's aliasing constructor) shares a scene its caller
  // keeps alive, as refine::Solver does. Throws as above, and aarad::Error for a null pointer.
  Hierarchy(std::shared_ptr<const Scene> scene, const MeshingOptions& options);
  ~Hierarchy();
  // A hierarchy moved from holds nothing: it may only be assigned to or destroyed.
  Hierarchy(Hierarchy&&) noexcept;
  Hierarchy& operator=(Hierarchy&&) noexcept;

  const Scene& scene() const;
  const MeshingOptions& options() const;  // with defaults resolved

  // Nodes. Patches are the top nodes of each surface (level 0); elements are their descendants. The accessors below
  // take a node below node_count() and do not check it (they run in the solver's inner loops); split(),
  // edge_neighbours() and leaf_polygon() check theirs and throw.
  std::size_t node_count() const;
  std::span<const NodeId> patches() const;
  NodeId parent(NodeId node) const;              // kNoNode for patches
  std::span<const NodeId> children(NodeId node) const;  // empty for leaves
  bool is_leaf(NodeId node) const;
  int level(NodeId node) const;
  NodeId patch(NodeId node) const;               // the patch a node belongs to (itself for a patch)
  std::uint32_t surface(NodeId node) const;      // index into scene().surfaces
  double area(NodeId node) const;
  Vec3 centroid(NodeId node) const;
  const Plane& plane(NodeId node) const;         // the surface's plane
  // Corners (not hanging vertices) counter-clockwise seen from the front: 3 or 4 points.
  std::vector<Vec3> corners(NodeId node) const;
  int corner_count(NodeId node) const;                    // 3 or 4
  void corners(NodeId node, std::vector<Vec3>& out) const;  // the same, into a reused buffer
  // Vertex indices of the corners, in the same order (the first corner_count(node) are meaningful): corners
  // of different nodes with equal indices are the same point, and corners at the same point have equal indices
  // except where faces of one surface touch at that point only (each fan of elements around it has its own copy,
  // so the leaf mesh stays manifold).
  std::array<std::uint32_t, 4> corner_vertices(NodeId node) const;
  // The leaf's face loop: its corners and the hanging vertices on its edges, counter-clockwise from its first
  // corner. Throws aarad::Error when `leaf` is not a leaf (as edge_neighbours does).
  void leaf_polygon(NodeId leaf, std::vector<Vec3>& out) const;
  // The same with every point's vertex index in `vertices`, in the same order (shared as corner_vertices' are: the
  // leaves on either side of an edge name its hanging vertices with the same indices).
  void leaf_polygon(NodeId leaf, std::vector<Vec3>& out, std::vector<std::uint32_t>& vertices) const;
  // The revision() at which the leaf's face loop last changed: when the leaf was made, or when a neighbour's split
  // put a new hanging vertex on one of its edges. A copy of the loops taken at revision r still holds every leaf
  // whose loop_revision is at most r.
  std::uint64_t loop_revision(NodeId leaf) const;

  // Radiosity B of every node and unshot radiosity dB (meaningful for patches), per channel.
  Rgb& radiosity(NodeId node);
  const Rgb& radiosity(NodeId node) const;
  Rgb& unshot(NodeId node);
  const Rgb& unshot(NodeId node) const;
  // The same for every node, indexed by NodeId, for loops over many nodes (the accessors above are out of line).
  // Valid until the next split adds nodes.
  std::span<Rgb> radiosities();
  std::span<Rgb> unshots();
  std::span<const Rgb> radiosities() const;
  std::span<const Rgb> unshots() const;
  // Adds `delta` to the radiosity of `leaf` and delta x area(leaf) / area(a) to every ancestor a, so each
  // inner node keeps the area-weighted mean of its leaves (an invariant check_invariants verifies). O(level).
  // Throws aarad::Error for a node that is not a leaf.
  void add_radiosity(NodeId leaf, const Rgb& delta);
  // Recomputes the radiosity of every inner node as the area-weighted mean of its children, bottom up. O(n).
  void update_inner_radiosity();
  // The same on `values` (one per node, indexed by NodeId) instead of the stored radiosity: leaves keep their
  // value, every inner node gets the area-weighted mean of its children's, bottom up. O(n).
  void average_inner_nodes(std::span<Rgb> values) const;

  // Leaves in a deterministic order (by node id). leaf_count() is O(1).
  std::vector<NodeId> leaves() const;
  std::size_t leaf_count() const;
  // Leaves below `node` (the node itself when it is a leaf), by node id.
  std::vector<NodeId> leaves_under(NodeId node) const;
  // The same, appended to `out`; `stack` is scratch. Allocates nothing once both have grown.
  void leaves_under(NodeId node, std::vector<NodeId>& out, std::vector<NodeId>& stack) const;

  // Increases whenever the leaf set changes, so callers can cache views of the leaves.
  std::uint64_t revision() const;

  // Counts of the initial meshing: patches().size() patches and this many level-1 elements.
  std::size_t initial_element_count() const;
  // Bytes held by the leaf mesh and the node arrays (container capacities).
  std::size_t memory_bytes() const;

  // Splits leaf `node` into four (quads into four quads, triangles into four triangles). Edge midpoints a
  // neighbour already made are reused; an unsplit neighbour gains the midpoint as a hanging vertex (and its
  // loop_revision becomes the new revision).
  // Children inherit the parent's B and unshot 0. Refused (ok = false) when the node is not a leaf, when
  // its level is max_level, when a child would be smaller than min_area, or when the node is too small for its
  // children's corners to be distinct points in floating point. With balance on, neighbours
  // are split first so edge-neighbours differ by at most one level.
  SplitResult split(NodeId node);
  // Whether split(node) would be accepted (the same tests, without composing a reason).
  bool can_split(NodeId node) const;
  // With balance: the leaves split(node) would split first so that edge-neighbours differ by at most one level (its
  // coarser edge-neighbours, theirs, and so on), into `out`; empty without balance. Each must accept its split, or
  // split(node) is refused.
  void forced_splits(NodeId node, std::vector<NodeId>& out) const;

  // Leaves of the same surface that share a piece of an edge with leaf `node` (across hanging vertices too),
  // in the order of the leaf's face loop. O(number of vertices on the leaf's loop).
  std::vector<NodeId> edge_neighbours(NodeId node) const;
  void edge_neighbours(NodeId node, std::vector<NodeId>& out) const;  // the same, into a reused buffer

  // The mesh of leaves; implementation types are in mesh/leaf_mesh.h.
  struct Impl;
  const Impl& impl() const { return *impl_; }
  Impl& impl() { return *impl_; }

 private:
  enum class Refusal { kNone, kMissing, kInner, kMaxLevel, kMinArea, kDegenerate };
  // Why split(node) would be refused (kNone: it would not); `smallest` gets the smallest child's area when the
  // area was tested.
  Refusal refusal(NodeId node, double& smallest) const;
  std::array<NodeId, 4> split_leaf(NodeId node);  // the split itself, no checks
  void require_leaf(NodeId node, const char* query) const;  // throws aarad::Error unless `node` is a leaf
  void split_coarser_neighbours(NodeId node, std::vector<NodeId>& also_split);
  // With balance: the first of forced_splits(node) that refuses a split (its refusal in `why`), or kNoNode.
  NodeId balance_blocker(NodeId node, Refusal& why) const;

  std::unique_ptr<Impl> impl_;
};

}  // namespace aarad::mesh
