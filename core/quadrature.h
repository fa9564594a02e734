// Gauss-Legendre quadrature on [0, 1] (Newton iteration on the Legendre polynomial P_n from Chebyshev-like
// first guesses; Press et al., Numerical Recipes, section 4.6), and product rules from it over polygons.
#pragma once

#include "aarad/core/math.h"

#include <cmath>
#include <cstddef>
#include <span>
#include <utility>
#include <vector>

namespace aarad {

// The n nodes in (0, 1) and their weights, which sum to 1: the integral of f over [0, 1] is about
// sum_i weights[i] f(nodes[i]), exact for polynomials of degree up to 2n - 1.
inline void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
  nodes.assign(static_cast<std::size_t>(n), 0.0);
  weights.assign(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double derivative = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = 0.0;
      for (int k = 1; k <= n; ++k) {
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p2) / k;
      }
      derivative = n * (x * p0 - p1) / (x * x - 1.0);
      const double step = p0 / derivative;
      x -= step;
      if (std::abs(step) < 1e-15) break;
    }
    nodes[static_cast<std::size_t>(i)] = 0.5 * (1.0 - x);
    weights[static_cast<std::size_t>(i)] = 1.0 / ((1.0 - x * x) * derivative * derivative);  // w on [-1, 1], / 2
  }
}

// A point of a quadrature over a polygon, with its weight: the fraction of the polygon's area it stands for.
struct AreaSample {
  Vec3 position{0.0};
  double weight = 0.0;
};

// Quadrature points over a planar convex polygon, their weights summing to 1: a triangle as a collapsed square, a
// quadrilateral by its bilinear map, a larger polygon as the fan of triangles from its first corner; each of those
// cut into cells x cells parts with n x n Gauss points in each. Empty for a polygon of no area.
// The rule into `samples` (cleared first), whose memory is reused.
inline void polygon_quadrature(std::span<const Vec3> corners, int n, int cells, std::vector<AreaSample>& samples) {
  std::vector<double> nodes, weights;
  gauss_legendre(n, nodes, weights);
  samples.clear();
  double total = 0.0;
  // The points over the unit square, mapped by `map`, which returns the point and the Jacobian there.
  const auto square = [&](auto&& map) {
    for (int ci = 0; ci < cells; ++ci) {
      for (int cj = 0; cj < cells; ++cj) {
        for (int i = 0; i < n; ++i) {
          for (int j = 0; j < n; ++j) {
            const double u = (ci + nodes[static_cast<std::size_t>(i)]) / cells;
            const double v = (cj + nodes[static_cast<std::size_t>(j)]) / cells;
            const double w = weights[static_cast<std::size_t>(i)] * weights[static_cast<std::size_t>(j)];
            const auto [p, jacobian] = map(u, v);
            samples.push_back({p, w * jacobian});
            total += w * jacobian;
          }
        }
      }
    }
  };
  const auto triangle = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    const double doubled = glm::length(glm::cross(b - a, c - b));
    square([&](double u, double v) { return std::pair{a + u * (b - a) + u * v * (c - b), u * doubled}; });
  };
  if (corners.size() == 3) {
    triangle(corners[0], corners[1], corners[2]);
  } else if (corners.size() == 4) {
    const Vec3 &a = corners[0], &b = corners[1], &c = corners[2], &d = corners[3];
    square([&](double u, double v) {
      const Vec3 p = (1 - u) * (1 - v) * a + u * (1 - v) * b + u * v * c + (1 - u) * v * d;
      const Vec3 du = (1 - v) * (b - a) + v * (c - d);
      const Vec3 dv = (1 - u) * (d - a) + u * (c - b);
      return std::pair{p, glm::length(glm::cross(du, dv))};
    });
  } else {
    for (std::size_t k = 1; k + 1 < corners.size(); ++k) triangle(corners[0], corners[k], corners[k + 1]);
  }
  if (!(total > 0.0)) {
    samples.clear();
    return;
  }
  for (AreaSample& s : samples) s.weight /= total;
}

inline std::vector<AreaSample> polygon_quadrature(std::span<const Vec3> corners, int n, int cells = 1) {
  std::vector<AreaSample> samples;
  polygon_quadrature(corners, n, cells, samples);
  return samples;
}

}  // namespace aarad
