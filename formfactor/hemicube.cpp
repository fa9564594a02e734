// The classical hemicube (Cohen and Greenberg 1985): point sampling, z-buffer and item buffer per face.
#include "formfactor/hemicube.h"

#include <tbb/parallel_for.h>

#include <limits>

namespace aarad::formfactor {

namespace {
constexpr std::uint32_t kNoItem = std::numeric_limits<std::uint32_t>::max();
}

HemicubeBackend::HemicubeBackend(int resolution) : geometry_(resolution) {}

void HemicubeBackend::shoot_face(HemicubeFace face, const ReceiverView& receivers, std::size_t max_vertices,
                                 FaceBuffers& b, std::vector<double>& sums) const {
  const int width = geometry_.width(face), height = geometry_.height(face);
  const std::size_t pixels = geometry_.pixels(face);
  const double half = 0.5 * geometry_.resolution();
  b.inverse_depth.assign(pixels, 0.0);
  b.item.assign(pixels, kNoItem);
  b.scratch.resize(clipped_capacity(max_vertices));
  b.clipped.resize(clipped_capacity(max_vertices));
  b.projected.resize(clipped_capacity(max_vertices));
  b.crossings.resize(clipped_capacity(max_vertices));
  const auto bit = static_cast<std::uint8_t>(1u << static_cast<int>(face));
  auto sample_y = [this, face](int row) { return geometry_.sample_y(face, row); };

  for (std::size_t i = 0; i < receivers.size(); ++i) {
    if ((prepared_.face_mask(i) & bit) == 0) continue;
    const std::size_t m = clip_to_face(prepared_.local_polygon(i), face, prepared_.outside_mask(i), b.scratch, b.clipped);
    if (m == 0) continue;
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    bool degenerate = false;
    for (std::size_t k = 0; k < m; ++k) {
      const Vec3& f = b.clipped[k];
      if (!(f.x > 0.0)) {
        degenerate = true;
        break;
      }
      b.projected[k] = project_to_pixels(face, f, half);
      lo = std::min(lo, 1.0 / f.x);
      hi = std::max(hi, 1.0 / f.x);
    }
    if (degenerate) continue;
    const InverseDepth depth = inverse_depth(face, prepared_.local_plane(i), half);
    const auto item = static_cast<std::uint32_t>(i);
    sample_polygon(std::span<const Vec2>(b.projected.data(), m), width, height, sample_y, b.crossings,
                   [&](int x, int y) {
                     // 1 / depth of the receiver's plane at the sample, kept within the polygon's range.
                     double z = depth.at(x + 0.5, sample_y(y));
                     if (!(z >= lo)) z = lo;
                     if (z > hi) z = hi;
                     const std::size_t p = static_cast<std::size_t>(y) * width + x;
                     if (z > b.inverse_depth[p]) {
                       b.inverse_depth[p] = z;
                       b.item[p] = item;
                     }
                   });
  }
  const std::span<const double> delta = geometry_.delta(face);
  for (std::size_t p = 0; p < pixels; ++p)
    if (b.item[p] != kNoItem) sums[b.item[p]] += delta[p];
}

void HemicubeBackend::compute(const Shooter& shooter, const ReceiverView& receivers,
                              std::span<const std::uint32_t> subset, std::span<double> out) {
  prepared_.prepare(shooter, receivers);
  std::size_t max_vertices = 3;
  for (std::size_t i = 0; i < receivers.size(); ++i) max_vertices = std::max(max_vertices, receivers.polygon(i).size());
  for (auto& sums : face_sums_) sums.assign(receivers.size(), 0.0);
  tbb::parallel_for(0, kHemicubeFaces, [&](int f) {
    shoot_face(static_cast<HemicubeFace>(f), receivers, max_vertices, buffers_.local(),
               face_sums_[static_cast<std::size_t>(f)]);
  });
  combine_face_sums(face_sums_, subset, out);
}

}  // namespace aarad::formfactor
