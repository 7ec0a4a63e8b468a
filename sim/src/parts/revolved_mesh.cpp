#include "parts/revolved_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>

namespace truecut::sim::parts {
namespace {

struct Ring {
  std::vector<std::uint32_t> ids;  // one id for a pole
  std::vector<double> angles;      // ψ of each vertex, rad, increasing from 0
};

Ring make_ring(MeshBuilder& b, const ProfilePoint& p, double edge_mm) {
  Ring r;
  if (p.rho_mm <= 0) {
    r.ids.push_back(b.vertex({0, 0, p.z_mm}));
    r.angles.push_back(0);
    return r;
  }
  const int n =
      std::max(8, static_cast<int>(std::ceil(2 * std::numbers::pi * p.rho_mm / edge_mm - 1e-9)));
  for (int k = 0; k < n; ++k) {
    const double psi = 2 * std::numbers::pi * k / n;
    r.ids.push_back(b.vertex({p.rho_mm * std::cos(psi), p.rho_mm * std::sin(psi), p.z_mm}));
    r.angles.push_back(psi);
  }
  return r;
}

// Triangles between ring a and the next ring b along the profile; each is
// counter-clockwise seen from outside (normal ≈ e_ψ × profile direction).
void stitch(MeshBuilder& b, const Ring& a, const Ring& c, int surface) {
  const std::size_t na = a.ids.size(), nc = c.ids.size();
  if (na == 1 && nc == 1) throw std::invalid_argument("revolve: two poles in a row");
  const auto angle = [](const Ring& r, std::size_t i) {
    return i == r.ids.size() ? 2 * std::numbers::pi : r.angles[i];
  };
  const auto id = [](const Ring& r, std::size_t i) { return r.ids[i % r.ids.size()]; };
  if (na == 1) {
    for (std::size_t j = 0; j < nc; ++j)
      b.triangle(a.ids[0], id(c, j + 1), id(c, j), surface);
    return;
  }
  if (nc == 1) {
    for (std::size_t i = 0; i < na; ++i)
      b.triangle(id(a, i), id(a, i + 1), c.ids[0], surface);
    return;
  }
  std::size_t i = 0, j = 0;
  while (i < na || j < nc) {
    if (j == nc || (i < na && angle(a, i + 1) <= angle(c, j + 1))) {
      b.triangle(id(a, i), id(a, i + 1), id(c, j), surface);
      ++i;
    } else {
      b.triangle(id(a, i), id(c, j + 1), id(c, j), surface);
      ++j;
    }
  }
}

}  // namespace

void revolve(MeshBuilder& b, const std::vector<ProfilePoint>& profile,
             const std::vector<int>& surface, double edge_mm) {
  if (profile.size() < 2 || surface.size() + 1 != profile.size())
    throw std::invalid_argument("revolve: a profile of n points needs n - 1 surface ids");
  Ring prev = make_ring(b, profile[0], edge_mm);
  for (std::size_t i = 1; i < profile.size(); ++i) {
    Ring next = make_ring(b, profile[i], edge_mm);
    stitch(b, prev, next, surface[i - 1]);
    prev = std::move(next);
  }
}

}  // namespace truecut::sim::parts
