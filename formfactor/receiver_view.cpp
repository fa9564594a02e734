#include "aarad/formfactor/receiver_view.h"

#include "aarad/core/error.h"
#include "aarad/core/polygon.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

namespace aarad::formfactor {

std::uint64_t ReceiverView::next_revision() {
  static std::atomic<std::uint64_t> last{0};
  return ++last;
}

void ReceiverView::clear() {
  revision_ = next_revision();
  refines_ = 0;
  vertices_.clear();
  offsets_.assign(1, 0);
  planes_.clear();
  surfaces_.clear();
  patches_.clear();
  points_.clear();
  corner_points_.clear();
  point_of_key_.clear();
  max_polygon_size_ = 0;
}

namespace {

// At least n, and at least twice the old capacity when it must grow: the solver rebuilds a view after every
// round of splits, a little larger each time, and exact reservations would move every array (into memory the
// kernel must fault in afresh) at every rebuild.
template <class T>
void reserve_at_least(std::vector<T>& v, std::size_t n) {
  if (v.capacity() < n) v.reserve(std::max(n, 2 * v.capacity()));
}

template <class T>
void copy_into(std::vector<T>& to, const std::vector<T>& from) {
  reserve_at_least(to, from.size());
  to.assign(from.begin(), from.end());
}

}  // namespace

void ReceiverView::reserve(std::size_t receivers, std::size_t vertices) {
  reserve_at_least(vertices_, vertices);
  reserve_at_least(offsets_, receivers + 1);
  reserve_at_least(planes_, receivers);
  reserve_at_least(surfaces_, receivers);
  reserve_at_least(patches_, receivers);
  reserve_at_least(points_, vertices);
  reserve_at_least(corner_points_, vertices);
}

void ReceiverView::start_from_points_of(const ReceiverView& other) {
  clear();
  copy_into(points_, other.points_);
  copy_into(point_of_key_, other.point_of_key_);
}

void ReceiverView::append_from(const ReceiverView& other, std::uint32_t first, std::uint32_t last) {
  if (first >= last) return;
  revision_ = next_revision();
  const std::uint32_t begin = other.offsets_[first], end = other.offsets_[last];
  const std::uint32_t base = offsets_.back();
  vertices_.insert(vertices_.end(), other.vertices_.begin() + begin, other.vertices_.begin() + end);
  corner_points_.insert(corner_points_.end(), other.corner_points_.begin() + begin,
                        other.corner_points_.begin() + end);
  for (std::uint32_t i = first; i < last; ++i) {
    const std::uint32_t next = other.offsets_[i + 1];
    offsets_.push_back(base + (next - begin));
    max_polygon_size_ = std::max<std::size_t>(max_polygon_size_, next - other.offsets_[i]);
  }
  planes_.insert(planes_.end(), other.planes_.begin() + first, other.planes_.begin() + last);
  surfaces_.insert(surfaces_.end(), other.surfaces_.begin() + first, other.surfaces_.begin() + last);
  patches_.insert(patches_.end(), other.patches_.begin() + first, other.patches_.begin() + last);
}

// A corner or plane that is not finite (a polygon 1e150 across, whose plane overflowed to nan) made the exact
// predicates of a shot abort the process (GMP raises SIGFPE on nan): refused here, with a message.
// A polygon wound the other way round its plane's normal gets a negative factor from the analytic back end and
// nothing from the hemicubes, which take it for a back face: refused. Only a polygon clearly facing away is (its
// vector area more than half its length against the normal); a sliver whose vector area is a rounding error passes.
void ReceiverView::check_receiver(std::span<const Vec3> polygon, const Plane& plane) const {
  const auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  if (!std::all_of(polygon.begin(), polygon.end(), finite) || !finite(plane.normal) || !std::isfinite(plane.d))
    throw Error("ReceiverView::add: receiver " + std::to_string(size()) +
                " has a corner or plane that is not finite (nan or inf); give finite corners and plane");
  Vec3 vector = vector_area(polygon);
  if (!finite(vector)) {
    // Overflowed (a polygon 1e200 across: nan, which passed the test below): its vector area's direction from the
    // polygon moved to its first corner and scaled by a power of two near its extent.
    double extent = 0.0;
    for (const Vec3& p : polygon) {
      const Vec3 d = glm::abs(p - polygon.front());
      extent = std::max({extent, d.x, d.y, d.z});
    }
    if (!std::isfinite(extent))
      throw Error("ReceiverView::add: receiver " + std::to_string(size()) +
                  " is too large for double precision (its corners' differences overflow); scale the scene down");
    const double scale = std::ldexp(1.0, -std::ilogb(extent));  // extent overflowed: far from subnormal
    vector = Vec3(0.0);
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
      vector += glm::cross((polygon[k] - polygon.front()) * scale, (polygon[k + 1] - polygon.front()) * scale);
  }
  if (glm::dot(vector, plane.normal) < -0.5 * glm::length(vector))
    throw Error("ReceiverView::add: receiver " + std::to_string(size()) +
                " runs clockwise seen from the side its plane's normal points to; reverse its corners or its plane");
}

std::uint32_t ReceiverView::add(std::span<const Vec3> polygon, const Plane& plane, std::uint32_t surface,
                                std::uint32_t patch) {
  check_receiver(polygon, plane);
  for (const Vec3& p : polygon) {
    corner_points_.push_back(static_cast<std::uint32_t>(points_.size()));
    points_.push_back(p);
  }
  return append(polygon, plane, surface, patch);
}

std::uint32_t ReceiverView::add(std::span<const Vec3> polygon, std::span<const std::uint32_t> keys, const Plane& plane,
                                std::uint32_t surface, std::uint32_t patch) {
  if (keys.size() != polygon.size())
    throw Error("ReceiverView::add: " + std::to_string(keys.size()) + " keys for " + std::to_string(polygon.size()) +
                " corners");
  check_receiver(polygon, plane);
  // On a conflict, the view is left as it was: the keys bound and the points added by this call are taken back.
  const std::size_t old_points = points_.size(), old_corners = corner_points_.size();
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const std::size_t key = keys[k];
    if (key >= point_of_key_.size()) point_of_key_.resize(std::max(key + 1, 2 * point_of_key_.size()), kNoPoint);
    std::uint32_t& point = point_of_key_[key];
    if (point == kNoPoint) {
      point = static_cast<std::uint32_t>(points_.size());
      points_.push_back(polygon[k]);
    } else if (points_[point] != polygon[k]) {
      for (std::size_t j = 0; j < k; ++j)
        if (point_of_key_[keys[j]] >= old_points) point_of_key_[keys[j]] = kNoPoint;
      points_.resize(old_points);
      corner_points_.resize(old_corners);
      throw Error("ReceiverView::add: key " + std::to_string(key) + " names two different points");
    }
    corner_points_.push_back(point);
  }
  return append(polygon, plane, surface, patch);
}

std::uint32_t ReceiverView::append(std::span<const Vec3> polygon, const Plane& plane, std::uint32_t surface,
                                   std::uint32_t patch) {
  revision_ = next_revision();
  vertices_.insert(vertices_.end(), polygon.begin(), polygon.end());
  max_polygon_size_ = std::max(max_polygon_size_, polygon.size());
  offsets_.push_back(static_cast<std::uint32_t>(vertices_.size()));
  planes_.push_back(plane);
  surfaces_.push_back(surface);
  patches_.push_back(patch);
  return static_cast<std::uint32_t>(planes_.size() - 1);
}

}  // namespace aarad::formfactor
