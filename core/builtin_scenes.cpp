// Built-in scenes. The Cornell box follows the official data of the Cornell Program of Computer Graphics
// (http://www.graphics.cornell.edu/online/box/data.html, as listed in ../shared/references.md) with the two
// fixes that reference names for a hemicube program that culls back faces. The office imitates the second
// test scene of Chandran, Kiran, Phani and Rai, section 4 (three office chairs and a pedestal table). The
// furnace is the closed-environment test of references.md: B = E / (1 - rho) everywhere.
#include "aarad/core/builtin_scenes.h"

#include "aarad/core/error.h"
#include "aarad/core/obj_import.h"
#include "aarad/core/polygon.h"

#include <glm/mat3x3.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

namespace aarad {
namespace {

// `polygon` with its vertex order reversed when its normal points away from `direction`.
std::vector<Vec3> facing(std::vector<Vec3> polygon, const Vec3& direction) {
  if (glm::dot(normal(polygon), direction) < 0.0) std::reverse(polygon.begin(), polygon.end());
  return polygon;
}

// A wall of a room: faces the room's centre.
std::vector<Vec3> inward(std::vector<Vec3> polygon, const Vec3& room_centre) {
  const Vec3 c = centroid(polygon);
  return facing(std::move(polygon), room_centre - c);
}

// A face of a solid: faces away from the solid's centre.
std::vector<Vec3> outward(std::vector<Vec3> polygon, const Vec3& solid_centre) {
  const Vec3 c = centroid(polygon);
  return facing(std::move(polygon), c - solid_centre);
}

// ---- Cutting convex holes out of a convex polygon -------------------------------------------------------

// The interval [lo, hi] of first coordinates where the horizontal line (second coordinate u) meets the
// convex polygon, or nullopt when it misses.
std::optional<std::pair<double, double>> cross_section(const std::vector<Vec2>& polygon, double u) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Vec2 a = polygon[i], b = polygon[(i + 1) % polygon.size()];
    if (u < std::min(a.y, b.y) || u > std::max(a.y, b.y)) continue;
    if (a.y == b.y) {
      lo = std::min({lo, a.x, b.x});
      hi = std::max({hi, a.x, b.x});
    } else {
      const double x = a.x + (b.x - a.x) * (u - a.y) / (b.y - a.y);
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  }
  if (lo > hi) return std::nullopt;
  return std::make_pair(lo, hi);
}

// Decomposes convex `outer` minus disjoint convex `holes` (strictly inside it) into convex pieces by
// sweeping along the second coordinate: each slab between consecutive vertex coordinates holds trapezoids
// between the holes. A vertex where a neighbouring piece has a corner is inserted into the edges the pieces
// share, so the pieces meet edge to edge (no T-junctions). Pieces come out counter-clockwise (y up).
std::vector<std::vector<Vec2>> cut_holes(const std::vector<Vec2>& outer, const std::vector<std::vector<Vec2>>& holes) {
  std::vector<double> events;
  for (const Vec2& p : outer) events.push_back(p.y);
  for (const auto& h : holes)
    for (const Vec2& p : h) events.push_back(p.y);
  std::sort(events.begin(), events.end());
  events.erase(std::unique(events.begin(), events.end()), events.end());

  struct Piece {
    double u0, u1;
    double left0, right0, left1, right1;  // first coordinates of the corners at u0 and u1
  };
  std::vector<Piece> pieces;
  for (std::size_t e = 0; e + 1 < events.size(); ++e) {
    const double u0 = events[e], u1 = events[e + 1];
    const auto o0 = cross_section(outer, u0), o1 = cross_section(outer, u1);
    if (!o0 || !o1) continue;
    struct Span {
      double lo0, hi0, lo1, hi1;
    };
    std::vector<Span> spans;
    for (const auto& h : holes) {
      double hmin = h[0].y, hmax = h[0].y;
      for (const Vec2& p : h) hmin = std::min(hmin, p.y), hmax = std::max(hmax, p.y);
      if (hmin > u0 || hmax < u1) continue;
      const auto s0 = cross_section(h, u0), s1 = cross_section(h, u1);
      spans.push_back({s0->first, s0->second, s1->first, s1->second});
    }
    std::sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) {
      return a.lo0 + a.hi0 + a.lo1 + a.hi1 < b.lo0 + b.hi0 + b.lo1 + b.hi1;
    });
    double left0 = o0->first, left1 = o1->first;
    for (const Span& s : spans) {
      pieces.push_back({u0, u1, left0, s.lo0, left1, s.lo1});
      left0 = s.hi0;
      left1 = s.hi1;
    }
    pieces.push_back({u0, u1, left0, o0->second, left1, o1->second});
  }

  // Corners on every sweep line, to insert where a neighbour's corner lies inside a shared edge.
  std::map<double, std::vector<double>> corners;
  for (const Piece& p : pieces) {
    corners[p.u0].insert(corners[p.u0].end(), {p.left0, p.right0});
    corners[p.u1].insert(corners[p.u1].end(), {p.left1, p.right1});
  }
  for (auto& [u, xs] : corners) {
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  }

  std::vector<std::vector<Vec2>> out;
  for (const Piece& p : pieces) {
    std::vector<Vec2> polygon;
    auto push = [&](const Vec2& v) {
      if (polygon.empty() || polygon.back() != v) polygon.push_back(v);
    };
    // Bottom edge left to right, then the right side, the top edge right to left, the left side.
    for (const double x : corners[p.u0])
      if (x >= p.left0 && x <= p.right0) push({x, p.u0});
    const auto& top = corners[p.u1];
    for (auto it = top.rbegin(); it != top.rend(); ++it)
      if (*it >= p.left1 && *it <= p.right1) push({*it, p.u1});
    if (polygon.size() > 1 && polygon.front() == polygon.back()) polygon.pop_back();
    if (polygon.size() >= 3 && signed_area(polygon) > 0.0) out.push_back(std::move(polygon));
  }
  return out;
}

// ---- Boxes and prisms ---------------------------------------------------------------------------------

glm::dmat3 rotation_y(double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  // Columns: images of x, y, z. Turns +z towards +x.
  return glm::dmat3(Vec3(c, 0.0, -s), Vec3(0.0, 1.0, 0.0), Vec3(s, 0.0, c));
}

glm::dmat3 rotation_x(double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  return glm::dmat3(Vec3(1.0, 0.0, 0.0), Vec3(0.0, c, s), Vec3(0.0, -s, c));
}

enum BoxSide { kMinusX, kPlusX, kMinusY, kPlusY, kMinusZ, kPlusZ };

// The six faces of the box [lo, hi] (in its own frame), mapped by p -> origin + rotation p, each facing out.
std::array<std::vector<Vec3>, 6> box_faces(const Vec3& lo, const Vec3& hi, const glm::dmat3& rotation = glm::dmat3(1.0),
                                           const Vec3& origin = Vec3(0.0)) {
  auto corner = [&](int i) {
    const Vec3 p((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
    return origin + rotation * p;
  };
  const Vec3 centre = origin + rotation * (0.5 * (lo + hi));
  auto quad = [&](int a, int b, int c, int d) { return outward({corner(a), corner(b), corner(c), corner(d)}, centre); };
  return {quad(0, 2, 6, 4), quad(1, 3, 7, 5), quad(0, 1, 5, 4), quad(2, 3, 7, 6), quad(0, 1, 3, 2), quad(4, 5, 7, 6)};
}

// A regular polygon of `sides` vertices around (cx, y, cz) in the horizontal plane, facing up or down.
std::vector<Vec3> disk(double cx, double cz, double radius, double y, int sides, bool up) {
  std::vector<Vec3> v;
  for (int i = 0; i < sides; ++i) {
    const double a = 2.0 * kPi * i / sides;
    v.emplace_back(cx + radius * std::cos(a), y, cz + radius * std::sin(a));
  }
  return facing(std::move(v), Vec3(0.0, up ? 1.0 : -1.0, 0.0));
}

// The side quads of a regular prism between heights y0 and y1, facing out.
std::vector<std::vector<Vec3>> prism_sides(double cx, double cz, double radius, double y0, double y1, int sides) {
  std::vector<std::vector<Vec3>> quads;
  const Vec3 centre(cx, 0.5 * (y0 + y1), cz);
  for (int i = 0; i < sides; ++i) {
    const double a = 2.0 * kPi * i / sides, b = 2.0 * kPi * (i + 1) / sides;
    const Vec3 p(cx + radius * std::cos(a), 0.0, cz + radius * std::sin(a));
    const Vec3 q(cx + radius * std::cos(b), 0.0, cz + radius * std::sin(b));
    quads.push_back(outward({Vec3(p.x, y0, p.z), Vec3(q.x, y0, q.z), Vec3(q.x, y1, q.z), Vec3(p.x, y1, p.z)}, centre));
  }
  return quads;
}

Camera look_at(const Vec3& eye, const Vec3& target, double vertical_fov) {
  Camera camera;
  camera.eye = eye;
  camera.forward = glm::normalize(target - eye);
  camera.up = glm::normalize(Vec3(0.0, 1.0, 0.0) - camera.forward.y * camera.forward);
  camera.vertical_fov = vertical_fov;
  return camera;
}

// The six walls of the axis-aligned room [lo, hi], facing in, as groups floor, ceiling, wall_south (min z),
// wall_north (max z), wall_west (min x), wall_east (max x).
void add_room(Scene& scene, const Vec3& lo, const Vec3& hi, std::uint32_t floor_material, std::uint32_t ceiling_material,
              std::uint32_t wall_material, bool with_floor = true) {
  const Vec3 centre = 0.5 * (lo + hi);
  auto f = box_faces(lo, hi);
  // box_faces points out of the box; a room's walls point in.
  for (auto& face : f) face = inward(std::move(face), centre);
  if (with_floor) scene.add_face(scene.add_group("floor"), floor_material, f[kMinusY]);
  scene.add_face(scene.add_group("ceiling"), ceiling_material, f[kPlusY]);
  scene.add_face(scene.add_group("wall_north"), wall_material, f[kPlusZ]);
  scene.add_face(scene.add_group("wall_south"), wall_material, f[kMinusZ]);
  scene.add_face(scene.add_group("wall_east"), wall_material, f[kPlusX]);
  scene.add_face(scene.add_group("wall_west"), wall_material, f[kMinusX]);
}

Scene finished(Scene scene) {
  scene.build_surfaces();
  scene.validate();
  return scene;
}

}  // namespace

Scene make_cornell_box() {
  Scene scene;
  scene.name = "cornell";
  const std::uint32_t white = scene.add_material({"white", Rgb(0.725, 0.71, 0.68), Rgb(0.0)});
  const std::uint32_t red = scene.add_material({"red", Rgb(0.63, 0.065, 0.05), Rgb(0.0)});
  const std::uint32_t green = scene.add_material({"green", Rgb(0.14, 0.45, 0.091), Rgb(0.0)});
  const std::uint32_t light = scene.add_material({"light", Rgb(0.78), Rgb(17.0, 12.0, 4.0)});
  const Vec3 room(278.0, 274.4, 279.6);  // the middle of the room, for facing walls inwards

  // Block footprints (x, z) from the official bottom vertices of the blocks' sides.
  const std::vector<Vec2> short_footprint{{130, 65}, {82, 225}, {240, 272}, {290, 114}};
  const std::vector<Vec2> tall_footprint{{423, 247}, {265, 296}, {314, 456}, {472, 406}};

  // Floor: the official quad minus both footprints, as convex pieces of one group (one physical surface).
  const std::vector<Vec2> floor_outline{{552.8, 0}, {0, 0}, {0, 559.2}, {549.6, 559.2}};
  const std::uint32_t floor = scene.add_group("floor");
  for (const auto& piece : cut_holes(floor_outline, {short_footprint, tall_footprint})) {
    std::vector<Vec3> v;
    for (const Vec2& p : piece) v.emplace_back(p.x, 0.0, p.y);
    scene.add_face(floor, white, inward(std::move(v), room));
  }

  scene.add_face(scene.add_group("ceiling"), white,
                 inward({{556, 548.8, 0}, {556, 548.8, 559.2}, {0, 548.8, 559.2}, {0, 548.8, 0}}, room));
  scene.add_face(scene.add_group("back_wall"), white,
                 inward({{549.6, 0, 559.2}, {0, 0, 559.2}, {0, 548.8, 559.2}, {556, 548.8, 559.2}}, room));
  // The official left wall bends by 3.2 mm: two planar triangles sharing the diagonal from the floor's
  // front corner to the ceiling's back corner.
  const std::uint32_t left = scene.add_group("left_wall");
  scene.add_face(left, red, inward({{552.8, 0, 0}, {549.6, 0, 559.2}, {556, 548.8, 559.2}}, room));
  scene.add_face(left, red, inward({{552.8, 0, 0}, {556, 548.8, 559.2}, {556, 548.8, 0}}, room));
  scene.add_face(scene.add_group("right_wall"), green,
                 inward({{0, 0, 559.2}, {0, 0, 0}, {0, 548.8, 0}, {0, 548.8, 559.2}}, room));
  // The light, 0.1 mm below the ceiling so the two never share a plane and a depth.
  scene.add_face(scene.add_group("light"), light,
                 inward({{343, 548.7, 227}, {343, 548.7, 332}, {213, 548.7, 332}, {213, 548.7, 227}}, room));

  // Blocks: top and four sides each, facing out of the block; no bottom (the floor is cut beneath).
  auto add_block = [&](const std::string& name, const std::vector<Vec2>& footprint, double height) {
    const std::uint32_t g = scene.add_group(name);
    Vec3 centre(0.0, 0.5 * height, 0.0);
    for (const Vec2& p : footprint) centre += Vec3(p.x, 0.0, p.y) / static_cast<double>(footprint.size());
    std::vector<Vec3> top;
    for (const Vec2& p : footprint) top.emplace_back(p.x, height, p.y);
    scene.add_face(g, white, outward(std::move(top), centre));
    for (std::size_t i = 0; i < footprint.size(); ++i) {
      const Vec2 a = footprint[i], b = footprint[(i + 1) % footprint.size()];
      scene.add_face(g, white,
                     outward({{a.x, 0, a.y}, {b.x, 0, b.y}, {b.x, height, b.y}, {a.x, height, a.y}}, centre));
    }
  };
  add_block("short_block", short_footprint, 165.0);
  add_block("tall_block", tall_footprint, 330.0);

  // Focal length 0.035 and film 0.025 x 0.025: vertical field 2 atan(0.0125 / 0.035).
  scene.camera = Camera{Vec3(278, 273, -800), Vec3(0, 0, 1), Vec3(0, 1, 0), 2.0 * std::atan(0.0125 / 0.035)};
  // Millimetres: 260 patches and 1 040 initial elements, which keep the AA hemicube's solve short.
  scene.meshing = MeshingHint{140.0, 70.0, 60.0};
  return finished(std::move(scene));
}

Scene make_office() {
  Scene scene;
  scene.name = "office";
  const std::uint32_t carpet = scene.add_material({"carpet", Rgb(0.45, 0.42, 0.38), Rgb(0.0)});
  const std::uint32_t ceiling = scene.add_material({"ceiling_white", Rgb(0.80, 0.80, 0.78), Rgb(0.0)});
  const std::uint32_t paint = scene.add_material({"wall_paint", Rgb(0.70, 0.68, 0.62), Rgb(0.0)});
  const std::uint32_t lamp = scene.add_material({"lamp", Rgb(0.78), Rgb(12.0, 11.5, 10.0)});
  const std::uint32_t wood = scene.add_material({"wood", Rgb(0.55, 0.36, 0.20), Rgb(0.0)});
  const std::array<std::uint32_t, 3> fabric{scene.add_material({"fabric_blue", Rgb(0.15, 0.25, 0.55), Rgb(0.0)}),
                                            scene.add_material({"fabric_red", Rgb(0.55, 0.15, 0.12), Rgb(0.0)}),
                                            scene.add_material({"fabric_green", Rgb(0.18, 0.45, 0.20), Rgb(0.0)})};

  const Vec3 lo(0.0), hi(5.0, 3.0, 6.0);
  add_room(scene, lo, hi, carpet, ceiling, paint);

  // Two 1.2 x 0.6 m ceiling lights, 1 mm below the ceiling, facing down.
  const double light_y = hi.y - 0.001;
  for (int i = 0; i < 2; ++i) {
    const double z0 = i == 0 ? 1.9 : 3.9;
    scene.add_face(scene.add_group("light_" + std::to_string(i + 1)), lamp,
                   facing({{1.9, light_y, z0}, {3.1, light_y, z0}, {3.1, light_y, z0 + 0.6}, {1.9, light_y, z0 + 0.6}},
                          Vec3(0, -1, 0)));
  }

  // The pedestal table: a 24-sided top 1.2 m across with a 4 cm edge band, an octagonal column and a
  // 16-sided base with a bottom, a closed solid standing on the floor. The sides of the three prisms stand for
  // round surfaces: each prism is a smoothing group, shaded smoothly around in the images.
  const double tx = 2.5, tz = 3.2;
  const std::uint32_t table = scene.add_group("table");
  scene.add_face(table, wood, disk(tx, tz, 0.6, 0.75, 24, true));
  scene.add_face(table, wood, disk(tx, tz, 0.6, 0.71, 24, false));
  for (auto& q : prism_sides(tx, tz, 0.6, 0.71, 0.75, 24)) scene.add_face(table, wood, std::move(q), 0, 1);
  for (auto& q : prism_sides(tx, tz, 0.05, 0.04, 0.71, 8)) scene.add_face(table, wood, std::move(q), 0, 2);
  scene.add_face(table, wood, disk(tx, tz, 0.3, 0.04, 16, true));
  for (auto& q : prism_sides(tx, tz, 0.3, 0.0, 0.04, 16)) scene.add_face(table, wood, std::move(q), 0, 3);
  scene.add_face(table, wood, disk(tx, tz, 0.3, 0.0, 16, false));

  // Three chairs around the table, facing it. In a chair's own frame the sitter faces +z: a 46 x 46 cm
  // seat 42-48 cm high, a back 4 cm thick rising to 95 cm at the rear, four 3.5 cm legs. Hidden faces
  // (where the back sits on the seat, the legs' tops under the seat) are left out; the legs have bottoms.
  const std::array<double, 3> angles{20.0, 140.0, 250.0};  // degrees around the table, 0 = towards +z
  for (int c = 0; c < 3; ++c) {
    const double theta = angles[static_cast<std::size_t>(c)] * kPi / 180.0;
    const Vec3 origin(tx + 0.95 * std::sin(theta), 0.0, tz + 0.95 * std::cos(theta));
    const glm::dmat3 turn = rotation_y(theta + kPi);
    const std::uint32_t g = scene.add_group("chair_" + std::to_string(c + 1));
    const std::uint32_t m = fabric[static_cast<std::size_t>(c)];
    for (auto& f : box_faces({-0.23, 0.42, -0.23}, {0.23, 0.48, 0.23}, turn, origin)) scene.add_face(g, m, std::move(f));
    const auto back = box_faces({-0.23, 0.48, -0.23}, {0.23, 0.95, -0.19}, turn, origin);
    for (const int side : {kMinusX, kPlusX, kPlusY, kMinusZ, kPlusZ}) scene.add_face(g, m, back[static_cast<std::size_t>(side)]);
    for (const double x : {-0.22, 0.185})
      for (const double z : {-0.22, 0.185}) {
        const auto leg = box_faces({x, 0.0, z}, {x + 0.035, 0.42, z + 0.035}, turn, origin);
        for (const int side : {kMinusX, kPlusX, kMinusY, kMinusZ, kPlusZ})
          scene.add_face(g, m, leg[static_cast<std::size_t>(side)]);
      }
  }

  scene.camera = look_at(Vec3(2.5, 1.6, 0.35), Vec3(2.5, 0.55, 3.2), 55.0 * kPi / 180.0);
  // Metres. Sizes that mesh the office to about the paper's 5 591 patches and 15 784 elements: 5 588 patches and
  // 14 127 initial elements, which adaptive substructuring then refines.
  scene.meshing = MeshingHint{0.185, 0.177, 1e-4};
  return finished(std::move(scene));
}

Scene make_furnace() {
  Scene scene;
  scene.name = "furnace";
  // E = 1 and rho = 0.5 on every surface: B = E / (1 - rho) = 2 exactly, whatever occludes what.
  const std::uint32_t glow = scene.add_material({"furnace", Rgb(0.5), Rgb(1.0)});
  add_room(scene, Vec3(0.0), Vec3(4.0, 3.0, 5.0), glow, glow, glow);
  for (auto& f : box_faces({0.6, 0.5, 1.0}, {1.6, 1.4, 2.2})) scene.add_face(scene.add_group("block_a"), glow, std::move(f));
  const glm::dmat3 turn = rotation_y(35.0 * kPi / 180.0) * rotation_x(15.0 * kPi / 180.0);
  for (auto& f : box_faces({-0.5, -0.45, -0.35}, {0.5, 0.45, 0.35}, turn, Vec3(2.6, 1.7, 3.4)))
    scene.add_face(scene.add_group("block_b"), glow, std::move(f));
  scene.camera = look_at(Vec3(2.0, 1.5, 0.3), Vec3(2.0, 1.3, 3.0), 60.0 * kPi / 180.0);
  return finished(std::move(scene));
}

std::vector<std::string> builtin_scene_names() { return {"cornell", "office", "furnace"}; }

Scene load_scene(const std::string& name_or_path) {
  if (name_or_path == "cornell") return make_cornell_box();
  if (name_or_path == "office") return make_office();
  if (name_or_path == "furnace") return make_furnace();
  if (name_or_path.empty())
    throw Error("the scene's name is empty; give a built-in scene (cornell, office, furnace) or the path of an OBJ file");
  return import_obj(name_or_path);
}

}  // namespace aarad
