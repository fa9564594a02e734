// The anti-aliased hemicube: Chandran, Kiran, Phani and Rai, section 3.2 (see aa_hemicube.h).
#include "formfactor/aa_hemicube.h"

#include "core/polygon.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace aarad::formfactor {
namespace {

// The plane order of the coverage walk's overfilled layers (coverage_list.h, CoverageWalk): receiver `back` lies
// behind receiver `front`'s plane, seen from the shooting point, when every corner of it is on the far side of that
// plane or on it, and some corner strictly behind. "On" allows for the rounding of a corner computed on the plane
// (the points where a floor is cut along a wall's foot): 1e-12 of the coordinates' and the plane offset's size, some
// four thousand units in the last place, yet only 1e-5 for a scene 1e7 from the origin (1e-10 gave the same numbers
// in the partition furnace and in a furnace room with a box turned by 0.35 rad standing on its floor).
//
// The part of `back` in a pixel that `fronts` cover in the image (hidden_part): the receivers are projected as the
// task rasterized them (`project`, into the task's pixel coordinates, counter-clockwise), `back` clipped to the
// pixel's square, and the areas of its intersections with each front added up. Areas add up over the pieces of a
// split receiver, on either side, so a leaf's pieces are still hidden together as the leaf was (the factors a
// reused row keeps stay those of a fresh shot).
template <class Project>
struct PlaneOrder {
  static constexpr bool kActive = true;
  const ReceiverView& receivers;
  Vec3 eye;
  const Project* project = nullptr;  // project(receiver, out)
  detail::OrderBuffers* buffers = nullptr;
  std::size_t height = 1;  // pixels per column (the arena's pixel p is column p / height, row p % height)
  std::size_t pixel = 0;

  PlaneOrder at(std::size_t p) const {
    PlaneOrder bound = *this;
    bound.pixel = p;
    return bound;
  }

  double hidden_part(std::uint32_t back, std::span<const CoverageEntry> fronts) const {
    std::vector<Vec2>& shape = buffers->back;
    std::vector<Vec2>& in_pixel = buffers->in_pixel;
    std::vector<Vec2>& both = buffers->both;
    std::vector<Vec2>& scratch = buffers->scratch;
    const auto x = static_cast<double>(pixel / height), y = static_cast<double>(pixel % height);
    const std::array<Vec2, 4> square = {Vec2(x, y), Vec2(x + 1.0, y), Vec2(x + 1.0, y + 1.0), Vec2(x, y + 1.0)};
    (*project)(back, shape);
    if (shape.size() < 3) return 1.0;  // nothing on this face: hidden, as the plane says
    const Box box = box_of(shape);
    if (box.x_min >= x && box.x_max <= x + 1.0 && box.y_min >= y && box.y_max <= y + 1.0) {
      in_pixel.assign(shape.begin(), shape.end());  // a piece inside the pixel (most are)
    } else {
      convex_intersection(square, shape, in_pixel, scratch);
    }
    const double area = in_pixel.size() >= 3 ? signed_area(in_pixel) : 0.0;
    if (!(area > 0.0)) return 1.0;  // no area in the pixel: hidden, as the plane says
    const Box inside = box_of(in_pixel);
    double hidden = 0.0;
    for (std::size_t i = 0; i < fronts.size() && hidden < area; ++i) {
      const std::span<const Vec2> front_shape = projected(fronts[i].receiver);
      if (front_shape.size() < 3 || !inside.meets(box_of(front_shape))) continue;
      convex_intersection(in_pixel, front_shape, both, scratch);
      if (both.size() >= 3) hidden += std::max(0.0, signed_area(both));
    }
    return std::min(1.0, hidden / area);
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

  bool operator()(std::uint32_t front, std::uint32_t back) const {
    const Plane& plane = receivers.plane(front);
    if (!(plane.signed_distance(eye) > 0.0)) return false;  // seen edge on: nothing lies behind it
    bool strictly = false;
    for (const Vec3& corner : receivers.polygon(back)) {
      const double distance = plane.signed_distance(corner);
      const double on = 1e-12 * (std::max({std::abs(corner.x), std::abs(corner.y), std::abs(corner.z)}) +
                                 std::abs(plane.d));
      if (distance > on) return false;
      strictly = strictly || distance < -on;
    }
    return strictly;
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
  // Receiver i as place() projects it, counter-clockwise, into `out` (empty when it has nothing on the face): the
  // plane order's view of it.
  const auto project = [&](std::uint32_t i, std::vector<Vec2>& out) {
    ProjectedBox unused;
    const std::size_t m = clip_to_face(prepared_.local_polygon(i, b.local), face, prepared_.outside_mask(i), b.scratch,
                                       b.clipped);
    out.clear();
    if (m == 0 || !project_clipped(face, std::span<const Vec3>(b.clipped.data(), m), half, shift, b.projected, unused))
      return;
    out.assign(b.projected.begin(), b.projected.begin() + static_cast<std::ptrdiff_t>(m));
    if (signed_area(out) < 0.0) std::reverse(out.begin(), out.end());
  };
  // A re-shot subset: only the pixels its receivers may cover matter.
  const bool masked = tiles != nullptr;
  if (masked && tiles->empty()) {
    task_entries_[static_cast<std::size_t>(task)] = 0;
    return;
  }
  b.arena.reset(width, height);

  for (const std::uint32_t i : candidates) {
    const std::size_t m = place(i);
    if (m == 0 || (masked && !tiles->overlaps(box.x_min, box.x_max, box.y_min, box.y_max))) continue;
    InverseDepth depth = inverse_depth(face, prepared_.local_plane(i), half);
    depth.gamma += depth.alpha * shift;  // in the task's pixel coordinates
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
      PlaneOrder<decltype(project)>{receivers, eye_, &project, &b.order, column_height});
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
