// The near-field correction of a shot (see near_field.h): Wallace, Elmquist and Haines 1989, section 3, for the
// receiver's side; Baum, Rushmeier and Winget 1989, eq. 9, for the point-to-polygon factors.
#include "aarad/refine/near_field.h"

#include "aarad/core/polygon.h"
#include "aarad/core/quadrature.h"
#include "aarad/formfactor/analytic.h"
#include "aarad/formfactor/hemicube_geometry.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace aarad::refine {
namespace {

// A receiver is corrected when its radius is at most this times the shooting patch's size: its radius, or its width
// when that is smaller (patch_extent).
constexpr double kSmaller = 0.75;
// A receiver too large to be corrected from its centroid is corrected from points over the patch: 2 x 2 Gauss points
// in each of 1, 2 x 2, 4 x 4 ... cells, up to kPatchLevels rules, until two rules in a row agree to kPatchAgree.
// A back end that shot from kFinePoints points or more has averaged over the patch already, finer than that and
// with what each point sees: its factors of large receivers stand.
constexpr int kPatchLevels = 4;
constexpr std::size_t kFinePoints = 64;
// A small receiver facing the patch close by gets the mean over it of the exact factor to the patch: from its centroid,
// then by 2 x 2 Gauss points in 1, 4, 16 and 64 cells, until two rules in a row agree to kPatchAgree, or to
// kReceiverFloor (point factors are at most 1).
constexpr int kReceiverLevels = 4;
constexpr double kFacing = 0.5;  // cos 60 degrees: a receiver facing the patch within 60 degrees
constexpr double kReceiverFloor = 1e-4;
constexpr double kPatchAgree = 0.01;
// The far receivers of a shot are scaled by at most this factor (or its inverse) to keep the shot's total.
constexpr double kFarChange = 1.25;

// The unoccluded factor from the differential area at `point` with unit normal `normal` to the part of `polygon`
// in front of it. `local` and `clipped` are scratch.
double unoccluded_factor(const Vec3& point, const Vec3& normal, std::span<const Vec3> polygon,
                         std::vector<Vec3>& local, std::vector<Vec3>& clipped) {
  const formfactor::Shooter frame = formfactor::Shooter::from_normal(point, normal);
  local.resize(polygon.size());
  clipped.resize(formfactor::plane_clipped_capacity(polygon.size()));
  bool behind = false, in_front = false;
  for (std::size_t v = 0; v < polygon.size(); ++v) {
    local[v] = formfactor::to_local(frame, polygon[v]);
    behind |= local[v].z < 0.0;
    in_front |= local[v].z > 0.0;
  }
  if (!in_front) return 0.0;
  std::span<const Vec3> visible = local;
  if (behind) visible = std::span<const Vec3>(clipped.data(), formfactor::clip_to_front(local, clipped));
  return std::max(0.0, formfactor::polygon_form_factor(Vec3(0.0), Vec3(0.0, 0.0, 1.0), visible));
}

// The part of `polygon` in front of the plane through `origin` with unit normal `normal`, clipped as the back ends
// clip (formfactor::clip_to_front, in that plane's frame), back in scene coordinates into `out`; empty when less
// than a polygon is left. `local` and `clipped` are scratch.
void clip_to_front_of(std::span<const Vec3> polygon, const Vec3& origin, const Vec3& normal, std::vector<Vec3>& local,
                      std::vector<Vec3>& clipped, std::vector<Vec3>& out) {
  const formfactor::Shooter frame = formfactor::Shooter::from_normal(origin, normal);
  local.resize(polygon.size());
  clipped.resize(formfactor::plane_clipped_capacity(polygon.size()));
  for (std::size_t v = 0; v < polygon.size(); ++v) local[v] = formfactor::to_local(frame, polygon[v]);
  const std::size_t m = formfactor::clip_to_front(local, clipped);
  out.clear();
  if (m < 3) return;
  for (std::size_t v = 0; v < m; ++v) {
    const Vec3& q = clipped[v];
    out.push_back(frame.centre + q.x * frame.tangent + q.y * frame.bitangent + q.z * frame.normal);
  }
}

// The size a receiver must be clearly below for its centroid to stand for it: the patch's radius, or its width (the
// smallest extent across it, for a convex polygon the least over its edges of the largest distance of a corner from
// the edge's line) when that is smaller. A receiver next to a sliver of width w sees the sliver's factor vary over a
// distance of about w, not over the sliver's radius: from the centroids of wall elements 20 times the width of a lamp
// strip 0.003 wide along their foot, the strip's factor was far below its mean over them, and the wall got half the
// strip's light (test NearField.ReceiversNextToASliverAreSmallerThanItsWidth). Squares, rectangles up to sides 1 : 1.7
// and equilateral triangles are wider than their radius.
double patch_extent(std::span<const Vec3> polygon, double radius) {
  double width = radius;
  for (std::size_t v = 0; v < polygon.size(); ++v) {
    const Vec3 edge = polygon[(v + 1) % polygon.size()] - polygon[v];
    const double length = glm::length(edge);
    if (!(length > 0.0)) continue;
    double farthest = 0.0;
    for (const Vec3& corner : polygon)
      farthest = std::max(farthest, glm::length(glm::cross(edge, corner - polygon[v])) / length);
    width = std::min(width, farthest);
  }
  return width;
}

// Ever finer rules, rule(first), rule(first + 1) ... up to level levels - 1, after `coarse`, the value of the
// coarsest: the first that agrees with the one before it to kPatchAgree (plus `floor`), or the finest.
template <class Rule>
double refine_until_agreed(double coarse, int first, int levels, double floor, Rule&& rule) {
  for (int level = first; level < levels; ++level) {
    const double fine = rule(level);
    if (std::abs(fine - coarse) <= kPatchAgree * fine + floor) return fine;
    coarse = fine;
  }
  return coarse;
}

}  // namespace

double NearFieldCorrection::receiver_average(const NearFieldShooter& shooter, std::span<const Vec3> part,
                                             const Vec3& centroid, const Vec3& normal, Scratch& scratch) {
  const auto rule = [&](int level) {
    polygon_quadrature(part, 2, 1 << level, scratch.receiver_points);
    double sum = 0.0;
    for (const AreaSample& point : scratch.receiver_points)
      sum += point.weight * unoccluded_factor(point.position, normal, shooter.polygon, scratch.local, scratch.clipped);
    return sum;
  };
  const double from_centroid = unoccluded_factor(centroid, normal, shooter.polygon, scratch.local, scratch.clipped);
  return refine_until_agreed(from_centroid, 0, kReceiverLevels, kReceiverFloor, rule);
}

double NearFieldCorrection::patch_average(const NearFieldShooter& shooter, std::span<const Vec3> polygon,
                                          Scratch& scratch) const {
  const auto rule = [&](int level) {
    double sum = 0.0;
    for (const AreaSample& point : patch_points_[static_cast<std::size_t>(level)])
      sum += point.weight * unoccluded_factor(point.position, shooter.normal, polygon, scratch.local, scratch.clipped);
    return sum;
  };
  return refine_until_agreed(rule(0), 1, kPatchLevels, 0.0, rule);
}

void NearFieldCorrection::set_patches(std::span<const Vec3> centroids, std::span<const double> radii) {
  patch_centroid_.assign(centroids.begin(), centroids.end());
  patch_radius_.assign(radii.begin(), radii.end());
  near_patch_.assign(patch_centroid_.size(), 0);
  near_patches_.clear();
  marked_radius_ = -1.0;
  listed_revision_ = 0;
  indexed_revision_ = 0;
}

double NearFieldCorrection::mark_near_patches(const NearFieldShooter& shooter) {
  double radius = 0.0;
  for (const Vec3& corner : shooter.polygon) radius = std::max(radius, glm::length(corner - shooter.centroid));
  if (radius == marked_radius_ && shooter.centroid == marked_centroid_) return radius;  // marked already
  marked_centroid_ = shooter.centroid;
  marked_radius_ = radius;
  listed_revision_ = 0;
  // Every point of a patch lies within its radius of its centroid.
  const double near_distance = reach_ * radius;
  for (std::uint32_t p : near_patches_) near_patch_[p] = 0;
  near_patches_.clear();
  for (std::uint32_t p = 0; p < patch_centroid_.size(); ++p) {
    if (patch_radius_[p] < 0.0) continue;  // no patch has this id
    const double within = near_distance + patch_radius_[p];
    const Vec3 d = patch_centroid_[p] - shooter.centroid;
    if (glm::dot(d, d) <= within * within) {
      near_patch_[p] = 1;
      near_patches_.push_back(p);
    }
  }
  return radius;
}

void NearFieldCorrection::index_patches(const formfactor::ReceiverView& receivers) {
  if (receivers.revision() == indexed_revision_ && receivers.size() == indexed_size_) return;
  // A counting sort of the receivers by patch id (ids past the table of patches are never near).
  patch_start_.assign(patch_centroid_.size() + 1, 0);
  for (std::uint32_t i = 0; i < receivers.size(); ++i)
    if (receivers.patch(i) < patch_centroid_.size()) ++patch_start_[receivers.patch(i) + 1];
  for (std::size_t p = 1; p < patch_start_.size(); ++p) patch_start_[p] += patch_start_[p - 1];
  by_patch_.resize(patch_start_.back());
  std::vector<std::uint32_t> next(patch_start_.begin(), patch_start_.end() - 1);
  for (std::uint32_t i = 0; i < receivers.size(); ++i)
    if (receivers.patch(i) < patch_centroid_.size()) by_patch_[next[receivers.patch(i)]++] = i;
  indexed_revision_ = receivers.revision();
  indexed_size_ = receivers.size();
}

std::span<const std::uint8_t> NearFieldCorrection::candidates(const NearFieldShooter& shooter,
                                                              const formfactor::ReceiverView& receivers) {
  candidate_.assign(receivers.size(), 0);
  if (!(reach_ > 0.0)) return candidate_;
  mark_near_patches(shooter);
  listed_.clear();
  if (patch_centroid_.empty()) {  // no table of patches: every receiver is a candidate
    for (std::uint32_t i = 0; i < receivers.size(); ++i) listed_.push_back(i);
  } else {
    // The receivers of the near patches, from the view's receivers grouped by patch, in receiver order.
    index_patches(receivers);
    for (const std::uint32_t p : near_patches_) {
      if (p + 1 >= patch_start_.size()) continue;  // no receiver has this patch
      listed_.insert(listed_.end(), by_patch_.begin() + patch_start_[p], by_patch_.begin() + patch_start_[p + 1]);
    }
    std::sort(listed_.begin(), listed_.end());
  }
  for (const std::uint32_t i : listed_) candidate_[i] = 1;
  listed_revision_ = receivers.revision();
  listed_size_ = receivers.size();
  return candidate_;
}

void NearFieldCorrection::apply(const NearFieldShooter& shooter, const formfactor::ReceiverView& receivers,
                                std::span<const std::uint32_t> subset, std::span<double> ff) {
  shape(shooter, receivers, subset, ff);
  write(subset, ff);
}

// Receiver i of a shot's near field as shape() takes it: left as the back end gave it, shaped (its G), or to be
// shaped from the patch's side (the fraction seen, which patch_average then multiplies). Reads only the shot and
// the view, and writes only `scratch`: receivers are shaped in parallel.
NearFieldCorrection::Shaped NearFieldCorrection::shape_receiver(const NearFieldShooter& shooter,
                                                                 const formfactor::ReceiverView& receivers,
                                                                 std::uint32_t i, std::span<const double> ff,
                                                                 double near_squared, double size,
                                                                 Scratch& scratch) const {
  if (!(ff[i] > 0.0)) return {};  // hidden, culled or behind: nothing to shape
  if (!near_patch(receivers.patch(i))) return {};
  const std::span<const Vec3> polygon = receivers.polygon(i);
  const double area = aarad::area(polygon);
  const Vec3 centroid = aarad::centroid(polygon);
  const Vec3 d = centroid - shooter.centroid;
  if (!(glm::dot(d, d) < near_squared) || !(area > 0.0)) return {};
  // Only receivers clearly smaller than the patch, and than its width: for them the centroid stands for the whole
  // better than the patch's centroid stands for the patch.
  double receiver_radius = 0.0;
  for (const Vec3& corner : polygon) receiver_radius = std::max(receiver_radius, glm::length(corner - centroid));
  const bool small = receiver_radius <= kSmaller * size;
  if (!small && shooter.points.size() >= kFinePoints) return {};
  // What the back end saw of the receiver: its factor over the factor it would have had with nothing in front.
  double unoccluded = 0.0;
  if (!shooter.unoccluded.empty()) {
    unoccluded = shooter.unoccluded[i];
  } else {
    for (std::size_t p = 0; p < shooter.points.size(); ++p)
      unoccluded += shooter.weights[p] * unoccluded_factor(shooter.points[p], shooter.normal, polygon, scratch.local,
                                                           scratch.clipped);
  }
  const double seen = unoccluded > 0.0 ? std::min(1.0, ff[i] / unoccluded) : 1.0;
  // A receiver as large as the patch or larger: the patch's own points stand for it better than one point of
  // either, so the factor with nothing occluding is averaged over the patch (patch_average, once the rules are made).
  if (!small) return {Shaped::kFromPatch, seen};
  // A receiver crossing the patch's plane (a wall through a shelf's plane): only its part in front of the patch
  // sees it, and that part's centroid stands for it. The receiver's own centroid may lie behind the patch
  // (which it then does not see at all) or just in front of it, at the junction, where the factor is largest.
  double front_area = area;
  Vec3 front_centroid = centroid;
  bool crosses = false;
  for (const Vec3& corner : polygon)
    crosses |= glm::dot(shooter.normal, corner - shooter.centroid) < -1e-9 * receiver_radius;
  if (crosses) {
    clip_to_front_of(polygon, shooter.centroid, shooter.normal, scratch.local, scratch.clipped, scratch.front);
    front_area = scratch.front.empty() ? 0.0 : aarad::area(scratch.front);
    if (front_area > 0.0) front_centroid = aarad::centroid(scratch.front);
  }
  // A receiver facing the patch closer to its plane than its own radius sees the patch's edge, where one lies
  // across it, as a step of about that height's width: there its centroid stands for it badly (a plate leaf
  // 0.002 under a lamp, its centroid just outside the lamp, gets nothing), and the factor is averaged over it.
  // Elsewhere, at a junction too, the factor is smooth across the receiver and its centroid gives it.
  const Vec3& receiver_normal = receivers.plane(i).normal;
  const bool facing_close = glm::dot(receiver_normal, shooter.normal) < -kFacing &&
                            glm::dot(shooter.normal, front_centroid - shooter.centroid) < receiver_radius;
  double from_receiver = 0.0;
  if (front_area > 0.0) {
    from_receiver =
        facing_close
            ? receiver_average(shooter, crosses ? std::span<const Vec3>(scratch.front) : polygon, front_centroid,
                               receiver_normal, scratch)
            : unoccluded_factor(front_centroid, receiver_normal, shooter.polygon, scratch.local, scratch.clipped);
  }
  return {Shaped::kShaped, seen * from_receiver * front_area / shooter.area};
}

void NearFieldCorrection::shape(const NearFieldShooter& shooter, const formfactor::ReceiverView& receivers,
                                std::span<const std::uint32_t> subset, std::span<const double> ff) {
  near_.clear();
  shaped_.clear();
  const bool whole_shot = subset.empty();
  if (whole_shot) {
    scale_ = 1.0;
    far_scale_ = 1.0;
    far_refused_ = false;
    near_back_end_ = 0.0;
    shot_total_ = 0.0;
  }
  if (!(reach_ > 0.0) || !(shooter.area > 0.0)) return;
  const double radius = mark_near_patches(shooter);
  const double near_distance = reach_ * radius;
  const double near_squared = near_distance * near_distance;
  const double size = patch_extent(shooter.polygon, radius);

  // The receivers to look at, in order: the subset, or the receivers of near patches that candidates() listed for
  // this shooter and view, or every receiver.
  const bool listed = whole_shot && listed_revision_ == receivers.revision() && listed_size_ == receivers.size();
  const bool every = whole_shot && !listed;
  const std::span<const std::uint32_t> among = listed ? std::span<const std::uint32_t>(listed_) : subset;
  const std::size_t count = every ? receivers.size() : among.size();
  const auto receiver_at = [&](std::size_t k) { return every ? static_cast<std::uint32_t>(k) : among[k]; };
  // Each receiver depends on the shot alone, so they are shaped in parallel (on one thread, the exact factors over a
  // receiver or the patch took 930 of the 8 315 samples the office's main thread spent outside parallel loops:
  // docs/benchmarks.md, "The office's main thread"); the totals are then added in the receivers' order, as one
  // thread would, so the numbers do not depend on the threads.
  found_.resize(count);
  std::atomic<bool> from_patch{false};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16), [&](const tbb::blocked_range<std::size_t>& range) {
    Scratch& scratch = scratch_.local();
    bool any = false;
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      found_[k] = shape_receiver(shooter, receivers, receiver_at(k), ff, near_squared, size, scratch);
      any = any || found_[k].state == Shaped::kFromPatch;
    }
    if (any) from_patch.store(true, std::memory_order_relaxed);
  });
  if (from_patch.load(std::memory_order_relaxed)) {
    patch_points_.resize(kPatchLevels);
    for (int level = 0; level < kPatchLevels; ++level)
      polygon_quadrature(shooter.polygon, 2, 1 << level, patch_points_[static_cast<std::size_t>(level)]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16), [&](const tbb::blocked_range<std::size_t>& range) {
      Scratch& scratch = scratch_.local();
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        if (found_[k].state != Shaped::kFromPatch) continue;
        found_[k].value *= patch_average(shooter, receivers.polygon(receiver_at(k)), scratch);
      }
    });
  }
  double back_end_total = 0.0, shaped_total = 0.0;
  for (std::size_t k = 0; k < count; ++k) {
    if (found_[k].state == Shaped::kLeft) continue;
    const std::uint32_t i = receiver_at(k);
    near_.push_back(i);
    shaped_.push_back(found_[k].value);
    back_end_total += ff[i];
    shaped_total += found_[k].value;
  }
  if (whole_shot) {
    if (!(shaped_total > 0.0)) {
      near_.clear();
      return;
    }
    // The shot's total stays what the back end sent. The far receivers take up the near field's change, all in
    // the same proportion, unless that would change them by more than kFarChange (a near field that is most of
    // what the patch sees: its total is then kept instead, and the far receivers are left alone).
    double shot_total = 0.0;
    for (double f : ff) shot_total += f > 0.0 ? f : 0.0;
    near_back_end_ = back_end_total;
    shot_total_ = shot_total;
    const double far_before = shot_total - back_end_total, far_after = shot_total - shaped_total;
    const double far_scale = far_before > 0.0 ? far_after / far_before : 0.0;
    if (far_scale >= 1.0 / kFarChange && far_scale <= kFarChange) {
      far_scale_ = far_scale;
    } else {
      scale_ = back_end_total / shaped_total;
      far_refused_ = true;
    }
  }
}

void NearFieldCorrection::write(std::span<const std::uint32_t> subset, std::span<double> ff) {
  const bool whole_shot = subset.empty();
  near_flag_.resize(ff.size(), 0);
  for (std::size_t k = 0; k < near_.size(); ++k) {
    ff[near_[k]] = scale_ * shaped_[k];
    near_flag_[near_[k]] = 1;
  }
  if (far_scale_ != 1.0) {
    const auto scale_far = [&](std::uint32_t i) {
      if (near_flag_[i] == 0 && ff[i] > 0.0) ff[i] *= far_scale_;
    };
    if (whole_shot) {
      for (std::uint32_t i = 0; i < ff.size(); ++i) scale_far(i);
    } else {
      for (std::uint32_t i : subset) scale_far(i);
    }
  }
  for (std::uint32_t i : near_) near_flag_[i] = 0;
}

}  // namespace aarad::refine
