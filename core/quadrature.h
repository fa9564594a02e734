// Gauss-Legendre quadrature on [0, 1] (Newton iteration on the Legendre polynomial P_n from Chebyshev-like
// first guesses; Press et al., Numerical Recipes, section 4.6).
#pragma once

#include "aarad/core/math.h"

#include <cmath>
#include <cstddef>
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

}  // namespace aarad
