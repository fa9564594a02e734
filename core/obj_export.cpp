// OBJ/MTL export (Wavefront OBJ and MTL as documented by Paul Bourke, "Object Files (.obj)" and "MTL
// material format"), the inverse of core/obj_import.cpp.
#include "aarad/core/obj_export.h"

#include "aarad/core/atomic_file.h"
#include "aarad/core/error.h"

#include <charconv>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>
#include <vector>

namespace aarad {
namespace {

// Shortest decimal text that reads back as the same double.
std::string number(double v) {
  if (v == 0.0) return "0";  // also turns -0 into 0
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}

std::string triple(double a, double b, double c) { return number(a) + " " + number(b) + " " + number(c); }

// The name each material is written under: blanks become underscores (an MTL name is one word), and a name that
// an earlier material already took ("red paint" and "red_paint", or two materials of one name) gets "_2", "_3",
// ..., so every material reads back as itself.
std::vector<std::string> material_names(const Scene& scene) {
  std::vector<std::string> names;
  std::set<std::string> taken;
  for (const Material& m : scene.materials) {
    std::string name = m.name.empty() ? std::string("unnamed") : m.name;
    for (char& ch : name)
      if (ch == ' ' || ch == '\t') ch = '_';
    std::string unique = name;
    for (int k = 2; taken.contains(unique); ++k) unique = name + "_" + std::to_string(k);
    taken.insert(unique);
    names.push_back(std::move(unique));
  }
  return names;
}

std::string comment_lines(const std::string& comment) {
  std::string out;
  if (comment.empty()) return out;
  std::istringstream in(comment);
  std::string line;
  while (std::getline(in, line)) out += line.empty() ? "#\n" : "# " + line + "\n";
  return out;
}


}  // namespace

std::string obj_text(const Scene& scene, const std::string& mtl_file_name, const std::string& comment) {
  std::ostringstream out;
  out << comment_lines(comment);
  if (scene.camera) {
    const Camera& c = *scene.camera;
    out << "# aarad camera: eye " << triple(c.eye.x, c.eye.y, c.eye.z) << " forward "
        << triple(c.forward.x, c.forward.y, c.forward.z) << " up " << triple(c.up.x, c.up.y, c.up.z)
        << " vertical_fov " << number(c.vertical_fov) << "\n";
  }
  if (scene.meshing) {
    const MeshingHint& m = *scene.meshing;
    out << "# aarad meshing: patch_size " << number(m.patch_size) << " element_size " << number(m.element_size)
        << " min_area " << number(m.min_area) << "\n";
  }
  out << "mtllib " << mtl_file_name << "\n";

  // Distinct vertices in order of first use, numbered from 1.
  std::map<std::tuple<double, double, double>, std::size_t> index;
  std::vector<std::vector<std::size_t>> face_indices(scene.faces.size());
  for (const Group& g : scene.groups)
    for (const std::uint32_t fi : g.faces)
      for (const Vec3& v : scene.faces[fi].vertices) {
        const auto key = std::make_tuple(v.x == 0.0 ? 0.0 : v.x, v.y == 0.0 ? 0.0 : v.y, v.z == 0.0 ? 0.0 : v.z);
        const auto [it, inserted] = index.try_emplace(key, index.size() + 1);
        if (inserted) out << "v " << triple(v.x, v.y, v.z) << "\n";
        face_indices[fi].push_back(it->second);
      }

  const std::vector<std::string> materials = material_names(scene);
  std::uint32_t smoothing = 0;  // `s` holds until the next `s`, across `o` lines; a file starts with it off
  for (const Group& g : scene.groups) {
    if (g.faces.empty()) continue;
    out << "o " << g.name << "\n";
    std::optional<std::uint32_t> material;
    for (const std::uint32_t fi : g.faces) {
      const Face& f = scene.faces[fi];
      if (material != f.material) {
        material = f.material;
        out << "usemtl " << materials[f.material] << "\n";
      }
      if (smoothing != f.smoothing) {
        smoothing = f.smoothing;
        out << "s " << (smoothing == 0 ? std::string("off") : std::to_string(smoothing)) << "\n";
      }
      out << "f";
      for (const std::size_t i : face_indices[fi]) out << " " << i;
      out << "\n";
    }
  }
  return out.str();
}

std::string mtl_text(const Scene& scene, const std::string& comment) {
  std::ostringstream out;
  out << comment_lines(comment);
  const std::vector<std::string> names = material_names(scene);
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    const Material& m = scene.materials[i];
    out << "newmtl " << names[i] << "\n";
    out << "Kd " << triple(m.reflectance.r, m.reflectance.g, m.reflectance.b) << "\n";
    out << "Ke " << triple(m.emission.r, m.emission.g, m.emission.b) << "\n";
  }
  return out.str();
}

void write_obj(const Scene& scene, const std::string& obj_path, const std::string& comment) {
  const std::filesystem::path obj(obj_path);
  std::filesystem::path mtl = obj;
  mtl.replace_extension(".mtl");
  write_bytes_atomically(mtl, mtl_text(scene, comment));
  write_bytes_atomically(obj, obj_text(scene, mtl.filename().string(), comment));
}

}  // namespace aarad
