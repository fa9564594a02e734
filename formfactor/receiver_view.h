// The flat, read-only view of receivers that form-factor back ends see. The solver builds it from the
// patch/element hierarchy; tests build it from plain polygons. formfactor/ never includes mesh/.
#pragma once

#include "aarad/core/math.h"

#include <cstdint>
#include <span>
#include <vector>

namespace aarad::formfactor {

// Receiver i is the convex or concave planar polygon
//   vertices[offsets[i]] .. vertices[offsets[i + 1] - 1],
// counter-clockwise seen from its front side (the side planes[i].normal points to), of any number of vertices;
// a vertex may lie on the segment between its neighbours (the solver's receivers carry the hanging vertices of their
// leaves' edges, refine/receiver_cache.h).
// surface[i] is its physical-surface id (pieces of one surface never occlude each other);
// patch[i] is its parent patch id (back-face culling is decided per patch, as the paper does): receivers that share
// a patch id must lie in one plane, facing one way, as the pieces of one patch do, since a back end decides them all
// on the plane of the patch's first receiver (a receiver facing the shooter under a patch id whose first receiver
// faces away gets 0, unchecked). Polygons that are not pieces of one patch each take a patch id of their own.
//
// Shared points. Every corner also names a point of points(): corners of neighbouring receivers that are the
// same vertex name the same point, so a back end can transform each point once per shot instead of once per
// corner (a vertex of a grid of elements is a corner of four of them). add() without keys gives every corner
// a point of its own.
class ReceiverView {
 public:
  void clear();
  void reserve(std::size_t receivers, std::size_t vertices);
  // Appends a receiver and returns its index. `plane` is the polygon's own: plane_of(polygon) (core/polygon.h)
  // gives it, its normal on the side from which the polygon runs counter-clockwise. Throws aarad::Error for a
  // polygon wound clockwise round the plane's normal, or with a corner or plane that is not finite (and then leaves
  // the view as it was).
  std::uint32_t add(std::span<const Vec3> polygon, const Plane& plane, std::uint32_t surface, std::uint32_t patch);
  // The same, with a caller's key per corner (keys[k] for polygon[k]): corners with equal keys share one point.
  // Equal keys must come with equal coordinates (checked: throws aarad::Error otherwise, and leaves the view as it
  // was). Keys are small integers, such as vertex indices of a mesh: the view keeps a table as long as the largest
  // key.
  std::uint32_t add(std::span<const Vec3> polygon, std::span<const std::uint32_t> keys, const Plane& plane,
                    std::uint32_t surface, std::uint32_t patch);

  // Empties the view but keeps the points (and keys) of `other`, so that receivers of `other` can be copied
  // with append_from() and new ones added with keys against the same points.
  void start_from_points_of(const ReceiverView& other);
  // Appends receivers [first, last) of `other`, which must be the view this one started from, in order.
  void append_from(const ReceiverView& other, std::uint32_t first, std::uint32_t last);

  std::size_t size() const { return planes_.size(); }
  // Names the view's contents: it changes whenever receivers are added or cleared, and no two views that were ever
  // filled differently share one (a copy keeps its original's). What is derived from a view and kept between shots
  // is keyed on it with size() (BackFaceCulling's deciding receivers, the near-field correction's lists).
  std::uint64_t revision() const { return revision_; }
  // Says that this view refines the view of revision `revision`: every receiver of a patch lies in the convex hull
  // of that patch's points there, and every patch that had receivers there has some here (the solver's views after
  // splits: a leaf's pieces tile it, a hanging vertex lies on an edge). What a back end derived per patch from that
  // view's points then still holds (PreparedReceivers' patch balls and boxes). clear() forgets it.
  void mark_refinement_of(std::uint64_t revision) { refines_ = revision; }
  // The revision this view refines, 0 when none.
  std::uint64_t refines() const { return refines_; }
  // The most corners of any receiver (0 when empty).
  std::size_t max_polygon_size() const { return max_polygon_size_; }
  std::span<const Vec3> polygon(std::size_t i) const {
    return {vertices_.data() + offsets_[i], vertices_.data() + offsets_[i + 1]};
  }
  const Plane& plane(std::size_t i) const { return planes_[i]; }
  std::uint32_t surface(std::size_t i) const { return surfaces_[i]; }
  std::uint32_t patch(std::size_t i) const { return patches_[i]; }

  std::span<const Vec3> vertices() const { return vertices_; }
  std::span<const std::uint32_t> offsets() const { return offsets_; }
  // The distinct points, and for every corner (index into vertices()) the point it is.
  std::span<const Vec3> points() const { return points_; }
  std::span<const std::uint32_t> corner_points() const { return corner_points_; }
  std::span<const Plane> planes() const { return planes_; }
  std::span<const std::uint32_t> surfaces() const { return surfaces_; }
  std::span<const std::uint32_t> patches() const { return patches_; }

 private:
  void check_receiver(std::span<const Vec3> polygon, const Plane& plane) const;
  std::uint32_t append(std::span<const Vec3> polygon, const Plane& plane, std::uint32_t surface, std::uint32_t patch);

  std::vector<Vec3> vertices_;
  std::vector<std::uint32_t> offsets_{0};
  std::vector<Plane> planes_;
  std::vector<std::uint32_t> surfaces_;
  std::vector<std::uint32_t> patches_;
  std::vector<Vec3> points_;
  std::vector<std::uint32_t> corner_points_;  // per corner: index into points_
  std::vector<std::uint32_t> point_of_key_;  // per caller key: index into points_, or kNoPoint
  std::size_t max_polygon_size_ = 0;
  std::uint64_t revision_ = next_revision();
  std::uint64_t refines_ = 0;
  static constexpr std::uint32_t kNoPoint = 0xFFFFFFFFu;
  // A revision no view has had yet (thread-safe).
  static std::uint64_t next_revision();
};

}  // namespace aarad::formfactor
