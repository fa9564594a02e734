// Export of the leaf mesh as binary PLY (Turk's polygon file format): one polygon per leaf element with its
// hanging vertices (so the file has no crack), vertex colours from the display reconstruction through the
// caller's VertexColour (a tone map), and per-face float properties radiosity_r, radiosity_g, radiosity_b,
// level, patch (../shared/design.md, "solve --out"). The bytes are those OpenMesh 9 writes with
// IO::Options::Binary | VertexColor | Custom and persistent face properties, except that a face's vertex count
// takes 4 bytes (`property list int int`, a count type OpenMesh's reader also takes) when a leaf has more than
// 255 vertices on its loop. OpenMesh writes the count in one byte whatever the face, and a larger face made every
// face and vertex after it unreadable.
#include "aarad/mesh/export_ply.h"

#include "aarad/core/atomic_file.h"
#include "aarad/core/error.h"
#include "aarad/mesh/display.h"
#include "aarad/mesh/leaf_mesh.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace aarad::mesh {
namespace {

// Little-endian bytes, whatever the machine's order (the header says binary_little_endian).
void append_u32(std::string& out, std::uint32_t value) {
  for (int byte = 0; byte < 4; ++byte) out += static_cast<char>((value >> (8 * byte)) & 0xFFu);
}
void append_float(std::string& out, float value) { append_u32(out, std::bit_cast<std::uint32_t>(value)); }
void append_double(std::string& out, double value) {
  const auto bits = std::bit_cast<std::uint64_t>(value);
  append_u32(out, static_cast<std::uint32_t>(bits));
  append_u32(out, static_cast<std::uint32_t>(bits >> 32));
}
// Whether `value` loses its magnitude in single precision: beyond the largest float (it would be inf), or non-zero
// below the smallest normal one (subnormal or 0). Scenes and lights may be scaled far beyond either
// (core/face_check.h, core/scene.h).
bool beyond_float(double value) {
  const double magnitude = std::abs(value);
  return magnitude > std::numeric_limits<float>::max() ||
         (magnitude != 0.0 && magnitude < std::numeric_limits<float>::min());
}

}  // namespace

void write_ply(const Hierarchy& hierarchy, std::span<const Rgb> node_values, const VertexColour& vertex_colour,
               const std::filesystem::path& path) {
  write_ply(hierarchy, node_values, build_display_mesh(hierarchy, node_values), vertex_colour, path);
}

void write_ply(const Hierarchy& hierarchy, std::span<const Rgb> node_values, const DisplayMesh& display,
               const VertexColour& vertex_colour, const std::filesystem::path& path) {
  const Hierarchy::Impl& m = hierarchy.impl();
  const std::vector<NodeId> leaves = hierarchy.leaves();

  std::vector<std::vector<std::uint32_t>> loops(leaves.size());
  std::size_t largest = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    for (auto v : m.mesh.fv_range(LeafMesh::FaceHandle(m.face[leaves[i]])))
      loops[i].push_back(static_cast<std::uint32_t>(v.idx()));
    if (loops[i].size() < 3) throw Error(path.string() + ": leaf " + std::to_string(leaves[i]) + " has no polygon");
    largest = std::max(largest, loops[i].size());
  }
  const bool wide_counts = largest > std::numeric_limits<std::uint8_t>::max();

  const std::size_t vertex_count = m.mesh.n_vertices();
  // Float points and radiosities, what viewers expect; double where single precision would lose them: beyond its
  // range (inf or 0), or, for the points, where rounding would move a vertex by more than a thousandth of the
  // shortest edge of any loop (a scene 1 across and 1e6 from the origin kept its points on a grid of 0.0625 in
  // floats, and half its faces collapsed).
  bool wide_points = false, wide_values = false;
  double shortest_edge = std::numeric_limits<double>::infinity();
  for (const std::vector<std::uint32_t>& loop : loops)
    for (std::size_t k = 0, j = loop.size() - 1; k < loop.size(); j = k++)
      shortest_edge = std::min(shortest_edge, glm::length(display.positions[loop[k]] - display.positions[loop[j]]));
  const double largest_shift = 1e-3 * shortest_edge;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double x = display.positions[v][k];
      wide_points |= beyond_float(x) || !(std::abs(x - static_cast<double>(static_cast<float>(x))) <= largest_shift);
    }
  }
  for (const NodeId leaf : leaves)
    for (int c = 0; c < 3; ++c) wide_values |= beyond_float(node_values[leaf][c]);
  const std::string point = wide_points ? "double" : "float", value = wide_values ? "double" : "float";
  std::string bytes = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertex_count) +
                      "\nproperty " + point + " x\nproperty " + point + " y\nproperty " + point + " z\n"
                      "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face " +
                      std::to_string(leaves.size()) + "\nproperty list " + (wide_counts ? "int" : "uchar") +
                      " int vertex_indices\nproperty " + value + " radiosity_r\nproperty " + value + " radiosity_g\n"
                      "property " + value + " radiosity_b\nproperty float level\nproperty float patch\nend_header\n";
  bytes.reserve(bytes.size() + 27 * vertex_count + leaves.size() * (24 + 8 * 5));
  const auto append_real = [&](bool wide, double x) {
    if (wide) {
      append_double(bytes, x);
    } else {
      append_float(bytes, static_cast<float>(x));
    }
  };
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const Vec3& p = display.positions[v];
    for (int k = 0; k < 3; ++k) append_real(wide_points, p[k]);
    for (const std::uint8_t c : vertex_colour(display.vertex_values[v])) bytes += static_cast<char>(c);
  }
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const NodeId leaf = leaves[i];
    if (wide_counts) {
      append_u32(bytes, static_cast<std::uint32_t>(loops[i].size()));
    } else {
      bytes += static_cast<char>(loops[i].size());
    }
    for (const std::uint32_t v : loops[i]) append_u32(bytes, v);
    const Rgb& b = node_values[leaf];
    for (int c = 0; c < 3; ++c) append_real(wide_values, b[c]);
    append_float(bytes, static_cast<float>(hierarchy.level(leaf)));
    append_float(bytes, static_cast<float>(hierarchy.patch(leaf)));
  }
  write_bytes_atomically(path, bytes);
}

}  // namespace aarad::mesh
