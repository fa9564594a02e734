// A small software renderer for the solution: the display triangles (mesh/display.h) rasterized from a
// pinhole camera with a z-buffer, back faces culled (so a closed room seen from outside shows its inside).
// Pixel centres are sampled; depth and the interpolated values are perspective-correct.
//   flat   each triangle takes its leaf element's value as is (like the paper's figures);
//   smooth the display mesh's vertex values interpolated across each triangle;
//   mesh   (draw_leaf_edges) the boundaries between leaf elements drawn over a tone-mapped flat image, found
//          where the per-pixel leaf id changes, so hidden edges never show.
#pragma once

#include "aarad/core/image.h"
#include "aarad/core/scene.h"
#include "aarad/mesh/display.h"

#include <cstdint>
#include <vector>

namespace aarad::refine {

enum class Shading { kFlat, kSmooth };

struct Rendering {
  Image image;                    // linear values times `scale`, black where nothing is seen
  std::vector<mesh::NodeId> leaf;  // per pixel, the leaf element seen (mesh::kNoNode for background)
  double scale = 1.0;
};

// node_values (indexed by NodeId, leaves read) colour flat triangles; display.vertex_values colour smooth ones.
// The image holds the values times `scale`, rounded to single precision: a power of two that brings them into its
// range (radiosity is linear in Ke, which may be 1e100 or 1e-300) scales them exactly, so the image divided by it
// is what scale 1 would give wherever that is within range.
Rendering render(const mesh::DisplayMesh& display, std::span<const Rgb> node_values, const Camera& camera,
                 int width, int height, Shading shading, double scale = 1.0);

// The power of two nearest below `exposure` (1 when it is not positive and finite): as Rendering's scale, it puts
// the values a tone map of that exposure shows near 1 in the image.
double image_scale(double exposure);

// Draws one-pixel lines where the leaf id of a pixel differs from its right or lower neighbour's: dark lines
// over bright pixels, light lines over dark ones; on the pixel, or on the neighbour when the pixel is background.
void draw_leaf_edges(Image8& image, const std::vector<mesh::NodeId>& leaf);

}  // namespace aarad::refine
