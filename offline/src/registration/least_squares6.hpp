// The 6×6 normal equations of a linearised rigid motion (rotation ω,
// translation τ), solved in the subspace the data determine.
#pragma once

#include <Eigen/Dense>

namespace truecut::offline::registration {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct Solution6 {
  Vector6d x = Vector6d::Zero();
  int rank = 0;  // directions of motion the data constrain (6 for a generic part)
};

// Minimum-norm solution of H·x = b over the eigen-directions of H whose
// eigenvalue exceeds rel_tol × the largest: a flat plate leaves the in-plane
// motions undetermined, a cylinder the turn about its axis, and those are then
// left at zero instead of drifting with the noise. H must be symmetric; the
// caller scales the rotation unknowns by a length so both kinds of eigenvalue
// are comparable.
//
// rel_tol 1e-3, not a rounding-level 1e-6: a tessellated surface of
// revolution constrains the turn about its axis only by the tilt of the
// normals within each facet (about 3e-5 of the best direction for 360 facets
// around), which says nothing about the machined part; at 1e-6 that turn was
// fitted to the facets and drifted by 0.57° on a cylinder
// (Registration.FacetsOfASurfaceOfRevolutionDoNotDetermineItsTurn).
inline Solution6 solve_in_determined_subspace(const Matrix6d& H, const Vector6d& b,
                                              double rel_tol = 1e-3) {
  Solution6 s;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(H);
  const double top = eig.eigenvalues().maxCoeff();
  if (!(top > 0.0)) return s;
  for (int k = 0; k < 6; ++k) {
    const double lambda = eig.eigenvalues()[k];
    if (lambda <= rel_tol * top) continue;
    const Vector6d u = eig.eigenvectors().col(k);
    s.x += u * (u.dot(b) / lambda);
    ++s.rank;
  }
  return s;
}

}  // namespace truecut::offline::registration
