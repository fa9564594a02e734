#include "aarad/core/polygon.h"

#include "aarad/core/predicates.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

namespace aarad {

Vec3 vector_area(std::span<const Vec3> polygon) {
  // Newell's method, relative to the first vertex to keep the products small far from the origin.
  Vec3 sum(0.0);
  if (polygon.size() < 3) return sum;
  const Vec3 o = polygon[0];
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) sum += glm::cross(polygon[i] - o, polygon[i + 1] - o);
  return 0.5 * sum;
}

double area(std::span<const Vec3> polygon) { return glm::length(vector_area(polygon)); }

double box_diagonal(std::span<const Vec3> points) {
  if (points.empty()) return 0.0;
  Vec3 lo = points.front(), hi = points.front();
  for (const Vec3& p : points) lo = glm::min(lo, p), hi = glm::max(hi, p);
  return glm::length(hi - lo);
}

Vec3 normal(std::span<const Vec3> polygon) {
  const Vec3 a = vector_area(polygon);
  const double len = glm::length(a);
  return len > 0.0 ? a / len : Vec3(0.0);
}

Vec3 centroid(std::span<const Vec3> polygon) {
  if (polygon.empty()) return Vec3(0.0);
  const Vec3 n = vector_area(polygon);
  const double twice_area_sq = glm::dot(n, n);
  const Vec3 o = polygon[0];
  Vec3 mean(0.0);
  for (const Vec3& v : polygon) mean += v;
  mean /= static_cast<double>(polygon.size());
  if (twice_area_sq == 0.0) return mean;
  // Fan triangles from the first vertex, weighted by their signed area along the polygon's normal.
  Vec3 weighted(0.0);
  double total = 0.0;
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
    const double w = glm::dot(glm::cross(polygon[i] - o, polygon[i + 1] - o), n);
    weighted += w * (o + polygon[i] + polygon[i + 1]) / 3.0;
    total += w;
  }
  return total != 0.0 ? weighted / total : mean;
}

Plane plane_of(std::span<const Vec3> polygon) {
  const Vec3 n = normal(polygon);
  return Plane{n, -glm::dot(n, centroid(polygon))};
}

double planarity_deviation(std::span<const Vec3> polygon) {
  const Plane p = plane_of(polygon);
  double worst = 0.0;
  for (const Vec3& v : polygon) worst = std::max(worst, std::abs(p.signed_distance(v)));
  return worst;
}

double signed_area(std::span<const Vec2> polygon) {
  if (polygon.size() < 3) return 0.0;
  const Vec2 o = polygon[0];
  double sum = 0.0;
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
    const Vec2 a = polygon[i] - o, b = polygon[i + 1] - o;
    sum += a.x * b.y - a.y * b.x;
  }
  return 0.5 * sum;
}

bool is_convex(std::span<const Vec2> polygon) {
  const std::size_t n = polygon.size();
  if (n < 3) return false;
  bool has_positive = false, has_negative = false;
  for (std::size_t i = 0; i < n; ++i) {
    const Sign s = orientation(polygon[i], polygon[(i + 1) % n], polygon[(i + 2) % n]);
    has_positive |= s == Sign::kPositive;
    has_negative |= s == Sign::kNegative;
  }
  // Turning one way only; a convex polygon also winds once, which simplicity ensures.
  return has_positive != has_negative && is_simple(polygon);
}

bool is_simple(std::span<const Vec2> polygon) {
  const std::size_t n = polygon.size();
  if (n < 3) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (polygon[i] == polygon[(i + 1) % n]) return false;
  // Edges i and j > i, (polygon[i], polygon[i + 1]) and (polygon[j], polygon[j + 1]) cyclically: do they meet
  // only as a simple polygon's edges may?
  const auto apart = [&](std::size_t i, std::size_t j) {
    const Vec2& a = polygon[i];
    const Vec2& b = polygon[(i + 1) % n];
    const Vec2& c = polygon[j];
    const Vec2& d = polygon[(j + 1) % n];
    if (j == i + 1 || (i == 0 && j == n - 1)) {
      // Adjacent edges share one vertex; they must not fold back over each other.
      const Vec2& shared = j == i + 1 ? b : a;
      const Vec2& p = j == i + 1 ? a : b;
      const Vec2& q = j == i + 1 ? d : c;
      return !(orientation(p, shared, q) == Sign::kZero && glm::dot(p - shared, q - shared) > 0.0);
    }
    return !segments_intersect(a, b, c, d);
  };
  // Only edges whose bounding boxes meet can meet: the edges in order of their smallest x, each against those after
  // it that start at or before its largest x, then by y. The boxes compare the coordinates themselves, so nothing
  // is passed over that the exact test would find; every pair of a face of n vertices was tested before (a circle of
  // 50 000 vertices took 11 s to import).
  const auto low_x = [&](std::size_t e) { return std::min(polygon[e].x, polygon[(e + 1) % n].x); };
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t e, std::size_t f) { return low_x(e) < low_x(f); });
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t e = order[k];
    const Vec2& a = polygon[e];
    const Vec2& b = polygon[(e + 1) % n];
    const double high_x = std::max(a.x, b.x), low_y = std::min(a.y, b.y), high_y = std::max(a.y, b.y);
    for (std::size_t m = k + 1; m < n && low_x(order[m]) <= high_x; ++m) {
      const std::size_t f = order[m];
      const Vec2& c = polygon[f];
      const Vec2& d = polygon[(f + 1) % n];
      if (std::max(c.y, d.y) < low_y || std::min(c.y, d.y) > high_y) continue;
      if (!apart(std::min(e, f), std::max(e, f))) return false;
    }
  }
  return true;
}

bool contains(std::span<const Vec2> polygon, const Vec2& p) {
  bool in = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Vec2& a = polygon[i];
    const Vec2& b = polygon[j];
    if ((a.y > p.y) == (b.y > p.y)) continue;  // the edge does not cross the horizontal line through p
    // p lies left of the crossing exactly when it lies left of the edge taken upwards.
    const bool upwards = b.y > a.y;
    if (orientation(upwards ? a : b, upwards ? b : a, p) == Sign::kPositive) in = !in;
  }
  return in;
}

int dropped_axis(const Vec3& n) {
  const Vec3 a = glm::abs(n);
  if (a.x >= a.y && a.x >= a.z) return 0;
  return a.y >= a.z ? 1 : 2;
}

void project_to_2d(std::span<const Vec3> polygon, const Vec3& n, std::span<Vec2> out) {
  // Drop the dominant axis of n; swap the remaining two when needed to keep the winding.
  const int drop = dropped_axis(n);
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  const bool flip = n[drop] < 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Vec3& p = polygon[i];
    out[i] = flip ? Vec2(p[v], p[u]) : Vec2(p[u], p[v]);
  }
}

namespace {

// Whether q lies in triangle (a, b, c) or on its boundary, exactly (a, b, c counter-clockwise).
bool in_triangle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& q) {
  return orientation(a, b, q) != Sign::kNegative && orientation(b, c, q) != Sign::kNegative &&
         orientation(c, a, q) != Sign::kNegative;
}

// Ear clipping of a large polygon: the vertices in a doubly linked ring, the walk going on from the last ear
// instead of starting again at the first vertex, and an ear's emptiness tested against the reflex vertices (only
// those can lie in an ear of a simple polygon; a vertex stays reflex until a neighbour is clipped) of the grid
// cells its box meets (about n cells over the polygon's box), not against all of them. A polygon with no ear left
// (not simple: a non-planar face seen along its normal may cross itself) has its next vertex clipped, as
// ear_clip_small does.
void ear_clip_large(std::span<const Vec2> p, std::vector<std::array<std::size_t, 3>>& triangles) {
  const std::size_t n = p.size();
  Vec2 low = p[0], high = p[0];
  for (const Vec2& v : p) {
    low = glm::min(low, v);
    high = glm::max(high, v);
  }
  const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  // Halves, so that a polygon spanning more than the largest double (corners near +-1e308) has a finite extent.
  const Vec2 extent = glm::max(0.5 * high - 0.5 * low, Vec2(std::numeric_limits<double>::min()));
  const auto cell_of = [&](double x, double lo, double size) {
    const double at = std::floor((0.5 * x - 0.5 * lo) / size * static_cast<double>(side));
    return at >= 0.0 ? static_cast<std::size_t>(std::min(at, static_cast<double>(side - 1))) : std::size_t{0};
  };
  std::vector<std::vector<std::size_t>> cells(side * side);
  for (std::size_t i = 0; i < n; ++i)
    cells[cell_of(p[i].y, low.y, extent.y) * side + cell_of(p[i].x, low.x, extent.x)].push_back(i);
  std::vector<std::size_t> next(n), prev(n);
  std::vector<std::uint8_t> removed(n, 0), reflex(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    next[i] = (i + 1) % n;
    prev[i] = (i + n - 1) % n;
  }
  const auto update_reflex = [&](std::size_t i) {
    reflex[i] = orientation(p[prev[i]], p[i], p[next[i]]) != Sign::kPositive;
  };
  for (std::size_t i = 0; i < n; ++i) update_reflex(i);
  const auto is_ear = [&](std::size_t a, std::size_t b, std::size_t c) {
    if (orientation(p[a], p[b], p[c]) != Sign::kPositive) return false;
    const Vec2 lo = glm::min(p[a], glm::min(p[b], p[c])), hi = glm::max(p[a], glm::max(p[b], p[c]));
    for (std::size_t y = cell_of(lo.y, low.y, extent.y); y <= cell_of(hi.y, low.y, extent.y); ++y)
      for (std::size_t x = cell_of(lo.x, low.x, extent.x); x <= cell_of(hi.x, low.x, extent.x); ++x)
        for (const std::size_t q : cells[y * side + x]) {
          if (reflex[q] == 0 || removed[q] != 0 || q == a || q == b || q == c || p[q] == p[a] || p[q] == p[b] ||
              p[q] == p[c])
            continue;
          if (in_triangle(p[a], p[b], p[c], p[q])) return false;
        }
    return true;
  };
  std::size_t remaining = n, at = 0, tried = 0;
  while (remaining > 3) {
    const std::size_t a = prev[at], c = next[at];
    if (tried < remaining && !is_ear(a, at, c)) {
      at = c;
      ++tried;
      continue;
    }
    triangles.push_back({a, at, c});
    removed[at] = 1;
    next[a] = c;
    prev[c] = a;
    update_reflex(a);
    update_reflex(c);
    --remaining;
    at = a;  // the ear's neighbours are the vertices whose ears changed
    tried = 0;
  }
  triangles.push_back({prev[at], at, next[at]});
}

// The plain algorithm for small polygons: every ear found by scanning the remaining vertices from the first.
void ear_clip_small(std::span<const Vec2> p, std::vector<std::array<std::size_t, 3>>& triangles) {
  std::vector<std::size_t> remaining(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) remaining[i] = i;
  while (remaining.size() > 3) {
    const std::size_t n = remaining.size();
    std::size_t ear = n;
    for (std::size_t k = 0; k < n && ear == n; ++k) {
      const std::size_t a = remaining[(k + n - 1) % n], b = remaining[k], c = remaining[(k + 1) % n];
      if (orientation(p[a], p[b], p[c]) != Sign::kPositive) continue;
      bool empty = true;
      for (const std::size_t q : remaining) {
        if (q == a || q == b || q == c || p[q] == p[a] || p[q] == p[b] || p[q] == p[c]) continue;
        if (orientation(p[a], p[b], p[q]) != Sign::kNegative && orientation(p[b], p[c], p[q]) != Sign::kNegative &&
            orientation(p[c], p[a], p[q]) != Sign::kNegative) {
          empty = false;
          break;
        }
      }
      if (empty) ear = k;
    }
    // A simple polygon always has an ear (Meisters' two-ears theorem); only straight runs remain otherwise.
    const std::size_t k = ear == n ? 0 : ear;
    triangles.push_back({remaining[(k + n - 1) % n], remaining[k], remaining[(k + 1) % n]});
    remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(k));
  }
  triangles.push_back({remaining[0], remaining[1], remaining[2]});
}

}  // namespace

// Polygons up to kSmallPolygon vertices (every face of the usual scene) are clipped as they always were, so their
// triangles do not change; larger ones took quadratic time or worse (a non-planar face of 100 000 vertices, 82 s).
void ear_clip(std::span<const Vec2> p, std::vector<std::array<std::size_t, 3>>& triangles) {
  constexpr std::size_t kSmallPolygon = 64;
  if (p.size() < 3) return;
  const auto finite = [](const Vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); };
  if (p.size() <= kSmallPolygon || !std::all_of(p.begin(), p.end(), finite)) {  // no grid of what is not finite
    ear_clip_small(p, triangles);
  } else {
    ear_clip_large(p, triangles);
  }
}

void convex_intersection(std::span<const Vec2> a, std::span<const Vec2> b, std::vector<Vec2>& out,
                         std::vector<Vec2>& scratch) {
  std::vector<Vec2>& current = out;
  current.assign(a.begin(), a.end());
  std::vector<Vec2>& next = scratch;
  for (std::size_t i = 0; i < b.size() && current.size() >= 3; ++i) {
    const Vec2 p = b[i], q = b[(i + 1) % b.size()];
    // Inside: on the left of the edge p -> q (or on it).
    const auto side = [&](const Vec2& v) { return (q.x - p.x) * (v.y - p.y) - (q.y - p.y) * (v.x - p.x); };
    next.clear();
    Vec2 prev = current.back();
    double prev_side = side(prev);
    for (const Vec2& cur : current) {
      const double cur_side = side(cur);
      if (cur_side >= 0.0) {
        if (prev_side < 0.0) next.push_back(prev + (cur - prev) * (prev_side / (prev_side - cur_side)));
        next.push_back(cur);
      } else if (prev_side >= 0.0) {
        if (prev_side > 0.0) next.push_back(prev + (cur - prev) * (prev_side / (prev_side - cur_side)));
      }
      prev = cur;
      prev_side = cur_side;
    }
    current.swap(next);
  }
}

double convex_intersection_area(std::span<const Vec2> a, std::span<const Vec2> b) {
  std::vector<Vec2> intersection, scratch;
  convex_intersection(a, b, intersection, scratch);
  return intersection.size() >= 3 ? std::max(0.0, signed_area(intersection)) : 0.0;
}

}  // namespace aarad
