// Export of the leaf mesh as binary PLY with vertex colours and per-face properties
// radiosity_r, radiosity_g, radiosity_b, level, patch (the outputs of docs/solver.md, "aarad solve").
#pragma once

#include "aarad/mesh/display.h"
#include "aarad/mesh/hierarchy.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>

namespace aarad::mesh {

// The 8-bit colour of a vertex from its display radiosity: a tone map (`aarad solve` passes the exposure and
// sRGB encoding of aarad::ToneMap, core/image.h, that its PNGs use).
using VertexColour = std::function<std::array<std::uint8_t, 3>(const Rgb&)>;

// node_values is indexed by NodeId (only leaves read): the per-face radiosity. Vertex colours are the
// display reconstruction of those values through `vertex_colour`. Written through write_file_atomically
// (core/atomic_file.h), so `path` is whole or untouched; throws aarad::Error naming the path on failure.
void write_ply(const Hierarchy& hierarchy, std::span<const Rgb> node_values, const VertexColour& vertex_colour,
               const std::filesystem::path& path);
// The same with the vertex colours from `display` (build_display_mesh of this hierarchy, from any values):
// `aarad solve` writes the solution B per face and colours the vertices as smooth.png shows them, from the display
// mesh of the displayed values (with the ambient term) that its images are rendered from.
void write_ply(const Hierarchy& hierarchy, std::span<const Rgb> node_values, const DisplayMesh& display,
               const VertexColour& vertex_colour, const std::filesystem::path& path);

}  // namespace aarad::mesh
