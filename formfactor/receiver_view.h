// The flat, read-only view of receivers that form-factor back ends see. The solver builds it from the
// patch/element hierarchy; tests build it from plain polygons. formfactor/ never includes mesh/.
#pragma once

#include "core/math.h"

#include <cstdint>
#include <span>
#include <vector>

namespace aarad::formfactor {

// Receiver i is the convex or concave planar polygon
//   vertices[offsets[i]] .. vertices[offsets[i + 1] - 1],
// counter-clockwise seen from its front side (the side planes[i].normal points to).
// surface[i] is its physical-surface id (pieces of one surface never occlude each other);
// patch[i] is its parent patch id (back-face culling is decided per patch, as the paper does).
class ReceiverView {
 public:
  void clear();
  void reserve(std::size_t receivers, std::size_t vertices);
  // Appends a receiver and returns its index.
  std::uint32_t add(std::span<const Vec3> polygon, const Plane& plane, std::uint32_t surface, std::uint32_t patch);

  std::size_t size() const { return planes_.size(); }
  std::span<const Vec3> polygon(std::size_t i) const {
    return {vertices_.data() + offsets_[i], vertices_.data() + offsets_[i + 1]};
  }
  const Plane& plane(std::size_t i) const { return planes_[i]; }
  std::uint32_t surface(std::size_t i) const { return surfaces_[i]; }
  std::uint32_t patch(std::size_t i) const { return patches_[i]; }

  std::span<const Vec3> vertices() const { return vertices_; }
  std::span<const std::uint32_t> offsets() const { return offsets_; }
  std::span<const Plane> planes() const { return planes_; }
  std::span<const std::uint32_t> surfaces() const { return surfaces_; }
  std::span<const std::uint32_t> patches() const { return patches_; }

 private:
  std::vector<Vec3> vertices_;
  std::vector<std::uint32_t> offsets_{0};
  std::vector<Plane> planes_;
  std::vector<std::uint32_t> surfaces_;
  std::vector<std::uint32_t> patches_;
};

}  // namespace aarad::formfactor
