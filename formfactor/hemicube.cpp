// The classical hemicube (Cohen and Greenberg 1985): point sampling, z-buffer and item buffer per face.
#include "aarad/formfactor/hemicube.h"

#include "aarad/formfactor/coverage_list.h"

#include <tbb/parallel_for.h>

#include <limits>

namespace aarad::formfactor {

namespace {
constexpr std::uint32_t kNoItem = std::numeric_limits<std::uint32_t>::max();
}

HemicubeBackend::HemicubeBackend(int resolution) : geometry_(resolution) {}

void HemicubeBackend::shoot_task(const FaceTask& task, std::span<const std::uint32_t> candidates,
                                 std::span<const std::uint32_t> surfaces, const TileMask* tiles,
                                 std::size_t max_vertices, FaceBuffers& b, std::span<double> sums,
                                 UnoccludedList& unoccluded) const {
  const HemicubeFace face = task.face;
  // The buffers hold the task's columns [task.x0, task.x1) of the face, row-major.
  const int face_width = geometry_.width(face), width = task.x1 - task.x0, height = geometry_.height(face);
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const double half = 0.5 * geometry_.resolution();
  b.local.resize(max_vertices);
  b.scratch.resize(clipped_capacity(max_vertices));
  b.clipped.resize(clipped_capacity(max_vertices));
  b.projected.resize(clipped_capacity(max_vertices));
  b.crossings.resize(clipped_capacity(max_vertices));
  auto sample_y = [this, face](int row) { return geometry_.sample_y(face, row); };
  const std::span<const double> delta = geometry_.delta(face);
  unoccluded.clear();
  // Below N = 4 the top face's quarter tasks have no columns (face_tasks): nothing to sample, and the row loop's
  // &b.item[0] of an empty buffer was undefined behaviour (UBSan).
  if (width == 0) return;

  // Receiver i clipped and projected (face pixel coordinates) into b.projected, with its box; 0 vertices when it is
  // degenerate or no sample x + 1/2 of the task's columns lies in [x_min, x_max).
  ProjectedBox box;
  const auto place = [&](std::uint32_t i) -> std::size_t {
    const std::size_t m = clip_to_face(prepared_.local_polygon(i, b.local), face, prepared_.outside_mask(i), b.scratch,
                                       b.clipped);
    if (m == 0 || !project_clipped(face, std::span<const Vec3>(b.clipped.data(), m), half, 0.0, b.projected, box) ||
        box.x_max <= task.x0 + 0.5 || box.x_min > task.x1 - 0.5)
      return 0;
    return m;
  };
  // A re-shot subset: only the pixels its receivers may cover matter (tiles in the task's columns).
  const bool masked = tiles != nullptr;
  if (masked && tiles->empty()) return;
  b.inverse_depth.assign(pixels, 0.0);
  b.item.assign(pixels, kNoItem);

  for (const std::uint32_t i : candidates) {
    const std::size_t m = place(i);
    if (m == 0 || (masked && !tiles->overlaps(box.x_min - task.x0, box.x_max - task.x0, box.y_min, box.y_max)))
      continue;
    const InverseDepth depth = inverse_depth(face, prepared_.local_plane(i), half);
    const std::uint32_t item = i;
    const auto sample = [&](int x, int y) {
      // 1 / depth of the receiver's plane at the sample, kept within the polygon's range.
      double inverse_depth = depth.at(x + 0.5, sample_y(y));
      if (!(inverse_depth >= box.lo)) inverse_depth = box.lo;
      if (inverse_depth > box.hi) inverse_depth = box.hi;
      const std::size_t p = static_cast<std::size_t>(y) * width + (x - task.x0);
      // Nearer, or at the same key and in front by the rule of equal keys (coverage_list.h): which of two surfaces
      // on one another in one plane a sample shows does not depend on the receivers' order.
      if (inverse_depth > b.inverse_depth[p] ||
          (inverse_depth == b.inverse_depth[p] && b.item[p] != kNoItem &&
           in_front_at_equal_key(surfaces[i], surfaces[b.item[p]]))) {
        b.inverse_depth[p] = inverse_depth;
        b.item[p] = item;
      }
    };
    const std::span<const Vec2> polygon(b.projected.data(), m);
    double seen = 0.0;  // with keep_unoccluded: the delta form factors of the receiver's samples, in front or not
    if (i < keep_unoccluded_.size() && keep_unoccluded_[i] != 0) {
      sample_polygon(polygon, task.x0, task.x1, height, sample_y, b.crossings, [&](int x, int y) {
        sample(x, y);
        seen += delta[static_cast<std::size_t>(y) * face_width + x];
      });
    } else {
      sample_polygon(polygon, task.x0, task.x1, height, sample_y, b.crossings, sample);
    }
    if (seen > 0.0) unoccluded.emplace_back(item, seen);
  }
  for (int y = 0; y < height; ++y) {
    const std::uint32_t* item = &b.item[static_cast<std::size_t>(y) * width];
    const double* row = &delta[static_cast<std::size_t>(y) * face_width + task.x0];
    for (int x = 0; x < width; ++x)
      if (item[x] != kNoItem) sums[item[x]] += row[x];
  }
}

void HemicubeBackend::compute(const Shooter& shooter, const ReceiverView& receivers,
                              std::span<const std::uint32_t> subset, std::span<double> out) {
  check_shot(shooter, receivers, subset, out);
  prepared_.prepare_subset(shooter, receivers, subset, geometry_);
  const std::size_t max_vertices = std::max<std::size_t>(3, receivers.max_polygon_size());
  const std::array<FaceTask, kFaceTasks> tasks = face_tasks(geometry_.resolution());
  sums_.start(tasks, geometry_.resolution(), prepared_, receivers.size());
  run_face_tasks(sums_.loads(), [&](int t) {
    shoot_task(tasks[static_cast<std::size_t>(t)], sums_.receivers(t), receivers.surfaces(),
               subset.empty() ? nullptr : &prepared_.subset_tiles(t), max_vertices, buffers_.local(), sums_.sums(t),
               task_unoccluded_[static_cast<std::size_t>(t)]);
  });
  sums_.combine(subset, out);
}

bool HemicubeBackend::add_unoccluded(std::span<double> out) const {
  add_unoccluded_lists(task_unoccluded_, out);
  return true;
}

}  // namespace aarad::formfactor
