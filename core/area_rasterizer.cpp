// Exact area scan conversion: Chandran, Kiran, Phani and Rai, "Anti-aliased hemicubes for radiosity",
// section 2.1 and Figure 4 (edge traversal into A and C, carry adjustment by a prefix sum per column).
// docs/area-rasterizer.md derives the per-pixel formulas and the exact clipping used here.
//
// Per edge, per pixel crossed, with coordinates of the edge piece inside the pixel (entering e, leaving l,
// measured from the pixel's lower left corner) Figure 4 adds s (x_e - x_l)(y_e + y_l) / 2 to A and
// s (x_e - x_l) p_y to C. Here every edge runs from its endpoint of smaller x to the other (so a shared
// edge produces the very same crossing points in both polygons), and the sign of Figure 4 becomes
// `sign` = +1 for edges that run right to left in a counter-clockwise polygon (its top side) and -1 for
// the others, multiplied by -1 for a clockwise polygon so coverage is positive for either winding.
#include "aarad/core/area_rasterizer.h"

#include "aarad/core/error.h"
#include "aarad/core/predicates.h"

#include <CGAL/Exact_rational.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace aarad {
namespace {

constexpr int kMaxSide = 1 << 15;

// Sign of twice the signed area (the shoelace sum) of `polygon`, exactly. The sum is taken about the first vertex,
// which keeps it accurate for polygons far from the origin, and used when it is larger than its rounding error
// bound, otherwise it is redone in exact rationals. Each term d_a.x d_b.y - d_b.x d_a.y, d = p - first vertex,
// has its products within 3 eps (two differences and a product) and its difference within eps of the
// magnitudes |d_a.x d_b.y| + |d_b.x d_a.y|; adding n terms adds at most n eps of them: (n + 4) eps in all, to first
// order, taken generously as (2n + 8) eps. A product that underflows is off by up to half the smallest subnormal
// besides (differences and sums that underflow are exact), an error no relative bound covers: below
// kPredicateFilterFloor, as the predicates do (core/predicates.h), the exact sum decides. Above it the margin taken
// beyond (n + 4) eps covers those 2n halves many times over. (Adding 2n smallest subnormals to the bound instead had
// every call make and multiply a subnormal at run time, as GCC folds no constant that underflows: a third of
// traverse_edges' samples.) Returns the sign and, in `twice_area`, the best double value.
int exact_orientation(std::span<const Vec2> polygon, double& twice_area) {
  const std::size_t n = polygon.size();
  const Vec2 origin = polygon[0];
  double sum = 0.0, magnitude = 0.0;
  Vec2 a(0.0, 0.0);  // the first vertex, about itself
  for (std::size_t i = 1; i <= n; ++i) {
    const Vec2 b = i == n ? Vec2(0.0, 0.0) : polygon[i] - origin;
    const double t0 = a.x * b.y, t1 = b.x * a.y;
    sum += t0 - t1;
    magnitude += std::abs(t0) + std::abs(t1);
    a = b;
  }
  twice_area = sum;
  if (!std::isfinite(magnitude)) return 0;  // a non-finite coordinate, or one so large products overflow
  if (magnitude >= kPredicateFilterFloor) {
    const double bound = static_cast<double>(2 * n + 8) * std::numeric_limits<double>::epsilon() * magnitude;
    if (sum > bound) return 1;
    if (sum < -bound) return -1;
  }
  using Q = CGAL::Exact_rational;
  Q exact = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 p = polygon[i];
    const Vec2 q = polygon[i + 1 == n ? 0 : i + 1];
    exact += Q(p.x) * Q(q.y) - Q(q.x) * Q(p.y);
  }
  twice_area = CGAL::to_double(exact);
  return static_cast<int>(CGAL::sign(exact));
}

}  // namespace

AreaRasterizer::AreaRasterizer(int width, int height) : width_(width), height_(height) { set_viewport(width, height); }

void AreaRasterizer::set_viewport(int width, int height) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw Error("AreaRasterizer: viewport " + std::to_string(width) + " x " + std::to_string(height) +
                " is out of range; use a width and height between 1 and " + std::to_string(kMaxSide));
  width_ = width;
  height_ = height;
  // Sized for a polygon covering the whole viewport; each polygon packs its bounding box at the start. Every cell
  // and column is back to zero after each polygon, so growing with zeros keeps them all zero.
  const std::size_t cells = static_cast<std::size_t>(width) * static_cast<std::size_t>(height + 1);
  if (cells_.size() < cells) cells_.resize(cells, Cell{});
  if (columns_.size() < static_cast<std::size_t>(width)) columns_.resize(static_cast<std::size_t>(width), Column{});
}

RasterResult AreaRasterizer::rasterize_into(std::span<const Vec2> polygon, std::span<double> image) {
  if (image.size() != static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_))
    throw Error("AreaRasterizer::rasterize_into: the image has " + std::to_string(image.size()) +
                " values; pass width * height = " + std::to_string(width_) + " * " + std::to_string(height_));
  double* pixels = image.data();
  const std::ptrdiff_t row = width_;
  return rasterize(polygon, [pixels, row](int x, int y, double coverage) { pixels[y * row + x] += coverage; });
}

RasterResult AreaRasterizer::traverse_edges(std::span<const Vec2> polygon) {
  RasterResult result;
  column_begin_ = column_end_ = 0;
  const std::size_t n = polygon.size();
  if (n < 3) return result;
  double twice_area = 0.0;
  const int orientation = exact_orientation(polygon, twice_area);
  if (orientation == 0) return result;
  result.signed_area = 0.5 * twice_area;
  result.winding = orientation > 0 ? Winding::kCounterClockwise : Winding::kClockwise;

  double min_x = polygon[0].x, max_x = min_x, min_y = polygon[0].y, max_y = min_y;
  for (const Vec2& v : polygon) {
    min_x = std::min(min_x, v.x);
    max_x = std::max(max_x, v.x);
    min_y = std::min(min_y, v.y);
    max_y = std::max(max_y, v.y);
  }
  if (max_x <= 0.0 || min_x >= width_ || max_y <= 0.0 || min_y >= height_) return result;  // wholly outside
  column_begin_ = static_cast<int>(std::max(min_x, 0.0));
  column_end_ = ceil_to_int(std::min(max_x, static_cast<double>(width_)));
  // The box's rows, up to the row of max_y (height_ when the polygon reaches above the viewport: that row
  // holds the carry from above), packed column by column at the start of the scratch buffers so a small
  // polygon touches few cache lines.
  row_begin_ = static_cast<int>(std::max(min_y, 0.0));
  const int row_top = ceil_to_int(std::min(max_y, static_cast<double>(height_)));
  stride_ = row_top - row_begin_ + 1;

  const double winding_sign = orientation > 0 ? 1.0 : -1.0;
  if (column_end_ - column_begin_ == 1 && min_x >= 0.0 && max_x <= width_ && min_y >= 0.0 &&
      max_y < row_begin_ + 1.0) {
    single_ = true;
    single_coverage_ = single_pixel_area(polygon, winding_sign);
    return result;
  }
  for (std::size_t i = 0; i < n; ++i) add_edge(polygon[i], polygon[i + 1 == n ? 0 : i + 1], winding_sign);
  return result;
}

// A polygon inside one pixel, strictly below its top line and inside the viewport. The general traversal would
// put every edge piece into this one cell: for an edge running from a to b (a.x < b.x) it adds
// sign (b.x - a.x) ((a.y - row) + (b.y - row)) / 2 to A and nothing but zero-width pieces elsewhere, and the
// carry phase reports A + 0. This is that sum, term for term and in the same order, so the coverage is the
// same bit for bit as the traversal's (an edge along the viewport's bottom, which the traversal only marks,
// has (a.y - row) + (b.y - row) = 0 here).
double AreaRasterizer::single_pixel_area(std::span<const Vec2> polygon, double winding_sign) const {
  const double row = row_begin_;
  const std::size_t n = polygon.size();
  double area = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 p = polygon[i], q = polygon[i + 1 == n ? 0 : i + 1];
    if (p.x == q.x) continue;  // vertical: adds nothing
    const bool forward = p.x < q.x;
    const Vec2 a = forward ? p : q, b = forward ? q : p;
    const double sign = forward ? -winding_sign : winding_sign;
    const double d0 = sign * (b.x - a.x);
    area += 0.5 * d0 * ((a.y - row) + (b.y - row));
  }
  return area;
}
// Columns [x0, x1) of an edge part below the viewport: it adds nothing, but the pixels above it down to
// row 0 may be covered by the carry of the edges above, so those columns are scanned down to row 0.
void AreaRasterizer::mark_bottom(double x0, double x1) {
  for (int x = static_cast<int>(x0); x < x1; ++x) columns_[static_cast<std::size_t>(x - column_begin_)].to_bottom = 1;
}

// An edge part above the viewport: for the pixels of the viewport it is the horizontal line y = height
// (the area under it is clamped to the full column), so it only carries its projected width into the
// whole column below.
void AreaRasterizer::add_top_carry(double x0, double x1, double sign) {
  for (int x = static_cast<int>(x0); x < x1; ++x) {
    const double width = std::min(x1, x + 1.0) - std::max(x0, static_cast<double>(x));
    columns_[static_cast<std::size_t>(x - column_begin_)].top_carry += sign * width;
  }
}

void AreaRasterizer::add_edge(Vec2 p, Vec2 q, double winding_sign) {
  if (p.x == q.x) return;  // vertical: no projected width, no area under it (Figure 4 skips it)
  // Traverse from smaller to larger x whatever the direction in the polygon.
  Vec2 a = p, b = q;
  double sign = -winding_sign;  // left to right: the bottom side of a counter-clockwise polygon
  if (p.x > q.x) {
    a = q;
    b = p;
    sign = winding_sign;
  }
  const double width = width_, height = height_;
  if (b.x <= 0.0 || a.x >= width) return;  // left or right of the viewport: no pixel column affected
  if (a.y <= 0.0 && b.y <= 0.0) {
    mark_bottom(std::max(a.x, 0.0), std::min(b.x, width));
    return;
  }
  if (a.y >= height && b.y >= height) {
    add_top_carry(std::max(a.x, 0.0), std::min(b.x, width), sign);
    return;
  }

  // Clip x to [0, width]; the ordinate at a cut is interpolated from the nearer endpoint.
  const double slope = (b.y - a.y) / (b.x - a.x);
  const double y_low = std::min(a.y, b.y), y_high = std::max(a.y, b.y);
  auto y_at = [&](double x) {
    const double y = (x - a.x <= b.x - x) ? a.y + (x - a.x) * slope : b.y - (b.x - x) * slope;
    return std::clamp(y, y_low, y_high);
  };
  double x0 = a.x, y0 = a.y, x1 = b.x, y1 = b.y;
  if (x0 < 0.0) {
    x0 = 0.0;
    y0 = y_at(0.0);
  }
  if (x1 > width) {
    x1 = width;
    y1 = y_at(width);
  }

  if (y0 == y1) {  // horizontal (after clipping): lies in one band
    if (y0 >= height)
      add_top_carry(x0, x1, sign);
    else if (y0 <= 0.0)
      mark_bottom(x0, x1);
    else
      add_clipped_piece(x0, y0, x1, y1, slope, 0.0, sign);
    return;
  }

  // Clip y: the parts above the viewport carry into the top, the parts below only open their columns.
  // Abscissae of the cuts are interpolated from the nearer endpoint of [x0, x1].
  const double inverse_slope = (b.x - a.x) / (b.y - a.y);
  const double cx0 = x0, cy0 = y0, cx1 = x1, cy1 = y1;
  auto x_at = [&](double y) {
    const double x = (std::abs(y - cy0) <= std::abs(cy1 - y)) ? cx0 + (y - cy0) * inverse_slope
                                                              : cx1 - (cy1 - y) * inverse_slope;
    return std::clamp(x, cx0, cx1);
  };
  if (y0 < y1) {  // rising
    if (y1 > height) {
      const double cut = x_at(height);
      add_top_carry(cut, x1, sign);
      x1 = cut;
      y1 = height;
    }
    if (y0 < 0.0) {
      const double cut = x_at(0.0);
      mark_bottom(x0, cut);
      x0 = cut;
      y0 = 0.0;
    }
  } else {  // falling
    if (y0 > height) {
      const double cut = x_at(height);
      add_top_carry(x0, cut, sign);
      x0 = cut;
      y0 = height;
    }
    if (y1 < 0.0) {
      const double cut = x_at(0.0);
      mark_bottom(cut, x1);
      x1 = cut;
      y1 = 0.0;
    }
  }
  if (x0 < x1) add_clipped_piece(x0, y0, x1, y1, slope, inverse_slope, sign);
}

// The pixel traversal of Figure 4 for an edge piece inside the viewport: 0 <= x0 < x1 <= width and
// 0 <= y0, y1 <= height, running left to right. Column crossings are interpolated from (x0, y0) along
// `slope`, row crossings from (x0, y0) along 1 / slope, each clamped to the piece so rounding never
// makes a sub-piece run backwards. A column whose piece crosses at most one row line (every column of an
// edge with |slope| <= 1) is done without a branch: two cells, the second one given zero width when there
// is no crossing. Steeper pieces loop over their rows.
void AreaRasterizer::add_clipped_piece(double x0, double y0, double x1, double y1, double slope,
                                       double inverse_slope, double sign) {
  if (y0 <= y1) {
    if (sign > 0.0)
      trace_piece<true, 1>(x0, y0, x1, y1, slope, inverse_slope);
    else
      trace_piece<true, -1>(x0, y0, x1, y1, slope, inverse_slope);
  } else {
    if (sign > 0.0)
      trace_piece<false, 1>(x0, y0, x1, y1, slope, inverse_slope);
    else
      trace_piece<false, -1>(x0, y0, x1, y1, slope, inverse_slope);
  }
}

template <bool kRising, int kSign>
void AreaRasterizer::trace_piece(double x0, double y0, double x1, double y1, double slope, double inverse_slope) {
  constexpr double sign = kSign;
  constexpr int side = kSign > 0 ? 0 : 1;  // +1: the polygon lies below the edge
  const double y_min = std::min(y0, y1), y_max = std::max(y0, y1);
  const int last_column = ceil_to_int(x1) - 1;
  const std::ptrdiff_t stride = stride_;
  int x = static_cast<int>(x0);
  Cell* cells = column(x) - row_begin_;  // indexed by the row
  Column* state = columns_.data() + (x - column_begin_);
  double xe = x0, ye = y0;  // entering point of the current column
  // The piece from (xe, ye) to (xl, yl) inside column x.
  auto trace_column = [&](double xl, double yl) {
    int first, last;  // the rows touched in this column, first <= last
    if constexpr (kRising) {  // ye <= yl
      int row = static_cast<int>(ye);
      first = row;
      if (yl <= row + 2.0) {
        const double t = row + 1.0;
        const bool split = t < yl;
        const double crossing = std::clamp(x0 + (t - y0) * inverse_slope, xe, xl);
        const double xc = split ? crossing : xl;
        const double yc = std::min(t, yl);
        const double d0 = sign * (xc - xe), d1 = sign * (xl - xc);
        cells[row].area += 0.5 * d0 * ((ye - row) + (yc - row));
        cells[row].carry += d0;
        const int next = row + static_cast<int>(split);
        cells[next].area += 0.5 * d1 * (yl - t);  // from 0 at the crossing (d1 is 0 without one)
        cells[next].carry += d1;
        last = next;
      } else {  // crossings at row + 1, ..., last: at least two
        const int top_row = static_cast<int>(yl) - (static_cast<int>(yl) == yl);
        double t = row + 1.0;
        double xa = std::clamp(x0 + (t - y0) * inverse_slope, xe, xl);
        double dx = sign * (xa - xe);
        cells[row].area += 0.5 * dx * ((ye - row) + 1.0);
        cells[row].carry += dx;
        for (++row; row < top_row; ++row) {  // whole rows: the piece runs from their bottom to their top
          t += 1.0;
          const double xc = std::clamp(x0 + (t - y0) * inverse_slope, xe, xl);
          dx = sign * (xc - xa);
          cells[row].area += 0.5 * dx;
          cells[row].carry += dx;
          xa = xc;
        }
        dx = sign * (xl - xa);
        cells[row].area += 0.5 * dx * (yl - row);
        cells[row].carry += dx;
        last = row;
      }
    } else {  // falling: ye >= yl
      int row = static_cast<int>(ye);
      if (row == ye && yl < ye) --row;  // entering exactly on a row line from above
      last = row;
      if (yl >= row - 1.0) {
        const double t = row;
        const bool split = t > yl;
        const double crossing = std::clamp(x0 + (t - y0) * inverse_slope, xe, xl);
        const double xc = split ? crossing : xl;
        const double yc = std::max(t, yl);
        const double d0 = sign * (xc - xe), d1 = sign * (xl - xc);
        cells[row].area += 0.5 * d0 * ((ye - row) + (yc - row));
        cells[row].carry += d0;
        const int next = row - static_cast<int>(split);
        cells[next].area += 0.5 * d1 * (1.0 + (yl - (t - 1.0)));  // from 1 at the crossing (d1 is 0 without one)
        cells[next].carry += d1;
        first = next;
      } else {  // crossings at row, ..., bottom_row + 1: at least two
        const int bottom_row = static_cast<int>(yl);
        double t = row;
        double xa = std::clamp(x0 + (t - y0) * inverse_slope, xe, xl);
        double dx = sign * (xa - xe);
        cells[row].area += 0.5 * dx * (ye - row);
        cells[row].carry += dx;
        for (--row; row > bottom_row; --row) {  // whole rows: the piece runs from their top to their bottom
          t -= 1.0;
          const double xc = std::clamp(x0 + (t - y0) * inverse_slope, xe, xl);
          dx = sign * (xc - xa);
          cells[row].area += 0.5 * dx;
          cells[row].carry += dx;
          xa = xc;
        }
        dx = sign * (xl - xa);
        cells[row].area += 0.5 * dx * (1.0 + (yl - row));
        cells[row].carry += dx;
        first = row;
      }
    }
    state->low[side] = std::min(state->low[side], first);
    state->high[side] = std::max(state->high[side], last);
  };
  for (; x < last_column; ++x, cells += stride, ++state) {
    const double xl = x + 1.0;
    const double yl = std::clamp(y0 + (xl - x0) * slope, y_min, y_max);
    trace_column(xl, yl);
    xe = xl;
    ye = yl;
  }
  trace_column(x1, y1);
}

}  // namespace aarad
