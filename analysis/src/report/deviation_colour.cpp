#include <algorithm>
#include <cmath>

#include "truecut/analysis/report/deviation_image.hpp"

namespace truecut::analysis::report {

std::array<std::uint8_t, 3> deviation_colour(double value, double limit) {
  if (!std::isfinite(value) || !(limit > 0)) return {150, 150, 150};
  const double t = std::clamp(value / limit, -1.0, 1.0);
  // Blue (-1) -> light green (0) -> red (+1), each channel linear per half.
  const std::array<double, 3> minus{40, 90, 220}, zero{200, 235, 200}, plus{220, 50, 40};
  const auto& far = t < 0 ? minus : plus;
  const double a = std::abs(t);
  std::array<std::uint8_t, 3> c{};
  for (int i = 0; i < 3; ++i)
    c[i] = static_cast<std::uint8_t>(std::lround(zero[i] + (far[i] - zero[i]) * a));
  return c;
}

}  // namespace truecut::analysis::report
