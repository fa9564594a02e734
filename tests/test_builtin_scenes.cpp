// Tests of the built-in scenes (core/builtin_scenes.h): the Cornell box against the official coordinates
// of shared/references.md (areas worked out by hand below, inward normals, both traps fixed, the official
// camera), the furnace (closed, E = 1 and rho = 0.5 everywhere, floating blocks) and the office (closed
// room, twelve groups, lights under the ceiling). data/scenes/<name>.obj and .mtl must equal what
// core/obj_export.h writes for each built-in, so the files never drift from the code; to regenerate them
// after changing a built-in, run this test with AARAD_UPDATE_SCENES=1 in the environment.
#include "aarad/core/builtin_scenes.h"
#include "aarad/core/error.h"
#include "aarad/core/obj_export.h"
#include "aarad/core/obj_import.h"
#include "aarad/core/polygon.h"
#include "aarad/core/predicates.h"
#include "tests/solver_test_scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

namespace aarad {
namespace {

double group_area(const Scene& scene, const std::string& name) {
  const auto g = scene.find_group(name);
  if (!g) {
    ADD_FAILURE() << "no group " << name;
    return 0.0;
  }
  double a = 0.0;
  for (const std::uint32_t s : scene.groups[*g].surfaces) a += scene.surfaces[s].area;
  return a;
}

const Group& group(const Scene& scene, const std::string& name) {
  const auto g = scene.find_group(name);
  if (!g) throw Error("no group " + name);
  return scene.groups[*g];
}

// Sum of the vector areas of some faces: zero for a closed, consistently oriented surface.
Vec3 net_vector_area(const Scene& scene, const std::vector<std::string>& groups) {
  Vec3 sum(0.0);
  for (const std::string& name : groups)
    for (const std::uint32_t f : group(scene, name).faces) sum += vector_area(scene.faces[f].vertices);
  return sum;
}

Vec3 mean_vertex(const Scene& scene, const std::string& name) {
  Vec3 sum(0.0);
  double n = 0.0;
  for (const std::uint32_t f : group(scene, name).faces)
    for (const Vec3& v : scene.faces[f].vertices) sum += v, n += 1.0;
  return sum / n;
}

// Every face planar and convex (what the mesh layer gets from the built-ins).
void expect_planar_convex_faces(const Scene& scene) {
  for (std::size_t i = 0; i < scene.faces.size(); ++i) {
    const auto& v = scene.faces[i].vertices;
    EXPECT_LE(planarity_deviation(v), 1e-9 * scene.diagonal()) << scene.name << " face " << i;
    std::vector<Vec2> flat(v.size());
    project_to_2d(v, normal(v), flat);
    EXPECT_TRUE(is_convex(flat)) << scene.name << " face " << i;
    EXPECT_GT(signed_area(flat), 0.0) << scene.name << " face " << i;
  }
}

// ---- Cornell box ---------------------------------------------------------------------------------------

// Areas from the official coordinates (millimetres), by hand:
//   floor quad (552.8,0,0) (0,0,0) (0,0,559.2) (549.6,0,559.2): a trapezoid, 559.2 x (552.8 + 549.6) / 2
//     = 308231.04; short block footprint (130,65) (82,225) (240,272) (290,114), shoelace: 27633;
//     tall block footprint (423,247) (265,296) (314,456) (472,406), shoelace: 27626.5.
//   ceiling 556 x 559.2 = 310915.2; back wall, a trapezoid in x-y: 548.8 x (549.6 + 556) / 2 = 303376.64;
//   right wall 559.2 x 548.8 = 306888.96; light 130 x 105 = 13650.
constexpr double kFloorOutline = 559.2 * (552.8 + 549.6) / 2.0;
constexpr double kShortFootprint = 27633.0;
constexpr double kTallFootprint = 27626.5;

// Heron's formula, independent of the Newell area in core/polygon.cpp.
double heron(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double x = glm::length(b - a), y = glm::length(c - b), z = glm::length(a - c);
  const double s = 0.5 * (x + y + z);
  return std::sqrt(s * (s - x) * (s - y) * (s - z));
}

TEST(BuiltinScenes, scene_cornell_groups_and_areas) {
  const Scene scene = make_cornell_box();
  EXPECT_EQ(scene.name, "cornell");
  EXPECT_TRUE(scene.warnings.empty());
  std::vector<std::string> names;
  for (const Group& g : scene.groups) names.push_back(g.name);
  EXPECT_EQ(names, (std::vector<std::string>{"floor", "ceiling", "back_wall", "left_wall", "right_wall", "light",
                                             "short_block", "tall_block"}));
  const double rel = 1e-12;
  EXPECT_NEAR(group_area(scene, "floor"), kFloorOutline - kShortFootprint - kTallFootprint, rel * kFloorOutline);
  EXPECT_NEAR(group_area(scene, "ceiling"), 556.0 * 559.2, rel * 3e5);
  EXPECT_NEAR(group_area(scene, "back_wall"), 548.8 * (549.6 + 556.0) / 2.0, rel * 3e5);
  EXPECT_NEAR(group_area(scene, "right_wall"), 559.2 * 548.8, rel * 3e5);
  EXPECT_NEAR(group_area(scene, "light"), 130.0 * 105.0, rel * 1e4);
  const Vec3 a(552.8, 0, 0), b(549.6, 0, 559.2), c(556, 548.8, 559.2), d(556, 548.8, 0);
  EXPECT_NEAR(group_area(scene, "left_wall"), heron(a, b, c) + heron(a, c, d), 1e-9 * 3e5);
  // Blocks: top = footprint; each side = the footprint edge's length x the height.
  auto sides = [](const std::vector<Vec2>& fp, double h) {
    double s = 0.0;
    for (std::size_t i = 0; i < fp.size(); ++i) s += std::hypot(fp[(i + 1) % 4].x - fp[i].x, fp[(i + 1) % 4].y - fp[i].y) * h;
    return s;
  };
  EXPECT_NEAR(group_area(scene, "short_block"),
              kShortFootprint + sides({{130, 65}, {82, 225}, {240, 272}, {290, 114}}, 165.0), 1e-9 * 1e5);
  EXPECT_NEAR(group_area(scene, "tall_block"),
              kTallFootprint + sides({{423, 247}, {265, 296}, {314, 456}, {472, 406}}, 330.0), 1e-9 * 1e5);
}

TEST(BuiltinScenes, scene_cornell_normals_point_into_the_room) {
  const Scene scene = make_cornell_box();
  const Vec3 room_centre(278.0, 274.4, 279.6);
  for (const std::string name : {"floor", "ceiling", "back_wall", "left_wall", "right_wall", "light"})
    for (const std::uint32_t f : group(scene, name).faces) {
      const auto& v = scene.faces[f].vertices;
      EXPECT_GT(glm::dot(normal(v), glm::normalize(room_centre - centroid(v))), 0.1) << name;
    }
  // Block faces point out of their block.
  for (const std::string name : {"short_block", "tall_block"}) {
    const Vec3 centre = mean_vertex(scene, name);
    for (const std::uint32_t f : group(scene, name).faces) {
      const auto& v = scene.faces[f].vertices;
      EXPECT_GT(glm::dot(normal(v), centroid(v) - centre), 0.0) << name;
    }
  }
  EXPECT_EQ(scene.surfaces[group(scene, "floor").surfaces[0]].plane.normal, Vec3(0, 1, 0));
  EXPECT_EQ(scene.surfaces[group(scene, "light").surfaces[0]].plane.normal, Vec3(0, -1, 0));
  expect_planar_convex_faces(scene);
}

TEST(BuiltinScenes, scene_cornell_traps_fixed) {
  const Scene scene = make_cornell_box();
  // The light is 0.1 mm below the ceiling, in its own plane.
  const Surface& light = scene.surfaces[group(scene, "light").surfaces[0]];
  const Surface& ceiling = scene.surfaces[group(scene, "ceiling").surfaces[0]];
  EXPECT_NEAR(-light.plane.d / light.plane.normal.y, 548.7, 1e-12);
  EXPECT_NEAR(-ceiling.plane.d / ceiling.plane.normal.y, 548.8, 1e-12);
  // The floor: several convex pieces, one physical surface, none covering a block's footprint.
  const Group& floor = group(scene, "floor");
  EXPECT_GE(floor.faces.size(), 3u);
  ASSERT_EQ(floor.surfaces.size(), 1u);
  for (const Vec2 inside : {Vec2(185.5, 169), Vec2(368.5, 351.25)})  // the footprints' vertex means
    for (const std::uint32_t f : floor.faces) {
      std::vector<Vec2> flat;
      for (const Vec3& v : scene.faces[f].vertices) flat.emplace_back(v.x, v.z);
      bool inside_piece = true;  // facing +y, a piece runs clockwise in (x, z): inside is on the right
      for (std::size_t i = 0; i < flat.size(); ++i)
        inside_piece &= orientation(flat[i], flat[(i + 1) % flat.size()], inside) != Sign::kPositive;
      EXPECT_FALSE(inside_piece) << "floor face " << f << " covers a block";
    }
  // The pieces meet edge to edge: no vertex of one lies inside an edge of another (no T-junctions).
  for (const std::uint32_t f : floor.faces)
    for (const std::uint32_t g : floor.faces) {
      if (f == g) continue;
      const auto& edge_face = scene.faces[g].vertices;
      for (const Vec3& p : scene.faces[f].vertices)
        for (std::size_t i = 0; i < edge_face.size(); ++i) {
          const Vec3& a = edge_face[i];
          const Vec3& b = edge_face[(i + 1) % edge_face.size()];
          if (p == a || p == b) continue;
          const Vec2 p2(p.x, p.z), a2(a.x, a.z), b2(b.x, b.z);
          const bool on_edge = orientation(a2, b2, p2) == Sign::kZero && glm::dot(p2 - a2, p2 - b2) < 0.0;
          EXPECT_FALSE(on_edge) << "T-junction at (" << p.x << ", " << p.z << ")";
        }
    }
  // The left wall: two planar triangles in two planes, deliberately, without a warning.
  const Group& left = group(scene, "left_wall");
  EXPECT_EQ(left.faces.size(), 2u);
  EXPECT_EQ(left.surfaces.size(), 2u);
  for (const std::uint32_t f : left.faces) EXPECT_EQ(scene.faces[f].vertices.size(), 3u);
}

TEST(BuiltinScenes, scene_cornell_official_camera_and_materials) {
  const Scene scene = make_cornell_box();
  ASSERT_TRUE(scene.camera.has_value());
  EXPECT_EQ(scene.camera->eye, Vec3(278, 273, -800));
  EXPECT_EQ(scene.camera->forward, Vec3(0, 0, 1));
  EXPECT_EQ(scene.camera->up, Vec3(0, 1, 0));
  EXPECT_DOUBLE_EQ(scene.camera->vertical_fov, 2.0 * std::atan(0.0125 / 0.035));
  auto material = [&](const std::string& g) { return scene.material_of_surface(group(scene, g).surfaces[0]); };
  EXPECT_EQ(material("floor").reflectance, Rgb(0.725, 0.71, 0.68));
  EXPECT_EQ(material("left_wall").reflectance, Rgb(0.63, 0.065, 0.05));
  EXPECT_EQ(material("right_wall").reflectance, Rgb(0.14, 0.45, 0.091));
  EXPECT_EQ(material("light").emission, Rgb(17, 12, 4));
  EXPECT_GT(material("light").reflectance.min_component(), 0.0);
  int emitters = 0;
  for (std::uint32_t s = 0; s < scene.surfaces.size(); ++s) emitters += scene.material_of_surface(s).emits();
  EXPECT_EQ(emitters, 1);
}

// ---- Furnace -------------------------------------------------------------------------------------------

TEST(BuiltinScenes, scene_furnace_is_closed_and_uniform) {
  const Scene scene = make_furnace();
  EXPECT_TRUE(scene.warnings.empty());
  for (std::uint32_t s = 0; s < scene.surfaces.size(); ++s) {
    EXPECT_EQ(scene.material_of_surface(s).emission, Rgb(1.0));
    EXPECT_EQ(scene.material_of_surface(s).reflectance, Rgb(0.5));
  }
  // The room and each block are closed, consistently oriented surfaces.
  const std::vector<std::string> room{"floor", "ceiling", "wall_north", "wall_south", "wall_east", "wall_west"};
  EXPECT_LT(glm::length(net_vector_area(scene, room)), 1e-12);
  EXPECT_NEAR(group_area(scene, "floor") + group_area(scene, "ceiling") + group_area(scene, "wall_north") +
                  group_area(scene, "wall_south") + group_area(scene, "wall_east") + group_area(scene, "wall_west"),
              2.0 * (4 * 3 + 4 * 5 + 3 * 5), 1e-12);
  const Vec3 room_centre(2.0, 1.5, 2.5);
  for (const std::string& name : room)
    for (const std::uint32_t f : group(scene, name).faces)
      EXPECT_GT(glm::dot(normal(scene.faces[f].vertices), room_centre - centroid(scene.faces[f].vertices)), 0.0);
  // Blocks: six outward faces each, closed; areas 2 (1 x 0.9 + 1 x 1.2 + 0.9 x 1.2) and 2 (1 x 0.9 + 1 x 0.7
  // + 0.9 x 0.7); floating strictly inside the room and apart from each other.
  EXPECT_NEAR(group_area(scene, "block_a"), 2.0 * (1.0 * 0.9 + 1.0 * 1.2 + 0.9 * 1.2), 1e-12);
  EXPECT_NEAR(group_area(scene, "block_b"), 2.0 * (1.0 * 0.9 + 1.0 * 0.7 + 0.9 * 0.7), 1e-12);
  Vec3 lo[2], hi[2];
  int i = 0;
  for (const std::string name : {"block_a", "block_b"}) {
    const Group& g = group(scene, name);
    EXPECT_EQ(g.faces.size(), 6u);
    EXPECT_EQ(g.surfaces.size(), 6u);
    EXPECT_LT(glm::length(net_vector_area(scene, {name})), 1e-12);
    const Vec3 centre = mean_vertex(scene, name);
    lo[i] = Vec3(1e9), hi[i] = Vec3(-1e9);
    for (const std::uint32_t f : g.faces) {
      EXPECT_GT(glm::dot(normal(scene.faces[f].vertices), centroid(scene.faces[f].vertices) - centre), 0.0);
      for (const Vec3& v : scene.faces[f].vertices) lo[i] = glm::min(lo[i], v), hi[i] = glm::max(hi[i], v);
    }
    EXPECT_GT(glm::min(lo[i].x, glm::min(lo[i].y, lo[i].z)), 0.1) << name;
    EXPECT_LT(hi[i].x, 3.9);
    EXPECT_LT(hi[i].y, 2.9);
    EXPECT_LT(hi[i].z, 4.9);
    ++i;
  }
  const bool apart = hi[0].x < lo[1].x || hi[1].x < lo[0].x || hi[0].z < lo[1].z || hi[1].z < lo[0].z;
  EXPECT_TRUE(apart);
  expect_planar_convex_faces(scene);
}

// ---- Office --------------------------------------------------------------------------------------------

// No two faces of a built-in scene lie on one another; a scene that has them is reported with the area.
TEST(BuiltinScenes, scene_coplanar_overlaps_are_found_and_the_built_ins_have_none) {
  for (const char* name : {"cornell", "office", "furnace"})
    EXPECT_TRUE(load_scene(name).coplanar_overlaps().empty()) << name;
  // The unit cube (floor at y = 0, facing +y) with a rug on its floor, a tile beside the rug (sharing an edge
  // with it: no overlap), the floor's face copied into a group of its own, and a panel whose two sides lie in
  // one plane (facing opposite ways: not compared).
  Scene cube = test::unit_cube();
  const auto grey = cube.add_material({"rug", Rgb(0.5), Rgb(0.0)});
  const auto floor = cube.find_group("floor");
  ASSERT_TRUE(floor.has_value());
  const std::vector<Vec3> floor_face = cube.faces[cube.groups[*floor].faces.front()].vertices;
  const Vec3 up(0, 1, 0);
  test::add_facing(cube, cube.add_group("rug"), grey, {{0.2, 0, 0.2}, {0.5, 0, 0.2}, {0.5, 0, 0.6}, {0.2, 0, 0.6}}, up);
  test::add_facing(cube, cube.add_group("tile"), grey, {{0.5, 0, 0.2}, {0.7, 0, 0.2}, {0.7, 0, 0.6}, {0.5, 0, 0.6}}, up);
  cube.add_face(cube.add_group("copy"), grey, floor_face);
  const std::uint32_t panel = cube.add_group("panel");
  const std::vector<Vec3> panel_face = {{0.3, 0.3, 0.5}, {0.6, 0.3, 0.5}, {0.6, 0.6, 0.5}, {0.3, 0.6, 0.5}};
  test::add_facing(cube, panel, grey, panel_face, Vec3(0, 0, 1));
  test::add_facing(cube, panel, grey, panel_face, Vec3(0, 0, -1));
  cube.build_surfaces();
  std::map<std::pair<std::string, std::string>, double> found;
  for (const Scene::CoplanarOverlap& o : cube.coplanar_overlaps()) {
    std::string a = cube.groups[cube.surfaces[o.a].group].name, b = cube.groups[cube.surfaces[o.b].group].name;
    if (b < a) std::swap(a, b);
    found[{a, b}] = o.area;
  }
  const double floor_area = area(floor_face);
  const std::map<std::pair<std::string, std::string>, double> expected = {
      {{"floor", "rug"}, 0.12}, {{"floor", "tile"}, 0.08}, {{"copy", "floor"}, floor_area},
      {{"copy", "rug"}, 0.12},  {{"copy", "tile"}, 0.08}};
  ASSERT_EQ(found.size(), expected.size());
  for (const auto& [pair, value] : expected) {
    ASSERT_TRUE(found.count(pair)) << pair.first << " " << pair.second;
    EXPECT_NEAR(found[pair], value, 1e-12) << pair.first << " " << pair.second;
  }
  // Faces of one surface on one another: one entry with a == b.
  Scene twice = test::unit_cube();
  const std::uint32_t g = *twice.find_group("floor");
  test::add_facing(twice, g, twice.faces[twice.groups[g].faces.front()].material,
                   {{0.1, 0, 0.1}, {0.4, 0, 0.1}, {0.4, 0, 0.3}, {0.1, 0, 0.3}}, Vec3(0, 1, 0));
  twice.build_surfaces();
  const auto self = twice.coplanar_overlaps();
  ASSERT_EQ(self.size(), 1u);
  EXPECT_EQ(self[0].a, self[0].b);
  EXPECT_NEAR(self[0].area, 0.06, 1e-12);
}

// Surfaces may hide one another unless each lies on or in front of every other's plane (one convex room).
TEST(BuiltinScenes, scene_occlusion_witness_only_where_surfaces_may_hide_others) {
  EXPECT_FALSE(test::unit_cube().occlusion_witness().has_value());
  EXPECT_FALSE(test::two_unit_squares().occlusion_witness().has_value());
  const auto group_name = [](const Scene& scene, std::uint32_t surface) {
    return scene.groups[scene.surfaces[surface].group].name;
  };
  // The furnace's floating blocks face out: the room lies behind their faces.
  const Scene furnace = make_furnace();
  const auto witness = furnace.occlusion_witness();
  ASSERT_TRUE(witness.has_value());
  EXPECT_EQ(group_name(furnace, witness->front).rfind("block_", 0), 0u) << group_name(furnace, witness->front);
  double deepest = 0.0;  // the witness holds: a vertex of `behind` lies behind the plane of `front`
  for (std::uint32_t f : furnace.surfaces[witness->behind].faces)
    for (const Vec3& v : furnace.faces[f].vertices)
      deepest = std::min(deepest, furnace.surfaces[witness->front].plane.signed_distance(v));
  EXPECT_LT(deepest, -1e-6 * furnace.diagonal());
  // The unit cube with a small quad floating inside it, facing the floor: the ceiling lies behind the quad.
  Scene cube = test::unit_cube();
  const auto grey = cube.add_material({"quad", Rgb(0.5), Rgb(0.0)});
  test::add_facing(cube, cube.add_group("quad"), grey, {{0.4, 0.5, 0.4}, {0.6, 0.5, 0.4}, {0.6, 0.5, 0.6}, {0.4, 0.5, 0.6}},
                   {0, -1, 0});
  cube.build_surfaces();
  const auto inside = cube.occlusion_witness();
  ASSERT_TRUE(inside.has_value());
  EXPECT_EQ(group_name(cube, inside->front), "quad");
  // A dent of a millionth of the diagonal or less is rounding, not a hiding place.
  Scene flat = test::unit_cube();
  flat.faces.front().vertices.front().y -= 0.5e-6 * flat.diagonal();
  EXPECT_FALSE(flat.occlusion_witness().has_value());
}

TEST(BuiltinScenes, scene_office_room_lights_and_furniture) {
  const Scene scene = make_office();
  EXPECT_TRUE(scene.warnings.empty());
  EXPECT_EQ(scene.groups.size(), 12u);  // the paper's twelve surfaces, as groups
  const std::vector<std::string> room{"floor", "ceiling", "wall_north", "wall_south", "wall_east", "wall_west"};
  EXPECT_LT(glm::length(net_vector_area(scene, room)), 1e-12);
  EXPECT_NEAR(group_area(scene, "floor"), 5.0 * 6.0, 1e-12);
  // Lights: 1.2 x 0.6 m, 1 mm below the 3 m ceiling, facing down, the only emitters.
  for (const std::string name : {"light_1", "light_2"}) {
    EXPECT_NEAR(group_area(scene, name), 0.72, 1e-12);
    const Surface& s = scene.surfaces[group(scene, name).surfaces[0]];
    EXPECT_EQ(s.plane.normal, Vec3(0, -1, 0));
    EXPECT_NEAR(-s.plane.d / s.plane.normal.y, 2.999, 1e-12);
    EXPECT_TRUE(scene.materials[s.material].emits());
  }
  int emitters = 0;
  for (std::uint32_t s = 0; s < scene.surfaces.size(); ++s) emitters += scene.material_of_surface(s).emits();
  EXPECT_EQ(emitters, 2);
  // The table is a closed solid: top, underside and band close the disk, the column's sides close on
  // themselves, the base has a bottom.
  EXPECT_LT(glm::length(net_vector_area(scene, {"table"})), 1e-12);
  // Each chair: the seat is closed; what is left open is hidden where solids meet: the back's bottom
  // (0.46 x 0.04 on the seat) and the four legs' tops (0.035 x 0.035 under the seat), so the net vector
  // area is +y (0.46 x 0.04 - 4 x 0.035^2).
  for (const std::string name : {"chair_1", "chair_2", "chair_3"}) {
    const Vec3 net = net_vector_area(scene, {name});
    EXPECT_NEAR(net.y, 0.46 * 0.04 - 4.0 * 0.035 * 0.035, 1e-12) << name;
    EXPECT_NEAR(std::hypot(net.x, net.z), 0.0, 1e-12) << name;
  }
  // Everything stands inside the room, on the floor and below the lights.
  for (const std::string name : {"table", "chair_1", "chair_2", "chair_3"})
    for (const std::uint32_t f : group(scene, name).faces)
      for (const Vec3& v : scene.faces[f].vertices) {
        EXPECT_GE(v.y, 0.0);
        EXPECT_LT(v.y, 1.0);
        EXPECT_GT(std::min(v.x, v.z), 0.5);
        EXPECT_LT(v.x, 4.5);
        EXPECT_LT(v.z, 5.5);
      }
  // The camera is inside the room, looking at the table.
  ASSERT_TRUE(scene.camera.has_value());
  const Camera& c = *scene.camera;
  EXPECT_GT(std::min({c.eye.x, c.eye.y, c.eye.z}), 0.0);
  EXPECT_LT(c.eye.y, 3.0);
  EXPECT_GT(glm::dot(c.forward, glm::normalize(mean_vertex(scene, "table") - c.eye)), 0.99);
  expect_planar_convex_faces(scene);
}

// ---- Files in data/scenes ------------------------------------------------------------------------------

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// Whether two OBJ/MTL texts say the same: the same lines and words, numbers equal to within `tolerance`
// (so a last-bit difference of sin and cos in another C library does not count as drift). Returns the
// first difference, or an empty string.
std::string text_difference(const std::string& file, const std::string& expected, double tolerance) {
  std::istringstream a(file), b(expected);
  std::string la, lb;
  int line = 0;
  while (true) {
    const bool more_a = static_cast<bool>(std::getline(a, la)), more_b = static_cast<bool>(std::getline(b, lb));
    ++line;
    if (!more_a && !more_b) return {};
    if (more_a != more_b) return "line " + std::to_string(line) + ": one text ends before the other";
    std::istringstream wa(la), wb(lb);
    std::string x, y;
    while (true) {
      const bool ga = static_cast<bool>(wa >> x), gb = static_cast<bool>(wb >> y);
      if (!ga && !gb) break;
      if (ga != gb) return "line " + std::to_string(line) + ": '" + la + "' vs '" + lb + "'";
      if (x == y) continue;
      char* end_x = nullptr;
      char* end_y = nullptr;
      const double nx = std::strtod(x.c_str(), &end_x), ny = std::strtod(y.c_str(), &end_y);
      if (*end_x != '\0' || *end_y != '\0' || end_x == x.c_str() || !(std::abs(nx - ny) <= tolerance))
        return "line " + std::to_string(line) + ": '" + la + "' vs '" + lb + "'";
    }
  }
}

TEST(BuiltinScenes, scene_data_files_match_builtins) {
  const bool update = std::getenv("AARAD_UPDATE_SCENES") != nullptr;
  for (const std::string& name : builtin_scene_names()) {
    const Scene scene = load_scene(name);
    const std::string comment = "aarad built-in scene '" + name + "' (core/builtin_scenes.cpp), written by "
                                "core/obj_export.cpp.\nRegenerate: AARAD_UPDATE_SCENES=1 <build>/tests/test_builtin_scenes";
    const std::string base = std::string(AARAD_SOURCE_DIR) + "/data/scenes/" + name;
    if (update) write_obj(scene, base + ".obj", comment);
    const double tolerance = 1e-12 * scene.diagonal();
    EXPECT_EQ(text_difference(read_text(base + ".obj"), obj_text(scene, name + ".mtl", comment), tolerance), "")
        << base << ".obj differs from the built-in; regenerate with AARAD_UPDATE_SCENES=1";
    EXPECT_EQ(text_difference(read_text(base + ".mtl"), mtl_text(scene, comment), tolerance), "")
        << base << ".mtl differs from the built-in; regenerate with AARAD_UPDATE_SCENES=1";
  }
}

TEST(BuiltinScenes, scene_data_files_import_like_builtins) {
  for (const std::string& name : builtin_scene_names()) {
    const Scene builtin = load_scene(name);
    const Scene imported = import_obj(std::string(AARAD_SOURCE_DIR) + "/data/scenes/" + name + ".obj");
    EXPECT_TRUE(imported.warnings.empty()) << name << ": " << imported.warnings.front();
    ASSERT_EQ(imported.surfaces.size(), builtin.surfaces.size()) << name;
    ASSERT_EQ(imported.groups.size(), builtin.groups.size()) << name;
    for (std::size_t s = 0; s < builtin.surfaces.size(); ++s) {
      EXPECT_NEAR(imported.surfaces[s].area, builtin.surfaces[s].area, 1e-12 * builtin.surfaces[s].area) << name << " surface " << s;
      EXPECT_EQ(imported.surfaces[s].faces.size(), builtin.surfaces[s].faces.size()) << name << " surface " << s;
    }
    EXPECT_EQ(imported.materials.size(), builtin.materials.size());
  }
}

}  // namespace
}  // namespace aarad
