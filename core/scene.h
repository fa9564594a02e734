// The scene model: groups of planar polygons with materials, grouped into physical surfaces.
// Import (core/obj_import.h) and the built-in scenes (core/builtin_scenes.h) produce it; the mesh layer
// meshes its physical surfaces; the solver reads materials through them.
#pragma once

#include "aarad/core/math.h"
#include "aarad/core/rgb.h"

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace aarad {

// The largest emitted radiosity, and the largest emitted flux of a scene, accepted per channel. The solver
// multiplies fluxes by area ratios and sums them; far below the largest double, these bounds keep every such
// sum finite. Radiosity is linear in the emission, so a scene can always be scaled into them.
inline constexpr double kMaxEmission = 1e100;
inline constexpr double kMaxEmittedFlux = 1e200;
// The smallest emitted radiosity and reflectance accepted per channel, other than 0. Below about 1e-308 a double
// loses digits (subnormal numbers): a unit box lit with Ke 1e-308 solved 20 % off, with Ke 1e-316 it split into
// 422 000 elements in 10 shots and ended off by 2 to 4 times, and with Ke 1e-320 it came out black.
inline constexpr double kMinEmission = 1e-100;
inline constexpr double kMinReflectance = 1e-100;
// Distances below this fraction of the scene's diagonal are rounding errors of the input: faces whose vertices lie
// that close to one plane join one surface (build_surfaces), and the initial meshing joins vertices, and T-junctions,
// that close to each other.
inline constexpr double kPlaneDistance = 1e-6;
// A face smaller than this fraction of the scene's diagonal is below what the meshing resolves (its vertices lie
// within a few kPlaneDistance of one another): the importer skips it with a warning.
inline constexpr double kSmallestFace = 10.0 * kPlaneDistance;
// How far from the origin a scene may lie, in multiples of its diagonal: there doubles still resolve a tenth of
// kPlaneDistance of the diagonal (their spacing at a coordinate x is about x x 2.2e-16). A unit box 1e13 from the
// origin solved 6 % off, 1e14 out 2.4 % of its light escaped, and 1e15 out the hemicube found its faces turned
// round; the office solves alike at the origin and 4e9 of its diagonals out. The bound is 4.5e8.
inline constexpr double kMaxRemoteness = 0.1 * kPlaneDistance / std::numeric_limits<double>::epsilon();

struct Material {
  std::string name;
  Rgb reflectance{0.5};  // rho per channel, each in [0, 1)
  Rgb emission{0.0};     // emitted radiosity (exitance) per channel, >= 0

  bool emits() const { return emission.max_component() > 0.0; }
};

// One planar polygon of the scene. Its vertices run counter-clockwise seen from its front side, the side
// its normal points to and the side that receives and emits light.
struct Face {
  std::vector<Vec3> vertices;
  std::uint32_t group = 0;
  std::uint32_t material = 0;
  std::uint32_t surface = 0;  // index into Scene::surfaces
  int source_line = 0;        // line in the OBJ file, 0 for built-in geometry
  // OBJ smoothing group (`s N`; 0 for `s off` or none). Faces of one group (`o`/`g`) with the same nonzero
  // smoothing group are pieces of one curved surface: smooth.png and the PLY's vertex colours interpolate
  // across their shared edges (mesh/display.h). It changes no radiosity.
  std::uint32_t smoothing = 0;
};

// A named OBJ group ("o" or "g"); it holds one or more physical surfaces.
struct Group {
  std::string name;
  std::vector<std::uint32_t> faces;
  std::vector<std::uint32_t> surfaces;
};

// The faces of one group that lie in one plane and share one material. Pieces of one physical surface
// never occlude each other (the paper's identical-z exception, section 3.2.1).
struct Surface {
  std::uint32_t group = 0;
  std::uint32_t material = 0;
  std::uint32_t smoothing = 0;  // the smoothing group all its faces have (Face::smoothing); 0 when they differ
  Plane plane;  // the front side is the lit side
  std::vector<std::uint32_t> faces;
  double area = 0.0;
};

// A pinhole camera for images. vertical_fov is the full vertical angle in radians.
struct Camera {
  Vec3 eye{0.0};
  Vec3 forward{0.0, 0.0, 1.0};  // unit
  Vec3 up{0.0, 1.0, 0.0};       // unit, orthogonal to forward
  double vertical_fov = 0.6981317007977318;  // 40 degrees
};

// Meshing sizes chosen by a scene's author, in scene units (refine::default_meshing gives them to the hierarchy;
// 0 leaves a size to the hierarchy's default, relative to the scene's size).
struct MeshingHint {
  double patch_size = 0.0;    // longest patch edge
  double element_size = 0.0;  // longest initial element edge
  double min_area = 0.0;      // smallest element a split may create
  int source_line = 0;        // of the OBJ file's "# aarad meshing:" comment (0: not from a file)
};

class Scene {
 public:
  std::string name;  // built-in name or the OBJ path
  std::vector<Material> materials;
  std::vector<Group> groups;
  std::vector<Face> faces;
  std::vector<Surface> surfaces;
  std::optional<Camera> camera;
  std::optional<MeshingHint> meshing;  // the built-ins' sizes, or an OBJ file's "# aarad meshing:" comment
  std::vector<std::string> warnings;  // what import fixed or skipped, each naming file and line

  // add_group returns the index of the group named `group_name`, creating it on first use; add_face adds
  // a face to group index `group` with material index `material` and smoothing group `smoothing` (0: none).
  // The face's surface is assigned by build_surfaces(). A group that does not exist throws aarad::Error; a
  // material that does not exist is reported by validate().
  std::uint32_t add_group(const std::string& group_name);
  std::uint32_t add_material(const Material& material);
  void add_face(std::uint32_t group, std::uint32_t material, std::vector<Vec3> vertices, int source_line = 0,
                std::uint32_t smoothing = 0);

  // Groups faces into physical surfaces (same group, same plane within a tolerance relative to the scene
  // size, same material) and fills Surface::area, Surface::smoothing and Group::surfaces. Call after the last
  // add_face.
  void build_surfaces();

  // Checks what every consumer relies on: at least one face, materials with rho 0 or in [kMinReflectance, 1) and
  // emission 0 or in [kMinEmission, kMaxEmission], finite vertices, none farther from the origin than
  // kMaxRemoteness diagonals, faces that pass the importer's checks (core/face_check.h: three distinct
  // vertices, coordinates of at most 1e50 and a size of at least 1e-50, not all on one line, a boundary that
  // neither crosses nor touches itself), an emitted flux (emission x area) below kMaxEmittedFlux, every face in a
  // built surface. Throws aarad::InputError naming the scene otherwise, and for a face its index in `faces` and its
  // group. Importers and built-ins call it before handing a scene out, and mesh::Hierarchy before meshing one. A
  // face that is not planar is accepted (the importer splits it; validate cannot).
  void validate() const;

  // Axis-aligned bounds and their diagonal, the scene's size for relative tolerances and defaults.
  Vec3 bounds_min() const;
  Vec3 bounds_max() const;
  double diagonal() const;

  double total_area() const;
  const Material& material_of_surface(std::uint32_t surface) const { return materials[surfaces[surface].material]; }
  // The group named `group_name`, or nullopt.
  std::optional<std::uint32_t> find_group(const std::string& group_name) const;

  // Whether some surfaces may hide others. They cannot when every surface lies on or in front of the plane of
  // every other, as the walls of one convex room do: a segment between two points on the boundary of a convex
  // region meets that boundary only at its ends (or along a plane holding both). Returns a witness, a surface
  // and another with a vertex behind its plane by more than 1e-6 of the scene's diagonal, or nullopt. Back
  // ends that ignore visibility (the analytic one) are exact only without a witness.
  struct OcclusionWitness {
    std::uint32_t front = 0;   // the surface whose plane...
    std::uint32_t behind = 0;  // ...has a vertex of this one behind it
  };
  std::optional<OcclusionWitness> occlusion_witness() const;

  // Overlaps between faces that lie in one plane and face the same way (a rug laid on a floor, a face copied
  // into a second group): both are lit there and both count the area, where a real scene would have one of
  // them. One entry per pair of surfaces (a <= b; a == b when faces of one surface overlap each other) whose
  // faces overlap over more than 1e-6 of the smaller surface's area, with that area and the lines of the pair of
  // faces that overlap most. Faces that only share edges do not overlap; the two sides of a panel face
  // opposite ways and are not compared.
  // The pairs are as many as the faces laid on one another allow: n copies of one face make n (n - 1) / 2. The
  // search stops after `most_pairs` candidate pairs of surfaces, or as many pairs of faces that share area, and
  // returns the overlaps found by then; `complete`, when given, says whether it saw them all.
  struct CoplanarOverlap {
    std::uint32_t a = 0, b = 0;
    double area = 0.0;
    int line_a = 0, line_b = 0;
  };
  std::vector<CoplanarOverlap> coplanar_overlaps(std::size_t most_pairs = std::numeric_limits<std::size_t>::max(),
                                                 bool* complete = nullptr) const;

  // A camera that frames the scene's bounds from outside, used when the scene has none.
  Camera fitted_camera(double aspect) const;
};

}  // namespace aarad
