#include "parts/revolved_stock.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace truecut::sim::parts {

void add_disc_boxes(std::vector<StockBox>& out, double rho_in_mm, double rho_out_mm, double z0_mm,
                    double z1_mm) {
  if (!(rho_out_mm > rho_in_mm && rho_in_mm > 0 && z1_mm > z0_mm))
    throw std::invalid_argument("add_disc_boxes: needs 0 < rho_in < rho_out and z0 < z1");
  const double q = (rho_in_mm / rho_out_mm) * (rho_in_mm / rho_out_mm);
  // Outer corner at angle θ: (ρ_out cos θ, ρ_out sin θ). The first rectangle
  // reaches ρ_in along X; each next one is turned as far as the inner corner
  // (a_next, b_prev) allows: cos² θ_next = q − sin² θ_prev.
  double theta = std::acos(rho_in_mm / rho_out_mm);
  for (int guard = 0; guard < 100000; ++guard) {
    const double a = rho_out_mm * std::cos(theta), b = rho_out_mm * std::sin(theta);
    out.push_back({{-a, -b, z0_mm}, {a, b, z1_mm}});
    if (b >= rho_in_mm) return;
    const double c2 = q - std::sin(theta) * std::sin(theta);
    theta = c2 > 0 ? std::acos(std::sqrt(c2)) : std::numbers::pi / 2;
  }
  throw std::logic_error("add_disc_boxes: no convergence");
}

void add_dome_boxes(std::vector<StockBox>& out, double r_in_mm, double r_out_mm,
                    double z_centre_mm) {
  if (!(r_out_mm > r_in_mm && r_in_mm > 0))
    throw std::invalid_argument("add_dome_boxes: needs 0 < r_in < r_out");
  const double ri2 = r_in_mm * r_in_mm, ro2 = r_out_mm * r_out_mm;
  const double g = 0.5 * (ro2 - ri2);
  double h0 = 0;
  while (h0 < r_in_mm) {
    const double h1 = std::min(std::sqrt(h0 * h0 + g), r_in_mm);
    const double rho_in = std::sqrt(std::max(ri2 - h0 * h0, 1e-12));
    const double rho_out = std::sqrt(ro2 - h1 * h1);
    add_disc_boxes(out, rho_in, rho_out, z_centre_mm + h0, z_centre_mm + h1);
    h0 = h1;
  }
}

}  // namespace truecut::sim::parts
