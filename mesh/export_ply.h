// Export of the leaf mesh as binary PLY with vertex colours and per-face properties
// radiosity_r, radiosity_g, radiosity_b, level, patch (the output contract of ../shared/design.md).
#pragma once

#include "mesh/hierarchy.h"

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
// display reconstruction of display_values (the same indexing; node_values when empty) through `vertex_colour`:
// `aarad solve` writes the solution B per face and colours its vertices as smooth.png shows them, with the
// display-only ambient term. Written through write_file_atomically (core/atomic_file.h), so `path` is whole or
// untouched; throws aarad::Error naming the path on failure.
void write_ply(const Hierarchy& hierarchy, std::span<const Rgb> node_values, const VertexColour& vertex_colour,
               const std::filesystem::path& path, std::span<const Rgb> display_values = {});

}  // namespace aarad::mesh
