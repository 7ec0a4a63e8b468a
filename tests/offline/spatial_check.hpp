// Brute-force nearest-neighbour spacing of a small point set, for checking
// samplings.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace truecut::offline::test_spatial {

struct Spacing {
  double min_mm = std::numeric_limits<double>::infinity();
  double max_mm = 0.0;  // the largest nearest-neighbour distance
};

inline Spacing nearest_spacing(const std::vector<Eigen::Vector3d>& p) {
  Spacing s;
  for (std::size_t i = 0; i < p.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < p.size(); ++j) {
      if (j != i) best = std::min(best, (p[i] - p[j]).norm());
    }
    s.min_mm = std::min(s.min_mm, best);
    s.max_mm = std::max(s.max_mm, best);
  }
  return s;
}

}  // namespace truecut::offline::test_spatial
