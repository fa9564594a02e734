// Small hand-built scenes and helpers shared by the hierarchy, split and invariant tests.
#pragma once

#include "aarad/core/scene.h"
#include "aarad/mesh/invariants.h"

#include <string>
#include <vector>

namespace aarad::test {

// One planar polygon (counter-clockwise seen from +z) in the plane z = 0 as a one-group scene.
inline Scene polygon_scene(const std::vector<Vec2>& polygon, const std::string& name = "polygon") {
  Scene scene;
  scene.name = name;
  const std::uint32_t material = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
  const std::uint32_t group = scene.add_group(name);
  std::vector<Vec3> vertices;
  for (const Vec2& p : polygon) vertices.emplace_back(p.x, p.y, 0.0);
  scene.add_face(group, material, vertices);
  scene.build_surfaces();
  return scene;
}

inline Scene square_scene() { return polygon_scene({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, "square"); }
inline Scene rectangle_scene() { return polygon_scene({{0, 0}, {2, 0}, {2, 1}, {0, 1}}, "rectangle"); }
inline Scene triangle_scene() { return polygon_scene({{0, 0}, {1, 0}, {0, 1}}, "triangle"); }
// Concave: the unit L of area 3.
inline Scene l_scene() { return polygon_scene({{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}, "l_shape"); }

inline std::string describe(const std::vector<mesh::Violation>& violations) {
  std::string out;
  for (const auto& v : violations) out += v.invariant + " (node " + std::to_string(v.node) + "): " + v.message + "\n";
  return out;
}

inline bool reports(const std::vector<mesh::Violation>& violations, const std::string& invariant) {
  for (const auto& v : violations)
    if (v.invariant == invariant) return true;
  return false;
}

}  // namespace aarad::test
