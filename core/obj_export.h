// Writes a scene as OBJ/MTL that core/obj_import.h reads back to the same faces, groups, materials and
// camera (coordinates in the shortest text that parses back to the same double). data/scenes/ holds the
// built-in scenes written this way.
#pragma once

#include "aarad/core/scene.h"

#include <string>

namespace aarad {

// The OBJ text: an optional comment (each line prefixed with "# "), the camera comment when the scene has
// a camera, `mtllib <mtl_file_name>`, the distinct vertices, then per group `o <name>` with its faces in
// order (`usemtl` where the material changes). Spaces in material names become underscores, and a name taken by an
// earlier material gets "_2", "_3", ... (each material reads back as itself).
std::string obj_text(const Scene& scene, const std::string& mtl_file_name, const std::string& comment = "");
// The MTL text: per material `newmtl`, `Kd` (reflectance) and `Ke` (emission).
std::string mtl_text(const Scene& scene, const std::string& comment = "");
// Writes `obj_path` and, beside it, the MTL file with the same stem, each whole or not at all
// (core/atomic_file.h). Throws aarad::Error when a file cannot be written.
void write_obj(const Scene& scene, const std::string& obj_path, const std::string& comment = "");

}  // namespace aarad
