// Small scene builders shared by the form-factor tests: receivers from plain polygons, rectangles, boxes,
// and closed forms from Howell's catalog (../shared/references.md).
#pragma once

#include "aarad/core/math.h"
#include "aarad/core/polygon.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/hemicube_geometry.h"
#include "aarad/formfactor/receiver_view.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace aarad::formfactor::testing {

using Polygon = std::vector<Vec3>;

// Rectangle origin, origin + e1, origin + e1 + e2, origin + e2: counter-clockwise seen from the side
// e1 x e2 points to.
inline Polygon rectangle(const Vec3& origin, const Vec3& e1, const Vec3& e2) {
  return {origin, origin + e1, origin + e1 + e2, origin + e2};
}

inline Polygon reversed(Polygon p) { return Polygon(p.rbegin(), p.rend()); }

// A regular m-gon of radius r in the plane z = h, centred at (cx, cy), facing down (-z).
inline Polygon disk_facing_down(double cx, double cy, double h, double r, int m) {
  Polygon p;
  for (int k = 0; k < m; ++k) {
    const double t = -2.0 * kPi * k / m;  // clockwise seen from above = counter-clockwise seen from below
    p.push_back({cx + r * std::cos(t), cy + r * std::sin(t), h});
  }
  return p;
}

// The rectangle split into nx x ny coplanar pieces (same orientation).
inline std::vector<Polygon> grid(const Vec3& origin, const Vec3& e1, const Vec3& e2, int nx, int ny) {
  std::vector<Polygon> pieces;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      pieces.push_back(rectangle(origin + (double(i) / nx) * e1 + (double(j) / ny) * e2, e1 / double(nx), e2 / double(ny)));
  return pieces;
}

// Adds a receiver with the plane of its polygon.
inline std::uint32_t add(ReceiverView& view, const Polygon& polygon, std::uint32_t surface, std::uint32_t patch) {
  return view.add(polygon, plane_of(polygon), surface, patch);
}

// Adds all pieces of one surface, each its own patch starting at `first_patch`; returns the indices.
inline std::vector<std::uint32_t> add_surface(ReceiverView& view, const std::vector<Polygon>& pieces,
                                              std::uint32_t surface, std::uint32_t first_patch) {
  std::vector<std::uint32_t> ids;
  const Plane plane = plane_of(pieces.front());
  for (std::size_t k = 0; k < pieces.size(); ++k)
    ids.push_back(view.add(pieces[k], plane, surface, first_patch + static_cast<std::uint32_t>(k)));
  return ids;
}

// The six inward-facing faces of the box [lo, hi], each cut into n x n pieces; surface s = face index.
inline void add_box(ReceiverView& view, const Vec3& lo, const Vec3& hi, int n) {
  const Vec3 d = hi - lo;
  const Vec3 ex(d.x, 0, 0), ey(0, d.y, 0), ez(0, 0, d.z);
  const std::vector<std::vector<Polygon>> faces = {
      grid(lo, ex, ey, n, n),                    // z = lo: normal +z (into the box)
      grid(lo + ez, ey, ex, n, n),               // z = hi: normal -z
      grid(lo, ey, ez, n, n),                    // x = lo: normal +x
      grid(lo + ex, ez, ey, n, n),               // x = hi: normal -x
      grid(lo, ez, ex, n, n),                    // y = lo: normal +y
      grid(lo + ey, ex, ez, n, n),               // y = hi: normal -y
  };
  std::uint32_t patch = 0;
  for (std::uint32_t s = 0; s < faces.size(); ++s) {
    add_surface(view, faces[s], s, patch);
    patch += static_cast<std::uint32_t>(faces[s].size());
  }
}

// A shooter frame at `centre` with `normal`, rotated by `angle` about the normal (so face seams and pixel
// rows meet receivers' edges at arbitrary angles).
inline Shooter rotated_shooter(const Vec3& centre, const Vec3& normal, double angle) {
  Shooter s = Shooter::from_normal(centre, normal);
  const Vec3 t = std::cos(angle) * s.tangent + std::sin(angle) * s.bitangent;
  s.bitangent = glm::cross(s.normal, t);
  s.tangent = t;
  return s;
}

// Howell B-3: differential area parallel to an a x b rectangle, its normal through a corner, distance c.
inline double howell_b3(double a, double b, double c) {
  const double A = a / c, B = b / c;
  const double sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
  return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * kPi);
}

// Howell B-2: differential area to a rectangle in a perpendicular plane at distance c; the rectangle spans
// [0, b] along the line through the foot of the perpendicular parallel to the element, and [0, a] along the
// element's normal, with a corner at that foot: X = a / b, Y = c / b.
inline double howell_b2(double a, double b, double c) {
  const double X = a / b, Y = c / b, r = std::sqrt(X * X + Y * Y);
  return (std::atan(1 / Y) - Y / r * std::atan(1 / r)) / (2 * kPi);
}

// Off-axis parallel disk of radius a at distance h, offset r (references.md).
inline double howell_disk(double a, double h, double r) {
  const double R = r / a, H = h / a;
  return 0.5 * (1 - (H * H + R * R - 1) / std::sqrt((1 + H * H + R * R) * (1 + H * H + R * R) - 4 * R * R));
}

// The inverse of to_face: local coordinates (u, v, w) of a point given in face coordinates (a, l1, l2).
inline Vec3 from_face(HemicubeFace face, const Vec3& q) {
  switch (face) {
    case HemicubeFace::kTop: return {q.y, q.z, q.x};
    case HemicubeFace::kPosU: return {q.x, q.y, q.z};
    case HemicubeFace::kNegU: return {-q.x, q.y, q.z};
    case HemicubeFace::kPosV: return {q.y, q.x, q.z};
    case HemicubeFace::kNegV: return {q.y, -q.x, q.z};
  }
  return q;
}

inline double relative_error(double value, double reference) { return std::abs(value - reference) / std::abs(reference); }

}  // namespace aarad::formfactor::testing
