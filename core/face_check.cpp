// The checks of a scene face (face_check.h). The order matters for the messages: a face whose vertices lie on one
// line is reported as such before its projection is looked at, and a bow-tie, whose Newell area may vanish, as
// self-intersecting rather than of zero area.
#include "aarad/core/face_check.h"

#include "aarad/core/polygon.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace aarad {

FaceCheck check_face(std::span<const Vec3> vertices) {
  FaceCheck check;
  // Drop repeated consecutive vertices (cyclically).
  std::vector<Vec3>& v = check.vertices;
  for (const Vec3& p : vertices)
    if (v.empty() || p != v.back()) v.push_back(p);
  while (v.size() > 1 && v.front() == v.back()) v.pop_back();
  std::size_t unique = 0;
  for (std::size_t i = 0; i < v.size() && unique < 3; ++i)
    if (std::find(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v[i]) == v.begin() + static_cast<std::ptrdiff_t>(i))
      ++unique;
  if (unique < 3) {
    check.problem = FaceProblem::kFewerThanThreeDistinct;
    return check;
  }

  // Within the bounds, the squared lengths below stay inside a double's range wherever a decision depends on them:
  // at 1e80 they overflowed (a valid face looked self-intersecting), at 1e-100 they underflowed (it looked like a
  // line).
  Vec3 lo = v[0], hi = v[0];
  for (const Vec3& p : v) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const Vec3 reach = glm::max(glm::abs(lo), glm::abs(hi));
  if (std::max({reach.x, reach.y, reach.z}) > kMaxCoordinate) {
    check.problem = FaceProblem::kTooLarge;
    return check;
  }
  const double size = glm::length(hi - lo);
  check.size = size;
  if (size < kMinFaceSize) {
    check.problem = FaceProblem::kTooSmall;
    return check;
  }

  // A reference plane that exists even when the Newell area vanishes (a symmetric bow-tie): through the
  // vertex farthest from v0 and the vertex farthest from that line.
  std::size_t far = 0;
  for (std::size_t i = 1; i < v.size(); ++i)
    if (glm::length(v[i] - v[0]) > glm::length(v[far] - v[0])) far = i;
  Vec3 widest(0.0);
  for (std::size_t i = 1; i < v.size(); ++i) {
    const Vec3 c = glm::cross(v[far] - v[0], v[i] - v[0]);
    if (glm::length(c) > glm::length(widest)) widest = c;
  }
  if (glm::length(widest) <= kZeroAreaFraction * size * size) {
    check.problem = FaceProblem::kCollinear;
    return check;
  }
  const Vec3 newell = vector_area(v);
  const bool newell_zero = 2.0 * glm::length(newell) <= kZeroAreaFraction * size * size;
  check.normal = newell_zero ? glm::normalize(widest) : glm::normalize(newell);

  check.flat.resize(v.size());
  project_to_2d(v, check.normal, check.flat);
  if (!is_simple(check.flat)) {
    check.problem = FaceProblem::kSelfIntersecting;
    return check;
  }
  if (newell_zero) {
    check.problem = FaceProblem::kZeroArea;
    return check;
  }

  Vec3 mean(0.0);
  for (const Vec3& p : v) mean += p;
  mean /= static_cast<double>(v.size());
  for (const Vec3& p : v) check.deviation = std::max(check.deviation, std::abs(glm::dot(check.normal, p - mean)));
  return check;
}

}  // namespace aarad
