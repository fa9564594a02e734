// The classical hemicube: Cohen and Greenberg, "The hemi-cube: a radiosity solution for complex environments",
// SIGGRAPH 1985. Receivers are clipped and projected onto the five faces (hemicube_geometry.h), every pixel is
// sampled at one point with a z-buffer and an item buffer, and every receiver gets the delta form factors of
// the pixels it wins. This is the baseline the anti-aliased hemicube (aa_hemicube.h) is compared against.
#pragma once

#include "aarad/core/math.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/hemicube_geometry.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace aarad::formfactor {

// One crossing of a scan line with a polygon edge: its x and the edge's direction (+1 up, -1 down).
struct ScanCrossing {
  double x;
  int direction;
};

// Point-sampling scan conversion with a consistent fill rule. Calls visit(x, y) for every pixel of columns
// [column_begin, column_end) and rows [0, height) whose sample point (x + 1/2, sample_y(y)) lies inside `polygon`
// (either winding; the non-zero winding rule). A sample point on an edge belongs to the polygon on the edge's
// right in x, or above it for a horizontal edge (half-open spans [x_left, x_right) and edges [y_low, y_high)): of
// two polygons sharing an edge exactly one takes it. Crossings are computed from each edge's endpoints in
// canonical order, so both polygons compute the same x. `crossings` needs room for polygon.size() entries.
template <class SampleY, class Visit>
void sample_polygon(std::span<const Vec2> polygon, int column_begin, int column_end, int height, SampleY&& sample_y,
                    std::span<ScanCrossing> crossings, Visit&& visit) {
  const std::size_t m = polygon.size();
  if (m < 3) return;
  double ymin = polygon[0].y, ymax = polygon[0].y;
  for (const Vec2& p : polygon) {
    ymin = std::min(ymin, p.y);
    ymax = std::max(ymax, p.y);
  }
  const int row_lo = std::max(0, floor_to_int(ymin - 0.5));
  const int row_hi = std::min(height - 1, floor_to_int(ymax));
  for (int row = row_lo; row <= row_hi; ++row) {
    const double yc = sample_y(row);
    if (yc < ymin || yc >= ymax) continue;
    std::size_t count = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const Vec2& p = polygon[i];
      const Vec2& q = polygon[i + 1 == m ? 0 : i + 1];
      if (p.y == q.y) continue;
      const bool up = p.y < q.y;
      const Vec2& lo = up ? p : q;
      const Vec2& hi = up ? q : p;
      if (!(lo.y <= yc && yc < hi.y)) continue;
      const double x = lo.x + (yc - lo.y) * (hi.x - lo.x) / (hi.y - lo.y);
      // Insertion sort by x (lists hold two crossings for a convex polygon).
      std::size_t k = count++;
      while (k > 0 && crossings[k - 1].x > x) {
        crossings[k] = crossings[k - 1];
        --k;
      }
      crossings[k] = ScanCrossing{x, up ? 1 : -1};
    }
    int winding = 0;
    for (std::size_t k = 0; k + 1 < count; ++k) {
      winding += crossings[k].direction;
      if (winding == 0) continue;
      // Columns whose centre c + 1/2 lies in [x_k, x_{k+1}); x - 1/2 is exact for |x| < 2^52.
      const int c0 = std::max(column_begin, ceil_to_int(crossings[k].x - 0.5));
      const int c1 = std::min(column_end, ceil_to_int(crossings[k + 1].x - 0.5));
      for (int c = c0; c < c1; ++c) visit(c, row);
    }
  }
}

// The classical hemicube back end ("hemicube").
class HemicubeBackend final : public FormFactorBackend {
 public:
  explicit HemicubeBackend(int resolution);

  std::string_view name() const override { return "hemicube"; }
  void compute(const Shooter& shooter, const ReceiverView& receivers, std::span<const std::uint32_t> subset,
               std::span<double> out) override;
  bool keep_unoccluded(std::span<const std::uint8_t> wanted) override {
    keep_unoccluded_ = wanted;
    return true;
  }
  bool add_unoccluded(std::span<double> out) const override;

 private:
  struct FaceBuffers {
    std::vector<double> inverse_depth;  // per pixel; 0 = nothing seen yet
    std::vector<std::uint32_t> item;    // per pixel: receiver index
    std::vector<Vec3> local, scratch, clipped;  // a receiver in local coordinates; clipping buffers
    std::vector<Vec2> projected;
    std::vector<ScanCrossing> crossings;
  };
  // One task of a shot: every candidate, or for a subset (`tiles`: PreparedReceivers::subset_tiles) only those
  // whose box meets its tiles. `surfaces` holds the receivers' physical-surface ids.
  void shoot_task(const FaceTask& task, std::span<const std::uint32_t> candidates,
                  std::span<const std::uint32_t> surfaces, const TileMask* tiles, std::size_t max_vertices,
                  FaceBuffers& buffers, std::span<double> sums, UnoccludedList& unoccluded) const;

  HemicubeGeometry geometry_;
  PreparedReceivers prepared_;
  TaskSums sums_;
  std::array<UnoccludedList, kFaceTasks> task_unoccluded_;
  std::span<const std::uint8_t> keep_unoccluded_;
  tbb::enumerable_thread_specific<FaceBuffers> buffers_;
};

}  // namespace aarad::formfactor
