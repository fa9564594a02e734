// `aarad inspect SCENE [--json]`: loads and validates a scene (built-in name or OBJ path) and shows what
// the solver will see: groups, physical surfaces, areas, materials, emitters and the import's warnings.
#include "apps/aarad/commands.h"

#include "aarad/core/builtin_scenes.h"
#include "aarad/core/error.h"
#include "aarad/core/scene.h"
#include "aarad/refine/report.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace aarad::app {
namespace {

nlohmann::json rgb_json(const Rgb& c) { return nlohmann::json::array({c.r, c.g, c.b}); }
nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

bool is_builtin(const std::string& name) {
  const auto names = builtin_scene_names();
  return std::find(names.begin(), names.end(), name) != names.end();
}

nlohmann::json report(const Scene& scene, bool builtin) {
  nlohmann::json j;
  j["scene"] = scene.name;
  j["source"] = builtin ? "built-in" : "obj";
  j["bounds"] = {{"min", vec_json(scene.bounds_min())}, {"max", vec_json(scene.bounds_max())}};
  j["diagonal"] = scene.diagonal();
  j["total_area"] = scene.total_area();
  if (scene.camera) {
    const Camera& c = *scene.camera;
    j["camera"] = {{"eye", vec_json(c.eye)}, {"forward", vec_json(c.forward)}, {"up", vec_json(c.up)},
                   {"vertical_fov", c.vertical_fov}};
  } else {
    j["camera"] = nullptr;
  }
  j["materials"] = nlohmann::json::array();
  for (const Material& m : scene.materials)
    j["materials"].push_back({{"name", m.name}, {"reflectance", rgb_json(m.reflectance)}, {"emission", rgb_json(m.emission)}});
  j["groups"] = nlohmann::json::array();
  for (const Group& g : scene.groups) {
    double a = 0.0;
    for (const std::uint32_t s : g.surfaces) a += scene.surfaces[s].area;
    j["groups"].push_back({{"name", g.name}, {"faces", g.faces.size()}, {"surfaces", g.surfaces}, {"area", a}});
  }
  j["surfaces"] = nlohmann::json::array();
  j["emitters"] = nlohmann::json::array();
  Rgb flux(0.0);
  for (std::uint32_t i = 0; i < scene.surfaces.size(); ++i) {
    const Surface& s = scene.surfaces[i];
    const Material& m = scene.materials[s.material];
    j["surfaces"].push_back({{"id", i},
                             {"group", scene.groups[s.group].name},
                             {"material", m.name},
                             {"faces", s.faces.size()},
                             {"area", s.area},
                             {"normal", vec_json(s.plane.normal)},
                             {"offset", s.plane.d}});
    if (m.emits()) {
      j["emitters"].push_back({{"surface", i},
                               {"group", scene.groups[s.group].name},
                               {"area", s.area},
                               {"emission", rgb_json(m.emission)},
                               {"flux", rgb_json(m.emission * s.area)}});
      flux += m.emission * s.area;
    }
  }
  j["emitted_flux"] = rgb_json(flux);
  j["warnings"] = scene.warnings;
  return j;
}

std::string fmt(const char* format, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}

std::string rgb_text(const Rgb& c) { return fmt("%.4g", c.r) + " " + fmt("%.4g", c.g) + " " + fmt("%.4g", c.b); }
std::string vec_text(const Vec3& v) { return "(" + fmt("%.6g", v.x) + ", " + fmt("%.6g", v.y) + ", " + fmt("%.6g", v.z) + ")"; }

void print_table(const Scene& scene, bool builtin) {
  std::printf("scene      %s (%s)\n", scene.name.c_str(), builtin ? "built-in" : "OBJ file");
  std::printf("bounds     %s .. %s, diagonal %.6g\n", vec_text(scene.bounds_min()).c_str(),
              vec_text(scene.bounds_max()).c_str(), scene.diagonal());
  std::printf("size       %zu faces, %zu groups, %zu physical surfaces, total area %.6g\n", scene.faces.size(),
              scene.groups.size(), scene.surfaces.size(), scene.total_area());
  if (scene.camera) {
    const Camera& c = *scene.camera;
    std::printf("camera     eye %s forward %s up %s, vertical fov %.4g deg\n", vec_text(c.eye).c_str(),
                vec_text(c.forward).c_str(), vec_text(c.up).c_str(), c.vertical_fov * 180.0 / kPi);
  } else {
    std::printf("camera     none (images use a camera fitted to the bounds)\n");
  }

  std::printf("\nmaterials\n  %-3s %-16s %-24s %s\n", "#", "name", "reflectance (Kd)", "emission (Ke)");
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    const Material& m = scene.materials[i];
    std::printf("  %-3zu %-16s %-24s %s\n", i, m.name.c_str(), rgb_text(m.reflectance).c_str(), rgb_text(m.emission).c_str());
  }

  std::printf("\ngroups\n  %-16s %6s %9s %14s  %s\n", "name", "faces", "surfaces", "area", "materials");
  for (const Group& g : scene.groups) {
    double a = 0.0;
    std::vector<std::string> names;
    for (const std::uint32_t s : g.surfaces) {
      a += scene.surfaces[s].area;
      const std::string& n = scene.materials[scene.surfaces[s].material].name;
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
    }
    std::string materials;
    for (const std::string& n : names) materials += (materials.empty() ? "" : ", ") + n;
    std::printf("  %-16s %6zu %9zu %14.6g  %s\n", g.name.c_str(), g.faces.size(), g.surfaces.size(), a, materials.c_str());
  }

  std::printf("\nphysical surfaces\n  %-4s %-16s %-16s %6s %14s  %s\n", "id", "group", "material", "faces", "area", "normal");
  for (std::size_t i = 0; i < scene.surfaces.size(); ++i) {
    const Surface& s = scene.surfaces[i];
    std::printf("  %-4zu %-16s %-16s %6zu %14.6g  %s\n", i, scene.groups[s.group].name.c_str(),
                scene.materials[s.material].name.c_str(), s.faces.size(), s.area, vec_text(s.plane.normal).c_str());
  }

  std::printf("\nemitters\n");
  Rgb flux(0.0);
  for (std::size_t i = 0; i < scene.surfaces.size(); ++i) {
    const Surface& s = scene.surfaces[i];
    const Material& m = scene.materials[s.material];
    if (!m.emits()) continue;
    flux += m.emission * s.area;
    std::printf("  surface %-4zu %-16s area %-12.6g emission %-20s flux %s\n", i, scene.groups[s.group].name.c_str(),
                s.area, rgb_text(m.emission).c_str(), rgb_text(m.emission * s.area).c_str());
  }
  std::printf("  total emitted flux %s\n", rgb_text(flux).c_str());

  std::printf("\nwarnings (%zu)\n", scene.warnings.size());
  for (const std::string& w : scene.warnings) std::printf("  %s\n", printable(w).c_str());
}

}  // namespace

void add_inspect_command(CLI::App& app) {
  struct Options {
    std::string scene;
    bool json = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand("inspect", "Load and validate a scene; show its groups, physical surfaces, "
                                                    "areas, materials, emitters and warnings");
  command->add_option("scene", options->scene, "Built-in scene (" + [] {
    std::string s;
    for (const std::string& n : builtin_scene_names()) s += (s.empty() ? "" : ", ") + n;
    return s;
  }() + ") or path of an OBJ file")->required();
  command->add_flag("--json", options->json, "Print one JSON object on stdout instead of tables");
  command->callback([options] {
    const Scene scene = load_scene(options->scene);
    const bool builtin = is_builtin(options->scene);
    if (options->json) {
      std::cout << refine::json_text(report(scene, builtin), 2) << '\n';
    } else {
      print_table(scene, builtin);
    }
    set_exit_code(0);
  });
}

}  // namespace aarad::app
