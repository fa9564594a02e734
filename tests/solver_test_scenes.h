// Small hand-built scenes for the solver tests (shared by tests/test_solver*.cpp and test_outputs*.cpp).
#pragma once

#include "aarad/core/polygon.h"
#include "aarad/core/scene.h"

#include <algorithm>
#include <string>
#include <vector>

namespace aarad::test {

// Adds a planar polygon whose front side faces `front` (the vertex order is reversed when needed).
inline void add_facing(Scene& scene, std::uint32_t group, std::uint32_t material, std::vector<Vec3> vertices,
                       const Vec3& front) {
  if (glm::dot(plane_of(vertices).normal, front) < 0.0) std::reverse(vertices.begin(), vertices.end());
  scene.add_face(group, material, std::move(vertices));
}

// Two unit squares at gap 1 facing each other (references.md, "Two unit squares"): "emitter" at z = 0 facing
// +z with E = 1, "receiver" at z = 1 facing -z, both rho = 0.5.
inline Scene two_unit_squares() {
  Scene scene;
  scene.name = "two-squares";
  const auto emitter = scene.add_material({"emitter", Rgb(0.5), Rgb(1.0)});
  const auto grey = scene.add_material({"grey", Rgb(0.5), Rgb(0.0)});
  add_facing(scene, scene.add_group("emitter"), emitter, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {0, 0, 1});
  add_facing(scene, scene.add_group("receiver"), grey, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, {0, 0, -1});
  scene.build_surfaces();
  return scene;
}

// The closed unit cube of references.md: inward faces, floor (y = 0) emits `floor_emission`, every face
// reflects `rho`. Groups: floor, ceiling, wall_x0, wall_x1, wall_z0, wall_z1. `origin` is where its corner (0, 0, 0)
// goes (a scene far from the origin).
inline Scene unit_cube(double floor_emission = 1.0, double rho = 0.5, double size = 1.0,
                       const Vec3& origin = Vec3(0.0)) {
  Scene scene;
  scene.name = "unit-cube";
  const auto light = scene.add_material({"floor", Rgb(rho), Rgb(floor_emission)});
  const auto grey = scene.add_material({"grey", Rgb(rho), Rgb(0.0)});
  const double s = size;
  const auto at = [&](std::vector<Vec3> corners) {
    for (Vec3& p : corners) p += origin;
    return corners;
  };
  add_facing(scene, scene.add_group("floor"), light, at({{0, 0, 0}, {s, 0, 0}, {s, 0, s}, {0, 0, s}}), {0, 1, 0});
  add_facing(scene, scene.add_group("ceiling"), grey, at({{0, s, 0}, {s, s, 0}, {s, s, s}, {0, s, s}}), {0, -1, 0});
  add_facing(scene, scene.add_group("wall_x0"), grey, at({{0, 0, 0}, {0, s, 0}, {0, s, s}, {0, 0, s}}), {1, 0, 0});
  add_facing(scene, scene.add_group("wall_x1"), grey, at({{s, 0, 0}, {s, s, 0}, {s, s, s}, {s, 0, s}}), {-1, 0, 0});
  add_facing(scene, scene.add_group("wall_z0"), grey, at({{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0}}), {0, 0, 1});
  add_facing(scene, scene.add_group("wall_z1"), grey, at({{0, 0, s}, {s, 0, s}, {s, s, s}, {0, s, s}}), {0, 0, -1});
  scene.build_surfaces();
  return scene;
}

}  // namespace aarad::test
