// The scene model: faces, groups and materials, and the grouping of faces into physical surfaces.
// A physical surface is what the paper's identical-z exception needs (Chandran et al., section 3.2.1):
// pieces of one surface never occlude each other. Here it is the faces of one group that share one plane,
// one facing direction and one material (../shared/design.md, "Scene files").
#include "aarad/core/scene.h"

#include "aarad/core/error.h"
#include "aarad/core/face_check.h"
#include "aarad/core/polygon.h"

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

namespace aarad {
namespace {

// Planes of two faces agree when their unit normals differ by less than about 1.4e-5 radians and every
// vertex of the second lies within kPlaneDistance (scene.h) x the scene diagonal of the first face's plane.
constexpr double kNormalDotTolerance = 1e-10;

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string text_of(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

// A face lies farther from the origin than kMaxRemoteness diagonals of the scene.
std::string remoteness_message(const std::string& face, double coordinate, double diagonal, const Vec3& low,
                               const Vec3& high) {
  const Vec3 centre = 0.5 * (low + high);
  return face + " lies too far from the origin for the scene's size: a coordinate of " + text_of(coordinate) +
         " where the scene is " + text_of(diagonal) + " across (" + text_of(coordinate / diagonal) +
         " times; at most " + text_of(kMaxRemoteness) + "). Doubles there are " +
         text_of(coordinate * std::numeric_limits<double>::epsilon()) + " apart, too coarse for its geometry; move "
         "the scene nearer the origin, e.g. subtract its centre (" + text_of(centre.x) + ", " + text_of(centre.y) +
         ", " + text_of(centre.z) + ") from every vertex";
}

}  // namespace

std::uint32_t Scene::add_group(const std::string& group_name) {
  if (const auto found = find_group(group_name)) return *found;
  groups.push_back(Group{group_name, {}, {}});
  return static_cast<std::uint32_t>(groups.size() - 1);
}

std::uint32_t Scene::add_material(const Material& material) {
  materials.push_back(material);
  return static_cast<std::uint32_t>(materials.size() - 1);
}

void Scene::add_face(std::uint32_t group, std::uint32_t material, std::vector<Vec3> vertices, int source_line,
                     std::uint32_t smoothing) {
  if (group >= groups.size())
    throw Error("Scene::add_face: group " + std::to_string(group) + " does not exist (the scene has " +
                std::to_string(groups.size()) + " groups); make it with add_group first");
  Face face;
  face.vertices = std::move(vertices);
  face.group = group;
  face.material = material;
  face.source_line = source_line;
  face.smoothing = smoothing;
  faces.push_back(std::move(face));
  groups[group].faces.push_back(static_cast<std::uint32_t>(faces.size() - 1));
}

void Scene::build_surfaces() {
  surfaces.clear();
  for (Group& g : groups) g.surfaces.clear();
  const double tolerance = kPlaneDistance * diagonal();
  // A face joins the first surface of its group (in the order they were made) whose material it shares, whose
  // normal is within kNormalDotTolerance of its own, and whose plane holds its vertices within `tolerance`. The last two bound the surface's offset d: |n_s . v + d_s| <= tolerance with |n_s - n_f| <=
  // sqrt(2 kNormalDotTolerance) = e gives d_s within tolerance + e |v| of -n_f . v for every vertex v of the face.
  // So only the surfaces whose d lies in that window are tried (kept sorted by d): a mesh of n faces in n planes
  // took n^2 / 2 tests (5 s for 80 000 triangles). Planes tangent to one sphere about the origin all have about the
  // same d, though (a tessellated ball centred there: 160 000 triangles, 89 s), so the surfaces are also binned by
  // normal, in cubes of kNormalCell per coordinate: a normal within e of the face's, each coordinate within
  // kNormalReach > e (rounding included), lies in one of the cells that the box of that reach about the face's
  // normal meets (one cell, unless the normal lies within kNormalReach of a cell's side).
  const double normal_reach = std::sqrt(2.0 * kNormalDotTolerance);
  constexpr double kNormalCell = 1e-4, kNormalReach = 2e-5;
  using Cell = std::array<std::int64_t, 3>;
  struct CellHash {
    std::size_t operator()(const Cell& c) const {
      return static_cast<std::size_t>(c[0] * 73856093 ^ c[1] * 19349663 ^ c[2] * 83492791);
    }
  };
  const auto cell_of = [](const Vec3& n) {
    return Cell{static_cast<std::int64_t>(std::floor(n.x / kNormalCell)),
                static_cast<std::int64_t>(std::floor(n.y / kNormalCell)),
                static_cast<std::int64_t>(std::floor(n.z / kNormalCell))};
  };
  for (std::uint32_t gi = 0; gi < groups.size(); ++gi) {
    Group& group = groups[gi];
    std::unordered_map<Cell, std::multimap<double, std::uint32_t>, CellHash> by_normal;  // by normal, then by d
    for (const std::uint32_t fi : group.faces) {
      Face& face = faces[fi];
      const Plane plane = plane_of(face.vertices);
      double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
      for (const Vec3& v : face.vertices) {
        const double centre = -glm::dot(plane.normal, v), length = glm::length(v);
        // The window, widened by rounding's share (the products above and the tests below are each within a few
        // ulps of |v|).
        const double reach = tolerance + normal_reach * length + 1e-12 * (length + tolerance);
        lo = std::max(lo, centre - reach);
        hi = std::min(hi, centre + reach);
      }
      std::optional<std::uint32_t> match;
      const Cell own = cell_of(plane.normal);
      const Cell first = cell_of(plane.normal - kNormalReach), last = cell_of(plane.normal + kNormalReach);
      for (std::int64_t x = first[0]; x <= last[0]; ++x)
        for (std::int64_t y = first[1]; y <= last[1]; ++y)
          for (std::int64_t z = first[2]; z <= last[2]; ++z) {
            const auto cell = by_normal.find(Cell{x, y, z});
            if (cell == by_normal.end()) continue;
            const std::multimap<double, std::uint32_t>& by_offset = cell->second;
            for (auto it = by_offset.lower_bound(lo); it != by_offset.end() && it->first <= hi; ++it) {
              const std::uint32_t si = it->second;
              if (match && si > *match) continue;  // the first surface made wins, as a scan in order would find
              const Surface& s = surfaces[si];
              if (s.material != face.material) continue;
              if (glm::dot(s.plane.normal, plane.normal) < 1.0 - kNormalDotTolerance) continue;
              const bool in_plane = std::all_of(face.vertices.begin(), face.vertices.end(), [&](const Vec3& v) {
                return std::abs(s.plane.signed_distance(v)) <= tolerance;
              });
              if (in_plane) match = si;
            }
          }
      if (!match) {
        Surface s;
        s.group = gi;
        s.material = face.material;
        s.smoothing = face.smoothing;
        s.plane = plane;
        surfaces.push_back(s);
        match = static_cast<std::uint32_t>(surfaces.size() - 1);
        group.surfaces.push_back(*match);
        by_normal[own].emplace(plane.d, *match);
      }
      Surface& s = surfaces[*match];
      if (!s.faces.empty() && s.smoothing != face.smoothing) s.smoothing = 0;  // its faces disagree: none
      s.faces.push_back(fi);
      s.area += area(face.vertices);
      face.surface = *match;
    }
  }
}

void Scene::validate() const {
  const std::string where = name.empty() ? std::string("scene") : name;
  if (faces.empty()) throw InputError(where, 0, "the scene has no faces; add at least one polygon");
  for (const Material& m : materials) {
    for (int c = 0; c < 3; ++c) {
      if (!(m.reflectance[c] == 0.0 || (m.reflectance[c] >= kMinReflectance && m.reflectance[c] < 1.0)))
        throw InputError(where, 0, "material '" + m.name + "': reflectance must be 0 or lie in [1e-100, 1) per "
                                   "channel: at 1 or more the solution would not converge, and below 1e-100 doubles "
                                   "lose the digits of what it reflects");
      if (!(m.emission[c] == 0.0 || (m.emission[c] >= kMinEmission && m.emission[c] <= kMaxEmission)))
        throw InputError(where, 0, "material '" + m.name + "': emission must be 0 or lie in [1e-100, 1e100] per "
                                   "channel");
    }
  }
  std::size_t surface_faces = 0;
  for (const Surface& s : surfaces) surface_faces += s.faces.size();
  if (surface_faces != faces.size())
    throw Error(where + ": physical surfaces are not built; call Scene::build_surfaces() after the last add_face");
  const double smallest = kSmallestFace * diagonal();
  const double farthest = kMaxRemoteness * diagonal();
  for (std::size_t fi = 0; fi < faces.size(); ++fi) {
    const Face& f = faces[fi];
    if (f.group >= groups.size())
      throw InputError(where, f.source_line, "face " + std::to_string(fi) + " refers to group " +
                                                 std::to_string(f.group) + ", which does not exist");
    const std::string face = "face " + std::to_string(fi) + " (group '" + groups[f.group].name + "')";
    if (f.material >= materials.size())
      throw InputError(where, f.source_line, face + " refers to material " + std::to_string(f.material) +
                                                 ", which does not exist");
    if (f.surface >= surfaces.size())
      throw InputError(where, f.source_line, face + " refers to physical surface " + std::to_string(f.surface) +
                                                 ", which does not exist; call Scene::build_surfaces()");
    if (f.vertices.size() < 3) throw InputError(where, f.source_line, face + " has fewer than three vertices");
    for (const Vec3& v : f.vertices)
      if (!finite(v)) throw InputError(where, f.source_line, face + " has a vertex that is not finite");
    // The importer's checks (core/face_check.h): the initial meshing would crash on such a face.
    switch (check_face(f.vertices).problem) {
      case FaceProblem::kNone:
        break;
      case FaceProblem::kFewerThanThreeDistinct:
        throw InputError(where, f.source_line, face + " has fewer than three distinct vertices; fix or remove it");
      case FaceProblem::kTooLarge:
        throw InputError(where, f.source_line, face + " is too large for double precision (a coordinate beyond 1e50, "
                                                      "where the solver's products of lengths overflow); scale the "
                                                      "scene down");
      case FaceProblem::kTooSmall:
        throw InputError(where, f.source_line, face + " is too small for double precision (its size is below "
                                                      "1e-50, where the solver's products of lengths underflow); "
                                                      "scale the scene up");
      case FaceProblem::kCollinear:
        throw InputError(where, f.source_line, face + " has zero area or is too thin to resolve: its vertices lie "
                                                      "on one line to within 1e-12 of its size; remove it or fix its "
                                                      "vertices");
      case FaceProblem::kSelfIntersecting:
        throw InputError(where, f.source_line, face + " intersects itself (two of its edges cross or touch); list "
                                                      "its vertices in order around its boundary, or split it into "
                                                      "simple polygons");
      case FaceProblem::kZeroArea:
        throw InputError(where, f.source_line, face + " has zero area: its boundary encloses less than 1e-12 of "
                                                      "its size squared; remove it or fix its vertices");
    }
    // Below what the initial meshing resolves, which welds vertices closer than kPlaneDistance of the diagonal:
    // such a face would collapse there (CGAL's mesher crashed on one; the importer skips them).
    if (box_diagonal(f.vertices) < smallest)
      throw InputError(where, f.source_line, face + " is smaller than 1e-5 of the scene's diagonal, below what the "
                                                    "meshing resolves; remove it or scale it up");
    for (const Vec3& v : f.vertices) {
      const double coordinate = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
      if (coordinate > farthest)
        throw InputError(where, f.source_line, remoteness_message(face, coordinate, diagonal(), bounds_min(),
                                                                  bounds_max()));
    }
  }
  Rgb flux{};
  for (const Face& f : faces) flux += materials[f.material].emission * area(f.vertices);
  for (int c = 0; c < 3; ++c) {
    if (!(flux[c] <= kMaxEmittedFlux))
      throw InputError(where, 0, "the emitted flux (emission x area, summed over the lights) is too large for the "
                                 "solver's sums; scale the emission or the geometry down (radiosity is linear in "
                                 "the emission)");
  }
}

namespace {

// A face projected into its surface's plane (counter-clockwise), cut into convex pieces, with their bounds.
struct FlatFace {
  std::vector<std::vector<Vec2>> pieces;
  Vec2 lo, hi;
  std::uint32_t index = 0;  // the face's index in the scene
  int line = 0;
};

std::vector<FlatFace> flatten(const Scene& scene, const Surface& surface, const Vec3& normal) {
  std::vector<FlatFace> flat;
  std::vector<Vec2> projected;
  std::vector<std::array<std::size_t, 3>> triangles;
  for (const std::uint32_t fi : surface.faces) {
    const Face& face = scene.faces[fi];
    projected.resize(face.vertices.size());
    project_to_2d(face.vertices, normal, projected);
    FlatFace f;
    f.index = fi;
    f.line = face.source_line;
    f.lo = Vec2(std::numeric_limits<double>::infinity());
    f.hi = -f.lo;
    for (const Vec2& p : projected) {
      f.lo = glm::min(f.lo, p);
      f.hi = glm::max(f.hi, p);
    }
    if (is_convex(projected)) {
      f.pieces.push_back(projected);
    } else {
      triangles.clear();
      ear_clip(projected, triangles);
      for (const auto& t : triangles) f.pieces.push_back({projected[t[0]], projected[t[1]], projected[t[2]]});
    }
    flat.push_back(std::move(f));
  }
  return flat;
}

// A box for CGAL's box_intersection_d (Zomorodian and Edelsbrunner, "Fast software for box intersections", 2002):
// bounds lo, hi on the two axes u, v that a projection keeps and a plane's offset d +- a window, stored in the
// order u, d, v. The algorithm splits its sets along the last dimension first and scans along the first; a set it
// cannot split, since most of its boxes share their lower bound there, it scans whole along the first dimension
// (CGAL/Box_intersection_d/segment_tree.h, modified_two_way_scan). All the surfaces of one plane share d: with d
// last, every one of them was scanned against every other overlapping it along u, quadratic where they lie side by
// side along v (40 000 planks, each its own group: 2.2 s); with d in the middle, only those that already meet
// along v are.
using OverlapBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

OverlapBox overlap_box(const Vec2& lo, const Vec2& hi, double d, double window, std::uint32_t info) {
  double low[3] = {lo.x, d - window, lo.y};
  double high[3] = {hi.x, d + window, hi.y};
  return OverlapBox(low, high, info);
}

// Overlapping area of two faces.
double overlap(const FlatFace& f, const FlatFace& g) {
  if (f.hi.x <= g.lo.x || g.hi.x <= f.lo.x || f.hi.y <= g.lo.y || g.hi.y <= f.lo.y) return 0.0;
  double sum = 0.0;
  for (const auto& p : f.pieces)
    for (const auto& q : g.pieces) sum += convex_intersection_area(p, q);
  return sum;
}

}  // namespace

std::vector<Scene::CoplanarOverlap> Scene::coplanar_overlaps(std::size_t most_pairs, bool* complete) const {
  std::vector<CoplanarOverlap> found;
  // Thrown from CGAL's callbacks to end a search that reached most_pairs.
  struct EnoughPairs {};
  if (complete != nullptr) *complete = true;
  const double tolerance = kPlaneDistance * diagonal();
  // Coincident planes have nearly equal offsets: pairs are looked for within a window of d. Two unit normals within
  // kNormalDotTolerance differ by at most sqrt(2 kNormalDotTolerance) in length, which moves d by that times the
  // distance of a shared point from the origin.
  double reach = 0.0;
  for (const Face& f : faces)
    for (const Vec3& v : f.vertices) reach = std::max(reach, glm::length(v));
  const double window = 2.0 * tolerance + std::sqrt(2.0 * kNormalDotTolerance) * reach;
  std::vector<std::uint32_t> order(surfaces.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t x, std::uint32_t y) { return surfaces[x].plane.d < surfaces[y].plane.d; });
  std::vector<std::uint32_t> position(surfaces.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) position[order[i]] = i;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> candidates;
  // Faces of one surface may overlap each other too.
  for (std::uint32_t s = 0; s < surfaces.size(); ++s) candidates.emplace_back(s, s);
  // Two surfaces are a candidate pair when, taking s as the one earlier in order of d and t the other, t's offset is
  // within the window above s's, the normals agree and t's vertices lie in s's plane. Testing every pair within
  // the window was quadratic where many surfaces share a plane (the tops of 20 000 cubes on a floor: 2 x 10^8
  // pairs, each then flattened, 5 minutes and 4 GB). Only pairs whose faces can overlap matter, though: the sum
  // below projects both onto the two axes that the normal of the pair's first surface (the lower index) does not
  // drop (polygon.h, project_to_2d: the coordinates themselves, unrounded) and skips every pair of faces whose
  // bounds there do not overlap strictly. So a pair whose surfaces' bounds on those two axes are disjoint or only
  // touch adds exactly nothing; the pairs left are found by intersecting boxes (CGAL's box_intersection_d), per
  // dropped axis k, of those two axes' bounds and of d +- the window.
  // Whether t's vertices lie in s's plane was a pass over them for every pair: quadratic where a surface of many
  // faces is in many pairs (a floor of 40 000 tiles under 4 000 decals, each its own group: 1 s). Most pairs are
  // settled by a bound instead. A vertex p of t lies n_s.p + d_s = (n_s - n_t).p + (d_s - d_t) + (n_t.p + d_t) from
  // s's plane, which over t's bounding box (centre c, half sizes h) is at most |(n_s - n_t).c + d_s - d_t| +
  // |n_s - n_t|.h + t's largest distance from its own plane. Where that is below the tolerance by 2^-40 of the sizes
  // involved, far more than these sums and the test itself round (a few times 2^-53 of them), every vertex passes
  // the test; otherwise they are tested one by one, as before, but the vertices of t farthest along 14 directions
  // (the axes and the diagonals) first: that distance is about affine in p, so where a vertex is out of the plane
  // one of those usually is (a floor of 40 000 tiles tilted by 2e-6 radians under 4 000 flat decals, each in the
  // floor's plane only around itself: 0.45 s in passes over the floor that stopped late, 0.04 s this way).
  struct Extent {
    Vec3 centre{0.0}, half{0.0};
    double deviation = 0.0;  // the largest |signed_distance| of a vertex from the surface's own plane
    double size = 0.0;       // the largest |coordinate| of a vertex
    std::vector<Vec3> extremes;  // the vertices farthest along the 14 directions, of surfaces of over 4 faces
  };
  std::vector<Extent> extents(surfaces.size());
  for (std::uint32_t si = 0; si < surfaces.size(); ++si) {
    Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    Extent& e = extents[si];
    const bool with_extremes = surfaces[si].faces.size() > 4;
    std::array<std::pair<double, Vec3>, 14> farthest;
    farthest.fill({-std::numeric_limits<double>::infinity(), Vec3(0.0)});
    for (const std::uint32_t fi : surfaces[si].faces)
      for (const Vec3& p : faces[fi].vertices) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
        e.deviation = std::max(e.deviation, std::abs(surfaces[si].plane.signed_distance(p)));
        if (!with_extremes) continue;
        const double x = p.x, y = p.y, z = p.z;
        const std::array<double, 14> along{x,         -x,        y,         -y,         z,          -z,
                                           x + y + z, x + y - z, x - y + z, x - y - z,  -x + y + z, -x + y - z,
                                           -x - y + z, -x - y - z};
        for (std::size_t i = 0; i < along.size(); ++i)
          if (along[i] > farthest[i].first) farthest[i] = {along[i], p};
      }
    if (surfaces[si].faces.empty()) continue;
    if (with_extremes)
      for (const auto& [distance, p] : farthest) e.extremes.push_back(p);
    e.centre = 0.5 * (lo + hi);
    e.half = glm::max(hi - e.centre, e.centre - lo);
    e.size = std::max({std::abs(lo.x), std::abs(lo.y), std::abs(lo.z), std::abs(hi.x), std::abs(hi.y), std::abs(hi.z)});
  }
  const auto surely_in_plane = [&](const Surface& s, const Surface& t, const Extent& e) {
    const Vec3 dn = s.plane.normal - t.plane.normal;
    const double bound = std::abs(glm::dot(dn, e.centre) + (s.plane.d - t.plane.d)) + glm::dot(glm::abs(dn), e.half) +
                         e.deviation;
    return bound + 0x1p-40 * (e.size + std::abs(s.plane.d) + std::abs(t.plane.d)) <= tolerance;
  };
  std::vector<OverlapBox> boxes;
  try {
    for (int k = 0; k < 3; ++k) {
      const int u = (k + 1) % 3, v = (k + 2) % 3;
      boxes.clear();
      for (std::uint32_t si = 0; si < surfaces.size(); ++si) {
        const Surface& s = surfaces[si];
        // A surface paired with one whose normal drops k: its own normal, within sqrt(2 kNormalDotTolerance) of that
        // one, has |n_k| within twice that of its largest component.
        const Vec3 a = glm::abs(s.plane.normal);
        if (a[k] < std::max({a.x, a.y, a.z}) - 1e-4) continue;
        Vec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        for (const std::uint32_t fi : s.faces)
          for (const Vec3& p : faces[fi].vertices) {
            lo = glm::min(lo, Vec2(p[u], p[v]));
            hi = glm::max(hi, Vec2(p[u], p[v]));
          }
        boxes.push_back(overlap_box(lo, hi, s.plane.d, window, si));
      }
      CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const OverlapBox& x, const OverlapBox& y) {
        std::uint32_t si = x.info(), ti = y.info();
        if (dropped_axis(surfaces[std::min(si, ti)].plane.normal) != k) return;  // that pair's axes are another k's
        if (position[ti] < position[si]) std::swap(si, ti);
        const Surface& s = surfaces[si];
        const Surface& t = surfaces[ti];
        if (!(t.plane.d - s.plane.d <= window)) return;
        if (glm::dot(s.plane.normal, t.plane.normal) < 1.0 - kNormalDotTolerance) return;
        const auto near = [&](const Vec3& p) { return std::abs(s.plane.signed_distance(p)) <= tolerance; };
        const Extent& e = extents[ti];
        const bool in_plane = surely_in_plane(s, t, e) ||
                              (std::all_of(e.extremes.begin(), e.extremes.end(), near) &&
                               std::all_of(t.faces.begin(), t.faces.end(), [&](std::uint32_t fi) {
                                 return std::all_of(faces[fi].vertices.begin(), faces[fi].vertices.end(), near);
                               }));
        if (!in_plane) return;
        candidates.emplace_back(std::min(si, ti), std::max(si, ti));
        if (candidates.size() - surfaces.size() >= most_pairs) throw EnoughPairs{};
      });
    }
  } catch (const EnoughPairs&) {
    if (complete != nullptr) *complete = false;
  }
  std::sort(candidates.begin(), candidates.end());
  // The faces of the pairs are matched the same way: per set of surfaces joined by pairs and per dropped axis k, a
  // box for each face of each surface in a pair whose first surface drops k (its bounds on the two axes kept, its
  // surface's d +- the window), and each pair of faces whose boxes meet and whose surfaces are a pair adds its
  // share. Each pair used to be swept on its own, along x over the second surface's faces sorted by left end, a
  // face of the first meeting those within its span extended to the left by the second's widest face: quadratic
  // where that face was long (80 000 tiles with a strip along them, 80 000 planks side by side: 8.2 and 22.8 s),
  // and flattening and sorting both surfaces of every pair was quadratic where a surface of many faces was in many
  // pairs (a floor of 40 000 tiles under 4 000 decals, each its own group: 85 s). The boxes are closed and hold the
  // coordinates overlap() compares strictly, so every pair of faces with a share is found; each surface is
  // flattened once per projection, and the shares are summed in the sweep's order (a's faces in order, b's by left
  // end as std::sort put them), which keeps the areas and the lines of the largest share bit for bit.
  std::vector<std::uint32_t> first_pair(surfaces.size() + 1, 0);  // a's pairs are candidates[first_pair[a] ...)
  std::vector<std::array<bool, 3>> in_axis(surfaces.size(), {false, false, false});
  for (std::uint32_t c = 0; c < candidates.size(); ++c) {
    const auto [a, b] = candidates[c];
    ++first_pair[a + 1];
    if (a == b && surfaces[a].faces.size() < 2) continue;
    const int k = dropped_axis(surfaces[a].plane.normal);
    in_axis[a][k] = in_axis[b][k] = true;
  }
  for (std::size_t a = 0; a < surfaces.size(); ++a) first_pair[a + 1] += first_pair[a];
  // A surface flattened in the projection of a pair's first surface (which only depends on the axis it drops and
  // the sign of the normal there), once, sorted by left end as the sweep sorted it; rank[p] is where the face
  // surfaces[s].faces[p] went.
  struct Flattened {
    std::vector<FlatFace> sorted;
    std::vector<std::uint32_t> rank;
  };
  std::vector<std::uint32_t> position_in_surface(faces.size());
  for (const Surface& s : surfaces)
    for (std::uint32_t p = 0; p < s.faces.size(); ++p) position_in_surface[s.faces[p]] = p;
  std::deque<Flattened> flattened;  // a deque: references stay valid as it grows
  std::vector<std::array<std::int32_t, 6>> flattened_index(surfaces.size());
  for (auto& f : flattened_index) f.fill(-1);
  const auto flat = [&](std::uint32_t s, const Vec3& n) -> const Flattened& {
    const int k = dropped_axis(n);
    std::int32_t& i = flattened_index[s][2 * k + (n[k] < 0.0)];
    if (i < 0) {
      Flattened f;
      f.sorted = flatten(*this, surfaces[s], n);
      std::sort(f.sorted.begin(), f.sorted.end(), [](const FlatFace& x, const FlatFace& y) { return x.lo.x < y.lo.x; });
      f.rank.resize(f.sorted.size());
      for (std::uint32_t r = 0; r < f.sorted.size(); ++r) f.rank[position_in_surface[f.sorted[r].index]] = r;
      i = static_cast<std::int32_t>(flattened.size());
      flattened.push_back(std::move(f));
    }
    return flattened[static_cast<std::size_t>(i)];
  };
  struct Share {
    std::uint32_t pair, first, second;  // the pair's index; a's face by position, b's by rank when sorted
    double area;
    int line_a, line_b;
  };
  std::vector<Share> shares;
  int k = 0;  // the dropped axis of the pairs being matched
  const auto match = [&](const OverlapBox& x, const OverlapBox& y) {
    // overlap() finds nothing unless the bounds overlap strictly on both axes (0 and 2 of the boxes).
    if (!(x.min_coord(0) < y.max_coord(0) && y.min_coord(0) < x.max_coord(0) && x.min_coord(2) < y.max_coord(2) &&
          y.min_coord(2) < x.max_coord(2)))
      return;
    std::uint32_t fi = x.info(), gi = y.info();
    std::uint32_t a = faces[fi].surface, b = faces[gi].surface;
    if (a > b || (a == b && fi > gi)) {  // one surface against itself: its faces in order of index, as the sweep
      std::swap(fi, gi);
      std::swap(a, b);
    }
    const auto end = candidates.begin() + first_pair[a + 1];
    const auto c = std::lower_bound(candidates.begin() + first_pair[a], end, std::pair{a, b});
    if (c == end || c->second != b || dropped_axis(surfaces[a].plane.normal) != k) return;
    const Vec3 n = surfaces[a].plane.normal;
    const Flattened& fa = flat(a, n);
    const Flattened& fb = flat(b, n);
    const std::uint32_t first = position_in_surface[fi], second = fb.rank[position_in_surface[gi]];
    const FlatFace& f = fa.sorted[fa.rank[first]];
    const FlatFace& g = fb.sorted[second];
    const double shared = overlap(f, g);
    if (shared == 0.0) return;  // adds nothing to the sum and is no largest share
    shares.push_back(Share{static_cast<std::uint32_t>(c - candidates.begin()), first, second, shared, f.line, g.line});
    if (shares.size() >= most_pairs) throw EnoughPairs{};
  };
  // Per set, since surfaces of about one d that are no pair (noise splits a plane into surfaces out of each other's
  // plane) would otherwise be matched for nothing: 20 000 planks turned off the axes and written to 7 digits, 1 873
  // surfaces and 3 pairs besides their own, gave 632 000 pairs of boxes at once, 367 000 of no pair, twice the
  // sweep's time. A set's flattened surfaces are dropped after it, as no pair reaches beyond it.
  std::vector<std::uint32_t> component(surfaces.size());
  for (std::uint32_t si = 0; si < component.size(); ++si) component[si] = si;
  const auto find = [&](std::uint32_t si) {
    while (component[si] != si) si = component[si] = component[component[si]];
    return si;
  };
  for (const auto& [a, b] : candidates)
    if (a != b) component[find(a)] = find(b);
  std::vector<std::uint32_t> by_component(surfaces.size());
  for (std::uint32_t si = 0; si < by_component.size(); ++si) by_component[si] = si;
  for (std::uint32_t si = 0; si < component.size(); ++si) component[si] = find(si);
  std::sort(by_component.begin(), by_component.end(),
            [&](std::uint32_t x, std::uint32_t y) { return std::pair{component[x], x} < std::pair{component[y], y}; });
  try {
    for (std::size_t i = 0, j = 0; i < by_component.size(); i = j) {
      for (j = i; j < by_component.size() && component[by_component[j]] == component[by_component[i]]; ++j) {}
      for (k = 0; k < 3; ++k) {
        const int u = (k + 1) % 3, v = (k + 2) % 3;
        boxes.clear();
        for (std::size_t m = i; m < j; ++m) {
          const std::uint32_t si = by_component[m];
          if (!in_axis[si][k]) continue;
          const Surface& s = surfaces[si];
          for (const std::uint32_t fi : s.faces) {
            Vec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
            for (const Vec3& p : faces[fi].vertices) {
              lo = glm::min(lo, Vec2(p[u], p[v]));
              hi = glm::max(hi, Vec2(p[u], p[v]));
            }
            boxes.push_back(overlap_box(lo, hi, s.plane.d, window, fi));
          }
        }
        if (boxes.size() >= 2) CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), match);
      }
      flattened.clear();
      for (std::size_t m = i; m < j; ++m) flattened_index[by_component[m]].fill(-1);
    }
  } catch (const EnoughPairs&) {
    if (complete != nullptr) *complete = false;
  }
  std::sort(shares.begin(), shares.end(), [](const Share& x, const Share& y) {
    return std::tie(x.pair, x.first, x.second) < std::tie(y.pair, y.first, y.second);
  });
  for (std::size_t i = 0; i < shares.size();) {
    const auto [a, b] = candidates[shares[i].pair];
    CoplanarOverlap o{a, b, 0.0, 0, 0};
    double largest = 0.0;
    const std::uint32_t pair = shares[i].pair;
    for (; i < shares.size() && shares[i].pair == pair; ++i) {
      const Share& share = shares[i];
      o.area += share.area;
      if (share.area > largest) {
        largest = share.area;
        o.line_a = share.line_a;
        o.line_b = share.line_b;
      }
    }
    // The shares are areas in the projection that drops the first surface's dominant axis k, |n_k| times the areas
    // in the plane: a rug on the floor of a room turned off the axes was reported over 87 % of its area.
    const Vec3& n = surfaces[a].plane.normal;
    o.area /= std::abs(n[dropped_axis(n)]);
    if (o.area > 1e-6 * std::min(surfaces[a].area, surfaces[b].area)) found.push_back(o);
  }
  return found;
}

Vec3 Scene::bounds_min() const {
  if (faces.empty()) return Vec3(0.0);
  Vec3 lo(std::numeric_limits<double>::infinity());
  for (const Face& f : faces)
    for (const Vec3& v : f.vertices) lo = glm::min(lo, v);
  return lo;
}

Vec3 Scene::bounds_max() const {
  if (faces.empty()) return Vec3(0.0);
  Vec3 hi(-std::numeric_limits<double>::infinity());
  for (const Face& f : faces)
    for (const Vec3& v : f.vertices) hi = glm::max(hi, v);
  return hi;
}

double Scene::diagonal() const { return glm::length(bounds_max() - bounds_min()); }

double Scene::total_area() const {
  double sum = 0.0;
  for (const Face& f : faces) sum += area(f.vertices);
  return sum;
}

std::optional<Scene::OcclusionWitness> Scene::occlusion_witness() const {
  const double tolerance = 1e-6 * diagonal();
  for (std::uint32_t s = 0; s < surfaces.size(); ++s) {
    const Plane& plane = surfaces[s].plane;
    for (const Face& face : faces) {
      if (face.surface == s) continue;
      for (const Vec3& v : face.vertices) {
        if (plane.signed_distance(v) < -tolerance) return OcclusionWitness{s, face.surface};
      }
    }
  }
  return std::nullopt;
}

std::optional<std::uint32_t> Scene::find_group(const std::string& group_name) const {
  for (std::uint32_t i = 0; i < groups.size(); ++i)
    if (groups[i].name == group_name) return i;
  return std::nullopt;
}

Camera Scene::fitted_camera(double aspect) const {
  // From outside the bounds, a little above, looking slightly down, far enough that the bounding sphere fits both
  // fields of view. The direction is the Cornell box's convention (looking along +z from the -z side) unless the
  // scene shows much more of its front faces from another side: the renderer culls back faces, and a wall facing
  // +z, or a plane seen edge-on, came out black. Each direction is scored by the area of front faces it sees,
  // projected onto it; a closed room scores the same from every side (its vector areas sum to zero) and keeps the
  // convention, as does any scene the conventional view shows at least half as well as the best one.
  std::array<Vec3, 6> directions{Vec3(0.0, -0.2, 1.0), Vec3(0.0, -0.2, -1.0), Vec3(1.0, -0.2, 0.0),
                                 Vec3(-1.0, -0.2, 0.0), Vec3(0.0, -1.0, 0.2), Vec3(0.0, 1.0, 0.2)};
  for (Vec3& d : directions) d = glm::normalize(d);
  std::array<double, 6> seen{};
  for (const Face& face : faces) {
    const Vec3 a = vector_area(face.vertices);  // area times the front normal
    for (std::size_t k = 0; k < directions.size(); ++k) seen[k] += std::max(0.0, -glm::dot(a, directions[k]));
  }
  std::size_t best = 0;
  for (std::size_t k = 1; k < directions.size(); ++k)
    if (seen[k] > seen[best]) best = k;
  if (!(seen[best] > 2.0 * seen[0])) best = 0;

  Camera camera;
  const Vec3 centre = 0.5 * (bounds_min() + bounds_max());
  // No floor in absolute units: a scene 1e-12 across was framed as if it were 1e-9 across, a dot.
  const double diagonal_length = diagonal();
  const double radius = diagonal_length > 0.0 ? 0.5 * diagonal_length : 1.0;
  camera.forward = directions[best];
  camera.up = glm::normalize(Vec3(0.0, 1.0, 0.0) - camera.forward.y * camera.forward);
  const double half_vertical = 0.5 * camera.vertical_fov;
  const double half_horizontal = std::atan(std::max(aspect, 1e-6) * std::tan(half_vertical));
  const double half = std::min(half_vertical, half_horizontal);
  camera.eye = centre - camera.forward * (radius / std::sin(half));
  return camera;
}

}  // namespace aarad
