// Hemicube geometry shared by the classical and the anti-aliased hemicube: the shooter's frame, the five
// faces and their pixel grids, the delta form-factor tables, back-face culling, and the clipping of receivers
// to the space in front of the shooter and to each face's frustum.
//
// Sources: Cohen and Greenberg, "The hemi-cube", SIGGRAPH 1985 (faces, delta form factors); Chandran, Kiran,
// Phani and Rai, "Anti-aliased hemicubes for radiosity", section 3.2 (back-face culling of the parent patch,
// clipping onto the hemicube); Sutherland and Hodgman 1974 (reentrant polygon clipping).
//
// Coordinates. Local coordinates (u, v, w) = (tangent, bitangent, normal) . (p - centre). Every face has an
// axis a (the coordinate along its outward direction) and two lateral coordinates (l1, l2):
//   top  (w): a = w,  l1 = u, l2 = v      side +u: a = u,  l1 = v, l2 = w      side -u: a = -u, l1 = v, l2 = w
//                                          side +v: a = v,  l1 = u, l2 = w      side -v: a = -v, l1 = u, l2 = w
// The frustum of a face is { a >= |l1|, a >= l2, and l2 >= -a on the top / l2 >= 0 on a side }: all five
// are bounded by planes through the shooter's centre, and they tile the half-space w >= 0.
// Pixel coordinates of a face (y up, pixel (x, y) covers [x, x+1) x [y, y+1)):
//   x = (l1 / a + 1) N / 2,   y = (l2 / a + 1) N / 2 on the top,   y = (l2 / a) N / 2 on a side.
// The top face is N x N pixels, a side face N x ceil(N / 2). For odd N the side faces' last row (at the seam
// with the top face) is a half row: only its lower half, [N/2 - 1/2, N/2), lies inside the face; its delta form
// factor is the integral over that half, and the classical hemicube samples the centre of that half.
//
// Exactness. The world-to-local transform is computed once per vertex per shot in doubles, so a vertex shared
// by several receivers gets one set of local coordinates. Every sidedness decision afterwards is exact on those
// doubles: the sign of w is decided by side_of_plane (core/predicates.h), and the face planes a -+ l = 0 are
// decided by the sign of the computed difference fl(a - l), which IEEE-754 rounding makes exactly the sign of
// a - l (zero exactly when a == l). Intersection points are computed in doubles from the edge's endpoints in a
// canonical (lexicographic) order, so two receivers that share an edge get bit-identical points, and the
// coordinate the plane fixes is snapped onto it (l := a, l := -a or l2 := 0), so the projected cut lies exactly
// on the face's border (pixel coordinate 0, N or N/2). Hence neighbours cover complementary areas: no gap, no
// double count.
#pragma once

#include "aarad/core/math.h"
#include "aarad/core/predicates.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/receiver_view.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

namespace aarad::formfactor {

enum class HemicubeFace : int { kTop = 0, kPosU = 1, kNegU = 2, kPosV = 3, kNegV = 4 };
inline constexpr int kHemicubeFaces = 5;

// Smallest and largest hemicube resolution accepted by the back ends.
inline constexpr int kMinResolution = 2;
inline constexpr int kMaxResolution = 8192;

// Which integral of the cosine kernel a delta form factor holds.
enum class DeltaRule {
  kMidpoint,   // Cohen and Greenberg 1985: the kernel at the cell centre times the cell area
  kExactCell,  // the exact form factor of the cell (closed form of its corners), which sums to 1
};

// Exact form factor from the origin (normal +w) to the rectangle [0, x] x [0, y] of the plane w = 1: Howell's
// B-3 with c = 1, signed (odd in x and in y), so cells follow by inclusion-exclusion of their corners.
double top_corner_form_factor(double x, double y);
// Exact form factor from the origin (normal +w) to the rectangle {u = 1, 0 <= v <= y, 0 <= w <= z}, odd in y:
//   (1 / 2 pi) [atan(y) - atan(y / sqrt(1 + z^2)) / sqrt(1 + z^2)]   (Baum et al. eq. 9 on that rectangle).
double side_corner_form_factor(double y, double z);

// The pixel grids and delta form-factor tables of a hemicube of resolution N.
class HemicubeGeometry {
 public:
  explicit HemicubeGeometry(int resolution, DeltaRule rule = DeltaRule::kExactCell);

  int resolution() const { return resolution_; }
  int width(HemicubeFace) const { return resolution_; }
  int height(HemicubeFace face) const { return face == HemicubeFace::kTop ? resolution_ : side_rows_; }
  std::size_t pixels(HemicubeFace face) const {
    return static_cast<std::size_t>(width(face)) * static_cast<std::size_t>(height(face));
  }
  // Delta form factor of every pixel of a face, row y at offset y * width: the form factor of the part of the
  // pixel inside the face. The five tables sum to 1 (kExactCell) or to 1 + O(1 / N^2) (kMidpoint).
  std::span<const double> delta(HemicubeFace face) const { return face == HemicubeFace::kTop ? top_ : side_; }
  // y (pixel units) at which the classical hemicube samples row `row` of a face: row + 1/2, or the centre of
  // the inside half for the half row.
  double sample_y(HemicubeFace face, int row) const {
    return face != HemicubeFace::kTop && row == side_rows_ - 1 ? half_row_sample_y_ : row + 0.5;
  }
  // Sum of the delta form factors of one face, and of all five.
  double face_total(HemicubeFace face) const;
  double total() const;

 private:
  int resolution_;
  int side_rows_;
  double half_row_sample_y_;
  // The top face's table and the side faces' one: the four side faces are congruent, so one table serves them.
  std::vector<double> top_, side_;
};

// The w of to_local for a point the floating-point filter could not sign (w: that unsure value), with its sign
// decided by side_of_plane: 0 in the plane, else w or the smallest normal double of the exact sign.
double signed_plane_distance(const Shooter& shooter, const Vec3& p, double w);
// Local coordinates (u, v, w) of p in the shooter's frame. The sign of w is made exactly the sign of
// normal . (p - centre) (side_of_plane), and w is exactly 0 when p lies in the shooter's plane. Inline: it runs
// for every mesh vertex in every shot, and almost every point is decided by the filter.
inline Vec3 to_local(const Shooter& shooter, const Vec3& p) {
  bool certain = false;
  double w = side_of_plane_value(shooter.centre, shooter.normal, p, certain);
  if (!certain) [[unlikely]] w = signed_plane_distance(shooter, p, w);
  const Vec3 d = p - shooter.centre;
  return {glm::dot(shooter.tangent, d), glm::dot(shooter.bitangent, d), w};
}
// Face coordinates (a, l1, l2) of a local point (see the table at the top of this file). Exact.
inline Vec3 to_face(HemicubeFace face, const Vec3& q) {
  switch (face) {
    case HemicubeFace::kTop: return {q.z, q.x, q.y};
    case HemicubeFace::kPosU: return {q.x, q.y, q.z};
    case HemicubeFace::kNegU: return {-q.x, q.y, q.z};
    case HemicubeFace::kPosV: return {q.y, q.x, q.z};
    case HemicubeFace::kNegV: return {-q.y, q.x, q.z};
  }
  return q;
}
// A receiver plane in local coordinates: normal rotated into the frame, d = signed distance of the shooter's
// centre (positive when the centre is on the front side).
inline Plane plane_to_local(const Shooter& shooter, const Plane& plane) {
  const Vec3& n = plane.normal;
  return Plane{{glm::dot(n, shooter.tangent), glm::dot(n, shooter.bitangent), glm::dot(n, shooter.normal)},
               plane.signed_distance(shooter.centre)};
}

// Back-face culling (paper, section 3.2): whether the front side of `plane` strictly contains `centre`,
// decided exactly (sign_of_linear).
bool faces_point(const Plane& plane, const Vec3& centre);
// Back-face culling per parent patch: receiver i faces a point when its patch does. A patch is decided once
// (faces_point), on the plane of its first receiver (receivers are coplanar with their patch), so all its pieces are
// culled together; sparse patch ids (patch_ids_dense) fall back to each receiver's own plane.
// Which receiver decides for each patch is kept between calls and found again only when the view changed
// (ReceiverView::revision and size), so a shot decides its patches in parallel, with no pass over the receivers.
// Whether patch ids up to `max_patch` over `receivers` receivers are few enough for tables by patch id: at most 16 x
// receivers + 1024. BackFaceCulling decides per patch, and PreparedReceivers::prepare_subset skips by patch, only then.
inline bool patch_ids_dense(std::uint32_t max_patch, std::size_t receivers) {
  return receivers > 0 && max_patch <= 16 * receivers + 1024;
}
class BackFaceCulling {
 public:
  // Decides every patch (or receiver) for a shot from `centre`; parallel, the same for any thread count.
  void decide(const Vec3& centre, const ReceiverView& receivers);
  // The same, except that with dense patch ids a patch is decided when first asked about (faces, patch_faces): a
  // subset's shot asks about few of the patches, and a whole shot decides them in its parallel pass over the
  // receivers instead of a pass of its own. Those may then be asked from several threads at once (a decision
  // depends on the patch and the centre only, so two threads deciding one patch store the same value).
  void decide_when_asked(const Vec3& centre, const ReceiverView& receivers);
  // Whether receiver i of the view of the last decide() or decide_when_asked() faces its centre.
  bool faces(std::size_t i) const { return per_patch_ ? patch_faces(patches_[i]) : receiver_faces_[i] != 0; }
  // Whether the receivers of patch p face the centre, when patches are decided (dense patch ids) and p has receivers.
  bool patch_faces(std::uint32_t p) const {
    std::uint8_t faces = std::atomic_ref<std::uint8_t>(patch_faces_[p]).load(std::memory_order_relaxed);
    if (faces == kUndecided) [[unlikely]] {
      faces = faces_point(planes_[patch_decider_[p]], centre_) ? 1 : 0;
      std::atomic_ref<std::uint8_t>(patch_faces_[p]).store(faces, std::memory_order_relaxed);
    }
    return faces != 0;
  }

 private:
  static constexpr std::uint8_t kUndecided = 2;
  void find_deciders(const ReceiverView& receivers);
  std::uint64_t revision_ = 0;  // of the view the deciders were found for (revisions start at 1)
  std::size_t size_ = 0;
  bool per_patch_ = false;
  std::span<const std::uint32_t> patches_;
  std::vector<std::uint32_t> decider_patch_, decider_receiver_;  // per patch that has receivers: its first receiver
  std::vector<std::uint32_t> patch_decider_;  // per patch id with receivers: its first receiver
  std::span<const Plane> planes_;
  Vec3 centre_{0.0};
  // Per patch id: 1 when it faces the centre, 0 when not, kUndecided until asked after decide_when_asked().
  mutable std::vector<std::uint8_t> patch_faces_;
  std::vector<std::uint8_t> receiver_faces_;  // per receiver, with sparse patch ids
};

inline constexpr std::uint32_t face_outcode_mask(HemicubeFace face) { return 0xFu << (4 * static_cast<int>(face)); }
inline constexpr std::uint32_t kOutcodeUNotPositive = 1u << 20;  // !(u > 0)
inline constexpr std::uint32_t kOutcodeUNotNegative = 1u << 21;  // !(u < 0)
inline constexpr std::uint32_t kOutcodeVNotPositive = 1u << 22;  // !(v > 0)
inline constexpr std::uint32_t kOutcodeVNotNegative = 1u << 23;  // !(v < 0)
// The top face's quarter lines u = -w / 2 and u = w / 2 (columns N / 4 and 3 N / 4 for N divisible by 4), with a
// margin of 1e-9 (|u| + |w|): a point not flagged lies beyond the line by far more than clipping's rounding moves
// the points it makes on the edges from it (face_tasks).
inline constexpr std::uint32_t kOutcodeNotRightOfQuarter = 1u << 24;       // !(2u + w > margin)
inline constexpr std::uint32_t kOutcodeNotLeftOfQuarter = 1u << 25;        // !(2u + w < -margin)
inline constexpr std::uint32_t kOutcodeNotRightOfThreeQuarters = 1u << 26;  // !(2u - w > margin)
inline constexpr std::uint32_t kOutcodeNotLeftOfThreeQuarters = 1u << 27;   // !(2u - w < -margin)

namespace detail {
// The outcode bits that difference k of frustum_outcode's (w - u, w + u, w - v, w + v, u - v, u + v) sets when it
// is negative (negative[1 << k]) or positive (positive[1 << k]); entry m is the OR over the bits of m.
struct OutcodeTables {
  std::array<std::uint32_t, 64> negative{}, positive{};
  constexpr OutcodeTables() {
    // Where each difference's sign lands in the outcode (see frustum_outcode).
    constexpr std::uint32_t kNegative[6] = {1u << 0, 1u << 1, 1u << 2, 1u << 3, (1u << 4) | (1u << 17),
                                            (1u << 5) | (1u << 13)};
    constexpr std::uint32_t kPositive[6] = {1u << 6, 1u << 10, 1u << 14, 1u << 18, (1u << 9) | (1u << 12),
                                            (1u << 8) | (1u << 16)};
    for (int m = 0; m < 64; ++m)
      for (int k = 0; k < 6; ++k)
        if ((m >> k) & 1) {
          negative[static_cast<std::size_t>(m)] |= kNegative[k];
          positive[static_cast<std::size_t>(m)] |= kPositive[k];
        }
  }
};
inline constexpr OutcodeTables kOutcodeTables{};
}  // namespace detail

// Outcodes of a local point: bit 4 f + k is set when the point is strictly outside plane k of face f
// (k = 0: a - l1 >= 0, 1: a + l1 >= 0, 2: a - l2 >= 0, 3: a + l2 >= 0 on the top, l2 >= 0 on a side). More bits
// say on which side the point lies of the lines where face tasks meet: u = 0, v = 0 and the top face's quarter
// lines (task_mask).
inline std::uint32_t frustum_outcode(const Vec3& local) {
  // face_outcode of every face, written out on (u, v, w): the same differences as through to_face, so the same
  // exact signs, without the per-face shuffle (this runs for every mesh vertex in every shot). The twenty
  // differences are six and their negatives: y - x is exactly -(x - y) and x + y is y + x in the rounding to
  // nearest the program runs in (-frounding-math keeps the compiler from assuming so), so "-(x) < 0" is "x > 0".
  // Bit k of the outcode, with a = w - u, b = w + u, c = w - v, d = w + v, e = u - v, f = u + v:
  //   top: a < 0 (0), b < 0 (1), c < 0 (2), d < 0 (3)   +u: e < 0 (4), f < 0 (5), a > 0 (6)
  //   -u:  f > 0 (8), e > 0 (9), b > 0 (10)              +v: e > 0 (12), f < 0 (13), c > 0 (14)
  //   -v:  f > 0 (16), e < 0 (17), d > 0 (18)            bit 3 of every side face: w < 0
  // The six "< 0" and the six "> 0" form two 6-bit masks, mapped to their bits by detail::kOutcodeTables.
  const double u = local.x, v = local.y, w = local.z;
  const double a = w - u, b = w + u, c = w - v, d = w + v, e = u - v, f = u + v;
  const unsigned negative = static_cast<unsigned>(a < 0.0) | static_cast<unsigned>(b < 0.0) << 1 |
                            static_cast<unsigned>(c < 0.0) << 2 | static_cast<unsigned>(d < 0.0) << 3 |
                            static_cast<unsigned>(e < 0.0) << 4 | static_cast<unsigned>(f < 0.0) << 5;
  const unsigned positive = static_cast<unsigned>(a > 0.0) | static_cast<unsigned>(b > 0.0) << 1 |
                            static_cast<unsigned>(c > 0.0) << 2 | static_cast<unsigned>(d > 0.0) << 3 |
                            static_cast<unsigned>(e > 0.0) << 4 | static_cast<unsigned>(f > 0.0) << 5;
  const std::uint32_t below = static_cast<std::uint32_t>(w < 0.0) * 0x88880u;  // bit 3 of every side face
  const double margin = 1e-9 * (std::abs(u) + std::abs(w)), quarter = 2.0 * u + w, three_quarters = 2.0 * u - w;
  const std::uint32_t sides = static_cast<std::uint32_t>(!(u > 0.0)) |
                              static_cast<std::uint32_t>(!(u < 0.0)) << 1 |
                              static_cast<std::uint32_t>(!(v > 0.0)) << 2 |
                              static_cast<std::uint32_t>(!(v < 0.0)) << 3 |
                              static_cast<std::uint32_t>(!(quarter > margin)) << 4 |
                              static_cast<std::uint32_t>(!(quarter < -margin)) << 5 |
                              static_cast<std::uint32_t>(!(three_quarters > margin)) << 6 |
                              static_cast<std::uint32_t>(!(three_quarters < -margin)) << 7;
  static_assert(kOutcodeUNotPositive == 1u << 20 && kOutcodeNotLeftOfThreeQuarters == 1u << 27);
  const std::uint32_t halves = sides << 20;  // kOutcodeUNotPositive to kOutcodeNotLeftOfThreeQuarters
  return below | halves | detail::kOutcodeTables.negative[negative] | detail::kOutcodeTables.positive[positive];
}

// Largest number of vertices one Sutherland-Hodgman pass against a plane can write for an m-gon, convex or
// concave: m + floor(m / 2). The pass writes every vertex inside and two crossings per run of vertices outside;
// each such run holds at least one vertex and is followed by at least one inside, so there are at most m / 2 of
// them and each adds at most one vertex net. (A convex polygon has at most one run: m + 1.)
inline constexpr std::size_t plane_clipped_capacity(std::size_t m) { return m + m / 2; }

// Largest number of vertices clip_to_face can return for an m-gon: four planes.
inline constexpr std::size_t clipped_capacity(std::size_t m) {
  for (int plane = 0; plane < 4; ++plane) m = plane_clipped_capacity(m);
  return m;
}

// Clips a polygon given in local coordinates to the frustum of `face` (Sutherland-Hodgman with exact
// sidedness, canonical intersection points and snapping; see the top of this file) and returns the polygon
// in face coordinates (a, l1, l2) in `out` (capacity clipped_capacity(polygon.size())), or 0 vertices when
// nothing is left. `scratch` needs the same capacity. `outside_mask` is the OR of the vertices' outcodes:
// planes no vertex is outside of are skipped.
std::size_t clip_to_face(std::span<const Vec3> local_polygon, HemicubeFace face, std::uint32_t outside_mask,
                         std::span<Vec3> scratch, std::span<Vec3> out);

// Pixel coordinates of a point in face coordinates with a > 0 (see the top of this file).
inline Vec2 project_to_pixels(HemicubeFace face, const Vec3& f, double half_resolution) {
  const double x = (f.y / f.x + 1.0) * half_resolution;
  const double y = face == HemicubeFace::kTop ? (f.z / f.x + 1.0) * half_resolution : (f.z / f.x) * half_resolution;
  return {x, y};
}

// A clipped polygon projected onto a face: its bounding box in pixels and the range of 1 / depth over its vertices.
struct ProjectedBox {
  double x_min, x_max, y_min, y_max;
  double lo, hi;  // smallest and largest 1 / depth (1 / a) of the vertices
};

// Projects the clipped polygon `clipped` (face coordinates) into `out`, moved left by `shift` pixels, and
// fills `box`. Returns false, leaving `box` undefined, when a vertex is not strictly in front of the shooter
// (a polygon squeezed onto the shooter's plane by the clipping: it covers no solid angle).
inline bool project_clipped(HemicubeFace face, std::span<const Vec3> clipped, double half_resolution, double shift,
                            std::span<Vec2> out, ProjectedBox& box) {
  box = {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
         std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
         std::numeric_limits<double>::infinity(), 0.0};
  for (std::size_t k = 0; k < clipped.size(); ++k) {
    const Vec3& f = clipped[k];
    if (!(f.x > 0.0)) return false;
    Vec2 p = project_to_pixels(face, f, half_resolution);
    p.x -= shift;
    out[k] = p;
    box.x_min = std::min(box.x_min, p.x);
    box.x_max = std::max(box.x_max, p.x);
    box.y_min = std::min(box.y_min, p.y);
    box.y_max = std::max(box.y_max, p.y);
    box.lo = std::min(box.lo, 1.0 / f.x);
    box.hi = std::max(box.hi, 1.0 / f.x);
  }
  return true;
}

// 1 / depth of a receiver plane along the rays of a face, as an affine function of pixel coordinates:
// the ray through pixel point (x, y) meets the plane at axis coordinate a = 1 / (alpha x + beta y + gamma).
// (1 / depth is affine in screen space, which makes it cheap per pixel.)
struct InverseDepth {
  double alpha = 0.0, beta = 0.0, gamma = 0.0;
  double at(double x, double y) const { return alpha * x + beta * y + gamma; }
};
inline InverseDepth inverse_depth(HemicubeFace face, const Plane& local_plane, double half_resolution) {
  // Ray through face point (l1 / a, l2 / a) = (X, Y) meets n . q + d = 0 at a = -d / (n_a + n_1 X + n_2 Y),
  // with X = x / h - 1 and Y = y / h - 1 (top) or y / h (side), h = half_resolution.
  const Vec3 n = to_face(face, local_plane.normal);
  const double k = -1.0 / local_plane.d;
  InverseDepth r;
  r.alpha = k * n.y / half_resolution;
  r.beta = k * n.z / half_resolution;
  r.gamma = k * (n.x - n.y - (face == HemicubeFace::kTop ? n.z : 0.0));
  return r;
}

// Columns [x0, x1) of one face: the unit of parallel work of both hemicubes. Every face is cut into strips of a
// quarter of the top face's pixels: the top face into four column quarters, each side face into its two column
// halves. Twelve tasks of one size, which two threads share evenly even when most of a shot's receivers lie in one
// face: a finely meshed floor seen from a wall fills one side face, and with six tasks of a side face's size the
// largest took 46 % of an office shot's work on average (docs/benchmarks.md).
struct FaceTask {
  HemicubeFace face;
  int x0, x1;
};
inline constexpr int kFaceTasks = 12;
inline std::array<FaceTask, kFaceTasks> face_tasks(int resolution) {
  const int n = resolution, h = n / 2, q = n / 4;
  std::array<FaceTask, kFaceTasks> tasks{FaceTask{HemicubeFace::kTop, 0, q}, FaceTask{HemicubeFace::kTop, q, h},
                                         FaceTask{HemicubeFace::kTop, h, h + q},
                                         FaceTask{HemicubeFace::kTop, h + q, n}};
  std::size_t k = 4;
  for (const HemicubeFace face :
       {HemicubeFace::kPosU, HemicubeFace::kNegU, HemicubeFace::kPosV, HemicubeFace::kNegV}) {
    tasks[k++] = FaceTask{face, 0, h};
    tasks[k++] = FaceTask{face, h, n};
  }
  return tasks;
}
// A set of face tasks: bit k for task k of face_tasks.
using TaskSet = std::uint16_t;
static_assert(kFaceTasks <= 16);

// Bits of PreparedReceivers::face_mask after the five faces': some vertex of the receiver lies on that side of a
// line where two tasks meet (from the outcodes' bits of the same names).
using FaceMask = std::uint16_t;
inline constexpr FaceMask kMaskUNotPositive = 1u << 5;
inline constexpr FaceMask kMaskUNotNegative = 1u << 6;
inline constexpr FaceMask kMaskVNotPositive = 1u << 7;
inline constexpr FaceMask kMaskVNotNegative = 1u << 8;
inline constexpr FaceMask kMaskNotRightOfQuarter = 1u << 9;
inline constexpr FaceMask kMaskNotLeftOfQuarter = 1u << 10;
inline constexpr FaceMask kMaskNotRightOfThreeQuarters = 1u << 11;
inline constexpr FaceMask kMaskNotLeftOfThreeQuarters = 1u << 12;
// The bits a receiver's face_mask needs, all of them, to cover part of the task's columns: its face, and the sides
// of the lines that bound the task's columns: a cheap test before clipping. Column x = (l1 / a + 1) N / 2 of a face
// (l1 = u on the top face and the v faces, v on the u faces) is N / 2 at l1 = 0, and on the top face N / 4 and
// 3 N / 4 at 2u + w = 0 and 2u - w = 0. Clipping keeps each of those linear functions within its range over the
// vertices (new vertices lie on edges; the quarter lines' margin covers the rounding), so a receiver with u > 0 at
// every vertex has nothing left of the top face's middle, and so on. A line off a pixel boundary (N odd, or not
// divisible by 4 for the quarters) gives no test on the side where its pixel column lies.
inline FaceMask task_mask(const FaceTask& task, int resolution) {
  const auto face = static_cast<FaceMask>(1u << static_cast<int>(task.face));
  const int n = resolution, h = n / 2;
  const bool even = n % 2 == 0, quarters = n % 4 == 0;
  const bool top = task.face == HemicubeFace::kTop;
  const FaceMask not_positive = top || task.face == HemicubeFace::kPosV || task.face == HemicubeFace::kNegV
                                    ? kMaskUNotPositive
                                    : kMaskVNotPositive;
  const FaceMask not_negative = not_positive == kMaskUNotPositive ? kMaskUNotNegative : kMaskVNotNegative;
  FaceMask need = face;
  if (task.x1 <= h) need |= not_positive;  // left of the middle: l1 <= 0 at some vertex
  if (task.x0 >= h && even) need |= not_negative;
  if (top && quarters) {
    if (task.x1 == n / 4) need |= kMaskNotRightOfQuarter;
    if (task.x0 == n / 4) need |= kMaskNotLeftOfQuarter;
    if (task.x1 == 3 * n / 4) need |= kMaskNotRightOfThreeQuarters;
    if (task.x0 == 3 * n / 4) need |= kMaskNotLeftOfThreeQuarters;
  }
  return need;
}

// The pixels of one task that a re-shot subset's receivers may cover (backend.h: compute() for a subset), as
// tiles of 2^k x 2^k pixels, at most 64 to a row of the mask. A pixel's coverage list or z-buffer entry depends
// only on the receivers that reach that pixel, so a receiver whose projected box meets no marked tile changes
// nothing the subset gets and is skipped: a re-shoot into a few new leaves rasterizes only what lies around them.
// Boxes are in the task's pixel coordinates; the pixels a box may touch are floor(min) .. floor(max) on each axis.
class TileMask {
 public:
  // An empty mask over a width x height viewport.
  void reset(int width, int height);
  void add(double x_min, double x_max, double y_min, double y_max);
  bool overlaps(double x_min, double x_max, double y_min, double y_max) const;
  bool empty() const { return empty_; }

 private:
  // Tiles [t0, t1] of the viewport's pixels [0, size) that the pixel range of [lo, hi] meets; false when none.
  bool tiles(double lo, double hi, int size, int& t0, int& t1) const;
  int width_ = 0, height_ = 0, shift_ = 0;
  bool empty_ = true;
  std::vector<std::uint64_t> rows_;  // bit t of row r: tile (t, r)
  int marked_low_ = 0, marked_high_ = -1;  // the rows with a marked tile lie in [marked_low_, marked_high_]
};

// Per face task, the receivers on its list: ids[k][0, size[k]). The vectors only grow, to the largest view seen: cut
// back to each list's length and grown again, they were zeroed over the difference in every shot (25 million
// instructions of memset over a single-thread Cornell box solve, docs/benchmarks.md).
struct TaskLists {
  std::array<std::vector<std::uint32_t>, kFaceTasks> ids;
  std::array<std::size_t, kFaceTasks> size{};
  std::span<const std::uint32_t> list(std::size_t k) const { return {ids[k].data(), size[k]}; }
};

// A range [lo, hi] of 1 / depth, lo >= 0 and hi possibly infinite (a surface reaching the plane of the face's
// centre, or behind it).
struct InverseDepthRange {
  double lo, hi;
};

// Per-shot preparation shared by both hemicubes: local coordinates, outcodes, culling and the faces each
// receiver may reach. Reused across shots without reallocating once warmed up.
class PreparedReceivers {
 public:
  // Fills everything for `shooter` over all receivers (all occlude); parallel over receivers, deterministic.
  void prepare(const Shooter& shooter, const ReceiverView& receivers);
  // The same for a shot into `subset` alone (backend.h), where a receiver outside the subset changes what the
  // subset gets only if it covers a pixel that one of the subset's receivers may cover: the back ends skip every
  // receiver whose projected box meets none of the subset's tiles (TileMask). Here whole patches are skipped before
  // any of their points is transformed: the subset's receivers are prepared and their tiles marked per face task,
  // then a patch's receivers are prepared only when a ball and a box round them may project onto a marked tile of
  // some task, and go only on the lists of those tasks (task_receivers). Every other receiver gets face mask 0. The
  // back ends rasterize the same receivers as after prepare(), so the numbers are the same; a re-shot subset usually
  // lies in a few parts of the hemicube, and most of the scene is never looked at. With sparse patch ids
  // (BackFaceCulling) this is prepare().
  void prepare_subset(const Shooter& shooter, const ReceiverView& receivers, std::span<const std::uint32_t> subset,
                      const HemicubeGeometry& geometry);
  // How many receivers the last prepare or prepare_subset prepared.
  std::size_t prepared_count() const { return prepared_count_; }
  // After prepare_subset: the tiles of task `index` of face_tasks that the subset's receivers may cover, in the
  // task's pixel coordinates (columns counted from its x0). A receiver whose projected box meets none of them changes
  // nothing the subset gets, and the back ends skip it.
  const TileMask& subset_tiles(int index) const { return masks_[static_cast<std::size_t>(index)]; }

  // Receiver i's vertices in local coordinates, copied into `buffer` (room for its corners).
  std::span<const Vec3> local_polygon(std::size_t i, std::span<Vec3> buffer) const {
    const std::size_t first = offsets_[i], count = offsets_[i + 1] - first;
    for (std::size_t k = 0; k < count; ++k) buffer[k] = point_local_[corner_points_[first + k]];
    return buffer.first(count);
  }
  // Bit f set when receiver i is not culled and may touch face f; then the kMask bits of the lines where tasks meet.
  FaceMask face_mask(std::size_t i) const { return face_mask_[i]; }
  // OR of the outcodes of receiver i's vertices.
  std::uint32_t outside_mask(std::size_t i) const { return outside_[i]; }
  // Receiver i's plane in local coordinates (plane_to_local), computed when asked: most receivers never need it.
  Plane local_plane(std::size_t i) const { return plane_to_local(shooter_, planes_[i]); }
  // After prepare or prepare_subset: finds what surface_inverse_depths gives for this shot (the AA hemicube's depth
  // keys; the classical hemicube does not ask).
  void prepare_surface_ranges(const ReceiverView& receivers);
  // Bounds on 1 / depth (1 / a in the coordinates of `face`) over receiver i's physical surface: over the box, on the
  // scene's axes, of the points of the view's receivers with its surface id (for a view marked as refining the one
  // the boxes were found for, that view's boxes, which hold it). The same for every piece of one surface in a shot,
  // whole or a subset.
  // In units of inverse_depth_scale(): the ranges are multiplied by it.
  InverseDepthRange surface_inverse_depths(std::size_t i, HemicubeFace face) const {
    return surface_ranges_[std::size_t{surface_slot_[i]} * kHemicubeFaces + static_cast<std::size_t>(face)];
  }
  // After prepare_surface_ranges: a power of two near the extent of the surfaces' boxes, by which the AA hemicube
  // multiplies every 1 / depth of the shot, so that its keys are near 1 at any scene scale. The keys' spreads are
  // floats (coverage_list.h), which hold 1e-38 to 3e38: a scene 1e45 across has keys near 1e-45, whose spreads
  // rounded to 0 or to the smallest subnormal, and one 1e-40 across keys near 1e40, whose spreads overflowed. A
  // power of two scales every key, spread and range exactly, so the lists, and the factors, are those of the scene
  // scaled to size, bit for bit.
  double inverse_depth_scale() const { return inverse_depth_scale_; }
  // After prepare_surface_ranges: the diagonal of the surfaces' boxes together (the scene's, for a view of a whole
  // scene), the scale of the scene's rounding (coverage_list.h, KeyRounding); 0 for an empty view.
  double diagonal() const { return diagonal_; }
  // For every task k of face_tasks on `face`, the receivers that may touch its columns (their face_mask has the
  // task_mask; after prepare_subset, only those it put on that task's list), in order, into lists' list k: one pass
  // without branches over the receivers for all the face's tasks, so a task's loop does not mispredict on every
  // other receiver.
  void task_receivers(HemicubeFace face, const std::array<FaceTask, kFaceTasks>& tasks, int resolution,
                      TaskLists& lists) const;

 private:
  // A ball holding every point of one patch's receivers (prepare_subset).
  struct PatchBall {
    Vec3 centre;
    double radius;
  };
  // Sets up a shot from `shooter` (back-face culling decides each patch when first asked about).
  void start(const Shooter& shooter, const ReceiverView& receivers);
  // surface_slot_ and surface_boxes_, found again when the view changed.
  void find_surface_boxes(const ReceiverView& receivers);
  // point_local_[p] and point_code_[p] of point p of the view, at `world`.
  void prepare_point(std::size_t p, const Vec3& world) {
    const Vec3 q = to_local(shooter_, world);
    point_local_[p] = q;
    point_code_[p] = frustum_outcode(q);
  }
  // outside_[i] and face_mask_[i] from the outcodes of receiver i's points.
  void prepare_receiver(std::size_t i);
  // masks_: per task, the tiles of the subset's receivers, which must be prepared.
  void mark_subset_tiles(std::span<const std::uint32_t> subset, const HemicubeGeometry& geometry);
  // The receivers of every patch and their balls, found again when the view changed; false with sparse patch ids.
  bool find_patch_balls(const ReceiverView& receivers);
  Shooter shooter_;
  std::span<const std::uint32_t> offsets_;
  std::span<const std::uint32_t> corner_points_;
  std::span<const Plane> planes_;
  std::vector<Vec3> point_local_;           // per point of the view: local coordinates
  std::vector<std::uint32_t> point_code_;   // per point: frustum_outcode
  std::vector<std::uint32_t> outside_;
  std::vector<FaceMask> face_mask_;
  BackFaceCulling culling_;
  std::size_t prepared_count_ = 0;
  // prepare_subset's state. task_bits_[i]: bit k when receiver i goes on task k's list; every bit for the subset's.
  static constexpr TaskSet kInSubset = 0xffff;
  bool subset_ = false;
  std::vector<TaskSet> task_bits_;
  std::array<TileMask, kFaceTasks> masks_;
  std::uint64_t balls_revision_ = 0;  // of the view the balls were found for (revisions start at 1)
  std::size_t balls_size_ = 0;
  bool balls_dense_ = false;
  // A box holding every point of one patch's receivers: centre, axes (two in the patch's plane, then its normal)
  // and half extents along them.
  struct PatchBox {
    Vec3 centre;
    std::array<Vec3, 3> axes;
    Vec3 half;
  };
  // The patches with receivers, one per slot, ordered so that kClusterPatches consecutive slots (a cluster) lie
  // close together; per slot its ball, box and (in prepare_subset) the tasks it may reach. A cluster's box, on the
  // scene's axes and holding its patches' boxes, is tested first, and before it the box of its group of
  // kGroupClusters consecutive clusters.
  static constexpr std::size_t kClusterPatches = 16, kGroupClusters = 8;
  // slot_patch_: `patches` in the order of their centres along a Morton curve.
  void group_patches(std::span<const std::uint32_t> patches, std::span<const Vec3> centres);
  std::vector<std::uint32_t> slot_patch_;
  std::vector<PatchBall> slot_balls_;
  std::vector<PatchBox> slot_boxes_;
  std::vector<TaskSet> slot_bits_;
  std::vector<PatchBox> cluster_boxes_, group_boxes_;
  std::vector<std::uint32_t> patch_first_;        // per patch id: its receivers are patch_receivers_[first, next)
  std::vector<std::uint32_t> patch_receivers_;
  std::vector<std::uint8_t> point_wanted_;    // per point, in prepare_subset: 1 once a listed receiver claimed it
  std::vector<std::uint32_t> reached_slots_;  // in prepare_subset: the slots of the patches that may reach a tile
  std::vector<std::uint32_t> listed_;         // the receivers prepare_subset may put on a list, in order
  std::vector<std::uint64_t> listed_bits_;    // bit i % 64 of word i / 64: receiver i is listed
  // Per receiver, a slot for its surface id (slots numbered in order of first appearance); per slot, the box on the
  // scene's axes of its receivers' points (lowest, highest), and per shot and face the range of 1 / a over that box.
  std::uint64_t surfaces_revision_ = 0;  // of the view the slots and boxes were found for
  std::size_t surfaces_size_ = 0;
  std::vector<std::uint32_t> surface_slot_;
  std::unordered_map<std::uint32_t, std::uint32_t> slot_of_surface_;
  std::vector<std::array<Vec3, 2>> surface_boxes_;
  std::vector<InverseDepthRange> surface_ranges_;  // kHemicubeFaces per slot, times inverse_depth_scale_
  double inverse_depth_scale_ = 1.0;
  double diagonal_ = 0.0;
};

// Per face task: (receiver, factor) for every receiver the task rasterized, with no occlusion (the back ends'
// add_unoccluded). Added up in task order, so the sums do not depend on the number of threads.
using UnoccludedList = std::vector<std::pair<std::uint32_t, double>>;
// Throws aarad::Error, adding nothing, when out is shorter than a receiver index in the lists.
void add_unoccluded_lists(std::span<const UnoccludedList> lists, std::span<double> out);

// Runs run(k) for k = 0 .. kFaceTasks - 1 on the threads of the current TBB arena, the tasks of most receivers
// (loads[k]: the receivers on task k's list) first: each thread takes the next task when it is free, so the small
// ones fill in at the end (longest processing time first). Six uneven tasks in index order left one thread
// waiting on the last big one. Each task's result depends only on the task, so the order changes no number.
void run_face_tasks(const std::array<std::size_t, kFaceTasks>& loads, const std::function<void(int)>& run);
// The partial form factors of a shot's face tasks: per task, a sum per receiver, and the receivers the task may
// add to (its PreparedReceivers::task_receivers). Combined in task order, so the result does not depend on the
// thread count; only the listed entries are read and cleared again, not every task's whole array.
class TaskSums {
 public:
  // Lists every task's receivers (in parallel) and makes every task's sums zero and as long as the view (cleared in
  // full only when the last shot did not reach combine(); a view of another size only sets the sums it adds).
  void start(const std::array<FaceTask, kFaceTasks>& tasks, int resolution, const PreparedReceivers& prepared,
             std::size_t receivers);
  std::span<double> sums(int task) { return sums_[static_cast<std::size_t>(task)]; }
  std::span<const std::uint32_t> receivers(int task) const { return lists_.list(static_cast<std::size_t>(task)); }
  // Per task, the receivers on its list (run_face_tasks' loads).
  std::array<std::size_t, kFaceTasks> loads() const;
  // out[i] = the tasks' sums added in task order, for every i of `subset` (every receiver when it is empty);
  // leaves every sum zero again.
  void combine(std::span<const std::uint32_t> subset, std::span<double> out);

 private:
  std::array<std::vector<double>, kFaceTasks> sums_;
  TaskLists lists_;
  bool clean_ = false;
};

// Checks a resolution for the back ends; throws aarad::Error naming the accepted range.
void check_resolution(int resolution);

}  // namespace aarad::formfactor
