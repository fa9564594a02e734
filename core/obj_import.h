// OBJ/MTL import into the scene model (the scene format of README.md, "The program", and docs/solver.md):
//   - each OBJ face is a polygon whose vertices run counter-clockwise seen from its lit side;
//   - a face belongs to the group named by the nearest preceding `o` or `g` (faces before any belong to a
//     group named after the file's stem); an `o` or `g` without a name starts a group named `unnamed_line_N`,
//     N its line, with a warning when faces follow it;
//   - `Kd` is the reflectance rho per channel, in [0, 1); `Ke` the emitted radiosity, >= 0.
// tinyobjloader parses the structure (groups, faces, materials); the importer reads the text once more
// for what tinyobjloader does not keep: line numbers of vertices, faces and material statements, the vertex
// count of each face (tinyobjloader keeps it in 8 bits; faces of 256 and more vertices are read whole), and the
// coordinates themselves with strtod (correctly rounded, and NaN and infinity recognised).
//
// Bad input and what happens (every message names the file and, where there is one, the line):
//   - missing or unreadable OBJ: InputError;
//   - missing MTL, or a `usemtl` of an undefined material: warning, the default material (rho 0.5 grey, no
//     emission). Every library of every `mtllib` line is read, wherever the line stands: a `usemtl` may come
//     before the `mtllib` that defines its material;
//   - a NaN or infinite coordinate, a vertex index out of range: InputError with the line;
//   - a self-intersecting face (its projection to its plane is not simple): InputError with the line;
//   - Kd outside [0, 1) (the solution would not converge), negative or non-finite Ke: InputError with
//     the MTL file and line;
//   - a face with fewer than three distinct vertices, or of zero area: skipped with a warning;
//   - a face out of the range of scales the solver's doubles handle (a coordinate beyond 1e50, or a size below
//     1e-50; core/face_check.h): skipped with a warning that says so (scale the scene; radiosity does not depend
//     on its scale);
//   - a non-planar face (a vertex farther than 1e-6 of the face's diagonal from its Newell plane): split
//     into triangles by ear clipping, with a warning.
// Warnings are collected in Scene::warnings.
//
// An optional comment line restores a camera (write_obj in core/obj_export.h writes it; other programs
// ignore it):
//   # aarad camera: eye X Y Z forward X Y Z up X Y Z vertical_fov RADIANS
// and another the meshing sizes the scene was made for (Scene::meshing, used by refine::default_meshing):
//   # aarad meshing: patch_size P element_size E min_area A
// (the three in any order; one left out, or 0, is picked from the scene's size). The file's text is read
// without a leading UTF-8 byte-order mark and without comments after a statement ("f 1 2 3 # lid"), with a
// statement whose line ends in a backslash continued on the next line (errors name its first line), and `fo`,
// an older spelling of `f`, as `f`; a face repeating an earlier one (the same vertices the same way round) is
// skipped with a warning, and so is a second definition of a material. A statement that OBJ does not have warns
// once, with its first line; points and lines (`p`, `l`) and free-form geometry have no area and are passed over.
#pragma once

#include "aarad/core/scene.h"

#include <string>

namespace aarad {

// Reads `obj_path` and the MTL libraries it names (relative to the OBJ's folder) into a scene whose
// physical surfaces are built and which passed Scene::validate(). Scene::name is `obj_path`.
// Throws aarad::InputError on bad input as listed above.
Scene import_obj(const std::string& obj_path);

}  // namespace aarad
