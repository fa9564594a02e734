#include "formfactor/receiver_view.h"

namespace aarad::formfactor {

void ReceiverView::clear() {
  vertices_.clear();
  offsets_.assign(1, 0);
  planes_.clear();
  surfaces_.clear();
  patches_.clear();
}

void ReceiverView::reserve(std::size_t receivers, std::size_t vertices) {
  vertices_.reserve(vertices);
  offsets_.reserve(receivers + 1);
  planes_.reserve(receivers);
  surfaces_.reserve(receivers);
  patches_.reserve(receivers);
}

std::uint32_t ReceiverView::add(std::span<const Vec3> polygon, const Plane& plane, std::uint32_t surface,
                                std::uint32_t patch) {
  vertices_.insert(vertices_.end(), polygon.begin(), polygon.end());
  offsets_.push_back(static_cast<std::uint32_t>(vertices_.size()));
  planes_.push_back(plane);
  surfaces_.push_back(surface);
  patches_.push_back(patch);
  return static_cast<std::uint32_t>(planes_.size() - 1);
}

}  // namespace aarad::formfactor
