#include "registration/least_squares6.hpp"
#include "truecut/offline/registration.hpp"

#include <Eigen/SVD>

#include <cmath>
#include <stdexcept>
#include <string>

namespace truecut::offline {

namespace {

using registration::Matrix6d;
using registration::Vector6d;

void check_sizes(std::size_t points, std::size_t displacements, std::size_t use,
                 std::size_t normals, bool need_normals) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("rigid-body motion: " + what);
  };
  if (displacements != points) {
    fail(std::to_string(displacements) + " displacements for " + std::to_string(points) +
         " points");
  }
  if (use != 0 && use != points)
    fail(std::to_string(use) + " flags for " + std::to_string(points) + " points");
  if (need_normals && normals != points) {
    fail(std::to_string(normals) + " normals for " + std::to_string(points) + " points");
  }
}

// The motion's matrix form x ↦ R(x − G) + G + t.
void finish(RigidBodyMotion& m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = m.rotation;
  T.translation() = m.barycentre_mm + m.translation_mm - m.rotation * m.barycentre_mm;
  m.transform = describe_transform(T);
}

}  // namespace

RigidBodyMotion fit_rigid_body_motion(std::span<const Eigen::Vector3d> P,
                                      std::span<const Eigen::Vector3d> v, RigidBodyFit fit,
                                      std::span<const std::uint8_t> use,
                                      std::span<const Eigen::Vector3d> normals) {
  const bool by_normal = fit == RigidBodyFit::kNormalComponents;
  check_sizes(P.size(), v.size(), use.size(), normals.size(), by_normal);
  auto used = [&](std::size_t i) { return use.empty() || use[i] != 0; };

  RigidBodyMotion m;
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (!used(i)) continue;
    m.barycentre_mm += P[i];
    ++m.points_used;
  }
  if (m.points_used < 3) {
    throw std::invalid_argument("rigid-body motion: " + std::to_string(m.points_used) +
                                " points, at least 3 needed");
  }
  m.barycentre_mm /= static_cast<double>(m.points_used);
  const Eigen::Vector3d G = m.barycentre_mm;
  const double n_used = static_cast<double>(m.points_used);

  if (!by_normal) {
    // Eq. 3–4: translation = mean displacement. Eq. 5–6: the rotation about
    // the barycentre that best maps P − G onto P + v − G − t (Kabsch/SVD, the
    // exact least-squares rotation).
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (used(i)) m.translation_mm += v[i];
    }
    m.translation_mm /= n_used;
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (!used(i)) continue;
      const Eigen::Vector3d a = P[i] - G;
      H += a * (a + v[i] - m.translation_mm).transpose();
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (V * U.transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    m.rotation = V * D * U.transpose();
    const Eigen::Vector3d sv = svd.singularValues();
    m.determined_directions = 3 + (sv[1] > 1e-9 * sv[0] ? 3 : (sv[0] > 0.0 ? 2 : 0));
  } else {
    // min Σ ((R(P − G) + G + t − P)·n − v·n)², Gauss-Newton from R = I, t = 0;
    // the first step is the linear (small-angle) solution.
    double spread = 0.0;
    for (std::size_t i = 0; i < P.size(); ++i) {
      if (used(i)) spread += (P[i] - G).squaredNorm();
    }
    const double L = std::max(std::sqrt(spread / n_used), 1e-9);
    for (int it = 0; it < 10; ++it) {
      Matrix6d H = Matrix6d::Zero();
      Vector6d g = Vector6d::Zero();
      for (std::size_t i = 0; i < P.size(); ++i) {
        if (!used(i)) continue;
        const Eigen::Vector3d& n = normals[i];
        const double r = m.displacement_at(P[i]).dot(n) - v[i].dot(n);
        Vector6d J;
        J.head<3>() = (m.rotation * (P[i] - G)).cross(n) / L;
        J.tail<3>() = n;
        H.selfadjointView<Eigen::Upper>().rankUpdate(J, 1.0);
        g -= r * J;
      }
      H.triangularView<Eigen::StrictlyLower>() = H.transpose();
      const registration::Solution6 s = registration::solve_in_determined_subspace(H, g);
      m.determined_directions = s.rank;
      const Eigen::Vector3d omega = s.x.head<3>() / L;
      const double angle = omega.norm();
      if (angle > 0.0) m.rotation = Eigen::AngleAxisd(angle, omega / angle) * m.rotation;
      m.translation_mm += s.x.tail<3>();
      if (angle * L < 1e-12 && s.x.tail<3>().norm() < 1e-12) break;
    }
  }

  double before = 0.0, after = 0.0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    if (!used(i)) continue;
    const Eigen::Vector3d rest = v[i] - m.displacement_at(P[i]);
    before += by_normal ? std::pow(v[i].dot(normals[i]), 2) : v[i].squaredNorm();
    after += by_normal ? std::pow(rest.dot(normals[i]), 2) : rest.squaredNorm();
  }
  m.rms_before_mm = std::sqrt(before / n_used);
  m.rms_after_mm = std::sqrt(after / n_used);
  finish(m);
  return m;
}

void remove_rigid_body_motion(const RigidBodyMotion& motion, RigidBodyFit fit,
                              std::span<const Eigen::Vector3d> P, std::span<Eigen::Vector3d> v,
                              std::span<const Eigen::Vector3d> normals) {
  const bool by_normal = fit == RigidBodyFit::kNormalComponents;
  check_sizes(P.size(), v.size(), 0, normals.size(), by_normal);
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Eigen::Vector3d u = motion.displacement_at(P[i]);
    v[i] -= by_normal ? Eigen::Vector3d(u.dot(normals[i]) * normals[i]) : u;
  }
}

}  // namespace truecut::offline
