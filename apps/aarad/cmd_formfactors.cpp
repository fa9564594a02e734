// `aarad formfactors SCENE --from GROUP`: point-to-group form factors from the centroid of one planar
// group, along its normal, through any back end. The report format is the contract of shared/design.md.
#include "apps/aarad/commands.h"

#include "aarad/core/builtin_scenes.h"
#include "aarad/core/error.h"
#include "aarad/core/polygon.h"
#include "aarad/core/predicates.h"
#include "aarad/formfactor/backend.h"
#include "aarad/refine/report.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

namespace aarad::app {
namespace {

struct FormFactorsOptions {
  std::string scene;
  std::string from;
  std::string method = "aa-hemicube";
  int resolution = 100;
  bool json = false;
};

// How many pieces the faces make, projected along n: faces that share a point (an edge, a corner, a vertex on an
// edge, or overlap), decided by exact predicates, are one piece. Faces are paired by their bounds, swept along x.
std::size_t count_pieces(const Scene& scene, std::span<const std::uint32_t> faces, const Vec3& n) {
  struct Flat {
    std::vector<Vec2> points;
    Vec2 low, high;
  };
  std::vector<Flat> flat(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const std::vector<Vec3>& vertices = scene.faces[faces[i]].vertices;
    flat[i].points.resize(vertices.size());
    project_to_2d(vertices, n, flat[i].points);
    flat[i].low = flat[i].high = flat[i].points.front();
    for (const Vec2& p : flat[i].points) {
      flat[i].low = glm::min(flat[i].low, p);
      flat[i].high = glm::max(flat[i].high, p);
    }
  }
  const auto touch = [](const Flat& a, const Flat& b) {
    for (std::size_t i = 0; i < a.points.size(); ++i) {
      const Vec2 &p = a.points[i], &q = a.points[(i + 1) % a.points.size()];
      for (std::size_t j = 0; j < b.points.size(); ++j)
        if (segments_intersect(p, q, b.points[j], b.points[(j + 1) % b.points.size()])) return true;
    }
    // No boundaries meet: one lies inside the other, or they are apart.
    return contains(a.points, b.points.front()) || contains(b.points, a.points.front());
  };
  std::vector<std::size_t> parent(faces.size()), order(faces.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto root = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return flat[a].low.x < flat[b].low.x; });
  std::size_t pieces = faces.size();
  for (std::size_t u = 0; u < order.size(); ++u) {
    const Flat& a = flat[order[u]];
    for (std::size_t v = u + 1; v < order.size() && flat[order[v]].low.x <= a.high.x; ++v) {
      const Flat& b = flat[order[v]];
      if (b.low.y > a.high.y || b.high.y < a.low.y) continue;
      const std::size_t ra = root(order[u]), rb = root(order[v]);
      if (ra == rb || !touch(a, b)) continue;
      parent[ra] = rb;
      --pieces;
    }
  }
  return pieces;
}

// The shooting point: the area centroid of the group's faces, which must all lie in one plane and make one piece.
formfactor::Shooter shooter_of_group(const Scene& scene, std::uint32_t group_index) {
  // Physical surfaces are split by material as well as by plane, and form factors do not depend on material:
  // with one material for the group's faces, the import's own rule (Scene::build_surfaces) splits them by plane
  // only.
  Scene one_material = scene;
  for (const std::uint32_t f : scene.groups[group_index].faces) one_material.faces[f].material = 0;
  one_material.build_surfaces();
  const Group& group = one_material.groups[group_index];
  // The faces to shoot from and their plane's normal.
  std::vector<std::uint32_t> faces = group.faces;
  Vec3 n = one_material.surfaces[group.surfaces.front()].plane.normal;
  if (group.surfaces.size() != 1) {
    const Plane& plane = one_material.surfaces[group.surfaces.front()].plane;
    const double tolerance = kPlaneDistance * scene.diagonal();
    bool one_plane = true, one_way = true;
    Vec3 vector_sum(0.0);
    for (const std::uint32_t f : group.faces) {
      for (const Vec3& v : scene.faces[f].vertices)
        one_plane = one_plane && std::abs(plane.signed_distance(v)) <= tolerance;
      const Vec3 a = vector_area(scene.faces[f].vertices);
      one_way = one_way && glm::dot(a, plane.normal) > 0.0;
      vector_sum += a;
    }
    if (one_plane && !one_way) {
      // Faces of one plane turned both ways (a two-sided panel) have no one normal to shoot along. That is not
      // "2 planes".
      throw Error("group '" + group.name + "' is not one planar polygon: its faces lie in one plane but face both "
                  "ways (a two-sided panel), so it has no one normal; pick a group whose faces all face one way");
    }
    if (!one_plane) {
      throw Error("group '" + group.name + "' is not one planar polygon: its faces lie in " +
                  std::to_string(group.surfaces.size()) + " planes; pick a planar group");
    }
    // Faces in one plane, within the scene's tolerance, that face one way, and whose normals still differ by more
    // than the import's surfaces allow (1e-10 in their dot product, about 1.4e-5 rad): small triangles of a disk
    // written with six decimals, as modellers write them, tilt by about that much. They are one planar polygon, and
    // its normal is their area-weighted one (a reviewer's lamp of 24 triangles was refused as two-sided).
    n = glm::normalize(vector_sum);
  }
  Vec3 weighted(0.0);
  double total = 0.0;
  for (std::uint32_t f : faces) {
    const double a = area(scene.faces[f].vertices);
    weighted += a * centroid(scene.faces[f].vertices);
    total += a;
  }
  if (!(total > 0.0)) throw Error("group '" + group.name + "' has zero area; pick a group with a real face");
  // Faces in one plane that do not touch (two lamps in one group) have their centroid between them, off every face:
  // factors from there belong to no point of the group.
  if (const std::size_t pieces = count_pieces(scene, faces, n); pieces > 1) {
    throw Error("group '" + group.name + "' is not one planar polygon: its faces lie in one plane but in " +
                std::to_string(pieces) + " pieces that do not touch, and its centroid lies between them; give each "
                "piece a group of its own and pick one");
  }
  const Vec3 point = weighted / total;
  // The centroid of a concave group (an L, a C) may lie off its faces: the factors are still from that point.
  Vec2 point_2d;
  project_to_2d(std::span<const Vec3>(&point, 1), n, std::span<Vec2>(&point_2d, 1));
  const bool on_a_face = std::any_of(faces.begin(), faces.end(), [&](std::uint32_t f) {
    const std::vector<Vec3>& vertices = scene.faces[f].vertices;
    std::vector<Vec2> face_2d(vertices.size());
    project_to_2d(vertices, n, face_2d);
    return contains(face_2d, point_2d);
  });
  if (!on_a_face) {
    std::fprintf(stderr,
                 "aarad: warning: the centroid of group '%s' lies outside its faces (the group is concave or in "
                 "pieces); the form factors are from that point, in the group's plane\n",
                 group.name.c_str());
  }
  return formfactor::Shooter::from_normal(point, n);
}

void run_formfactors(const FormFactorsOptions& options) {
  const Scene scene = load_scene(options.scene);
  print_scene_warnings(scene);
  const std::optional<std::uint32_t> from = scene.find_group(options.from);
  if (!from) {
    std::string known;
    for (const Group& g : scene.groups) known += (known.empty() ? "" : ", ") + g.name;
    std::string message = "scene '" + scene.name + "' has no group '" + options.from + "'; its groups are: " + known;
    // A group whose faces were all skipped on import (zero area, too few vertices) is not in the scene.
    const bool skipped = std::any_of(scene.warnings.begin(), scene.warnings.end(),
                                     [](const std::string& w) { return w.find("skipped") != std::string::npos; });
    if (skipped) message += " (faces skipped on import belong to no group: see the warnings above)";
    throw Error(message);
  }
  const formfactor::Shooter shooter = shooter_of_group(scene, *from);
  const std::unique_ptr<formfactor::FormFactorBackend> backend =
      formfactor::make_backend(options.method, {.resolution = options.resolution});
  warn_if_visibility_is_ignored(scene, *backend);

  // Every face of every other group is one receiver; a face's patch is itself.
  formfactor::ReceiverView receivers;
  std::vector<std::uint32_t> receiver_group;
  for (std::uint32_t f = 0; f < scene.faces.size(); ++f) {
    const Face& face = scene.faces[f];
    if (face.group == *from) continue;
    receivers.add(face.vertices, scene.surfaces[face.surface].plane, face.surface, f);
    receiver_group.push_back(face.group);
  }
  std::vector<double> factors(receivers.size(), 0.0);
  const auto start = std::chrono::steady_clock::now();
  backend->compute(shooter, receivers, {}, factors);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<double> per_group(scene.groups.size(), 0.0);
  for (std::size_t i = 0; i < factors.size(); ++i) per_group[receiver_group[i]] += factors[i];
  double total = 0.0;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (std::uint32_t g = 0; g < scene.groups.size(); ++g) {
    if (g == *from) continue;
    total += per_group[g];
    rows.push_back({{"name", scene.groups[g].name}, {"form_factor", per_group[g]}});
  }

  if (options.json) {
    nlohmann::ordered_json report = {
        {"from", options.from},
        {"point", {shooter.centre.x, shooter.centre.y, shooter.centre.z}},
        {"normal", {shooter.normal.x, shooter.normal.y, shooter.normal.z}},
        {"method", std::string(backend->name())},
        {"resolution", options.resolution},
        {"total", total},
        {"seconds", seconds},
        {"receivers", rows},
    };
    std::cout << refine::json_text(report) << '\n';
    return;
  }
  std::printf("form factors from '%s' of %s\n", options.from.c_str(), scene.name.c_str());
  std::printf("  point  (%.6g, %.6g, %.6g)\n", shooter.centre.x, shooter.centre.y, shooter.centre.z);
  std::printf("  normal (%.6g, %.6g, %.6g)\n", shooter.normal.x, shooter.normal.y, shooter.normal.z);
  std::printf("  method %s, resolution %d, %.3f ms\n\n", std::string(backend->name()).c_str(), options.resolution,
              seconds * 1e3);
  std::printf("  %-24s %14s\n", "group", "form factor");
  for (const auto& row : rows) {
    std::printf("  %-24s %14.8f\n", row["name"].get<std::string>().c_str(), row["form_factor"].get<double>());
  }
  std::printf("  %-24s %14.8f\n", "total", total);
}

}  // namespace

void add_formfactors_command(CLI::App& app) {
  auto options = std::make_shared<FormFactorsOptions>();
  CLI::App* cmd = app.add_subcommand("formfactors", "Form factors from the centroid of one group to every other group");
  cmd->add_option("scene", options->scene, "Built-in scene name (cornell, office, furnace) or OBJ file")->required();
  cmd->add_option("--from", options->from, "Group to shoot from: one planar polygon")->required();
  cmd->add_option("--ff", options->method, "Form-factor back end: aa-hemicube, hemicube or analytic")
      ->capture_default_str();
  cmd->add_option("--resolution", options->resolution, "Hemicube pixels along the full top face [2, 8192]")
      ->transform(whole_number_in(2, 8192))
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the report as one JSON object on stdout");
  cmd->callback([options] { run_formfactors(*options); });
}

}  // namespace aarad::app
