// The built-in scenes, compiled into the program so they work from any folder (the same geometry is in
// data/scenes/<name>.obj and .mtl, kept identical by tests/test_builtin_scenes.cpp), and the one entry
// point that resolves a scene argument.
#pragma once

#include "aarad/core/scene.h"

#include <string>
#include <vector>

namespace aarad {

// The Cornell box (Cornell Program of Computer Graphics, "Cornell Box Data"), millimetres, y up, with
// the official camera. Every normal points into the room (block faces point out of their blocks). The
// non-planar left wall is deliberately split into two triangles (no warning); the light is lowered by
// 0.1 mm so it is not coplanar with the ceiling; the floor is cut around the blocks' footprints into
// convex pieces without T-junctions between them (all in group "floor", one physical surface).
// Groups: floor, ceiling, back_wall, left_wall (red), right_wall (green), light, short_block, tall_block.
Scene make_cornell_box();

// An office in metres, y up, like the paper's second test (section 4): a closed 5 x 3 x 6 m room with
// two ceiling lights 1 mm below the ceiling, a round pedestal table (24-sided top with an edge band, an
// octagonal column, a 16-sided base) and three chairs (seat, back and four legs as boxes), each a closed
// solid standing on the floor. Twelve groups, as the paper's twelve surfaces: floor, ceiling, wall_north,
// wall_south, wall_east, wall_west, light_1, light_2, table, chair_1, chair_2, chair_3. Camera inside.
Scene make_office();

// A furnace (docs/solver.md, "Accuracy: the furnace"): a closed 4 x 3 x 5 room (inward normals) with
// two floating blocks (six outward faces each, touching nothing; one axis-aligned, one rotated about two
// axes). Every surface emits 1 and reflects 0.5, so the exact radiosity is B = 2 everywhere.
// Groups: floor, ceiling, wall_north, wall_south, wall_east, wall_west, block_a, block_b.
Scene make_furnace();

// "cornell", "office", "furnace".
std::vector<std::string> builtin_scene_names();

// A built-in scene by name, or else the OBJ file at `name_or_path` (core/obj_import.h). The scene is
// validated and its physical surfaces built. Throws aarad::InputError when the name is no built-in and
// the file cannot be read or is bad.
Scene load_scene(const std::string& name_or_path);

}  // namespace aarad
