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
//   only the touched cells are read and cleared again, column by column.
#pragma once

#include "core/math.h"

#include <bit>
#include <cstdint>
#include <span>
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

  // Phase 1 (edge traversal): fills cells_ and the touched row range of every column in
  // [column_begin_, column_end_). Returns the winding; nothing is touched for a degenerate polygon.
  RasterResult traverse_edges(std::span<const Vec2> polygon);
  void add_edge(Vec2 p, Vec2 q, double sign);
  void add_clipped_piece(double x0, double y0, double x1, double y1, double slope, double inverse_slope,
                         double sign);
  void add_top_carry(double x0, double x1, double sign);
  void mark_bottom(double x0, double x1);

  Cell* column(int x) { return cells_.data() + static_cast<std::ptrdiff_t>(x - column_begin_) * stride_; }
  std::uint64_t* touched_rows(int x) {
    return touched_.data() + static_cast<std::ptrdiff_t>(x - column_begin_) * mask_words_;
  }
  static void touch(std::uint64_t* touched, int row) { touched[row >> 6] |= std::uint64_t{1} << (row & 63); }
  // The highest row in [low, y] whose bit is set in `touched`, or low - 1.
  static int next_touched_row(const std::uint64_t* touched, int y, int low);

  static constexpr int kNoRow = 1 << 30;

  int width_, height_;
  // The current polygon's clipped bounding box: columns [column_begin_, column_end_), rows from
  // row_begin_, stride_ rows per column (the last one is row height_, the carry from above, when the
  // polygon reaches above the viewport). Scratch rows are numbered from row_begin_.
  int column_begin_ = 0, column_end_ = 0, row_begin_ = 0, stride_ = 1, mask_words_ = 1;
  std::vector<Cell> cells_;             // column-major over the box, all zero between calls
  std::vector<int> row_low_;            // per box column: lowest touched row, kNoRow when untouched
  std::vector<int> row_high_;           // per box column: highest touched row, -1 when untouched
  std::vector<std::uint64_t> touched_;  // per box column, one bit per row: cell written
};

// Phase 2 (carry adjustment), fused with the visit: for each touched column, run down from its highest
// touched row adding the carries of the rows above (the prefix sum of Figure 4), report the pixel and
// clear its cell for the next polygon. Rows without a touched cell between two touched ones all have the
// running carry as coverage (1 in the polygon's interior): they are reported without reading a cell,
// jumping from touched row to touched row with the column's bit mask.
template <class Visit>
RasterResult AreaRasterizer::rasterize(std::span<const Vec2> polygon, Visit&& visit) {
  const RasterResult result = traverse_edges(polygon);
  for (int x = column_begin_; x < column_end_; ++x) {
    const int low = row_low_[x - column_begin_];  // rows counted from row_begin_
    const int high = row_high_[x - column_begin_];
    row_low_[x - column_begin_] = kNoRow;
    row_high_[x - column_begin_] = -1;
    if (high < low) continue;  // no cell written in this column
    Cell* cells = column(x);
    std::uint64_t* touched = touched_rows(x);
    double carry = 0.0;
    int y = high;
    if (y == height_ - row_begin_) {  // the part of the polygon above the viewport covers the column below it
      carry = cells[y].carry;
      cells[y] = Cell{};
      --y;
    }
    while (y >= low) {
      const int next = next_touched_row(touched, y, low);  // low - 1 when none is left
      if (carry > kCoverageFloor) {
        const double coverage = carry < 1.0 ? carry : 1.0;
        for (int row = y; row > next; --row) visit(x, row + row_begin_, coverage);
      }
      if (next < low) break;
      const double coverage = cells[next].area + carry;
      carry += cells[next].carry;
      cells[next] = Cell{};
      if (coverage > kCoverageFloor) visit(x, next + row_begin_, coverage < 1.0 ? coverage : 1.0);
      y = next - 1;
    }
    for (int word = low >> 6; word <= high >> 6; ++word) touched[word] = 0;
  }
  column_begin_ = column_end_ = 0;
  return result;
}

inline int AreaRasterizer::next_touched_row(const std::uint64_t* touched, int y, int low) {
  int word = y >> 6;
  std::uint64_t bits = touched[word] & (~std::uint64_t{0} >> (63 - (y & 63)));
  const int low_word = low >> 6;
  while (bits == 0) {
    if (--word < low_word) return low - 1;
    bits = touched[word];
  }
  const int row = word * 64 + 63 - std::countl_zero(bits);
  return row >= low ? row : low - 1;
}

}  // namespace aarad
