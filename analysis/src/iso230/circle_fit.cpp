#include "circle_fit.hpp"

#include <Eigen/Dense>
#include <cmath>

namespace truecut::analysis::detail {

CircleFit fit_circle(const std::vector<double>& p, const std::vector<double>& q,
                     const std::vector<std::size_t>& use) {
  std::vector<std::size_t> idx = use;
  if (idx.empty())
    for (std::size_t i = 0; i < p.size(); ++i)
      idx.push_back(i);
  CircleFit f;
  if (idx.size() < 3) return f;
  // Centre the data first: the algebraic fit loses digits far from the origin.
  double mp = 0, mq = 0;
  for (auto i : idx)
    mp += p[i], mq += q[i];
  mp /= double(idx.size());
  mq /= double(idx.size());
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (auto i : idx) {
    const double x = p[i] - mp, y = q[i] - mq;
    const Eigen::Vector3d row(x, y, 1.0);
    ata += row * row.transpose();
    atb += row * (x * x + y * y);
  }
  const Eigen::Vector3d s = ata.ldlt().solve(atb);
  double cx = s(0) / 2, cy = s(1) / 2;
  double r = std::sqrt(std::max(0.0, s(2) + cx * cx + cy * cy));
  if (!std::isfinite(r) || r <= 0) return f;
  for (int iter = 0; iter < 20; ++iter) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (auto i : idx) {
      const double dx = p[i] - mp - cx, dy = q[i] - mq - cy;
      const double d = std::hypot(dx, dy);
      if (d == 0) continue;
      const Eigen::Vector3d j(-dx / d, -dy / d, -1.0);
      jtj += j * j.transpose();
      jtr += j * (d - r);
    }
    const Eigen::Vector3d step = jtj.ldlt().solve(-jtr);
    if (!step.allFinite()) break;
    cx += step(0), cy += step(1), r += step(2);
    if (step.norm() < 1e-12 * std::max(1.0, r)) break;
  }
  f.cp = cx + mp;
  f.cq = cy + mq;
  f.r = r;
  f.ok = std::isfinite(r) && r > 0;
  return f;
}

std::vector<double> fit_fourier(const std::vector<double>& theta, const std::vector<double>& v,
                                int order) {
  const int n = 2 * order + 1;
  if (int(theta.size()) < 2 * n) return {};
  Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd atb = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd row(n);
  for (std::size_t i = 0; i < theta.size(); ++i) {
    row(0) = 1;
    for (int k = 1; k <= order; ++k) {
      row(2 * k - 1) = std::cos(k * theta[i]);
      row(2 * k) = std::sin(k * theta[i]);
    }
    ata += row * row.transpose();
    atb += row * v[i];
  }
  Eigen::LDLT<Eigen::MatrixXd> ldlt(ata);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-10) return {};
  const Eigen::VectorXd x = ldlt.solve(atb);
  std::vector<double> out(2 * order + 2, 0.0);
  out[0] = x(0);
  for (int k = 1; k <= order; ++k) {
    out[2 * k] = x(2 * k - 1);
    out[2 * k + 1] = x(2 * k);
  }
  return out;
}

double eval_fourier(const std::vector<double>& c, double theta, int max_order) {
  double v = c[0];
  const int order = int(c.size() / 2) - 1;
  for (int k = 1; k <= std::min(order, max_order); ++k)
    v += c[2 * k] * std::cos(k * theta) + c[2 * k + 1] * std::sin(k * theta);
  return v;
}

}  // namespace truecut::analysis::detail
