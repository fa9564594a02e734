// Exact area scan conversion of polygons: the algorithm of Figure 4 of Chandran, Kiran, Phani and Rai,
// "Anti-aliased hemicubes for radiosity", section 2.1.
//
// Coordinates: pixel (x, y) of a width x height viewport covers [x, x+1) x [y, y+1); y grows upwards.
// Coverage is the fraction of the pixel's area inside the polygon, in [0, 1].
//
// (The implementation contract; see area_rasterizer.cpp.)
#pragma once

#include "core/math.h"

#include <cstdint>
#include <span>
#include <vector>

namespace aarad {

enum class Winding { kCounterClockwise, kClockwise, kDegenerate };

struct RasterResult {
  double signed_area = 0.0;  // in pixel units, positive for counter-clockwise (y up), before clipping
  Winding winding = Winding::kDegenerate;
};

// Reusable scratch state; no allocation per polygon once warmed up.
class AreaRasterizer {
 public:
  AreaRasterizer(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }

  // Scan-converts a simple polygon of either winding, clipped exactly to the viewport, and calls
  // visit(x, y, coverage) once for every pixel with coverage > 0, column by column.
  template <class Visit>
  RasterResult rasterize(std::span<const Vec2> polygon, Visit&& visit);

  // Adds the coverage of `polygon` to `image` (width * height values, row y at offset y * width).
  RasterResult rasterize_into(std::span<const Vec2> polygon, std::span<double> image);

 private:
  int width_, height_;
  // Filled by the implementation.
};

}  // namespace aarad
