// Exact area scan conversion of polygons: the algorithm of Figure 4 of Chandran, Kiran, Phani and Rai,
// "Anti-aliased hemicubes for radiosity", section 2.1 (edge traversal into an area array A and a carry
// array C, then a prefix sum of the carries down each column). docs/area-rasterizer.md explains it.
//
// Coordinates: pixel (x, y) of a width x height viewport covers [x, x+1) x [y, y+1); y grows upwards.
// Coverage is the fraction of the pixel's area inside the polygon, in [0, 1].
//
// Implementation contract (area_rasterizer.cpp):
// - Every edge adds, to each pixel of its column, the signed area between the edge and the bottom of the
//   viewport; parts left or right of the viewport add nothing, parts above it add the full column height,
//   parts below it add zero. Clipping is therefore exact and needs no polygon clipper.
// - An edge is traversed from its endpoint of smaller x to the other whatever its direction in the
//   polygon, with the sign carried separately, so an edge shared by two polygons of the same winding
//   cancels bit for bit: pieces of a polygon add up to the whole with no cracks and no double counting.
// - No allocation per call: scratch buffers sized to the viewport are allocated by the constructor and
//   only the row ranges that edges touched are read and cleared again, column by column.
#pragma once

#include "aarad/core/math.h"

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace aarad {

enum class Winding { kCounterClockwise, kClockwise, kDegenerate };

struct RasterResult {
  double signed_area = 0.0;  // in pixel units, positive for counter-clockwise (y up), before clipping
  Winding winding = Winding::kDegenerate;
};

// Reusable scratch state; no allocation per polygon once constructed. Not thread-safe: use one
// rasterizer per thread.
class AreaRasterizer {
 public:
  // Coverage below this fraction of a pixel is rounding noise of the carry sums (about 1e-16 per edge
  // piece) and is reported as no coverage; genuine coverage that small changes no sum by more than it.
  static constexpr double kCoverageFloor = 1e-13;

  // Throws aarad::Error unless 1 <= width, height <= 1 << 15.
  AreaRasterizer(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }

  // Makes the viewport width x height (as the constructor's; throws the same way), keeping the scratch buffers:
  // they grow to the largest viewport set and never shrink, so one rasterizer serves viewports of many sizes.
  void set_viewport(int width, int height);

  // Scan-converts a simple polygon (vertices in pixel units, either winding, first vertex not repeated),
  // clipped exactly to the viewport, and calls visit(x, y, coverage) once for every pixel with
  // coverage > kCoverageFloor: column by column (x increasing), inside a column y decreasing, over the
  // clipped bounding box only. Coverage is clamped to at most 1. A polygon with fewer than three
  // vertices, with all vertices collinear, or with a non-finite coordinate visits nothing and returns
  // Winding::kDegenerate. The winding is decided exactly (sign of the shoelace sum in exact arithmetic).
  template <class Visit>
  RasterResult rasterize(std::span<const Vec2> polygon, Visit&& visit);

  // Adds the coverage of `polygon` to `image` (width * height values, row y at offset y * width).
  // Throws aarad::Error when image.size() != width * height.
  RasterResult rasterize_into(std::span<const Vec2> polygon, std::span<double> image);

 private:
  // One pixel's accumulators of Figure 4: A (signed area under the edges inside the pixel, measured
  // from the pixel's bottom) and C (signed projected width of the edge pieces inside the pixel, which
  // covers every pixel below it in the column: the carry).
  struct Cell {
    double area = 0.0;
    double carry = 0.0;
  };

  static constexpr int kNoRow = 1 << 30;

  // What the edge traversal left in one column of the box (rows are pixel rows). Side 0 holds the rows
  // touched by the edges with the polygon below them (top side), side 1 by those with the polygon above
  // them (bottom side). For a convex polygon the two ranges are the column's top and bottom crossings
  // and every row strictly between them is untouched: its coverage is the running carry, reported
  // without reading a cell.
  struct Column {
    int low[2] = {kNoRow, kNoRow};  // lowest touched row per side, kNoRow when none
    int high[2] = {-1, -1};         // highest touched row per side, -1 when none
    double top_carry = 0.0;         // projected width of the edge parts above the viewport
    int to_bottom = 0;              // 1 when an edge part below the viewport crosses the column
  };

  // Phase 1 (edge traversal): fills cells_ and columns_ over [column_begin_, column_end_), or, for a polygon
  // inside one pixel, sets single_ and single_coverage_ instead. Returns the winding; nothing is touched for a
  // degenerate polygon.
  RasterResult traverse_edges(std::span<const Vec2> polygon);
  double single_pixel_area(std::span<const Vec2> polygon, double winding_sign) const;
  void add_edge(Vec2 p, Vec2 q, double sign);
  void add_clipped_piece(double x0, double y0, double x1, double y1, double slope, double inverse_slope,
                         double sign);
  template <bool kRising, int kSign>
  void trace_piece(double x0, double y0, double x1, double y1, double slope, double inverse_slope);
  void add_top_carry(double x0, double x1, double sign);
  void mark_bottom(double x0, double x1);

  Cell* column(int x) { return cells_.data() + static_cast<std::ptrdiff_t>(x - column_begin_) * stride_; }

  int width_, height_;
  // The current polygon's clipped bounding box: columns [column_begin_, column_end_), rows from
  // row_begin_, stride_ rows per column (up to the row of the polygon's top, which may be row height_: a
  // piece of edge lying on the line y = height_ leaves its carry there). Cell k of a box column is row
  // row_begin_ + k.
  int column_begin_ = 0, column_end_ = 0, row_begin_ = 0, stride_ = 1;
  // A polygon inside the single pixel (column_begin_, row_begin_): its coverage, computed without the cells.
  bool single_ = false;
  double single_coverage_ = 0.0;
  std::vector<Cell> cells_;      // column-major over the box, all zero between calls
  std::vector<Column> columns_;  // per box column, all Column{} between calls
};

// Phase 2 (carry adjustment), fused with the visit: for each column, run down from the top adding the
// carries of the rows above (the prefix sum of Figure 4), report the pixel and clear its cell for the
// next polygon. Only the row ranges touched by edges are read, as at most two dense runs (one per side,
// merged when they meet); the untouched rows above, between and below them all have the running carry as
// coverage (exactly 1 in a convex polygon's interior) and are reported without reading a cell.
template <class Visit>
RasterResult AreaRasterizer::rasterize(std::span<const Vec2> polygon, Visit&& visit) {
  const RasterResult result = traverse_edges(polygon);
  if (single_) {  // inside one pixel: its coverage is all there is
    single_ = false;
    const double coverage = single_coverage_;
    if (coverage > kCoverageFloor) visit(column_begin_, row_begin_, coverage < 1.0 ? coverage : 1.0);
    column_begin_ = column_end_ = 0;
    return result;
  }
  const int top = height_;  // the row above the viewport
  Cell* cells = column(column_begin_) - row_begin_;  // indexed by the row
  for (int x = column_begin_; x < column_end_; ++x, cells += stride_) {
    Column& state = columns_[static_cast<std::size_t>(x - column_begin_)];
    const Column touched = state;
    state = Column{};
    double carry = touched.top_carry;
    // Rows from `from` down to just above `to` are untouched: all have the running carry as coverage.
    auto fill = [&](int from, int to) {
      if (carry > kCoverageFloor) {
        const double coverage = carry < 1.0 ? carry : 1.0;
        for (int row = from; row > to; --row) visit(x, row, coverage);
      }
    };
    // Rows from `high` down to `low` are read (each may hold A and C), reported and cleared.
    auto dense = [&](int high, int low) {
      for (int row = high; row >= low; --row) {
        const double coverage = cells[row].area + carry;
        carry += cells[row].carry;
        cells[row] = Cell{};
        if (coverage > kCoverageFloor) visit(x, row, coverage < 1.0 ? coverage : 1.0);
      }
    };
    int high_a = touched.high[0], low_a = touched.low[0], high_b = touched.high[1], low_b = touched.low[1];
    if (high_b > high_a) {  // a reaches higher; an empty range has high -1, so a is empty only if b is
      std::swap(high_a, high_b);
      std::swap(low_a, low_b);
    }
    int y = top - 1;  // the next row to report
    if (high_a >= low_a) {
      if (high_b >= low_b && high_b + 1 >= low_a) {  // the ranges meet: one dense run
        low_a = std::min(low_a, low_b);
        high_b = -1;
      }
      if (high_a == top) {  // carry left by an edge piece on the line y = height_: not a pixel
        carry += cells[top].carry;
        cells[top] = Cell{};
        --high_a;
      }
      fill(y, high_a);
      dense(high_a, low_a);
      y = low_a - 1;
      if (high_b >= low_b) {
        fill(y, high_b);
        dense(high_b, low_b);
        y = low_b - 1;
      }
    }
    if (touched.to_bottom) fill(y, row_begin_ - 1);
  }
  column_begin_ = column_end_ = 0;
  return result;
}

}  // namespace aarad
