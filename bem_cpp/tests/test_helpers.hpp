#pragma once
// Test polygons shared by the GoogleTest files.
#include <cmath>

#include "bem/geometry.hpp"

namespace bem::test {

inline Points circle(Index n, double radius = 0.4) {
  Points X(n, 2);
  for (Index k = 0; k < n; ++k) {
    const double t = 2.0 * M_PI * static_cast<double>(k) / static_cast<double>(n);
    X(k, 0) = radius * std::cos(t);
    X(k, 1) = radius * std::sin(t);
  }
  return X;
}

/// Square [-s, s]^2 with m panels per side.
inline Points square(Index m, double s = 0.3) {
  Points X(4 * m, 2);
  const double c[4][2] = {{-s, -s}, {s, -s}, {s, s}, {-s, s}};
  for (int side = 0; side < 4; ++side)
    for (Index k = 0; k < m; ++k) {
      const double w = static_cast<double>(k) / static_cast<double>(m);
      const int e = (side + 1) % 4;
      X(side * m + k, 0) = (1 - w) * c[side][0] + w * c[e][0];
      X(side * m + k, 1) = (1 - w) * c[side][1] + w * c[e][1];
    }
  return X;
}

}  // namespace bem::test
