// Export of the leaf mesh as binary PLY (Turk's polygon file format): one polygon per leaf element with its
// hanging vertices (so the file has no crack), vertex colours from the display reconstruction through the
// caller's VertexColour (a tone map), and per-face float properties radiosity_r, radiosity_g, radiosity_b,
// level, patch (../shared/design.md, "solve --out"). OpenMesh writes persistent custom face properties with
// IO::Options::Custom.
// OpenMesh's PropertyT<VectorT<unsigned char, 3>>::push_back appends a default-constructed colour, whose
// components VectorT leaves uninitialized until they are set; GCC 12 reports that as -Wmaybe-uninitialized
// from a system header. Every colour is assigned before the mesh is written.
#if defined(__GNUC__) && !defined(__clang__)  // a GCC warning; Clang has no such group
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/IO/MeshIO.hh>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

#include "mesh/export_ply.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "mesh/display.h"
#include "mesh/leaf_mesh.h"

#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <fstream>

namespace aarad::mesh {

void write_ply(const Hierarchy& hierarchy, std::span<const Rgb> node_values, const VertexColour& vertex_colour,
               const std::filesystem::path& path) {
  const Hierarchy::Impl& m = hierarchy.impl();
  const DisplayMesh display = build_display_mesh(hierarchy, node_values);

  using ExportMesh = OpenMesh::PolyMesh_ArrayKernelT<>;  // float points: what viewers expect
  ExportMesh out;
  out.request_vertex_colors();
  const std::size_t vertex_count = m.mesh.n_vertices();
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const Vec3& p = display.positions[v];
    const auto vh = out.add_vertex(ExportMesh::Point(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)));
    const std::array<std::uint8_t, 3> c = vertex_colour(display.vertex_values[v]);
    out.set_color(vh, ExportMesh::Color(c[0], c[1], c[2]));
  }
  OpenMesh::FPropHandleT<float> radiosity_r, radiosity_g, radiosity_b, level, patch;
  out.add_property(radiosity_r, "radiosity_r");
  out.add_property(radiosity_g, "radiosity_g");
  out.add_property(radiosity_b, "radiosity_b");
  out.add_property(level, "level");
  out.add_property(patch, "patch");
  for (auto prop : {radiosity_r, radiosity_g, radiosity_b, level, patch}) out.property(prop).set_persistent(true);

  std::vector<ExportMesh::VertexHandle> loop;
  for (NodeId leaf : hierarchy.leaves()) {
    loop.clear();
    for (auto v : m.mesh.fv_range(LeafMesh::FaceHandle(m.face[leaf]))) loop.emplace_back(v.idx());
    const auto f = out.add_face(loop);
    if (!f.is_valid()) throw Error(path.string() + ": could not add leaf " + std::to_string(leaf) + " to the PLY mesh");
    const Rgb& b = node_values[leaf];
    out.property(radiosity_r, f) = static_cast<float>(b.r);
    out.property(radiosity_g, f) = static_cast<float>(b.g);
    out.property(radiosity_b, f) = static_cast<float>(b.b);
    out.property(level, f) = static_cast<float>(hierarchy.level(leaf));
    out.property(patch, f) = static_cast<float>(hierarchy.patch(leaf));
  }

  write_file_atomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
    if (!stream) throw Error(path.string() + ": cannot open " + temporary.string() + " for writing");
    const OpenMesh::IO::Options options =
        OpenMesh::IO::Options::Binary | OpenMesh::IO::Options::VertexColor | OpenMesh::IO::Options::Custom;
    const bool written = OpenMesh::IO::write_mesh(out, stream, ".ply", options);
    stream.close();
    if (!written || !stream) throw Error(path.string() + ": writing the PLY mesh failed");
  });
}

}  // namespace aarad::mesh
