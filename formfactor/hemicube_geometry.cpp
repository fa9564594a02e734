// Hemicube geometry: Cohen and Greenberg 1985 (faces, delta form factors), Chandran et al. section 3.2
// (culling and clipping), Sutherland and Hodgman 1974 (clipping). See hemicube_geometry.h for the conventions.
#include "aarad/formfactor/hemicube_geometry.h"

#include "aarad/core/error.h"
#include "aarad/core/predicates.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

namespace aarad::formfactor {

double top_corner_form_factor(double x, double y) {
  // Howell B-3 with c = 1: (1/2pi) [x/sqrt(1+x^2) atan(y/sqrt(1+x^2)) + y/sqrt(1+y^2) atan(x/sqrt(1+y^2))].
  const double sx = std::sqrt(1.0 + x * x), sy = std::sqrt(1.0 + y * y);
  return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2.0 * kPi);
}

double side_corner_form_factor(double y, double z) {
  const double s = std::sqrt(1.0 + z * z);
  return (std::atan(y) - std::atan(y / s) / s) / (2.0 * kPi);
}

HemicubeGeometry::HemicubeGeometry(int resolution, DeltaRule rule)
    // Checked before anything is computed from it (resolution + 1 overflows at INT_MAX).
    : resolution_((check_resolution(resolution), resolution)), side_rows_((resolution + 1) / 2) {
  const int n = resolution_;
  const double cell = 2.0 / n;
  const bool odd = n % 2 != 0;
  // Centre of the inside half of the half row, in pixel units: rows [N/2 - 1/2, N/2).
  half_row_sample_y_ = odd ? 0.5 * n - 0.25 : side_rows_ - 0.5;
  auto node = [n](int i) { return static_cast<double>(2 * i - n) / n; };  // -1 + 2 i / N
  auto height_node = [n](int r) { return std::min(1.0, static_cast<double>(2 * r) / n); };

  // Top face.
  std::vector<double>& top = top_;
  top.assign(static_cast<std::size_t>(n) * n, 0.0);
  if (rule == DeltaRule::kExactCell) {
    std::vector<double> corner(static_cast<std::size_t>(n + 1) * (n + 1));
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        corner[static_cast<std::size_t>(j) * (n + 1) + i] = top_corner_form_factor(node(i), node(j));
    for (int j = 0; j < n; ++j) {
      const double* lo = &corner[static_cast<std::size_t>(j) * (n + 1)];
      const double* hi = lo + (n + 1);
      for (int i = 0; i < n; ++i) top[static_cast<std::size_t>(j) * n + i] = (hi[i + 1] - hi[i]) - (lo[i + 1] - lo[i]);
    }
  } else {
    for (int j = 0; j < n; ++j) {
      const double y = node(j) + 0.5 * cell;
      for (int i = 0; i < n; ++i) {
        const double x = node(i) + 0.5 * cell, r = x * x + y * y + 1.0;
        top[static_cast<std::size_t>(j) * n + i] = cell * cell / (kPi * r * r);
      }
    }
  }

  // Side faces: one table (the four faces are congruent), row r = height above the base.
  std::vector<double>& side = side_;
  side.assign(static_cast<std::size_t>(n) * side_rows_, 0.0);
  if (rule == DeltaRule::kExactCell) {
    std::vector<double> corner(static_cast<std::size_t>(n + 1) * (side_rows_ + 1));
    for (int r = 0; r <= side_rows_; ++r)
      for (int i = 0; i <= n; ++i)
        corner[static_cast<std::size_t>(r) * (n + 1) + i] = side_corner_form_factor(node(i), height_node(r));
    for (int r = 0; r < side_rows_; ++r) {
      const double* lo = &corner[static_cast<std::size_t>(r) * (n + 1)];
      const double* hi = lo + (n + 1);
      for (int i = 0; i < n; ++i) side[static_cast<std::size_t>(r) * n + i] = (hi[i + 1] - hi[i]) - (lo[i + 1] - lo[i]);
    }
  } else {
    for (int r = 0; r < side_rows_; ++r) {
      const double z0 = height_node(r), z1 = height_node(r + 1), z = 0.5 * (z0 + z1), dz = z1 - z0;
      for (int i = 0; i < n; ++i) {
        const double y = node(i) + 0.5 * cell, q = y * y + z * z + 1.0;
        side[static_cast<std::size_t>(r) * n + i] = z * cell * dz / (kPi * q * q);
      }
    }
  }
}

double HemicubeGeometry::face_total(HemicubeFace face) const {
  double sum = 0.0;
  for (double d : delta(face)) sum += d;
  return sum;
}

double HemicubeGeometry::total() const {
  double sum = 0.0;
  for (int f = 0; f < kHemicubeFaces; ++f) sum += face_total(static_cast<HemicubeFace>(f));
  return sum;
}

void add_unoccluded_lists(std::span<const UnoccludedList> lists, std::span<double> out) {
  for (const UnoccludedList& list : lists)
    for (const auto& [receiver, factor] : list)
      if (receiver >= out.size())
        throw Error("add_unoccluded: " + std::to_string(out.size()) + " output values, but the last shot reached "
                    "receiver " + std::to_string(receiver) + "; pass one value per receiver");
  for (const UnoccludedList& list : lists)
    for (const auto& [receiver, factor] : list) out[receiver] += factor;
}

void run_face_tasks(const std::array<std::size_t, kFaceTasks>& loads, const std::function<void(int)>& run) {
  std::array<int, kFaceTasks> order{};
  for (int k = 0; k < kFaceTasks; ++k) order[static_cast<std::size_t>(k)] = k;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return loads[static_cast<std::size_t>(a)] > loads[static_cast<std::size_t>(b)];
  });
  std::atomic<int> next{0};
  const int workers = std::min(kFaceTasks, tbb::this_task_arena::max_concurrency());
  tbb::parallel_for(0, workers, [&](int) {
    for (int k = next++; k < kFaceTasks; k = next++) run(order[static_cast<std::size_t>(k)]);
  }, tbb::simple_partitioner());
}

void TaskSums::start(const std::array<FaceTask, kFaceTasks>& tasks, int resolution, const PreparedReceivers& prepared,
                     std::size_t receivers) {
  for (std::vector<double>& sums : sums_) {
    if (!clean_) {
      sums.assign(receivers, 0.0);
    } else if (sums.size() != receivers) {
      sums.resize(receivers, 0.0);  // every sum is zero already: only the new ones are set
    }
  }
  clean_ = false;
  tbb::parallel_for(0, kHemicubeFaces, [&](int face) {
    prepared.task_receivers(static_cast<HemicubeFace>(face), tasks, resolution, lists_);
  });
}

std::array<std::size_t, kFaceTasks> TaskSums::loads() const {
  std::array<std::size_t, kFaceTasks> loads{};
  for (std::size_t k = 0; k < loads.size(); ++k) loads[k] = lists_.size[k];
  return loads;
}

void TaskSums::combine(std::span<const std::uint32_t> subset, std::span<double> out) {
  if (subset.empty()) {
    // A task that does not list i has sums[i] == 0, and adding +0 changes no sum: the same numbers as adding
    // every task's entry in order. Ranges of receivers are disjoint, and every list is in receiver order, so the
    // ranges are added in parallel, each receiver's sum still in task order.
    const tbb::blocked_range<std::size_t> all(0, out.size(), 4096);
    tbb::parallel_for(all, [&](const tbb::blocked_range<std::size_t>& range) {
      std::fill(out.begin() + static_cast<std::ptrdiff_t>(range.begin()),
                out.begin() + static_cast<std::ptrdiff_t>(range.end()), 0.0);
      for (std::size_t k = 0; k < sums_.size(); ++k) {
        const std::span<const std::uint32_t> list = lists_.list(k);
        const auto first = std::lower_bound(list.begin(), list.end(), range.begin());
        const auto last = std::lower_bound(first, list.end(), range.end());
        for (auto it = first; it != last; ++it) {
          out[*it] += sums_[k][*it];
          sums_[k][*it] = 0.0;
        }
      }
    });
  } else {
    for (const std::uint32_t i : subset) {
      double sum = 0.0;
      for (const std::vector<double>& sums : sums_) sum += sums[i];
      out[i] = sum;
    }
    for (std::size_t k = 0; k < sums_.size(); ++k)
      for (const std::uint32_t i : lists_.list(k)) sums_[k][i] = 0.0;
  }
  clean_ = true;
}

void check_resolution(int resolution) {
  if (resolution < kMinResolution || resolution > kMaxResolution) {
    throw Error("hemicube resolution " + std::to_string(resolution) + " is out of range: use a value from " +
                std::to_string(kMinResolution) + " to " + std::to_string(kMaxResolution) +
                " (pixels along the full top face)");
  }
}

double signed_plane_distance(const Shooter& shooter, const Vec3& p, double w) {
  switch (side_of_plane(shooter.centre, shooter.normal, p)) {
    case Sign::kZero: return 0.0;
    case Sign::kPositive: return w > 0.0 ? w : std::numeric_limits<double>::min();
    case Sign::kNegative: return w < 0.0 ? w : -std::numeric_limits<double>::min();
  }
  return w;
}

bool faces_point(const Plane& plane, const Vec3& centre) {
  return sign_of_linear(plane.normal, plane.d, centre) == Sign::kPositive;
}

namespace {

// Value of plane k of a face at a point in face coordinates; the face keeps value >= 0.
inline double plane_value(bool top, int k, const Vec3& f) {
  switch (k) {
    case 0: return f.x - f.y;
    case 1: return f.x + f.y;
    case 2: return f.x - f.z;
    default: return top ? f.x + f.z : f.z;
  }
}

inline bool lexicographic_less(const Vec3& a, const Vec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

// The point where edge (p, q) crosses plane k (their values have strictly opposite signs), computed from the
// endpoints in canonical order and snapped onto the plane.
inline Vec3 crossing(bool top, int k, const Vec3& p, double vp, const Vec3& q, double vq) {
  const bool swap = lexicographic_less(q, p);
  const Vec3& a = swap ? q : p;
  const Vec3& b = swap ? p : q;
  const double va = swap ? vq : vp, vb = swap ? vp : vq;
  const double t = va / (va - vb);
  Vec3 x = a + t * (b - a);
  switch (k) {
    case 0: x.y = x.x; break;
    case 1: x.y = -x.x; break;
    case 2: x.z = x.x; break;
    default: x.z = top ? -x.x : 0.0; break;
  }
  return x;
}

}  // namespace

std::size_t clip_to_face(std::span<const Vec3> local_polygon, HemicubeFace face, std::uint32_t outside_mask,
                         std::span<Vec3> scratch, std::span<Vec3> out) {
  const bool top = face == HemicubeFace::kTop;
  const std::uint32_t planes = (outside_mask >> (4 * static_cast<int>(face))) & 0xFu;
  // Count the passes so that the last one writes into `out`.
  int passes = 0;
  for (int k = 0; k < 4; ++k) passes += (planes >> k) & 1u;
  Vec3* buffers[2] = {passes % 2 == 0 ? out.data() : scratch.data(), passes % 2 == 0 ? scratch.data() : out.data()};
  std::size_t count = local_polygon.size();
  for (std::size_t i = 0; i < count; ++i) buffers[0][i] = to_face(face, local_polygon[i]);
  int current = 0;
  for (int k = 0; k < 4 && count > 0; ++k) {
    if (((planes >> k) & 1u) == 0) continue;
    const Vec3* in = buffers[current];
    Vec3* result = buffers[1 - current];
    std::size_t written = 0;
    Vec3 prev = in[count - 1];
    double vprev = plane_value(top, k, prev);
    for (std::size_t i = 0; i < count; ++i) {
      const Vec3 cur = in[i];
      const double vcur = plane_value(top, k, cur);
      if (vcur >= 0.0) {
        if (vprev < 0.0 && vcur > 0.0) result[written++] = crossing(top, k, prev, vprev, cur, vcur);
        result[written++] = cur;
      } else if (vprev > 0.0) {
        result[written++] = crossing(top, k, prev, vprev, cur, vcur);
      }
      prev = cur;
      vprev = vcur;
    }
    count = written < 3 ? 0 : written;
    current = 1 - current;
  }
  return count;
}

void PreparedReceivers::start(const Shooter& shooter, const ReceiverView& receivers) {
  const std::size_t count = receivers.size();
  const std::size_t points = receivers.points().size();
  shooter_ = shooter;
  offsets_ = receivers.offsets();
  corner_points_ = receivers.corner_points();
  planes_ = receivers.planes();
  point_local_.resize(points);
  point_code_.resize(points);
  outside_.resize(count);
  face_mask_.resize(count);
  // Each patch is decided when asked: by its receivers as prepare() prepares them, in parallel, or as
  // prepare_subset() tests the few patches it looks at.
  culling_.decide_when_asked(shooter.centre, receivers);
}

void PreparedReceivers::prepare_surface_ranges(const ReceiverView& receivers) {
  const Shooter& shooter = shooter_;
  // Each surface's range of 1 / a on each face, from its box: a is linear, so over the box it lies within the
  // value at the box's centre plus or minus the half extents weighed by the face axis' absolute components. The
  // ranges are widened by 1e-12 of their magnitude, for the rounding of the box's centre and of the dot products.
  find_surface_boxes(receivers);
  Vec3 all_lo(std::numeric_limits<double>::infinity()), all_hi(-std::numeric_limits<double>::infinity());
  for (const auto& [lo, hi] : surface_boxes_) {
    all_lo = glm::min(all_lo, lo);
    all_hi = glm::max(all_hi, hi);
  }
  const Vec3 size = all_hi - all_lo;
  diagonal_ = surface_boxes_.empty() || !std::isfinite(glm::length(size)) ? 0.0 : glm::length(size);
  const double extent = std::max({size.x, size.y, size.z});
  const double scale = extent > 0.0 && std::isfinite(extent) ? std::ldexp(1.0, std::ilogb(extent)) : 1.0;
  inverse_depth_scale_ = scale;
  surface_ranges_.resize(surface_boxes_.size() * kHemicubeFaces);
  for (std::size_t slot = 0; slot < surface_boxes_.size(); ++slot) {
    const auto& [lo, hi] = surface_boxes_[slot];
    const Vec3 centre = 0.5 * (lo + hi) - shooter.centre, half = 0.5 * (hi - lo);
    // Centre and half width of (u, v, w) over the box.
    const Vec3 mid{glm::dot(shooter.tangent, centre), glm::dot(shooter.bitangent, centre),
                   glm::dot(shooter.normal, centre)};
    Vec3 reach{glm::dot(glm::abs(shooter.tangent), half), glm::dot(glm::abs(shooter.bitangent), half),
               glm::dot(glm::abs(shooter.normal), half)};
    reach += 1e-12 * (glm::abs(mid) + reach);
    for (int f = 0; f < kHemicubeFaces; ++f) {
      const auto face = static_cast<HemicubeFace>(f);
      // The face's axis a is one of +-u, +-v, +w (to_face).
      const double a_mid = to_face(face, mid).x, a_reach = to_face(face, reach).x;
      const double a_lo = a_mid - std::abs(a_reach), a_hi = a_mid + std::abs(a_reach);
      surface_ranges_[slot * kHemicubeFaces + static_cast<std::size_t>(f)] = {
          a_hi > 0.0 ? scale / a_hi : 0.0, a_lo > 0.0 ? scale / a_lo : std::numeric_limits<double>::infinity()};
    }
  }
}

void PreparedReceivers::find_surface_boxes(const ReceiverView& receivers) {
  const std::size_t count = receivers.size();
  if (surfaces_revision_ == receivers.revision() && surfaces_size_ == count) return;
  // A refinement of the view the boxes were found for keeps them: its receivers lie in the convex hulls of that
  // view's patches' points (ReceiverView::mark_refinement_of), so in the boxes, and belong to the same surfaces.
  // Only the slots are found again, unless a surface turns out to be new.
  const bool refined = surfaces_revision_ != 0 && receivers.refines() == surfaces_revision_;
  surfaces_revision_ = receivers.revision();
  surfaces_size_ = count;
  surface_slot_.resize(count);
  const std::span<const std::uint32_t> surfaces = receivers.surfaces();
  const std::span<const Vec3> points = receivers.points();
  // Slots for every receiver; with `grow`, new slots for new surfaces and the boxes grown over every corner.
  // False when a surface has no slot and `grow` is off.
  const auto find = [&](bool grow) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    std::uint32_t slot = 0;
    for (std::size_t i = 0; i < count; ++i) {
      // Receivers of one surface mostly follow one another: look the id up only when it changes.
      if (i == 0 || surfaces[i] != surfaces[i - 1]) {
        const auto it = slot_of_surface_.find(surfaces[i]);
        if (it != slot_of_surface_.end()) {
          slot = it->second;
        } else if (grow) {
          slot = static_cast<std::uint32_t>(surface_boxes_.size());
          slot_of_surface_.emplace(surfaces[i], slot);
          surface_boxes_.push_back({Vec3(kInf), Vec3(-kInf)});
        } else {
          return false;
        }
      }
      surface_slot_[i] = slot;
      if (!grow) continue;
      auto& [lo, hi] = surface_boxes_[slot];
      for (std::uint32_t v = offsets_[i]; v < offsets_[i + 1]; ++v) {
        const Vec3& p = points[corner_points_[v]];
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
    }
    return true;
  };
  if (refined && find(false)) return;
  slot_of_surface_.clear();
  surface_boxes_.clear();
  find(true);
}

void PreparedReceivers::prepare_receiver(std::size_t i) {
  if (!culling_.faces(i) || offsets_[i + 1] - offsets_[i] < 3) {
    face_mask_[i] = 0;  // culled: no face looks at its local coordinates
    return;
  }
  std::uint32_t all = ~0u, any = 0u;
  for (std::size_t v = offsets_[i]; v < offsets_[i + 1]; ++v) {
    const std::uint32_t code = point_code_[corner_points_[v]];
    all &= code;
    any |= code;
  }
  outside_[i] = any;
  FaceMask mask = 0;
  for (int f = 0; f < kHemicubeFaces; ++f) {
    if ((all & face_outcode_mask(static_cast<HemicubeFace>(f))) == 0) mask |= static_cast<FaceMask>(1u << f);
  }
  // The sides of the lines where tasks meet (task_mask) that some vertex reaches: outcode bits 20 to 27 are mask
  // bits 5 to 12, in the same order.
  static_assert(kOutcodeUNotPositive == 1u << 20 && kOutcodeNotLeftOfThreeQuarters == 1u << 27 &&
                kMaskUNotPositive == 1u << 5 && kMaskNotLeftOfThreeQuarters == 1u << 12);
  mask |= static_cast<FaceMask>(((any >> 20) & 0xffu) << 5);
  face_mask_[i] = mask;
}

void PreparedReceivers::prepare(const Shooter& shooter, const ReceiverView& receivers) {
  start(shooter, receivers);
  subset_ = false;
  const std::span<const Vec3> points = receivers.points();
  // Every point once (a vertex is a corner of up to four elements), then every receiver combines its corners'
  // outcodes.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t p = range.begin(); p != range.end(); ++p) prepare_point(p, points[p]);
                    });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, receivers.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) prepare_receiver(i);
                    });
  prepared_count_ = receivers.size();
}

bool PreparedReceivers::find_patch_balls(const ReceiverView& receivers) {
  const std::size_t count = receivers.size();
  if (balls_revision_ == receivers.revision() && balls_size_ == count) return balls_dense_;
  // A refinement of the view the balls were found for keeps them (ReceiverView::mark_refinement_of): a patch's
  // points stay in their convex hull, where the patch's ball and box hold them, and its extreme points stay.
  const bool refined = balls_dense_ && receivers.refines() == balls_revision_;
  balls_revision_ = receivers.revision();
  balls_size_ = count;
  const std::span<const std::uint32_t> patches = receivers.patches();
  std::uint32_t max_patch = 0;
  for (const std::uint32_t p : patches) max_patch = std::max(max_patch, p);
  balls_dense_ = patch_ids_dense(max_patch, count);
  if (!balls_dense_) return false;
  // The receivers of each patch, in order (a counting sort by patch id).
  const std::size_t patch_count = std::size_t{max_patch} + 1;
  patch_first_.assign(patch_count + 1, 0);
  for (const std::uint32_t p : patches) ++patch_first_[p + 1];
  for (std::size_t p = 0; p < patch_count; ++p) patch_first_[p + 1] += patch_first_[p];
  patch_receivers_.resize(count);
  {
    std::vector<std::uint32_t> next(patch_first_.begin(), patch_first_.end() - 1);
    for (std::uint32_t i = 0; i < count; ++i) patch_receivers_[next[patches[i]]++] = i;
  }
  // The patches with receivers in their slots, grouped into clusters (group_patches); grouped again only when that
  // set changed. The grouping decides how much a cluster's box rules out, never a result, and a solver's patches
  // stay where they are while their receivers split.
  std::size_t with_receivers = 0;
  for (std::size_t p = 0; p < patch_count; ++p) with_receivers += patch_first_[p] != patch_first_[p + 1] ? 1 : 0;
  bool regroup = slot_patch_.size() != with_receivers;
  for (std::size_t k = 0; k < slot_patch_.size() && !regroup; ++k) {
    const std::uint32_t p = slot_patch_[k];
    regroup = p >= patch_count || patch_first_[p] == patch_first_[p + 1];
  }
  if (refined && !regroup) return true;
  const std::span<const Vec3> points = receivers.points();
  const std::span<const std::uint32_t> offsets = receivers.offsets(), corners = receivers.corner_points();
  // Calls body(q) for every point of patch p's receivers.
  const auto for_each_point = [&](std::uint32_t p, auto&& body) {
    for (std::uint32_t k = patch_first_[p]; k < patch_first_[p + 1]; ++k) {
      const std::uint32_t i = patch_receivers_[k];
      for (std::uint32_t v = offsets[i]; v < offsets[i + 1]; ++v) body(points[corners[v]]);
    }
  };
  // The centre of the box of patch p's points.
  const auto centre_of = [&](std::uint32_t p) {
    Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for_each_point(p, [&](const Vec3& q) {
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
    });
    return 0.5 * (lo + hi);
  };
  if (regroup) {
    std::vector<std::uint32_t> patches_with_receivers;
    std::vector<Vec3> centres;
    for (std::uint32_t p = 0; p < patch_count; ++p) {
      if (patch_first_[p] == patch_first_[p + 1]) continue;
      patches_with_receivers.push_back(p);
      centres.push_back(centre_of(p));
    }
    group_patches(patches_with_receivers, centres);
  }
  // Per slot, the ball: centred on the box of the patch's points, with the largest distance to them as radius;
  // and the box: two axes in the plane of the patch's first receiver and its normal, the extents of the points
  // along them about the ball's centre, and a centre moved to their middle (prepare_subset widens both for
  // rounding). In slot order, so that prepare_subset reads them in sequence.
  const std::size_t slots = slot_patch_.size();
  slot_balls_.resize(slots);
  slot_boxes_.resize(slots);
  slot_bits_.resize(slots);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots, 64), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const std::uint32_t p = slot_patch_[k];
      const Vec3 centre = centre_of(p);
      double radius = 0.0;
      for_each_point(p, [&](const Vec3& q) { radius = std::max(radius, glm::length(q - centre)); });
      slot_balls_[k] = PatchBall{centre, radius};
      PatchBox& box = slot_boxes_[k];
      const Vec3 n = receivers.plane(patch_receivers_[patch_first_[p]]).normal;
      const Vec3 helper = std::abs(n.x) <= std::abs(n.y) && std::abs(n.x) <= std::abs(n.z) ? Vec3{1.0, 0.0, 0.0}
                          : std::abs(n.y) <= std::abs(n.z)                             ? Vec3{0.0, 1.0, 0.0}
                                                                                         : Vec3{0.0, 0.0, 1.0};
      box.axes[0] = glm::normalize(glm::cross(n, helper));
      box.axes[1] = glm::normalize(glm::cross(n, box.axes[0]));
      box.axes[2] = glm::normalize(n);
      Vec3 low(std::numeric_limits<double>::infinity()), high(-std::numeric_limits<double>::infinity());
      for_each_point(p, [&](const Vec3& q) {
        const Vec3 d = q - centre;
        const Vec3 t{glm::dot(d, box.axes[0]), glm::dot(d, box.axes[1]), glm::dot(d, box.axes[2])};
        low = glm::min(low, t);
        high = glm::max(high, t);
      });
      const Vec3 middle = 0.5 * (low + high);
      box.centre = centre + middle.x * box.axes[0] + middle.y * box.axes[1] + middle.z * box.axes[2];
      box.half = 0.5 * (high - low);
      const auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
      if (!finite(box.centre) || !finite(box.half))  // no normal to take (a degenerate plane): the ball's cube
        box = PatchBox{centre, {Vec3{1.0, 0.0, 0.0}, Vec3{0.0, 1.0, 0.0}, Vec3{0.0, 0.0, 1.0}}, Vec3(radius)};
    }
  });
  // Each cluster's box, on the scene's axes, holds its patches' boxes: a cluster lying along one wall (most do) is
  // flat, where a ball round it reached as far off the wall as along it. A group's box holds its clusters' boxes (over
  // an office solve the groups cut the regions projected from 32.0 to 26.4 million, docs/benchmarks.md).
  const auto enclose = [](std::span<const PatchBox> boxes) {
    Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const PatchBox& box : boxes) {
      Vec3 extent(0.0);
      for (int a = 0; a < 3; ++a) extent += glm::abs(box.axes[static_cast<std::size_t>(a)]) * box.half[a];
      lo = glm::min(lo, box.centre - extent);
      hi = glm::max(hi, box.centre + extent);
    }
    return PatchBox{0.5 * (lo + hi), {Vec3{1.0, 0.0, 0.0}, Vec3{0.0, 1.0, 0.0}, Vec3{0.0, 0.0, 1.0}}, 0.5 * (hi - lo)};
  };
  const auto enclose_runs = [&](std::span<const PatchBox> boxes, std::size_t run, std::vector<PatchBox>& out) {
    out.resize((boxes.size() + run - 1) / run);
    for (std::size_t c = 0; c < out.size(); ++c)
      out[c] = enclose(boxes.subspan(c * run, std::min(run, boxes.size() - c * run)));
  };
  enclose_runs(slot_boxes_, kClusterPatches, cluster_boxes_);
  enclose_runs(cluster_boxes_, kGroupClusters, group_boxes_);
  return true;
}

void PreparedReceivers::group_patches(std::span<const std::uint32_t> patches, std::span<const Vec3> centres) {
  // The box of the centres, cut into 1024 steps a side; the patches in the order of their steps' Morton codes.
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const Vec3& c : centres) {
    lo = glm::min(lo, c);
    hi = glm::max(hi, c);
  }
  const Vec3 scale = 1023.0 / glm::max(hi - lo, Vec3(1e-300));
  // Bits of a 10-bit step spread to every third place.
  const auto spread = [](std::uint64_t x) {
    std::uint64_t r = 0;
    for (int b = 0; b < 10; ++b) r |= ((x >> b) & 1u) << (3 * b);
    return r;
  };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(patches.size());
  for (std::size_t k = 0; k < patches.size(); ++k) {
    const Vec3 step = glm::clamp((centres[k] - lo) * scale, Vec3(0.0), Vec3(1023.0));
    const std::uint64_t key = spread(static_cast<std::uint64_t>(step.x)) |
                              spread(static_cast<std::uint64_t>(step.y)) << 1 |
                              spread(static_cast<std::uint64_t>(step.z)) << 2;
    keyed[k] = {key, patches[k]};
  }
  std::sort(keyed.begin(), keyed.end());
  slot_patch_.resize(keyed.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) slot_patch_[k] = keyed[k].second;
}

namespace {

// The pixels a region may project onto on one face: its centre in the face's coordinates, the box [x0, x1] x
// [y0, y1] in the face's pixel coordinates (project_clipped's before a task's shift); false when the region lies
// wholly behind the face's apex. Over the region each face coordinate stays within `radius` of the centre's (the
// same radius thrice for a ball): a lies in [a0, a1] = centre.a -+ radius.a and l in [l - radius.l, l + radius.l],
// so l / a lies in the interval quotient; for a region that reaches a <= 0 the face's frustum bounds it instead
// (below). A margin of 1e-6 pixels covers the rounding.
struct RegionPixels {
  double x0, x1, y0, y1;
};
bool region_pixels(const Vec3& centre, const Vec3& radius, bool top, double half, RegionPixels& pixels) {
  const double a0 = centre.x - radius.x, a1 = centre.x + radius.x;
  if (!(a1 > 0.0)) return false;  // wholly behind the face's apex: no point of it is in front of the face
  const auto quotient = [&](double l, double r, double& lo, double& hi) {
    const double l0 = l - r, l1 = l + r;
    if (a0 > 0.0) {
      lo = l0 / (l0 >= 0.0 ? a1 : a0);
      hi = l1 / (l1 >= 0.0 ? a0 : a1);
    } else {
      // The region reaches the apex plane, where l / a is unbounded; but the hemicubes clip to the face's frustum,
      // |l| <= a, so only its points with l / a in [-1, 1] land on the face, and with a <= a1 a coordinate that
      // keeps one sign stays beyond l0 / a1 (or l1 / a1).
      lo = l0 > 0.0 ? l0 / a1 : -1.0;
      hi = l1 < 0.0 ? l1 / a1 : 1.0;
    }
  };
  double x0, x1, y0, y1;
  quotient(centre.y, radius.y, x0, x1);
  quotient(centre.z, radius.z, y0, y1);
  constexpr double kMargin = 1e-6;
  const double y_offset = top ? 1.0 : 0.0;
  pixels = {(x0 + 1.0) * half - kMargin, (x1 + 1.0) * half + kMargin, (y0 + y_offset) * half - kMargin,
            (y1 + y_offset) * half + kMargin};
  return true;
}

// Whether those pixels meet a marked tile of a task's mask (its columns counted from `shift`).
bool pixels_may_cover(const RegionPixels& pixels, double shift, const TileMask& mask) {
  return mask.overlaps(pixels.x0 - shift, pixels.x1 - shift, pixels.y0, pixels.y1);
}

}  // namespace

void PreparedReceivers::mark_subset_tiles(std::span<const std::uint32_t> subset, const HemicubeGeometry& geometry) {
  // A clipped receiver's box as both hemicubes place it (project_clipped, moved left by the task's x0); those with
  // nothing in the task's columns mark no tile.
  const std::array<FaceTask, kFaceTasks> tasks = face_tasks(geometry.resolution());
  const double half = 0.5 * geometry.resolution();
  std::size_t largest = 3;
  for (const std::uint32_t i : subset) largest = std::max<std::size_t>(largest, offsets_[i + 1] - offsets_[i]);
  const std::size_t capacity = clipped_capacity(largest);
  tbb::parallel_for(0, kFaceTasks, [&](int k) {
    const FaceTask& task = tasks[static_cast<std::size_t>(k)];
    const int width = task.x1 - task.x0;
    TileMask& mask = masks_[static_cast<std::size_t>(k)];
    mask.reset(width, geometry.height(task.face));
    const FaceMask need = task_mask(task, geometry.resolution());
    std::vector<Vec3> local(capacity), scratch(capacity), clipped(capacity);
    std::vector<Vec2> projected(capacity);
    ProjectedBox box;
    for (const std::uint32_t i : subset) {
      if ((face_mask_[i] & need) != need) continue;
      const std::size_t m = clip_to_face(local_polygon(i, local), task.face, outside_[i], scratch, clipped);
      if (m != 0 &&
          project_clipped(task.face, std::span<const Vec3>(clipped.data(), m), half, task.x0, projected, box) &&
          box.x_max > 0.0 && box.x_min < width)
        mask.add(box.x_min, box.x_max, box.y_min, box.y_max);
    }
  });
}

void PreparedReceivers::prepare_subset(const Shooter& shooter, const ReceiverView& receivers,
                                       std::span<const std::uint32_t> subset, const HemicubeGeometry& geometry) {
  if (subset.empty()) {
    prepare(shooter, receivers);
    return;
  }
  if (!find_patch_balls(receivers)) {  // sparse patch ids: every receiver prepared, and only the tiles marked
    prepare(shooter, receivers);
    mark_subset_tiles(subset, geometry);
    return;
  }
  start(shooter, receivers);
  subset_ = true;
  const std::size_t count = receivers.size();
  const std::span<const Vec3> points = receivers.points();
  std::fill(face_mask_.begin(), face_mask_.end(), FaceMask{0});
  task_bits_.assign(count, 0);
  point_wanted_.assign(points.size(), 0);
  // Transforms receiver i's points that no receiver claimed before it. Called from several threads at once: a point
  // shared by receivers on two threads is claimed by one of them (its point_wanted_ byte, exchanged atomically) and
  // transformed once, and a transform depends on the point alone, so the result is the same whoever claims it. The
  // receivers' outcodes are combined (prepare_receiver) only after every claimed point is transformed.
  const auto transform_points = [&](std::uint32_t i) {
    for (std::size_t v = offsets_[i]; v < offsets_[i + 1]; ++v) {
      const std::uint32_t p = corner_points_[v];
      std::atomic_ref<std::uint8_t> wanted(point_wanted_[p]);
      if (wanted.load(std::memory_order_relaxed) == 0 && wanted.exchange(1, std::memory_order_relaxed) == 0)
        prepare_point(p, points[p]);
    }
  };

  // The subset's receivers go on every list their faces allow, as after prepare(); each prepared once (listed_),
  // should the subset name one twice.
  listed_.clear();
  for (const std::uint32_t i : subset) {
    if (task_bits_[i] == kInSubset) continue;
    task_bits_[i] = kInSubset;
    listed_.push_back(i);
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, listed_.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) transform_points(listed_[k]);
                    });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, listed_.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) prepare_receiver(listed_[k]);
                    });

  mark_subset_tiles(subset, geometry);
  const std::array<FaceTask, kFaceTasks> tasks = face_tasks(geometry.resolution());
  const double half = 0.5 * geometry.resolution();

  // Per patch that faces the shooter, the tasks whose tiles its ball and then its box may reach, after those of its
  // cluster's box (a cluster that reaches no tile rules out all its patches at once). A box, flat along its
  // patch's normal, bounds a patch seen face on far more tightly than a ball: in the office it leaves 65 % of the
  // receivers the balls listed. A ball's radius, and each half extent of a box, is widened by 1e-9 of (its size +
  // distances from the origin of it and of the shooter): far more than the rounding of any point the hemicubes
  // compute from the patch's points (transform, clipping), so they all lie inside.
  const double shooter_reach = glm::length(shooter.centre);
  const auto rotate = [&](const Vec3& v) {  // into the shooter's frame
    return Vec3{glm::dot(shooter.tangent, v), glm::dot(shooter.bitangent, v), glm::dot(shooter.normal, v)};
  };
  // Of `tasks_to_test`, the tasks whose tiles a region may reach: its centre `local` in the shooter's frame, and
  // each local coordinate within `extent` of the centre's over it.
  const auto region_reach = [&](const Vec3& local, const Vec3& extent, TaskSet tasks_to_test) {
    TaskSet bits = 0;
    // The region's pixels once per face (its tasks are consecutive in face_tasks), then each task's tiles.
    RegionPixels pixels{};
    bool on_face = false;
    for (int k = 0; k < kFaceTasks; ++k) {
      const FaceTask& task = tasks[static_cast<std::size_t>(k)];
      if (k == 0 || task.face != tasks[static_cast<std::size_t>(k - 1)].face) on_face = false;
      if ((tasks_to_test >> k & 1u) == 0) continue;
      if (!on_face) {
        on_face = true;
        if (!region_pixels(to_face(task.face, local), glm::abs(to_face(task.face, extent)),
                           task.face == HemicubeFace::kTop, half, pixels))
          pixels = {1.0, -1.0, 1.0, -1.0};  // behind the face: meets no tile
      }
      if (pixels_may_cover(pixels, task.x0, masks_[static_cast<std::size_t>(k)]))
        bits |= static_cast<TaskSet>(1u << k);
    }
    return bits;
  };
  const auto reach = [&](const PatchBall& ball, TaskSet tasks_to_test) {
    const double radius = ball.radius + 1e-9 * (ball.radius + glm::length(ball.centre) + shooter_reach);
    return region_reach(rotate(ball.centre - shooter.centre), Vec3(radius), tasks_to_test);
  };
  const auto box_reach = [&](const PatchBox& box, TaskSet tasks_to_test) {
    const Vec3 half_box = box.half + 1e-9 * (glm::length(box.half) + glm::length(box.centre) + shooter_reach);
    Vec3 extent(0.0);
    for (int k = 0; k < 3; ++k) extent += glm::abs(rotate(box.axes[k])) * half_box[k];
    return region_reach(rotate(box.centre - shooter.centre), extent, tasks_to_test);
  };
  TaskSet marked = 0;  // the tasks with a marked tile
  for (int k = 0; k < kFaceTasks; ++k)
    if (!masks_[static_cast<std::size_t>(k)].empty()) marked |= static_cast<TaskSet>(1u << k);
  const std::size_t slots = slot_patch_.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, group_boxes_.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      const TaskSet group = box_reach(group_boxes_[g], marked);
      const std::size_t clusters_end = std::min(cluster_boxes_.size(), (g + 1) * kGroupClusters);
      for (std::size_t c = g * kGroupClusters; c < clusters_end; ++c) {
        const TaskSet cluster = group != 0 ? box_reach(cluster_boxes_[c], group) : 0;
        const std::size_t first = c * kClusterPatches, last = std::min(slots, first + kClusterPatches);
        for (std::size_t k = first; k < last; ++k) {
          // The ball first (cheaper), then the box for the tasks the ball may reach.
          const bool tested = cluster != 0 && culling_.patch_faces(slot_patch_[k]);
          const TaskSet ball = tested ? reach(slot_balls_[k], cluster) : 0;
          slot_bits_[k] = ball != 0 ? box_reach(slot_boxes_[k], ball) : 0;
        }
      }
    }
  });

  // Their receivers, and the points of those; every receiver on a list, in order (task_receivers). Found through
  // the patches, marked in a bitmap of receivers and read back from it in order: a few thousand receivers of a
  // scene of tens of thousands, without a pass over all of them. In parallel over the patches reached, listed first:
  // they lie in few runs of slots (slots follow the patches' places), which would leave a parallel loop over all
  // slots with its work in one or two pieces. Each receiver belongs to one patch, so only its points
  // (transform_points) and its word of the bitmap (an atomic OR) are shared between threads.
  listed_bits_.assign((count + 63) / 64, 0);
  for (const std::uint32_t i : listed_) listed_bits_[i / 64] |= std::uint64_t{1} << (i % 64);
  reached_slots_.clear();
  for (std::size_t slot = 0; slot < slots; ++slot)
    if (slot_bits_[slot] != 0) reached_slots_.push_back(static_cast<std::uint32_t>(slot));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, reached_slots_.size(), 8),
                    [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t r = range.begin(); r != range.end(); ++r) {
      const std::uint32_t slot = reached_slots_[r];
      const std::uint32_t p = slot_patch_[slot];
      for (std::uint32_t k = patch_first_[p]; k < patch_first_[p + 1]; ++k) {
        const std::uint32_t i = patch_receivers_[k];
        if (task_bits_[i] != 0) continue;  // in the subset
        task_bits_[i] = slot_bits_[slot];
        transform_points(i);
        std::atomic_ref<std::uint64_t>(listed_bits_[i / 64]).fetch_or(std::uint64_t{1} << (i % 64),
                                                                      std::memory_order_relaxed);
      }
    }
  });
  listed_.clear();
  for (std::size_t w = 0; w < listed_bits_.size(); ++w)
    for (std::uint64_t bits = listed_bits_[w]; bits != 0; bits &= bits - 1)
      listed_.push_back(static_cast<std::uint32_t>(w * 64 + static_cast<std::size_t>(std::countr_zero(bits))));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, listed_.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        const std::uint32_t i = listed_[k];
                        if (task_bits_[i] != kInSubset) prepare_receiver(i);
                      }
                    });
  prepared_count_ = listed_.size();
}

void PreparedReceivers::task_receivers(HemicubeFace face, const std::array<FaceTask, kFaceTasks>& tasks,
                                       int resolution, TaskLists& lists) const {
  constexpr std::size_t kMost = 4;  // tasks on one face
  std::array<std::size_t, kMost> index{};
  std::array<FaceMask, kMost> need{};
  std::array<TaskSet, kMost> bit{};
  std::array<std::uint32_t*, kMost> out{};
  std::array<std::size_t, kMost> n{};
  std::size_t strips = 0;
  const std::size_t count = subset_ ? listed_.size() : face_mask_.size();
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    if (tasks[k].face != face) continue;
    index[strips] = k;
    need[strips] = task_mask(tasks[k], resolution);
    bit[strips] = static_cast<TaskSet>(1u << k);
    if (lists.ids[k].size() < count) lists.ids[k].resize(count);
    out[strips] = lists.ids[k].data();
    ++strips;
  }
  // The loop over the face's tasks unrolled (two or four of them).
  const auto run = [&]<std::size_t kStrips>(std::integral_constant<std::size_t, kStrips>, auto receiver_at,
                                            auto listed) {
    for (std::size_t j = 0; j < count; ++j) {
      const std::uint32_t i = receiver_at(j);
      const FaceMask mask = face_mask_[i];
      for (std::size_t t = 0; t < kStrips; ++t) {
        out[t][n[t]] = i;
        n[t] += static_cast<std::size_t>((mask & need[t]) == need[t] && listed(i, bit[t]));
      }
    }
  };
  const auto run_strips = [&](auto strip_count) {
    if (subset_) {
      run(strip_count, [&](std::size_t j) { return listed_[j]; },
          [&](std::uint32_t i, TaskSet b) { return (task_bits_[i] & b) != 0; });
    } else {
      run(strip_count, [](std::size_t j) { return static_cast<std::uint32_t>(j); },
          [](std::uint32_t, TaskSet) { return true; });
    }
  };
  if (strips == 4) {
    run_strips(std::integral_constant<std::size_t, 4>{});
  } else if (strips == 2) {
    run_strips(std::integral_constant<std::size_t, 2>{});
  } else {
    throw Error("face tasks: " + std::to_string(strips) + " tasks on one face");
  }
  for (std::size_t t = 0; t < strips; ++t) lists.size[index[t]] = n[t];
}

void TileMask::reset(int width, int height) {
  width_ = width;
  height_ = height;
  shift_ = 0;
  while (((width - 1) >> shift_) >= 64) ++shift_;
  rows_.assign(static_cast<std::size_t>(((height - 1) >> shift_) + 1), 0);
  empty_ = true;
  marked_low_ = static_cast<int>(rows_.size());
  marked_high_ = -1;
}

bool TileMask::tiles(double lo, double hi, int size, int& t0, int& t1) const {
  if (!(hi >= 0.0 && lo < size)) return false;  // also false for NaN
  const int p0 = lo <= 0.0 ? 0 : static_cast<int>(lo);  // floor, as lo > 0
  const int p1 = hi >= size ? size - 1 : static_cast<int>(hi);
  t0 = p0 >> shift_;
  t1 = p1 >> shift_;
  return true;
}

namespace {
// Bits t0 .. t1 of a row (0 <= t0 <= t1 < 64).
std::uint64_t tile_bits(int t0, int t1) { return (~std::uint64_t{0} >> (63 - t1)) & (~std::uint64_t{0} << t0); }
}  // namespace

void TileMask::add(double x_min, double x_max, double y_min, double y_max) {
  int x0, x1, y0, y1;
  if (!tiles(x_min, x_max, width_, x0, x1) || !tiles(y_min, y_max, height_, y0, y1)) return;
  const std::uint64_t bits = tile_bits(x0, x1);
  for (int y = y0; y <= y1; ++y) rows_[static_cast<std::size_t>(y)] |= bits;
  empty_ = false;
  marked_low_ = std::min(marked_low_, y0);
  marked_high_ = std::max(marked_high_, y1);
}

bool TileMask::overlaps(double x_min, double x_max, double y_min, double y_max) const {
  int x0, x1, y0, y1;
  if (!tiles(x_min, x_max, width_, x0, x1) || !tiles(y_min, y_max, height_, y0, y1)) return false;
  const std::uint64_t bits = tile_bits(x0, x1);
  // Only the rows with a marked tile can answer yes: a region tall next to the few rows a subset marks (a cluster
  // of patches, a receiver near the shooter) reads no more than those.
  y0 = std::max(y0, marked_low_);
  y1 = std::min(y1, marked_high_);
  for (int y = y0; y <= y1; ++y)
    if ((rows_[static_cast<std::size_t>(y)] & bits) != 0) return true;
  return false;
}

void BackFaceCulling::find_deciders(const ReceiverView& receivers) {
  const std::size_t count = receivers.size();
  const std::span<const std::uint32_t> patches = receivers.patches();
  std::uint32_t max_patch = 0;
  for (const std::uint32_t p : patches) max_patch = std::max(max_patch, p);
  per_patch_ = patch_ids_dense(max_patch, count);
  decider_patch_.clear();
  decider_receiver_.clear();
  patch_faces_.assign(per_patch_ ? static_cast<std::size_t>(max_patch) + 1 : 0, 0);
  patch_decider_.assign(patch_faces_.size(), 0);
  // In receiver order: a patch's first receiver decides, whatever the thread count. patch_faces_ marks the patches
  // seen while they are listed (decide() overwrites every listed entry).
  if (per_patch_) {
    for (std::uint32_t i = 0; i < count; ++i) {
      std::uint8_t& seen = patch_faces_[patches[i]];
      if (seen != 0) continue;
      seen = 1;
      decider_patch_.push_back(patches[i]);
      decider_receiver_.push_back(i);
      patch_decider_[patches[i]] = i;
    }
  }
  revision_ = receivers.revision();
  size_ = count;
}

void BackFaceCulling::decide_when_asked(const Vec3& centre, const ReceiverView& receivers) {
  if (receivers.revision() != revision_ || receivers.size() != size_) find_deciders(receivers);
  if (!per_patch_) {
    decide(centre, receivers);
    return;
  }
  patches_ = receivers.patches();
  planes_ = receivers.planes();
  centre_ = centre;
  std::fill(patch_faces_.begin(), patch_faces_.end(), kUndecided);
}

void BackFaceCulling::decide(const Vec3& centre, const ReceiverView& receivers) {
  if (receivers.revision() != revision_ || receivers.size() != size_) find_deciders(receivers);
  patches_ = receivers.patches();
  planes_ = receivers.planes();
  centre_ = centre;
  if (per_patch_) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, decider_patch_.size(), 512),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t k = range.begin(); k != range.end(); ++k)
                          patch_faces_[decider_patch_[k]] = faces_point(receivers.plane(decider_receiver_[k]), centre);
                      });
  } else {
    receiver_faces_.resize(receivers.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, receivers.size(), 512),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i != range.end(); ++i)
                          receiver_faces_[i] = faces_point(receivers.plane(i), centre);
                      });
  }
}

}  // namespace aarad::formfactor
