// The anti-aliased hemicube: Chandran, Kiran, Phani and Rai, section 3.2 (see aa_hemicube.h).
#include "aarad/formfactor/aa_hemicube.h"

#include "aarad/core/polygon.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace aarad::formfactor {
namespace {

// The plane order of the coverage walk's overfilled layers (coverage_list.h, CoverageWalk): receiver `back` lies
// behind receiver `front`'s plane, seen from the shooting point, when every corner of it is on the far side of that
// plane or on it, and some corner strictly behind; across it when some corners lie strictly on either side. "On"
// allows for the rounding of a corner computed on the plane (the points where a floor is cut along a wall's foot):
// 1e-12 of the coordinates' and the plane offset's size, some four thousand units in the last place, yet only 1e-5
// for a scene 1e7 from the origin (1e-10 gave the same numbers in the partition furnace and in a furnace room with
// a box turned by 0.35 rad standing on its floor).
//
// The parts of `back` in a pixel are areas in the image: the receivers are projected as the task rasterized them
// (`project`, into the task's pixel coordinates, counter-clockwise) and `back` clipped to the pixel's square. A cell
// of it (cell_part) is that polygon cut by the lines where the planes meet back's plane in the image (where the two
// planes' 1 / depth, affine in pixel coordinates, are equal); the part of a cell that `fronts` cover (hidden_part)
// adds up the areas of its intersections with each front. Areas add up over the pieces of a split receiver, on
// either side, and a cell of a leaf is made of the same cells of its pieces, so a leaf's pieces are still hidden
// together as the leaf was (the factors a reused row keeps stay those of a fresh shot).
template <class Project, class DepthOf>
struct PlaneOrder {
  static constexpr bool kActive = true;
  const ReceiverView& receivers;
  Vec3 eye;
  const Project* project = nullptr;   // project(receiver, out)
  const DepthOf* depth_of = nullptr;  // depth_of(receiver): 1 / depth of its plane in the task's pixel coordinates
  detail::OrderBuffers* buffers = nullptr;
  std::size_t height = 1;  // pixels per column (the arena's pixel p is column p / height, row p % height)
  std::size_t pixel = 0;
  KeyRounding rounding;  // the scene's rounding in this task's keys (coverage_list.h)

  PlaneOrder at(std::size_t p) const {
    PlaneOrder bound = *this;
    bound.pixel = p;
    return bound;
  }

  // `shape` clipped to the pixel's square, into buffers->in_pixel; returns its area.
  double in_pixel(std::span<const Vec2> shape) const {
    std::vector<Vec2>& out = buffers->in_pixel;
    const auto x = static_cast<double>(pixel / height), y = static_cast<double>(pixel % height);
    const std::array<Vec2, 4> square = {Vec2(x, y), Vec2(x + 1.0, y), Vec2(x + 1.0, y + 1.0), Vec2(x, y + 1.0)};
    const Box box = box_of(shape);
    if (box.x_min >= x && box.x_max <= x + 1.0 && box.y_min >= y && box.y_max <= y + 1.0) {
      out.assign(shape.begin(), shape.end());  // a piece inside the pixel (most are)
    } else {
      convex_intersection(square, shape, out, buffers->scratch);
    }
    return out.size() >= 3 ? signed_area(out) : 0.0;
  }

  // Receiver `back` in the pixel: its area there, its polygon there in buffers->whole (kept for the pixel and the
  // receiver last asked about: a receiver's cells and hidden parts are asked in turn).
  double whole_in_pixel(std::uint32_t back) const {
    detail::OrderBuffers& c = *buffers;
    if (c.whole_pixel == pixel && c.whole_receiver == back) return c.whole_area;
    (*project)(back, c.back);
    c.whole_area = 0.0;
    c.whole.clear();
    if (c.back.size() >= 3) {
      c.whole_area = in_pixel(c.back);
      c.whole.assign(c.in_pixel.begin(), c.in_pixel.end());
    }
    c.whole_pixel = pixel;
    c.whole_receiver = back;
    return c.whole_area;
  }

  // Receiver `back`'s cell (coverage_list.h, "What the walk knows") in the pixel: its area, its polygon in `cell`;
  // the area of the whole receiver in the pixel in `whole` (0 when it has none: then the cell is empty). A point of
  // `back` seen through pixel point (x, y) lies in front of plane h (on the shooting point's side) where it is
  // nearer along that ray than h's plane: where 1 / depth of back's plane exceeds h's. 1 / depth is affine in
  // pixel coordinates, so the cell is the receiver's part in the pixel clipped by lines.
  double cell_in_pixel(std::uint32_t back, std::span<const std::uint32_t> behind,
                       std::span<const std::uint32_t> in_front, double& whole, std::span<const Vec2>& cell) const {
    whole = whole_in_pixel(back);
    cell = buffers->whole;
    if (!(whole > 0.0)) return 0.0;
    if (behind.empty() && in_front.empty()) return whole;
    std::vector<Vec2>& a = buffers->cell;
    std::vector<Vec2>& b = buffers->cell_next;
    a.assign(buffers->whole.begin(), buffers->whole.end());
    const InverseDepth own = (*depth_of)(back);
    const auto keep = [&](std::uint32_t h, double side) {
      const InverseDepth other = (*depth_of)(h);
      clip_to_line(a, side * (own.alpha - other.alpha), side * (own.beta - other.beta),
                   side * (own.gamma - other.gamma), b);
      a.swap(b);
      return a.size() >= 3;
    };
    bool left = true;
    for (std::size_t i = 0; i < behind.size() && left; ++i) left = keep(behind[i], -1.0);
    for (std::size_t i = 0; i < in_front.size() && left; ++i) left = keep(in_front[i], 1.0);
    cell = a;
    return left ? std::max(0.0, signed_area(a)) : 0.0;
  }

  // The part of convex `polygon` where a x + b y + c >= 0, into `out`; points within a rounding of the line are on
  // it (an edge of no length has no side for a later clip).
  static void clip_to_line(std::span<const Vec2> polygon, double a, double b, double c, std::vector<Vec2>& out) {
    out.clear();
    if (polygon.empty()) return;
    double size = std::abs(c);
    for (const Vec2& p : polygon) size = std::max(size, std::abs(a * p.x) + std::abs(b * p.y));
    const double on = 1e-12 * size;
    const auto value = [&](const Vec2& p) {
      const double v = a * p.x + b * p.y + c;
      return std::abs(v) <= on ? 0.0 : v;
    };
    Vec2 previous = polygon.back();
    double previous_value = value(previous);
    for (const Vec2& current : polygon) {
      const double v = value(current);
      if ((previous_value < 0.0 && v > 0.0) || (previous_value > 0.0 && v < 0.0))
        out.push_back(previous + (current - previous) * (previous_value / (previous_value - v)));
      if (v >= 0.0) out.push_back(current);
      previous = current;
      previous_value = v;
    }
  }

  double cell_part(std::uint32_t back, std::span<const std::uint32_t> behind,
                   std::span<const std::uint32_t> in_front) const {
    // Where no plane's line crosses the pixel's square, the cell is the whole entry or nothing, whatever its shape
    // in the pixel (most entries across a plane lie across it elsewhere).
    const auto x = static_cast<double>(pixel / height), y = static_cast<double>(pixel % height);
    const InverseDepth own = (*depth_of)(back);
    bool crossed = false, outside = false;
    const auto side_of_square = [&](std::uint32_t h, double side) {
      const InverseDepth other = (*depth_of)(h);
      const double a = side * (own.alpha - other.alpha), b = side * (own.beta - other.beta),
                   c = side * (own.gamma - other.gamma);
      const double low = c + a * x + b * y + std::min(a, 0.0) + std::min(b, 0.0);
      const double high = c + a * x + b * y + std::max(a, 0.0) + std::max(b, 0.0);
      if (high < 0.0) outside = true;
      else if (low < 0.0) crossed = true;
    };
    for (const std::uint32_t h : behind) side_of_square(h, -1.0);
    for (const std::uint32_t h : in_front) side_of_square(h, 1.0);
    if (outside) return 0.0;
    if (!crossed) return 1.0;
    double whole = 0.0;
    std::span<const Vec2> unused;
    const double cell = cell_in_pixel(back, behind, in_front, whole, unused);
    // No area in the pixel: behind, as the planes say.
    if (!(whole > 0.0)) return behind.empty() ? 0.0 : (in_front.empty() ? 1.0 : 0.0);
    return std::clamp(cell / whole, 0.0, 1.0);
  }

  double hidden_part(std::uint32_t back, std::span<const std::uint32_t> behind,
                     std::span<const std::uint32_t> in_front, std::span<const CoverageEntry> fronts) const {
    double whole = 0.0;
    std::span<const Vec2> cell;
    const double area = cell_in_pixel(back, behind, in_front, whole, cell);
    if (!(whole > 0.0)) return 1.0;  // no area in the pixel: hidden, as the planes say
    if (!(area > 0.0)) return 0.0;
    const Box inside = box_of(cell);
    double hidden = 0.0;
    for (std::size_t i = 0; i < fronts.size() && hidden < area; ++i) {
      const std::span<const Vec2> front_shape = projected(fronts[i].receiver);
      if (front_shape.size() < 3 || !inside.meets(box_of(front_shape))) continue;
      convex_intersection(cell, front_shape, buffers->both, buffers->scratch);
      if (buffers->both.size() >= 3) hidden += std::max(0.0, signed_area(buffers->both));
    }
    return std::min(area, hidden) / whole;
  }

  struct Box {
    double x_min, x_max, y_min, y_max;
    bool meets(const Box& o) const {
      return x_min <= o.x_max && o.x_min <= x_max && y_min <= o.y_max && o.y_min <= y_max;
    }
  };
  static Box box_of(std::span<const Vec2> polygon) {
    Box b{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    for (const Vec2& p : polygon) {
      b.x_min = std::min(b.x_min, p.x);
      b.x_max = std::max(b.x_max, p.x);
      b.y_min = std::min(b.y_min, p.y);
      b.y_max = std::max(b.y_max, p.y);
    }
    return b;
  }

  // A front receiver's projection, made once per pixel (a wall's few entries hide many pieces of a floor).
  std::span<const Vec2> projected(std::uint32_t receiver) const {
    detail::OrderBuffers& c = *buffers;
    if (c.pixel != pixel) {
      c.pixel = pixel;
      c.fronts.clear();
      c.starts.assign(1, 0);
      c.points.clear();
    }
    for (std::size_t i = 0; i < c.fronts.size(); ++i)
      if (c.fronts[i] == receiver) return {c.points.data() + c.starts[i], c.starts[i + 1] - c.starts[i]};
    std::vector<Vec2>& shape = c.front;
    (*project)(receiver, shape);
    c.fronts.push_back(receiver);
    c.points.insert(c.points.end(), shape.begin(), shape.end());
    c.starts.push_back(c.points.size());
    return {c.points.data() + c.starts[c.starts.size() - 2], shape.size()};
  }

  PlaneSide side(std::uint32_t front, std::uint32_t back) const {
    const Plane& plane = receivers.plane(front);
    if (!(plane.signed_distance(eye) > 0.0)) return PlaneSide::kNotBehind;  // seen edge on: nothing lies behind it
    bool behind = false, in_front = false;
    for (const Vec3& corner : receivers.polygon(back)) {
      const double distance = plane.signed_distance(corner);
      const double on = 1e-12 * (std::max({std::abs(corner.x), std::abs(corner.y), std::abs(corner.z)}) +
                                 std::abs(plane.d));
      in_front = in_front || distance > on;
      behind = behind || distance < -on;
      if (in_front && behind) break;
    }
    return !behind ? PlaneSide::kNotBehind : in_front ? PlaneSide::kAcross : PlaneSide::kBehind;
  }
};

}  // namespace

AaHemicubeBackend::AaHemicubeBackend(int resolution) : geometry_(resolution) {
  tasks_ = face_tasks(geometry_.resolution());
  for (const HemicubeFace face : {HemicubeFace::kTop, HemicubeFace::kPosU}) {  // the top table, the sides' one
    const int width = geometry_.width(face), height = geometry_.height(face);
    const std::span<const double> weight = geometry_.delta(face);
    std::vector<double>& column = column_weight_[face == HemicubeFace::kTop ? 0 : 1];
    column.resize(weight.size());
    for (int x = 0; x < width; ++x)
      for (int y = 0; y < height; ++y)
        column[static_cast<std::size_t>(x) * height + y] = weight[static_cast<std::size_t>(y) * width + x];
  }
}

std::size_t AaHemicubeBackend::last_entries() const {
  std::size_t sum = 0;
  for (std::size_t n : task_entries_) sum += n;
  return sum;
}

void AaHemicubeBackend::shoot_task(int task, const ReceiverView& receivers, std::span<const std::uint32_t> candidates,
                                   const TileMask* tiles, std::size_t max_vertices, FaceBuffers& b,
                                   std::span<double> sums, UnoccludedList& unoccluded) {
  const FaceTask& t = tasks_[static_cast<std::size_t>(task)];
  const HemicubeFace face = t.face;
  // The task's viewport: columns [t.x0, t.x1) of the face, shifted to start at 0.
  const int width = t.x1 - t.x0, height = geometry_.height(face);
  unoccluded.clear();
  if (width == 0) return;  // below N = 4 the top face's quarter tasks have no columns (face_tasks)
  const double half = 0.5 * geometry_.resolution(), shift = t.x0;
  // One rasterizer per thread, set to this task's viewport (one per task and thread took 48 N^2 bytes a thread:
  // 3.2 GB at N = 8192).
  std::unique_ptr<AreaRasterizer>& raster = b.raster;
  if (!raster) raster = std::make_unique<AreaRasterizer>(width, height);
  raster->set_viewport(width, height);
  b.local.resize(max_vertices);
  b.scratch.resize(clipped_capacity(max_vertices));
  b.clipped.resize(clipped_capacity(max_vertices));
  b.projected.resize(clipped_capacity(max_vertices));
  StagedCoverageArena& arena = b.arena;
  const int half_row = face != HemicubeFace::kTop && geometry_.resolution() % 2 != 0 ? height - 1 : -1;
  // Entries offered to the arena, counted in a local (a counter in memory would chain every insertion).
  std::size_t offered = 0;
  // Delta form factors of the task's pixels, in the arena's column-major order.
  const double* weight =
      column_weight_[face == HemicubeFace::kTop ? 0 : 1].data() + static_cast<std::size_t>(t.x0) * height;
  const auto column_height = static_cast<std::size_t>(height);

  // Receiver i clipped and projected into b.projected, with its box; 0 vertices when it is degenerate or has nothing
  // in this task's columns.
  ProjectedBox box;
  const auto place = [&](std::uint32_t i) -> std::size_t {
    const std::size_t m = clip_to_face(prepared_.local_polygon(i, b.local), face, prepared_.outside_mask(i), b.scratch,
                                       b.clipped);
    if (m == 0 || !project_clipped(face, std::span<const Vec3>(b.clipped.data(), m), half, shift, b.projected, box) ||
        !(box.x_max > 0.0 && box.x_min < width))
      return 0;
    return m;
  };
  // Receiver i as place() projects it, counter-clockwise, into `out` (empty when it has nothing in this task's
  // columns): the plane order's view of it, asked after the rasterization (place() then reuses its buffers).
  const auto project = [&](std::uint32_t i, std::vector<Vec2>& out) {
    const std::size_t m = place(i);
    out.assign(b.projected.begin(), b.projected.begin() + static_cast<std::ptrdiff_t>(m));
    if (signed_area(out) < 0.0) std::reverse(out.begin(), out.end());
  };
  // 1 / depth of receiver i's plane on this face, in the task's pixel coordinates (as offer() keys it).
  // Scaled by the shot's power of two (PreparedReceivers::inverse_depth_scale), exactly.
  const double key_scale = prepared_.inverse_depth_scale();
  const auto depth_of = [&](std::uint32_t i) {
    InverseDepth depth = inverse_depth(face, prepared_.local_plane(i), half);
    depth.alpha *= key_scale;
    depth.beta *= key_scale;
    depth.gamma *= key_scale;
    depth.gamma += depth.alpha * shift;
    return depth;
  };
  // A re-shot subset: only the pixels its receivers may cover matter.
  const bool masked = tiles != nullptr;
  if (masked && tiles->empty()) {
    task_entries_[static_cast<std::size_t>(task)] = 0;
    return;
  }
  // The scene's rounding, kPlaneDistance x the receivers' diagonal (Scene's coplanarity), in this shot's keys
  // (coverage_list.h, KeyRounding).
  const double delta = kPlaneDistance * prepared_.diagonal() / key_scale;
  const KeyRounding rounding{2.0 * delta};
  b.arena.reset(width, height);
  b.arena.describe_receivers(receivers.size());

  for (const std::uint32_t i : candidates) {
    const std::size_t m = place(i);
    if (m == 0 || (masked && !tiles->overlaps(box.x_min, box.x_max, box.y_min, box.y_max))) continue;
    const InverseDepth depth = depth_of(i);  // in the task's pixel coordinates
    const std::uint32_t receiver = i;
    const std::uint32_t surface = receivers.surface(i);
    const InverseDepthRange surface_range = prepared_.surface_inverse_depths(i, face);
    // The entry's depth range in a pixel (coverage_list.h, "Layers"): the key is 1/depth of the receiver's plane
    // at one point of the pixel's closed square (its centre, or the corner nearest the shooter; docs/form-factors.md,
    // "Depth kept per receiver and pixel") and 1/depth is affine, so over the pixel it stays within |alpha| +
    // |beta| of that value. One bound per receiver, rounded up into a float.
    const double reach = std::abs(depth.alpha) + std::abs(depth.beta);
    float spread = static_cast<float>(reach);
    // One float up (a non-negative finite float's next is its bit pattern plus one: std::nextafter toward
    // infinity, without the library call per receiver).
    if (spread < reach) spread = std::bit_cast<float>(std::bit_cast<std::uint32_t>(spread) + 1u);
    arena.describe(receiver, spread, surface);
    // Offers the receiver's entry for pixel (x, y); returns its coverage as the walk will see it.
    const auto offer = [&](int x, int y, double coverage) {
      // The half row of a side face (odd N) lies half inside the face: its pixel is that inside half, so that
      // the walk's fractions refer to the area receivers can cover there.
      if (y == half_row) coverage = std::min(1.0, 2.0 * coverage);
      // 1/depth of the receiver's plane on the ray through the pixel centre, where every piece of one plane
      // agrees and other planes are met along the same ray.
      double inverse_depth = depth.at(x + 0.5, y + 0.5);
      if (!(inverse_depth > 0.0)) {
        // That ray meets the plane behind the shooter, or runs parallel to it (a grazing plane extrapolated past
        // the receiver, or a receiver close to the shooter crossing its plane): the receiver is seen in another
        // part of the pixel, where 1/depth is in (0, largest over the pixel]. The largest is at the corner nearest
        // the shooter, the centre's value + (|alpha| + |beta|) / 2, a function of the plane and the pixel only, so
        // every piece of one plane gets the same key here too, whichever receiver arrives first (a key taken from
        // the receiver's own box, as before, placed pieces of one plane at different depths, which made the
        // result depend on the receivers' order). It is the receiver's nearest possible depth in the pixel, the
        // one a nearer full entry must beat to hide it, and it stays within the spread of every 1/depth the
        // receiver has in the pixel (those lie in [largest - reach, largest]). Where rounding leaves it <= 0 the
        // plane is seen at infinity: key 0, still within the spread.
        inverse_depth += 0.5 * reach;
        if (!(inverse_depth > 0.0)) inverse_depth = 0.0;
      }
      // Kept within the 1/depth the receiver's surface can have on this face (the range over its box): where the
      // receiver covers part of the pixel and its plane runs nearly through the shooter, the centre's ray meets the
      // plane far beyond the receiver, and that value put a card seen edge-on behind the floor behind it
      // (docs/form-factors.md). The range is the surface's, so the pieces of one surface still share one key per
      // pixel; and it holds every 1/depth the receiver has in the pixel, so the key only moves towards those and
      // stays within the spread of each.
      inverse_depth = std::min(std::max(inverse_depth, surface_range.lo), surface_range.hi);
      // Key -1/depth orders like the depth without a division.
      ++offered;
      arena.insert(x, y, CoverageEntry{-inverse_depth, coverage, receiver, surface, spread});
      return coverage;
    };
    const std::span<const Vec2> polygon(b.projected.data(), m);
    double seen = 0.0;  // with keep_unoccluded: the receiver's factor in this task with nothing in front of it
    if (i < keep_unoccluded_.size() && keep_unoccluded_[i] != 0) {
      raster->rasterize(polygon, [&](int x, int y, double coverage) {
        seen += offer(x, y, coverage) * weight[static_cast<std::size_t>(x) * column_height + static_cast<std::size_t>(y)];
      });
    } else {
      raster->rasterize(polygon, offer);
    }
    if (seen > 0.0) unoccluded.emplace_back(receiver, seen);
  }
  task_entries_[static_cast<std::size_t>(task)] = offered;
  // Walk every list front to back, in the arena's column-major order.
  // Consecutive contributions of one receiver (its interior runs down a column) are summed in a register and
  // added to its total when the receiver changes: no chain of loads and stores through sums[] per pixel.
  std::uint32_t run_receiver = 0;
  double run_sum = 0.0;
  b.order.pixel = detail::OrderBuffers::kNoPixel;  // the last task's projections are not this one's
  b.order.whole_pixel = detail::OrderBuffers::kNoPixel;
  arena.take_all(
      [&](std::size_t pixel, std::uint32_t receiver, double visible) {
        const double contribution = visible * weight[pixel];
        if (receiver != run_receiver) {
          sums[run_receiver] += run_sum;
          run_receiver = receiver;
          run_sum = contribution;
        } else {
          run_sum += contribution;
        }
      },
      PlaneOrder<decltype(project), decltype(depth_of)>{receivers, eye_, &project, &depth_of, &b.order,
                                                        column_height, 0, rounding});
  if (!sums.empty()) sums[run_receiver] += run_sum;
}

void AaHemicubeBackend::compute(const Shooter& shooter, const ReceiverView& receivers,
                                std::span<const std::uint32_t> subset, std::span<double> out) {
  check_shot(shooter, receivers, subset, out);
  eye_ = shooter.centre;
  prepared_.prepare_subset(shooter, receivers, subset, geometry_);
  prepared_.prepare_surface_ranges(receivers);
  const std::size_t max_vertices = std::max<std::size_t>(3, receivers.max_polygon_size());
  sums_.start(tasks_, geometry_.resolution(), prepared_, receivers.size());
  run_face_tasks(sums_.loads(), [&](int task) {
    shoot_task(task, receivers, sums_.receivers(task), subset.empty() ? nullptr : &prepared_.subset_tiles(task),
               max_vertices, buffers_.local(), sums_.sums(task), task_unoccluded_[static_cast<std::size_t>(task)]);
  });
  sums_.combine(subset, out);
}

bool AaHemicubeBackend::add_unoccluded(std::span<double> out) const {
  add_unoccluded_lists(task_unoccluded_, out);
  return true;
}

}  // namespace aarad::formfactor
