// Exact point-to-polygon form factor: Baum, Rushmeier and Winget 1989, eq. 9 (Lambert's contour integral).
#include "aarad/formfactor/analytic.h"

#include "aarad/formfactor/hemicube_geometry.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace aarad::formfactor {

double polygon_form_factor(const Vec3& point, const Vec3& normal, std::span<const Vec3> polygon) {
  const std::size_t m = polygon.size();
  if (m < 3) return 0.0;
  // The factor depends only on the directions from the point: every vector is scaled by the power of two that
  // brings the largest offset near 1, which changes no bit of the result in the usual range, and keeps the lengths
  // and products below from overflowing (a receiver 1e77 across gave 0, one 1e200 across nan) or underflowing
  // (one 1e-200 across gave 0).
  double farthest = 0.0;  // the largest offset's largest component
  for (const Vec3& p : polygon) {
    const Vec3 r = glm::abs(p - point);
    farthest = std::max({farthest, r.x, r.y, r.z});
  }
  if (!(farthest > 0.0) || !std::isfinite(farthest)) return 0.0;
  // scalbn per component, not a product with 2^e: for a subnormal offset 2^e itself overflows.
  const int e = -std::ilogb(farthest);
  const auto scaled = [e](const Vec3& v) { return Vec3(std::scalbn(v.x, e), std::scalbn(v.y, e), std::scalbn(v.z, e)); };
  double sum = 0.0;
  Vec3 r0 = scaled(polygon[m - 1] - point);
  for (std::size_t i = 0; i < m; ++i) {
    const Vec3 r1 = scaled(polygon[i] - point);
    // R_{i+1} x R_i, as (v_{i+1} - v_i) x R_i: the same vector, without the cancellation of two nearly parallel
    // long vectors (a receiver small against its distance: at 1e-8 of it the direct product was noise).
    const Vec3 c = glm::cross(scaled(polygon[i] - polygon[i == 0 ? m - 1 : i - 1]), r0);
    double len = glm::length(c);
    if (len < 1e-140) {
      // |c|^2 underflows below about 1e-154: the length of c scaled by its largest component instead (an edge 1e-200
      // from the point, in its plane, came out as 0 and was dropped, with all of a wall's 0.5).
      const double largest = std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)});
      if (largest > 0.0) len = largest * glm::length(c / largest);
    }
    if (len > 0.0) {
      const double gamma = std::atan2(len, glm::dot(r0, r1));
      sum += gamma * glm::dot(normal, c) / len;
    }
    r0 = r1;
  }
  return sum / (2.0 * kPi);
}

namespace {

inline bool lexicographic_less(const Vec3& a, const Vec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

inline Vec3 horizon_crossing(const Vec3& p, const Vec3& q) {
  const bool swap = lexicographic_less(q, p);
  const Vec3& a = swap ? q : p;
  const Vec3& b = swap ? p : q;
  Vec3 x = a + (a.z / (a.z - b.z)) * (b - a);
  x.z = 0.0;
  return x;
}

}  // namespace

std::size_t clip_to_front(std::span<const Vec3> local_polygon, std::span<Vec3> out) {
  const std::size_t m = local_polygon.size();
  if (m < 3) return 0;
  std::size_t written = 0;
  Vec3 prev = local_polygon[m - 1];
  for (std::size_t i = 0; i < m; ++i) {
    const Vec3 cur = local_polygon[i];
    if (cur.z >= 0.0) {
      if (prev.z < 0.0 && cur.z > 0.0) out[written++] = horizon_crossing(prev, cur);
      out[written++] = cur;
    } else if (prev.z > 0.0) {
      out[written++] = horizon_crossing(prev, cur);
    }
    prev = cur;
  }
  return written < 3 ? 0 : written;
}

void AnalyticBackend::compute(const Shooter& shooter, const ReceiverView& receivers,
                              std::span<const std::uint32_t> subset, std::span<double> out) {
  check_shot(shooter, receivers, subset, out);
  culling_.decide(shooter.centre, receivers);
  const std::size_t count = subset.empty() ? receivers.size() : subset.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const tbb::blocked_range<std::size_t>& range) {
    Scratch& s = scratch_.local();
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const std::size_t i = subset.empty() ? k : subset[k];
      if (!culling_.faces(i)) {
        out[i] = 0.0;
        continue;
      }
      const std::span<const Vec3> polygon = receivers.polygon(i);
      s.local.resize(polygon.size());
      s.clipped.resize(plane_clipped_capacity(polygon.size()));
      bool behind = false, crossing = false;
      for (std::size_t v = 0; v < polygon.size(); ++v) {
        s.local[v] = to_local(shooter, polygon[v]);
        behind |= s.local[v].z < 0.0;
        crossing |= s.local[v].z > 0.0;
      }
      std::span<const Vec3> visible = s.local;
      if (behind) visible = std::span<const Vec3>(s.clipped.data(), crossing ? clip_to_front(s.local, s.clipped) : 0);
      out[i] = polygon_form_factor(Vec3(0.0), Vec3(0.0, 0.0, 1.0), visible);
    }
  });
}

}  // namespace aarad::formfactor
