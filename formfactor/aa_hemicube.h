// The anti-aliased hemicube: Chandran, Kiran, Phani and Rai, "Anti-aliased hemicubes for radiosity",
// section 3.2. Every receiver facing the shooter is clipped to each face's frustum (hemicube_geometry.h),
// projected, and scan-converted with the exact area rasterizer of the paper's Figure 4 (core/area_rasterizer.h);
// every pixel keeps a depth-sorted list of (receiver, A, depth, spread, surface) (coverage_list.h); walking each
// list front to back, a receiver gets E_k = A_k (1 - f_{k-1}) of the pixel's delta form factor, and receivers
// that meet inside the pixel share it side by side (coverage_list.h, "Layers"). Where a surface runs on behind
// another that meets it in the pixel (a floor past a wall's foot), the walk orders the overfilled layer by the
// receivers' planes, which this back end answers from the view's polygons (PlaneOrder in aa_hemicube.cpp;
// coverage_list.h, CoverageWalk).
//
// The depth kept per receiver and pixel is the distance along the face axis at which the ray through the pixel
// centre meets the receiver's plane, also where the receiver covers only part of the pixel; where that ray meets
// the plane behind the shooter (or runs parallel to it), 1 / depth at the pixel's corner nearest the shooter, the
// largest over the pixel. Why: 1 / depth is affine in pixel coordinates, so it costs one multiply-add per entry
// (the rasterizer reports coverage, not where in the pixel it lies); it depends on the plane and the pixel only, so
// every piece of one plane gets the same key whatever order the receivers come in, and two planes are compared
// along the same ray as a z-buffer compares them; with a spread of |alpha| + |beta| it bounds the depths the
// receiver can have in the pixel (docs/form-factors.md, "Depth kept per receiver and pixel"). Pieces of one
// physical surface are grouped by surface id, not by comparing depths, so coplanar pieces never occlude each
// other whatever rounding does to their planes.
//
// Parallel over twelve tasks of one size (face_tasks): the top face cut into four column quarters and each side
// face into its two column halves, so that two threads share the work evenly (one arena and one rasterizer per
// thread, set to each task's viewport), started largest first (run_face_tasks). The per-task partial sums are
// added in task order, so the numbers do not depend on the number of threads.
#pragma once

#include "aarad/core/area_rasterizer.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/coverage_list.h"
#include "aarad/formfactor/hemicube_geometry.h"

#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <memory>
#include <vector>

namespace aarad::formfactor {

namespace detail {
// The plane order's room (aa_hemicube.cpp): polygons in the task's pixel coordinates, and the projections of the
// front receivers of one pixel.
struct OrderBuffers {
  static constexpr std::size_t kNoPixel = ~std::size_t{0};
  std::vector<Vec2> back, in_pixel, front, both, scratch;
  std::size_t pixel = kNoPixel;  // the pixel whose fronts are kept
  std::vector<std::uint32_t> fronts;
  std::vector<std::size_t> starts;  // front i's points: [starts[i], starts[i + 1])
  std::vector<Vec2> points;
  std::vector<Vec2> cell, cell_next;  // a receiver's part in a pixel cut by planes (a cell of it)
  // The receiver last measured in a pixel: the pixel, the receiver, its part in the pixel and that part's area.
  std::size_t whole_pixel = kNoPixel;
  std::uint32_t whole_receiver = 0;
  std::vector<Vec2> whole;
  double whole_area = 0.0;
};
}  // namespace detail

class AaHemicubeBackend final : public FormFactorBackend {
 public:
  explicit AaHemicubeBackend(int resolution);

  std::string_view name() const override { return "aa-hemicube"; }
  void compute(const Shooter& shooter, const ReceiverView& receivers, std::span<const std::uint32_t> subset,
               std::span<double> out) override;
  bool keep_unoccluded(std::span<const std::uint8_t> wanted) override {
    keep_unoccluded_ = wanted;
    return true;
  }
  bool add_unoccluded(std::span<double> out) const override;

  // Entries offered to the coverage arena by the last compute(), summed over faces (for benchmarks): every
  // covered pixel of every clipped receiver, including full entries kept inline and entries the arena refused.
  std::size_t last_entries() const;

 private:
  static constexpr int kTasks = kFaceTasks;
  struct FaceBuffers {
    std::unique_ptr<AreaRasterizer> raster;  // set to each task's width x height viewport in turn
    StagedCoverageArena arena;
    std::vector<Vec3> local, scratch, clipped;  // a receiver in local coordinates; clipping buffers
    std::vector<Vec2> projected;
    detail::OrderBuffers order;
  };
  // One task of a shot: every candidate, or for a subset (`tiles`: PreparedReceivers::subset_tiles) only those
  // whose box meets its tiles.
  void shoot_task(int task, const ReceiverView& receivers, std::span<const std::uint32_t> candidates,
                  const TileMask* tiles, std::size_t max_vertices, FaceBuffers& buffers, std::span<double> sums,
                  UnoccludedList& unoccluded);

  HemicubeGeometry geometry_;
  // Delta form factors of the top face [0] and of the side faces [1] in the arena's column-major order (pixel
  // (x, y) at x * height + y).
  std::array<std::vector<double>, 2> column_weight_;
  PreparedReceivers prepared_;
  Vec3 eye_{0.0};  // the current shot's shooting point (the plane order of overfilled layers)
  std::array<FaceTask, kTasks> tasks_;
  TaskSums sums_;
  std::array<UnoccludedList, kTasks> task_unoccluded_;
  std::span<const std::uint8_t> keep_unoccluded_;
  std::array<std::size_t, kTasks> task_entries_{};
  tbb::enumerable_thread_specific<FaceBuffers> buffers_;
};

}  // namespace aarad::formfactor
