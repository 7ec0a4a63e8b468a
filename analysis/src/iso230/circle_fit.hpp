// Least-squares circle and Fourier fits used by the circular test.
#pragma once

#include <cstddef>
#include <vector>

namespace truecut::analysis::detail {

struct CircleFit {
  double cp = 0, cq = 0, r = 0;
  bool ok = false;
};

// Geometric least squares (minimises Σ (|P − c| − r)²), started from the
// algebraic (Kåsa) fit. `use` selects samples; empty means all.
CircleFit fit_circle(const std::vector<double>& p, const std::vector<double>& q,
                     const std::vector<std::size_t>& use = {});

// Least-squares a_0 + Σ_{k=1..K} a_k cos kθ + b_k sin kθ; returns
// {a_0, 0, a_1, b_1, ..., a_K, b_K} (size 2K+2), empty when singular.
std::vector<double> fit_fourier(const std::vector<double>& theta_rad,
                                const std::vector<double>& value, int order);
double eval_fourier(const std::vector<double>& coeffs, double theta_rad, int max_order);

}  // namespace truecut::analysis::detail
