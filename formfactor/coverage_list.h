// The per-pixel coverage lists of the anti-aliased hemicube: Chandran, Kiran, Phani and Rai, "Anti-aliased
// hemicubes for radiosity", section 3.2.1.
//
// Every pixel keeps the receivers that cover part of it, sorted front to back on insertion (insertion sort, as
// the paper does). Walking a list front to back, receiver k gets the visible fraction
//     E_k = A_k (1 - f_{k-1}),   f_k = f_{k-1} + E_k,   f_{-1} = 0,
// where A_k is the fraction of the pixel's area the receiver covers.
//
// Layers: entries that cannot be ordered inside the pixel. The recurrence treats every entry as lying behind
// the ones before it. That is wrong for receivers that are side by side in the pixel rather than one behind the
// other: pieces of one surface, and different surfaces that meet inside the pixel (two walls at a corner, a
// block standing on the floor). There the entry behind loses A_front A_back of its share (the paper's pure
// underestimation, section 3.2.5), a deficit along every junction of the scene. The paper lets entries at
// identical depth share the f in front of them; we generalise that rule. Each entry carries the range of its
// depth key over the part of the pixel it can occupy (key +- spread). Walking front to back, an entry whose range
// overlaps the ranges of the entries before it joins their layer (pieces of one surface always do). A layer
// whose coverages add up to at most 1 is taken as side by side: every entry gets A (1 - f_front), f_front being
// the f in front of the layer, and f grows by the layer's total after it; the pieces of a corner or of a tiled
// surface then add up exactly. A layer whose coverages add up to more than 1 must overlap in the pixel, so its
// entries are walked with the recurrence, a group of one surface at a time (consecutive entries of one surface
// share the f in front of their group). With no overlapping ranges this is the paper's walk, entry for entry.
//
// A full pixel. A group of one surface whose coverages add up to 1 (within kFullCoverage) hides everything
// behind it: the walk gives E = A (1 - 1) = 0 there. The arena then drops the entries behind that group and
// refuses new entries that would go behind it, so a covered pixel stops growing (the paper: "when the entire
// pixel area is consumed, no items are inserted"). Three kinds of entries are still accepted by a full pixel:
// entries in front of the full group (they occlude part of it; it stays full, since the group's own sum does not
// change); entries of the full group's own surface, which join the group (for a surface tiled by its pieces they
// are rounding crumbs; the walk caps the group so that f never exceeds 1); and entries of another plane whose depth
// range reaches into the group's, which may stand in front of part of it: the group's pieces tile the pixel, but
// where the surface runs on behind another that meets it there (a floor past the foot of a wall standing on it),
// some of them lie behind that other surface, and a walk that knows the planes (CoverageWalk) puts them after it.
// Fullness is decided from a group's own coverage sum, not from f, because the product form of f only reaches 1
// through a single full group. An entry dropped this way would get E = 0 from the walk anyway: its range lies
// behind the full group's, so it walks after the group, when f is 1. A single entry that covers the pixel (a full
// entry, kept inline by the arenas) is such a group of one: it keeps the partial entries whose ranges reach into its
// own, and is walked among them when they do (CoverageArena::walk_pixel), so that a leaf covering the pixel and its
// pieces covering it together are walked alike.
//
// Memory: pooled arrays per pixel list (PartialLists), reset per face or block without freeing; no heap
// allocation per entry once the pools have grown to the largest face seen.
#pragma once

#include "aarad/core/scene.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace aarad::formfactor {

inline constexpr std::uint32_t kNoSurface = 0xFFFFFFFFu;
// A group whose coverage sum reaches this hides what lies behind it.
inline constexpr double kFullCoverage = 1.0 - 1e-12;
// A layer whose coverages add up to at most 1 + kLayerSlack is taken as side by side: rounding, of the exact areas
// and of the scene's coordinates. Surfaces meeting at a junction of a file written in single precision (what
// Blender stores) or with few decimals, or far from the origin, overlap by a rounding of the coordinates, which
// in a pixel is far more than a rounding of its area (1e-9 here before): the recurrence then took A_front A_back
// from the one behind, as the paper's walk does at every junction. The Cornell box with its coordinates rounded to
// single precision lost 7.7e-4 of the light's first shot (elements at the blocks' feet up to 35 %), a closed box
// with one wall 1e-7 inside the others' ends 3.5e-4 to 2.3e-3 (test). What side by side gives too much when the
// entries do overlap is at most their overlap, here at most the slack (take_share caps the pixel at 1).
inline constexpr double kLayerSlack = 1e-4;
// Depth ranges closer than this, relative to the key, overlap: the rounding of two planes evaluated at a junction,
// which is that of the scene's coordinates, not of a double. Scene takes faces whose vertices lie within
// kPlaneDistance of the diagonal of one plane as coplanar (scene.h), and a depth is at most about the diagonal, so
// ranges that far apart are a rounding of the input. Two surfaces of different materials meeting in one plane (a
// ceiling and its lamp) have their planes fitted apart: in a rotated room written with 9 digits their keys differ by
// 1.2e-9 at their junction, while seen face on their spreads are 1e-11; with 1e-9 here the second was walked behind
// the first and lost A_1 A_2 of every pixel along the junction (the room's factors from its floor summed to
// 1 - 8.7e-5 at N = 100; now 1 - 1.7e-10, as with one material).
inline constexpr double kLayerTouch = kPlaneDistance;
// Keys closer than this, relative to the key, are one plane's (with equal spreads: same_plane_keys). Tighter than
// kLayerTouch: two planes meeting on a pixel's ray have equal keys there, and where the view is symmetric about
// their junction equal spreads too (a ceiling and a wall at a corner), which must not make them one plane.
inline constexpr double kSamePlaneKeys = 1e-9;

// The rounding of the scene's coordinates in the keys of one shot (see "Layers"). Scene takes faces whose vertices lie
// within delta = kPlaneDistance x its diagonal of one plane as coplanar: two surfaces of one plane, fitted apart, may
// lie up to 2 delta apart in depth where they meet, however far from the shooter. A key is s / a (a the depth along
// the face's axis, s the shot's power of two), so 2 delta of depth is 2 delta k^2 / s of key: kLayerTouch, relative
// to the key, is that only for surfaces a diagonal away. Nearer, two coplanar surfaces seen face on (spreads of 1e-7
// of the key) were two layers, and the second lost A_1 A_2 of every pixel along their junction: a room written with 6
// digits, its ceiling seen from its floor, had such keys 3.5e-6 apart, relative (test
// HemicubeAccuracy.TurnedRoomOfTwoMaterialsWrittenWithSixDigitsSumsToOne). Zero (the default, and what an order
// without a `rounding` member gives: the lists of the tests) keeps kLayerTouch alone.
struct KeyRounding {
  double touch = 0.0;  // keys k and k' are one plane's rounding apart when |k - k'| <= touch k^2 (2 delta / s)
  double touch_at(double key) const { return std::max(kLayerTouch * std::abs(key), touch * key * key); }
};

// The scene's rounding an order knows (its member `rounding`), none when it knows none.
template <class Order>
KeyRounding rounding_of(const Order& order) {
  if constexpr (requires { order.rounding; }) {
    return order.rounding;
  } else {
    return KeyRounding{};
  }
}

struct CoverageEntry {
  double depth = 0.0;     // any key that grows with the distance along the pixel's ray; smaller is nearer
  double coverage = 0.0;  // A: fraction of the pixel's area covered by the receiver, in [0, 1]
  std::uint32_t receiver = 0;
  std::uint32_t surface = 0;  // physical-surface id: entries of one surface do not occlude each other
  float spread = 0.0f;        // the key ranges over [depth - spread, depth + spread] in the pixel (rounded up)
};

// Whether two entries have the key of one plane in the pixel: equal keys (to kSamePlaneKeys, the rounding of two
// surfaces' planes computed apart) and equal spreads (to float rounding). Two different planes have equal keys only
// where they meet on the pixel's ray, and then equal spreads only by coincidence.
inline bool same_plane_keys(const CoverageEntry& a, const CoverageEntry& b) {
  return std::abs(a.depth - b.depth) <= kSamePlaneKeys * std::abs(b.depth) &&
         std::abs(a.spread - b.spread) <= 1e-6f * std::max(a.spread, b.spread);
}

// Equal keys. Two surfaces lying on one another in one plane (a lamp laid on a ceiling, which the import warns of)
// have the same key in every pixel they share, exactly when their planes are the same numbers. Which of them is in
// front there must not depend on the order the receivers arrive in: a leaf that won a pixel by arriving first, split,
// had pieces numbered after the other surface's, which then won; the pieces of the leaf shared its factor in
// proportion to what little they got at the pixel's edges, and a plate under such a lamp ended with radiosities from
// -383 to 366 (test HemicubeAccuracy.SurfacesOnOneAnotherInOnePlaneHideOneAnotherWhateverTheirPieces). At equal keys
// the surface with the lower id is in front, in both hemicubes: the first surface of the file.
inline bool in_front_at_equal_key(std::uint32_t surface, std::uint32_t other_surface) {
  return surface < other_surface;
}

// Whether `entry` lies wholly behind `full`, the head of a group of one surface that covers the pixel (or an entry
// that covers it alone): its depth range starts behind the group's, or it lies in the group's plane (coplanar
// surfaces, which the group's pieces cover), but for an entry at the group's very key that is in front of it by the
// rule of equal keys. An entry whose range reaches into the group's may lie in front of part of it, where a surface
// of the group runs on behind another (see "A full pixel" above), and is kept for the walk.
inline bool hidden_by_full_group(const CoverageEntry& full, const CoverageEntry& entry) {
  const double far = full.depth + full.spread;
  if (!(entry.depth - entry.spread <= far + kLayerTouch * std::abs(far))) return true;
  return same_plane_keys(entry, full) &&
         !(entry.depth == full.depth && in_front_at_equal_key(entry.surface, full.surface));
}

// Whether a full entry of `surface` at key `depth` takes a pixel whose nearest full entry is at `full_depth`, of
// `full_surface`: nearer, or at the same key and in front by the rule of equal keys.
inline bool takes_full_pixel(double depth, std::uint32_t surface, double full_depth, std::uint32_t full_surface) {
  return depth < full_depth || (depth == full_depth && in_front_at_equal_key(surface, full_surface));
}

// Adds `share` to a pixel's f (`covered`), capped so that f never exceeds 1 (overlapping pieces of one surface,
// rounding); returns what was added, E.
inline double take_share(double share, double& covered) {
  double e = std::min(share, 1.0 - covered);
  if (e < 0.0) e = 0.0;
  covered += e;
  return e;
}

// Where receiver `back` lies against the plane of receiver `front`, as the shooter sees it: wholly behind it (every
// point of it on the far side of that plane or on it, some strictly behind), across it (some points strictly on
// either side), or not behind it at all. Wherever `front` and a part of `back` behind its plane overlap in the image,
// `front` hides that part.
enum class PlaneSide : std::uint8_t { kNotBehind, kBehind, kAcross };

// What the walk knows of the receivers' places besides their keys: side(front, back), a PlaneSide. This one knows
// nothing (the lists of the tests, the paper's walk); the AA hemicube asks the receivers' polygons (aa_hemicube.cpp).
//
// An active order also measures parts of an entry of `back` in the pixel, as fractions of its area there. A cell
// of it is its part behind the planes of the receivers `behind` and in front of those of `in_front` (the whole
// entry when both are empty):
// - cell_part(back, behind, in_front): the cell;
// - hidden_part(back, behind, in_front, fronts): the part of the cell that the entries `fronts` cover in the image
//   (they are of a surface whose plane the cell lies behind); the rest of it is seen beside them (a floor's piece
//   past the end of a wall standing on it).
// Both are areas in the image, so they add up over the pieces of a split receiver. An order bound to a pixel comes
// from at(pixel).
struct NoPlaneOrder {
  static constexpr bool kActive = false;
  PlaneSide side(std::uint32_t /*front*/, std::uint32_t /*back*/) const { return PlaneSide::kNotBehind; }
};

// The front-to-back walk of section 3.2.1 with layers (see the top of this file). Walks one sorted list, then
// optionally one more entry behind it.
//
// An overfilled layer ordered by planes. Where a surface runs on behind another that meets it inside the pixel (a
// floor going on past the foot of a wall standing on it), the pixel holds pieces of the floor in front of the wall
// and behind it, one surface at one key, whose coverages add up to the pixel; with the wall's entry the layer is
// overfilled, and the recurrence by groups gave the floor the whole pixel and the wall's foot nothing. With a plane
// order (NoPlaneOrder above), where a plane of the layer has pieces both behind another surface's entry and not,
// the walk takes the layer's entries in rounds, those hidden by no other entry first (walk_by_planes): the floor in
// front and the wall's foot then share the pixel side by side, and the floor behind the wall gets what they leave.
class CoverageWalk {
 public:
  // Walks `list`, sorted front to back with the entries of one surface consecutive, calling emit(receiver, E).
  template <class Emit, class Order = NoPlaneOrder>
  void walk(std::span<const CoverageEntry> list, Emit&& emit, const Order& order = {}) {
    const std::size_t n = list.size();
    if (n == 1) {  // most partial pixels: nothing to layer
      emit(list[0].receiver, take(list[0].coverage * (1.0 - covered_)));
      return;
    }
    const KeyRounding rounding = rounding_of(order);
    std::size_t i = 0;
    while (i < n) {
      // The layer starting at i: whole groups of one surface, while the next group's range overlaps (within the
      // scene's rounding).
      std::size_t j = i;
      double far = -std::numeric_limits<double>::infinity(), sum = 0.0;
      do {
        const std::uint32_t surface = list[j].surface;
        do {
          far = std::max(far, list[j].depth + list[j].spread);
          sum += list[j].coverage;
          ++j;
        } while (j < n && list[j].surface == surface);
      } while (j < n && list[j].depth - list[j].spread <= far + rounding.touch_at(far));
      if (sum <= 1.0 + kLayerSlack) {
        // Side by side: every entry of the layer sees the f in front of it.
        const double open = 1.0 - covered_;
        for (std::size_t k = i; k < j; ++k) emit(list[k].receiver, take(list[k].coverage * open));
      } else {
        bool ordered = false;
        if constexpr (Order::kActive) ordered = walk_by_planes(list.subspan(i, j - i), emit, order);
        if (!ordered) overlapping(list.subspan(i, j - i), emit);
      }
      i = j;
    }
  }
  // The visible fraction of one more entry with coverage A behind everything walked so far.
  double behind(double coverage) { return take(coverage * (1.0 - covered_)); }
  // f after the entries walked so far.
  double covered() const { return covered_; }

 private:
  double take(double share) { return take_share(share, covered_); }

  // An overfilled layer, overlapping in the pixel: the recurrence, one group of one surface at a time, except that
  // groups of one plane (the same depth key along the pixel's ray and the same spread: coplanar surfaces, such as two
  // materials of one floor meeting along an edge) share the f in front of the first of them, the paper's identical-z
  // exception: they lie side by side, and the recurrence would take A_1 A_2 from the second. Entry k takes part with
  // the coverage part(k), none when it is 0 (its whole coverage, but in a round of walk_by_planes).
  template <class Emit, class Part>
  void overlapping(std::span<const CoverageEntry> layer, Emit& emit, Part&& part) {
    double open = 0.0;
    std::size_t head = 0, previous = 0;  // the first group of the current run of coplanar groups; the last entry
    bool first = true;
    for (std::size_t k = 0; k < layer.size(); ++k) {
      const double coverage = part(k);
      if (!(coverage > 0.0)) continue;
      if (first || (layer[k].surface != layer[previous].surface && !same_plane_keys(layer[k], layer[head]))) {
        open = 1.0 - covered_;
        head = k;
      }
      first = false;
      previous = k;
      emit(layer[k].receiver, take(coverage * open));
    }
  }
  template <class Emit>
  void overlapping(std::span<const CoverageEntry> layer, Emit& emit) {
    overlapping(layer, emit, [&](std::size_t k) { return layer[k].coverage; });
  }

  // The most entries and surfaces of a layer that walk_by_planes orders, the most planes an entry may lie across,
  // and the most parts of entries it keeps; larger layers take the recurrence.
  static constexpr std::size_t kMaxPlaneEntries = 512, kMaxPlaneSurfaces = 16, kMaxAcross = 3, kMaxParts = 1024;

  // An overfilled layer ordered by planes (see the class comment). Each surface of the layer is a plane, asked
  // through its first entry's receiver. Surface Q hides entry k of another surface P where k lies behind Q's plane
  // and no entry of Q lies behind P's plane: two faces meeting at a convex edge each lie behind the other's plane,
  // and lie side by side. An entry is cut into parts by the planes of its hiders that it lies across: each part
  // lies behind a set of them (and behind those the entry lies wholly behind) and is hidden by those surfaces; the
  // part behind none of them by none (Order::cell_part). A leaf across a plane and its pieces on either side of it
  // are then hidden alike, part for part. The parts go in rounds by how many surfaces hide them, fewest first. The
  // first round lies side by side (or, overfilled itself, takes the recurrence); each later round fills what the
  // rounds before left of the layer's share of the pixel, side by side when it fits, else in proportion to the
  // parts' coverages. Of a hidden part, what its hiders do not cover in the image (Order::hidden_part: a floor's
  // piece past the end of a wall standing on it) goes in the first round, when the first round still fits in the
  // pixel with it. So the layer gives out all of its share, as the side-by-side walk does (in a closed scene the
  // pixel is covered, and the recurrence's product would lose the rest where a covering group has dropped what lay
  // behind it): a part behind a wall takes only what the entries in front leave. A layer in which no surface hides
  // an entry of another lies side by side: it is overfilled by rounding only. False, with nothing emitted, when no
  // plane of the layer (a surface, or coplanar surfaces, which the walk takes as one) has parts both hidden and not
  // while some are hidden, or the layer is too large: then the recurrence walks it, as before. The planes are asked
  // n x (surfaces - 1) times.
  template <class Emit, class Order>
  bool walk_by_planes(std::span<const CoverageEntry> layer, Emit& emit, const Order& order) {
    const std::size_t n = layer.size();
    if (n > kMaxPlaneEntries) return false;
    // The surfaces, each a run of consecutive entries (the lists keep a surface's entries together).
    std::array<std::size_t, kMaxPlaneSurfaces + 1> run{};  // surface q's entries: [run[q], run[q + 1])
    std::size_t surfaces = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (k > 0 && layer[k].surface == layer[k - 1].surface) continue;
      if (surfaces == kMaxPlaneSurfaces) return false;
      run[surfaces++] = k;
    }
    run[surfaces] = n;
    if (surfaces < 2) return false;
    // behind_of[k], bit q: entry k lies behind surface q's plane, wholly or across it (across_of); some_behind[q],
    // bit p: some entry of q lies behind surface p's plane.
    std::array<std::uint16_t, kMaxPlaneEntries> behind_of, across_of;
    std::array<std::uint16_t, kMaxPlaneSurfaces> some_behind{};
    for (std::size_t p = 0; p < surfaces; ++p) {
      for (std::size_t k = run[p]; k < run[p + 1]; ++k) {
        std::uint16_t bits = 0, across = 0;
        for (std::size_t q = 0; q < surfaces; ++q) {
          if (q == p) continue;
          const PlaneSide side = order.side(layer[run[q]].receiver, layer[k].receiver);
          if (side != PlaneSide::kNotBehind) bits |= std::uint16_t(1u << q);
          if (side == PlaneSide::kAcross) across |= std::uint16_t(1u << q);
        }
        behind_of[k] = bits;
        across_of[k] = across;
        some_behind[p] |= bits;
      }
    }
    // mutual_of[p]: the surfaces some entry of which lies behind p's plane: they hide none of p's entries.
    std::array<std::uint16_t, kMaxPlaneSurfaces> mutual_of{};
    bool hidden_any = false;
    for (std::size_t p = 0; p < surfaces; ++p) {
      std::uint16_t& mutual = mutual_of[p];
      for (std::size_t q = 0; q < surfaces; ++q)
        if ((some_behind[q] >> p) & 1u) mutual |= std::uint16_t(1u << q);
      for (std::size_t k = run[p]; k < run[p + 1]; ++k) hidden_any = hidden_any || (behind_of[k] & ~mutual) != 0;
    }
    if (!hidden_any) {
      // No surface of the layer hides an entry of another (none lies behind another's plane, or each behind the
      // other's, as at a convex edge), so wherever they overlap in the image it is by the rounding of the
      // coordinates: a ceiling's tile whose corner, written with 6 digits, lies a little above the long edge of the
      // wall it meets, seen at grazing incidence from a lamp just under the ceiling, overlaps it by 1.07e-4 of a
      // pixel, over the slack, and the recurrence lost 0.24 of that pixel. They lie side by side.
      const double open = 1.0 - covered_;
      for (const CoverageEntry& e : layer) emit(e.receiver, take(e.coverage * open));
      return true;
    }
    // The entries' parts: front[k], entry k's part hidden by none (its whole coverage when nothing hides it); and
    // the hidden parts, each with its entry, the surfaces that hide it and its coverage. seen[p]: bit 0 when a part
    // of surface p is hidden by none, bit 1 when one is hidden.
    struct Hidden {
      std::uint16_t entry;
      std::uint16_t by;          // the surfaces that hide it
      std::uint16_t cut_behind;  // its cell: behind these surfaces' planes,
      std::uint16_t cut_front;   // and in front of these
      double coverage;
    };
    std::array<double, kMaxPlaneEntries> front;
    std::array<Hidden, kMaxParts> hidden;
    std::size_t parts = 0;
    std::array<std::uint8_t, kMaxPlaneSurfaces> seen{};
    std::array<std::uint32_t, kMaxAcross> behind_planes, front_planes;
    for (std::size_t p = 0; p < surfaces; ++p) {
      for (std::size_t k = run[p]; k < run[p + 1]; ++k) {
        const std::uint16_t by = behind_of[k] & ~mutual_of[p], across = across_of[k] & by, wholly = by & ~across;
        front[k] = 0.0;
        if (by == 0) {
          front[k] = layer[k].coverage;
          seen[p] |= 1;
          continue;
        }
        if (across == 0) {  // wholly behind every hider: one part
          if (parts == kMaxParts) return false;
          hidden[parts++] = Hidden{static_cast<std::uint16_t>(k), by, 0, 0, layer[k].coverage};
          seen[p] |= 2;
          continue;
        }
        // Across some hiders' planes: a part per set of them it lies behind (cells that are empty give nothing).
        std::array<std::uint32_t, kMaxAcross> planes;
        std::size_t count = 0;
        for (std::size_t q = 0; q < surfaces; ++q) {
          if (!((across >> q) & 1u)) continue;
          if (count == kMaxAcross) return false;
          planes[count++] = static_cast<std::uint32_t>(q);
        }
        // The cells partition the entry: the last (behind every plane it lies across) is what the others leave, and
        // a cell of less than a rounding of the entry is none (the cut's rounding).
        const std::uint32_t last = (1u << count) - 1;
        double left = layer[k].coverage;
        for (std::uint32_t subset = 0; subset <= last; ++subset) {
          std::size_t nb = 0, nf = 0;
          std::uint16_t cut_behind = 0;
          for (std::size_t i = 0; i < count; ++i) {
            const std::uint32_t receiver = layer[run[planes[i]]].receiver;
            if ((subset >> i) & 1u) {
              behind_planes[nb++] = receiver;
              cut_behind |= std::uint16_t(1u << planes[i]);
            } else {
              front_planes[nf++] = receiver;
            }
          }
          const std::uint16_t cell_by = wholly | cut_behind;
          double coverage = subset == last ? left
                                           : layer[k].coverage * order.cell_part(layer[k].receiver,
                                                                                 std::span(behind_planes.data(), nb),
                                                                                 std::span(front_planes.data(), nf));
          coverage = std::min(coverage, left);
          left -= coverage;
          if (!(coverage > 1e-12 * layer[k].coverage)) continue;
          if (cell_by == 0) {
            front[k] = coverage;
            seen[p] |= 1;
          } else {
            if (parts == kMaxParts) return false;
            hidden[parts++] = Hidden{static_cast<std::uint16_t>(k), cell_by, cut_behind,
                                     static_cast<std::uint16_t>(across & ~cut_behind), coverage};
            seen[p] |= 2;
          }
        }
      }
    }
    if (parts == 0) return false;
    // Where some plane runs on behind another surface: parts of one plane, some hidden and some not.
    bool runs_on = false;
    for (std::size_t p = 0; p < surfaces && !runs_on; ++p) {
      runs_on = seen[p] == 3;
      for (std::size_t q = p + 1; q < surfaces && !runs_on; ++q)
        runs_on = (seen[p] | seen[q]) == 3 && same_plane_keys(layer[run[p]], layer[run[q]]);
    }
    if (!runs_on) return false;
    // seen_part[h]: the part of hidden part h that its hiders do not cover in the image. It goes in the first
    // round, side by side with the parts nobody hides, when they all fit in the pixel; the rest goes in the part's
    // own round. The geometry is asked only where the first round leaves room (at a wall's end, not along its
    // foot), and no more once the seen parts overfill it (then none is taken).
    std::array<double, kMaxParts> seen_part;
    std::fill_n(seen_part.begin(), parts, 0.0);
    double room = 1.0 + kLayerSlack;
    for (std::size_t k = 0; k < n; ++k) room -= front[k];
    if (room > 2.0 * kLayerSlack) {
      bool fits = true;
      for (std::size_t h = 0; h < parts && fits; ++h) {
        const std::size_t k = hidden[h].entry;
        // The part's cell: behind the planes it was cut behind, in front of those it was cut in front of.
        std::size_t nb = 0, nf = 0;
        for (std::size_t q = 0; q < surfaces; ++q) {
          if ((hidden[h].cut_behind >> q) & 1u) behind_planes[nb++] = layer[run[q]].receiver;
          if ((hidden[h].cut_front >> q) & 1u) front_planes[nf++] = layer[run[q]].receiver;
        }
        // The parts each hiding surface covers, added (two hiders may overlap: then more is taken as hidden).
        double covered = 0.0;
        for (std::size_t q = 0; q < surfaces && covered < 1.0; ++q)
          if ((hidden[h].by >> q) & 1u)
            covered += order.hidden_part(layer[k].receiver, std::span(behind_planes.data(), nb),
                                         std::span(front_planes.data(), nf),
                                         layer.subspan(run[q], run[q + 1] - run[q]));
        seen_part[h] = std::max(0.0, hidden[h].coverage - layer[k].coverage * std::min(1.0, covered));
        room -= seen_part[h];
        fits = room >= 0.0;
      }
      if (!fits) std::fill_n(seen_part.begin(), parts, 0.0);
    }
    std::uint8_t most = 0;
    for (std::size_t h = 0; h < parts; ++h)
      most = std::max(most, static_cast<std::uint8_t>(std::popcount(hidden[h].by)));
    const double open = 1.0 - covered_;
    double used = 0.0;  // the fraction of the layer's share the rounds so far took
    for (std::uint8_t round = 0; round <= most; ++round) {
      // The parts of this round and their coverages: round 0, the parts hidden by none and the seen parts.
      const auto in_round = [&](std::size_t h) { return std::popcount(hidden[h].by) == round; };
      double sum = 0.0;
      std::size_t count = 0;
      if (round == 0) {
        for (std::size_t k = 0; k < n; ++k) {
          if (front[k] > 0.0) ++count;
          sum += front[k];
        }
        for (std::size_t h = 0; h < parts; ++h) {
          if (seen_part[h] > 0.0) ++count;
          sum += seen_part[h];
        }
      } else {
        for (std::size_t h = 0; h < parts; ++h) {
          if (!in_round(h)) continue;
          sum += hidden[h].coverage - seen_part[h];
          ++count;
        }
      }
      if (count == 0) continue;
      // Emits every part of the round with its coverage times `scale`.
      const auto emit_round = [&](double scale) {
        if (round == 0) {
          for (std::size_t k = 0; k < n; ++k)
            if (front[k] > 0.0) emit(layer[k].receiver, take(front[k] * scale));
          for (std::size_t h = 0; h < parts; ++h)
            if (seen_part[h] > 0.0) emit(layer[hidden[h].entry].receiver, take(seen_part[h] * scale));
        } else {
          for (std::size_t h = 0; h < parts; ++h) {
            const double part = hidden[h].coverage - seen_part[h];
            if (in_round(h) && part > 0.0) emit(layer[hidden[h].entry].receiver, take(part * scale));
          }
        }
      };
      if (sum <= 1.0 - used + kLayerSlack) {
        emit_round(open);
        used += sum;
      } else if (used == 0.0) {  // the first round overfilled, and so without seen parts
        const double before = covered_;
        overlapping(layer, emit, [&](std::size_t k) { return front[k]; });
        used = open > 0.0 ? (covered_ - before) / open : 1.0;
      } else {
        emit_round(std::max(0.0, 1.0 - used) / sum * open);  // sum > 1 - used >= 0
        used = 1.0;
      }
    }
    return true;
  }

  double covered_ = 0.0;
};

// Walks a list already sorted front to back, calling emit(receiver, E) for every entry; returns the final f.
// Entries of one surface must be consecutive (the arena keeps them so).
template <class Emit>
double resolve_front_to_back(std::span<const CoverageEntry> front_to_back, Emit&& emit) {
  CoverageWalk walk;
  walk.walk(front_to_back, emit);
  return walk.covered();
}

// Sorted lists of partially covering entries, one per pixel, in one pool: the list code of both arenas below.
// A list is a small contiguous array (capacity 2, doubled by moving to the end of the pool when full), kept
// sorted by insertion sort, so it is one or two cache lines whatever order receivers arrive in. An entry joins
// the group of its surface when the list has one (after its last piece), else goes in at its depth (behind
// entries at the same depth but for those it is in front of by the rule of equal keys; positions are decided at
// group heads only, so groups stay contiguous). A group whose coverages reach kFullCoverage drops the entries behind
// it and the list refuses new groups behind it (but for those whose depth range reaches into the group's: see "A
// full pixel" above).
// A group's coverage sum is its entries' coverages added front to back. The header keeps the group that took the
// last entry (its surface, where it ends, its sum): a pixel's entries mostly arrive a surface at a time (receivers
// come in index order, a surface's pieces mostly numbered together), and in the office 88 % of the entries that
// join a group join that one, without a scan of the list.
class PartialLists {
 public:
  // Empties every list (O(1) when the walk has cleared them) and makes room for `pixels` pixels.
  void reset(std::size_t pixels);

  // Inserts a partial entry (coverage < 1) into the list of `pixel`; false when a full group hides it.
  bool insert(std::size_t pixel, const CoverageEntry& entry) {
    std::uint32_t& list = head_[pixel];
    if (list != kNil) return insert_into(list, entry);
    // The first entry of a pixel (most partial pixels): a new list of capacity kFirstCapacity.
    if (used_ + 1 + kFirstCapacity > pool_.size()) grow(1 + kFirstCapacity);
    list = static_cast<std::uint32_t>(used_);
    used_ += 1 + kFirstCapacity;
    pool_[list].header = Header{1, kFirstCapacity, 0, entry.surface, 2, entry.coverage};
    pool_[list + 1].entry = entry;
    return true;
  }

  bool empty(std::size_t pixel) const { return head_[pixel] == kNil; }
  bool full(std::size_t pixel) const { return head_[pixel] != kNil && pool_[head_[pixel]].header.full != 0; }

  // The entries of `pixel` that a walk reaches, front to back, when the pixel's full entry is `full` (depth kFar
  // when none): the groups whose head is in front of it, and then those whose range reaches into its own (but for
  // groups of its surface or its plane).
  std::span<const CoverageEntry> reached(std::size_t pixel, const CoverageEntry& full) const {
    const Cell* cells = &pool_[head_[pixel]];
    const std::uint32_t count = cells[0].header.count;
    static_assert(sizeof(Cell) == sizeof(CoverageEntry));
    if (full.depth == kFar) return {&cells[1].entry, count};  // no full entry: every depth is in front of it
    std::uint32_t prev_surface = kNoSurface, k = 1;
    for (; k <= count; ++k) {
      const CoverageEntry& e = cells[k].entry;
      if (e.surface != prev_surface && !(e.depth < full.depth) &&
          (e.surface == full.surface || hidden_by_full_group(full, e)))
        break;  // a group behind the full entry
      prev_surface = e.surface;
    }
    return {&cells[1].entry, k - 1};
  }
  void clear(std::size_t pixel) { head_[pixel] = kNil; }
  // Marks every list cleared (the caller cleared every non-empty one), so the next reset() has nothing to do.
  void mark_clean() { clean_ = true; }
  void prefetch(std::size_t pixel) const {
    if (head_[pixel] != kNil) __builtin_prefetch(&pool_[head_[pixel]]);
  }

  static constexpr double kFar = std::numeric_limits<double>::infinity();

 private:
  static constexpr std::uint32_t kNil = 0xFFFFFFFFu;
  static constexpr std::uint32_t kFirstCapacity = 2;
  // A list is a header followed by `capacity` entries in the pool.
  struct Header {
    std::uint32_t count;
    std::uint32_t capacity;
    std::uint32_t full;          // the head of the nearest group that covers the pixel, 0 when none
    std::uint32_t last_surface;  // the group that took the last entry: its surface,
    std::uint32_t last_end;      // the index one past its last piece,
    double last_sum;             // and its coverages added front to back
  };
  union Cell {
    CoverageEntry entry;
    Header header;
    Cell() : header{0, 0, 0, kNoSurface, 0, 0.0} {}
  };
  static_assert(sizeof(Header) == sizeof(CoverageEntry));
  std::uint32_t allocate(std::uint32_t capacity);  // a list block: header + capacity entries
  void grow(std::size_t cells);                      // makes room for `cells` more cells in the pool
  bool insert_into(std::uint32_t& list, const CoverageEntry& entry);  // into a non-empty list

  std::vector<std::uint32_t> head_;  // per pixel: pool index of the list's header, or kNil
  std::vector<Cell> pool_;           // lists; pool_[0, used_) in use
  std::size_t used_ = 0;
  bool clean_ = true;  // every head is kNil
};

// A full entry's spread and surface, kept inline beside its depth and receiver.
struct FullMeta {
  float spread = 0.0f;
  std::uint32_t surface = kNoSurface;
};

// Per-pixel sorted lists in one pooled arena, every insertion applied at once (the reference form; the AA
// hemicube uses StagedCoverageArena, which builds the same lists block by block).
//
// Layout. An entry that covers its whole pixel (A >= kFullCoverage: the interior pixels of a receiver, most of
// the entries at high resolution) hides everything behind it, so only the nearest one matters: every pixel keeps
// it inline, as a z-buffer would (per-pixel arrays of depth, receiver, spread and surface: inserting a full entry
// touches 20 bytes per pixel, the classical hemicube's z-buffer and item buffer 12). Partially covering entries go
// into the pixel's sorted list (PartialLists). The walk merges the two: the inline entry takes its place by depth, and
// everything behind it gets E = 0. A partial entry behind the inline one is refused at insertion unless its depth
// range reaches into the inline entry's (of another surface and plane: "A full pixel" above); list entries that a
// nearer full entry hides later are skipped by the walk. Slots are cleared as take_all() reads them, so
// starting a face costs nothing.
class CoverageArena {
 public:
  // Empties every list (O(1) after take_all) and makes room for `pixels` pixels; keeps all memory.
  void reset(std::size_t pixels);

  // Inserts an entry into the list of `pixel` at its depth (behind entries at the same depth, but for the rule of
  // equal keys), or into the group of its surface when the list has one. Returns false when the pixel is full in
  // front of it.
  bool insert(std::size_t pixel, const CoverageEntry& entry) {
    ++entries_;
    if (entry.coverage >= kFullCoverage) {
      if (!takes_full_pixel(entry.depth, entry.surface, depth_[pixel], full_meta_[pixel].surface))
        return false;  // behind the nearest full entry
      depth_[pixel] = entry.depth;
      receiver_[pixel] = entry.receiver;
      full_meta_[pixel] = FullMeta{entry.spread, entry.surface};
      return true;
    }
    if (!(entry.depth < depth_[pixel]) && hidden_by_full(full_entry(pixel), entry)) return false;
    return lists_.insert(pixel, entry);
  }

  // Walks the list of `pixel` front to back, calling emit(receiver, E); returns the final f.
  template <class Emit>
  double resolve(std::size_t pixel, Emit&& emit) const {
    CoverageWalk walk;
    const auto emit_entry = [&](std::size_t, std::uint32_t receiver, double visible) { emit(receiver, visible); };
    walk_pixel(pixel, full_entry(pixel), lists_, pixel, merged_, walk, emit_entry, NoPlaneOrder{});
    return walk.covered();
  }

  // Walks every pixel's list in pixel order, calling emit(pixel, receiver, E), and empties the arena (so the
  // next reset() has nothing to clear).
  template <class Emit, class Order = NoPlaneOrder>
  void take_all(Emit&& emit, const Order& order = {}) {
    for (std::size_t p = 0; p < pixels_; ++p) {
      if (p + 16 < pixels_) lists_.prefetch(p + 16);
      take_pixel(p, depth_[p], receiver_[p], [&] { return full_entry(p); }, lists_, p, merged_, emit, order);
      depth_[p] = kFar;
    }
    lists_.mark_clean();
    clean_ = true;
  }

  // Calls visit(const CoverageEntry&) for the entries of `pixel` that the walk reaches, front to back (the
  // inline full entry with surface kNoSurface).
  template <class Visit>
  void for_each(std::size_t pixel, Visit&& visit) const {
    visit_entries(pixel, visit);
  }

  bool empty(std::size_t pixel) const { return depth_[pixel] == kFar && lists_.empty(pixel); }
  // Whether the pixel is covered: by a full entry, or by a group of the list.
  bool full(std::size_t pixel) const { return depth_[pixel] != kFar || lists_.full(pixel); }
  // Entries offered since the last reset (accepted or not).
  std::size_t entries() const { return entries_; }

  // The pixel's full entry (depth `full_depth`, kFar when none; full() makes it an entry, asked only when the pixel
  // has a list) and the list `list_pixel` of `lists`: calls emit(pixel, receiver, E) front to back and clears the
  // list. Shared with StagedCoverageArena.
  template <class Full, class Emit, class Order = NoPlaneOrder>
  static void take_pixel(std::size_t pixel, double full_depth, std::uint32_t full_receiver, const Full& full,
                         PartialLists& lists, std::size_t list_pixel, std::vector<CoverageEntry>& merged, Emit& emit,
                         const Order& order = {}) {
    if (lists.empty(list_pixel)) {
      if (full_depth != kFar) emit(pixel, full_receiver, 1.0);  // a lone full entry: E = 1
      return;
    }
    CoverageWalk walk;
    walk_pixel(pixel, full(), lists, list_pixel, merged, walk, emit, order);
    lists.clear(list_pixel);
  }

  // A partial entry that the pixel's full entry hides wholly: it lies behind the full entry's range, or in its plane
  // (pieces of the full entry's own surface there are crumbs of rounding).
  static bool hidden_by_full(const CoverageEntry& full, const CoverageEntry& entry) {
    return entry.surface == full.surface || hidden_by_full_group(full, entry);
  }

  // The walk of a pixel's list and its full entry. The full entry covers the pixel alone as a group of one surface
  // covers it with its pieces, and is walked as that group would be: behind the list (E = 1 - f) when no entry's
  // range reaches its own, else among the entries, in its place, so that the layers and the plane order see it
  // (a wall whose one leaf covers the pixel at its foot, with the floor's pieces in front of it and behind it).
  template <class Emit, class Order>
  static void walk_pixel(std::size_t pixel, const CoverageEntry& full, const PartialLists& lists,
                         std::size_t list_pixel, std::vector<CoverageEntry>& merged, CoverageWalk& walk, Emit& emit,
                         const Order& order) {
    const auto emit_here = [&](std::uint32_t receiver, double visible) { emit(pixel, receiver, visible); };
    const bool has_full = full.depth != kFar;
    std::span<const CoverageEntry> list;
    if (!lists.empty(list_pixel)) list = lists.reached(list_pixel, full);
    bool layered = false;
    if (has_full && !list.empty()) {
      double far = -std::numeric_limits<double>::infinity();
      for (const CoverageEntry& e : list) far = std::max(far, e.depth + e.spread);
      layered = full.depth - full.spread <= far + kLayerTouch * std::abs(far);
    }
    if (layered) {
      // The full entry after the group of its surface, or before the first group behind it.
      merged.clear();
      std::size_t position = list.size();
      for (std::size_t k = 0; k < list.size(); ++k) {
        const bool head = k == 0 || list[k].surface != list[k - 1].surface;
        if (list[k].surface == full.surface) {
          position = k + 1;
          while (position < list.size() && list[position].surface == full.surface) ++position;
          break;
        }
        if (head && position == list.size() &&
            (list[k].depth > full.depth ||
             (list[k].depth == full.depth && in_front_at_equal_key(full.surface, list[k].surface))))
          position = k;
      }
      merged.assign(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(position));
      merged.push_back(full);
      merged.insert(merged.end(), list.begin() + static_cast<std::ptrdiff_t>(position), list.end());
      list = merged;
    }
    if (!list.empty()) {
      if constexpr (Order::kActive) {
        walk.walk(list, emit_here, order.at(pixel));
      } else {
        walk.walk(list, emit_here, order);
      }
    }
    if (has_full && !layered) emit(pixel, full.receiver, walk.behind(1.0));
  }

  // The pixel's full entry as a list entry (depth kFar when it has none).
  CoverageEntry full_entry(std::size_t pixel) const {
    return CoverageEntry{depth_[pixel], 1.0, receiver_[pixel], full_meta_[pixel].surface, full_meta_[pixel].spread};
  }

  static constexpr double kFar = PartialLists::kFar;

 private:
  template <class Visit>
  void visit_entries(std::size_t pixel, Visit&& visit) const {
    const CoverageEntry full = full_entry(pixel);
    if (!lists_.empty(pixel))
      for (const CoverageEntry& e : lists_.reached(pixel, full)) visit(e);
    if (full.depth != kFar) visit(CoverageEntry{full.depth, 1.0, full.receiver, kNoSurface});
  }

  std::vector<double> depth_;            // per pixel: depth of the nearest full entry, kFar when none
  std::vector<std::uint32_t> receiver_;  // per pixel: the nearest full entry
  std::vector<FullMeta> full_meta_;      // per pixel: the nearest full entry's spread and surface
  mutable std::vector<CoverageEntry> merged_;  // a pixel's list with its full entry among the entries
  PartialLists lists_;
  std::size_t pixels_ = 0;
  bool clean_ = true;  // every pixel empty
  std::size_t entries_ = 0;
};

// The arena of the AA hemicube: the same lists as CoverageArena, built block by block so that they stay in
// cache. Pixels are column-major (pixel (x, y) at x * height + y, the area rasterizer's visiting order) and cut
// into blocks of 2^k whole columns of at most kBlockPixels pixels.
//
// Why. Receivers arrive in index order, each touching a few columns, while the walk goes in pixel order; lists
// built at once are scattered over a pool larger than the cache (at N = 1000, 1.1 million partial entries per
// shot), so both their insertion and the walk miss the cache on nearly every partial pixel. Here insert() keeps
// the z-buffer-like inline full entry at once, as CoverageArena does, and appends a partial entry that passes the
// inline depth test to its block's staging buffer (a sequential write). take_all() then replays, block by block,
// the staged entries in their arrival order into PartialLists sized for one block (which fits in L2), and walks
// that block's pixels. Each pixel's list receives the same entries in the same order as with CoverageArena (a
// full entry never depends on the lists, and a partial entry is tested against the inline entry at its arrival),
// so the lists, the walk and the emitted values are identical; only the time of the insertion sort moves.
//
// Pixels of one surface. Most partial entries (78 % of them in an office shot at N = 100) fall in pixels where
// every partial entry belongs to one physical surface and no full entry lies: the inside of a tiled floor or
// wall. Such a list is one group, in arrival order, and its walk gives every entry E = A, capped so that f never
// exceeds 1 (open = 1 - 0 for the group's one layer, whichever branch the walk takes). insert() notes per pixel
// whether its partial entries so far share one surface; the replay gives those pixels' entries their E directly,
// in arrival order with a running f per pixel, without building the list. The values are the walk's, bit for
// bit; they are emitted during the replay of their block, before the block's other pixels. Only when the face is
// one block (every face up to N = 128): there its per-pixel arrays stay in cache, and a shot at N = 100 is 8 %
// (Cornell box) to 17 % (office) faster; tried on faces of several blocks, it gained nothing at N = 300 and cost
// 15-25 % at N = 1000 (docs/benchmarks.md), where the bookkeeping at insertion and the replay's reads in arrival
// order cost more than the lists they save.
class StagedCoverageArena {
 public:
  static constexpr std::size_t kBlockPixels = 16384;

  // Empties the arena (O(1) after take_all) for a width x height face; keeps all memory.
  void reset(int width, int height);

  // The spread and surface of `receiver`'s entries on this face, which its full entries take from here (a full
  // entry keeps only its depth and receiver per pixel): to be given before its entries are offered, for receivers
  // numbered below the count given to describe_receivers.
  void describe_receivers(std::size_t count) {
    if (receiver_meta_.size() < count) receiver_meta_.resize(count);
  }
  void describe(std::uint32_t receiver, float spread, std::uint32_t surface) {
    receiver_meta_[receiver] = FullMeta{spread, surface};
  }

  // Offers an entry to pixel (x, y), 0 <= x < width, 0 <= y < height: a full entry in front of the inline one
  // replaces it, a partial one in front of it (or behind it, its range reaching into the inline one's) is staged,
  // anything else is dropped (as CoverageArena::insert).
  void insert(int x, int y, const CoverageEntry& entry) {
    const std::size_t pixel = static_cast<std::size_t>(x) * height_ + static_cast<std::size_t>(y);
    // The receiver most likely covers the same row two columns on, visited soon: fetch it now.
    __builtin_prefetch(&depth_[pixel + 2 * height_]);
    __builtin_prefetch(&receiver_[pixel + 2 * height_]);
    if (!(entry.depth < depth_[pixel])) [[unlikely]] {
      // Behind the nearest full entry: dropped, but for a partial entry whose range reaches into the full entry's,
      // and a full entry at its very key that is in front of it by the rule of equal keys.
      offer_behind_full(x, pixel, entry);
      return;
    }
    if (entry.coverage >= kFullCoverage) {
      depth_[pixel] = entry.depth;
      receiver_[pixel] = entry.receiver;
      return;
    }
    stage(x, pixel, entry);
  }

  // Walks every pixel front to back, calling emit(pixel, receiver, E), and empties the arena. Block by block;
  // within a block, first the pixels of one surface (entries in arrival order), then the others in pixel order.
  // Each pixel's entries come front to back, as CoverageArena::take_all gives them; overfilled layers are ordered
  // by `order` (CoverageWalk).
  template <class Emit, class Order = NoPlaneOrder>
  void take_all(Emit&& emit, const Order& order = {}) {
    for (std::size_t block = 0; block < blocks_; ++block) {
      const std::size_t begin = block * block_pixels_;
      const std::size_t end = std::min(begin + block_pixels_, pixels_);
      lists_.reset(end - begin);
      for (const Staged& s : stage_[block]) {
        const std::size_t p = begin + s.pixel;
        if (one_surface_pixels_ && surface_[p] != kMixed && depth_[p] == kFar) {
          // One group, one layer, open = 1: the walk's take(A), with this pixel's f.
          emit(p, s.entry.receiver, take_share(s.entry.coverage, covered_[s.pixel]));
        } else {
          lists_.insert(s.pixel, s.entry);
        }
      }
      if (one_surface_pixels_) {
        for (const Staged& s : stage_[block]) {  // only staged pixels have a surface or an f to clear
          surface_[begin + s.pixel] = kNoPartial;
          covered_[s.pixel] = 0.0;
        }
      }
      stage_[block].clear();
      for (std::size_t p = begin; p < end; ++p) {
        CoverageArena::take_pixel(p, depth_[p], receiver_[p], [&] { return full_entry(p); }, lists_, p - begin,
                                  merged_, emit, order);
        depth_[p] = kFar;
      }
      lists_.mark_clean();
    }
    clean_ = true;
  }


 private:
  static constexpr double kFar = PartialLists::kFar;
  struct Staged {
    CoverageEntry entry;
    std::uint32_t pixel;  // within the block
  };

  static constexpr std::uint32_t kNoPartial = 0xFFFFFFFFu, kMixed = 0xFFFFFFFEu;

  CoverageEntry full_entry(std::size_t pixel) const {
    const FullMeta& meta = receiver_meta_[receiver_[pixel]];
    return CoverageEntry{depth_[pixel], 1.0, receiver_[pixel], meta.surface, meta.spread};
  }
  void stage(int x, std::size_t pixel, const CoverageEntry& entry) {
    if (one_surface_pixels_) {
      // The pixel's one surface so far, or kMixed (ids from kMixed up count as mixed: they are the markers).
      std::uint32_t& only = surface_[pixel];
      const std::uint32_t surface = entry.surface < kMixed ? entry.surface : kMixed;
      if (only != surface) only = only == kNoPartial ? surface : kMixed;
    }
    const auto block = static_cast<std::size_t>(x) >> block_shift_;
    stage_[block].push_back(Staged{entry, static_cast<std::uint32_t>(pixel - block * block_pixels_)});
  }
  // Out of line and cold, so that the insertion stays as small as the z-buffer's test in the rasterizer's loop (inline,
  // the partial entries' test cost 5 % of the office's instructions). Every entry behind the inline one comes here,
  // but most are full entries at another key, dropped at once; guarding the call by kind and key in the loop counted
  // no fewer instructions (cachegrind, docs/benchmarks.md, "make goals at 8796bd2").
  [[gnu::noinline, gnu::cold]] void offer_behind_full(int x, std::size_t pixel, const CoverageEntry& entry) {
    if (entry.coverage < kFullCoverage) {
      if (!CoverageArena::hidden_by_full(full_entry(pixel), entry)) stage(x, pixel, entry);
    } else if (entry.depth == depth_[pixel] &&
               in_front_at_equal_key(entry.surface, receiver_meta_[receiver_[pixel]].surface)) {
      receiver_[pixel] = entry.receiver;
    }
  }

  std::vector<double> depth_;            // per pixel: depth of the nearest full entry, kFar when none
  std::vector<std::uint32_t> receiver_;  // per pixel: the nearest full entry
  std::vector<FullMeta> receiver_meta_;  // per receiver: its spread on this face and its surface (describe())
  std::vector<CoverageEntry> merged_;    // a pixel's list with its full entry among the entries
  std::vector<std::uint32_t> surface_;   // per pixel: the surface of all its staged entries, kNoPartial or kMixed
  std::vector<double> covered_;          // per pixel of a block: f of a pixel of one surface during the replay
  bool one_surface_pixels_ = false;      // whether this face takes the shortcut (one block)
  std::vector<std::vector<Staged>> stage_;  // per block: partial entries in arrival order
  PartialLists lists_;                      // the lists of one block
  std::size_t pixels_ = 0, height_ = 1, block_pixels_ = 1, blocks_ = 0;
  int block_shift_ = 0;
  bool clean_ = true;  // every pixel empty
};

}  // namespace aarad::formfactor
