// Joint-space mode of truecut_comp: joints -> forward kinematics -> TCP,
// and the corrected TCP -> inverse kinematics -> joints. Pure functions.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

#include <Eigen/Geometry>  // cross products
#include <algorithm>
#include <array>
#include <cmath>

#include "truecut/rt/core/comp_core.hpp"
#include "truecut/rt/core/comp_math.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"

namespace truecut::rt::comp {

inline bool joints_finite(const rt::AcJoints& j) noexcept {
  return std::isfinite(j.x_mm) && std::isfinite(j.y_mm) && std::isfinite(j.z_mm) &&
         std::isfinite(j.a_deg) && std::isfinite(j.c_deg);
}

inline bool params_finite(const rt::AcTrtParams& p) noexcept {
  return std::isfinite(p.x_rot_point_mm) && std::isfinite(p.y_rot_point_mm) &&
         std::isfinite(p.z_rot_point_mm) && std::isfinite(p.y_offset_mm) &&
         std::isfinite(p.z_offset_mm) && std::isfinite(p.tool_length_mm) &&
         std::isfinite(p.a_min_deg) && std::isfinite(p.a_max_deg);
}

// A soft limit at or beyond this magnitude, mm, is no limit (the pins'
// defaults).
inline constexpr double kNoSoftLimitMm = 1e30;

// The default bound of A's and C's corrections, deg: above the default
// max-tilt (0.57 deg), so that A can take it whole, and small enough that
// near A = 0, where a tilt sideways needs C to turn far, C stays put.
inline constexpr double kDefaultMaxRotaryCorrectionDeg = 1.0;

// Where the orientation correction's least squares starts to be damped
// (see rotary_correction()): sin(2 deg). Where A is tilted less than about
// this, the part of a tilt that only C could give is progressively left out
// rather than turning C by (tilt / sin A); above it the solution is exact.
inline constexpr double kRotaryDampingStart = 0.03489949670250097;

// The limits of the linear joints X Y Z (index 0 1 2) in joint mode, as the
// pins hold them: mm, as LinuxCNC's [JOINT_n]MIN_LIMIT / MAX_LIMIT.
struct JointLimits {
  // Largest |correction| of each joint; 0: no limit of its own. NaN or
  // negative: that joint is not corrected (and the clip is reported).
  std::array<double, 3> max_correction{0.0, 0.0, 0.0};
  // Soft limits; at or beyond ±kNoSoftLimitMm: none. NaN: that joint is not
  // corrected. A correction never pushes a joint past one (a command
  // already beyond it is left there, only corrections back inwards pass).
  std::array<double, 3> min_limit{-kNoSoftLimitMm, -kNoSoftLimitMm, -kNoSoftLimitMm};
  std::array<double, 3> max_limit{kNoSoftLimitMm, kNoSoftLimitMm, kNoSoftLimitMm};
  // Largest |correction| of A and C, deg, for the tool-orientation
  // correction (kDefaultMaxRotaryCorrectionDeg). NaN, negative or 0: that
  // joint does not move for it.
  double max_a_correction_deg = kDefaultMaxRotaryCorrectionDeg;
  double max_c_correction_deg = kDefaultMaxRotaryCorrectionDeg;
};

namespace detail {

// The allowed absolute range [lo, hi] of joint k for command `cmd`
// (lo <= cmd <= hi; ±inf: unbounded).
inline void joint_range(const JointLimits& l, int k, double cmd, double& lo, double& hi) noexcept {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  lo = -kInf;
  hi = kInf;
  const double mc = l.max_correction[k], mn = l.min_limit[k], mx = l.max_limit[k];
  if (!(mc >= 0.0) || std::isnan(mn) || std::isnan(mx)) {
    lo = hi = cmd;
    return;
  }
  if (mc > 0.0 && std::isfinite(mc)) {
    lo = cmd - mc;
    hi = cmd + mc;
  }
  if (mn > -kNoSoftLimitMm) lo = std::max(lo, std::min(mn, cmd));
  if (mx < kNoSoftLimitMm) hi = std::min(hi, std::max(mx, cmd));
}

}  // namespace detail

// The box the correction of X Y Z must stay in at `joints` (comp::step()
// clips to it); inactive when no limit is set. to_workpiece is d tcp / d
// (x, y, z), the table rotation, from the forward kinematics.
inline JointClip joint_clip(const rt::AcTrtParams& params, const rt::AcJoints& joints,
                            const rt::ToolPose& pose, const JointLimits& limits) noexcept {
  JointClip c;
  const double cmd[3] = {joints.x_mm, joints.y_mm, joints.z_mm};
  for (int k = 0; k < 3; ++k) {
    double lo, hi;
    detail::joint_range(limits, k, cmd[k], lo, hi);
    c.lo[k] = lo - cmd[k];
    c.hi[k] = hi - cmd[k];
    c.active = c.active || std::isfinite(lo) || std::isfinite(hi);
  }
  if (!c.active) return c;
  for (int k = 0; k < 3; ++k) {
    rt::AcJoints e = joints;
    (k == 0 ? e.x_mm : k == 1 ? e.y_mm : e.z_mm) += 1.0;
    c.to_workpiece.col(k) = rt::forward_ac(params, e).tcp_mm - pose.tcp_mm;
  }
  return c;
}

// Clamps the corrected joints `out` to the limits around the commanded
// `joints`, exactly (the inverse kinematics of a clipped correction lands
// on a limit only to rounding). Returns whether anything moved by more than
// rounding would (1e-9 mm).
inline bool clamp_joints(const JointLimits& limits, const rt::AcJoints& joints,
                         rt::AcJoints& out) noexcept {
  const double cmd[3] = {joints.x_mm, joints.y_mm, joints.z_mm};
  double* v[3] = {&out.x_mm, &out.y_mm, &out.z_mm};
  bool moved = false;
  for (int k = 0; k < 3; ++k) {
    double lo, hi;
    detail::joint_range(limits, k, cmd[k], lo, hi);
    const double c = std::clamp(*v[k], lo, hi);
    moved = moved || std::abs(c - *v[k]) > 1e-9;
    *v[k] = c;
  }
  return moved;
}

// The joints that put the TCP at tcp(joints) + correction_mm with the tool
// axis unchanged. A and C are passed through exactly (the correction is a
// translation), X Y Z come from the inverse kinematics with the input joints
// as hint. A zero correction returns the joints bit for bit. Should the
// inverse refuse (it cannot while A is within its travel), the translation is
// mapped through the rotation of the table taken from the forward kinematics,
// which is exact for the rigid A/C chain.
inline rt::AcJoints correct_joints(const rt::AcTrtParams& params, const rt::AcJoints& joints,
                                   const rt::ToolPose& pose, const Vec3& correction_mm) noexcept {
  if (correction_mm.isZero(0.0)) return joints;
  rt::ToolPose target = pose;
  target.tcp_mm += correction_mm;
  const rt::AcIkResult ik = rt::inverse_ac(params, target, joints);
  rt::AcJoints out = joints;
  if (ik.status == rt::AcIkStatus::kOk || ik.status == rt::AcIkStatus::kSingular) {
    out.x_mm = ik.joints.x_mm;
    out.y_mm = ik.joints.y_mm;
    out.z_mm = ik.joints.z_mm;
    return out;
  }
  // d tcp / d (x, y, z) is the table rotation (workpiece <- machine); its
  // transpose maps a TCP translation back to the linear joints.
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) {
    rt::AcJoints e = joints;
    (k == 0 ? e.x_mm : k == 1 ? e.y_mm : e.z_mm) += 1.0;
    m.col(k) = rt::forward_ac(params, e).tcp_mm - pose.tcp_mm;
  }
  const Vec3 d = m.transpose() * correction_mm;
  out.x_mm += d.x();
  out.y_mm += d.y();
  out.z_mm += d.z();
  return out;
}

// Joint mode, the orientation correction: how far A and C turn (deg) to
// rotate the tool axis by `rotation_rad` (a rotation vector, workpiece
// frame, about the TCP), and how much of that rotation they cannot give.
struct RotaryCorrection {
  double da_deg = 0.0;
  double dc_deg = 0.0;
  double shortfall_rad = 0.0;  // |tilted_axis(k, r) - the axis A and C give|
  bool clipped = false;        // a joint's bound cut the turn
};

// The tool axis k tilted by the rotation vector r: k + r x k, normalised.
// This is what a field's rotation means (to first order the rotation of k
// by r; for the milliradians of a correction the two differ by |r|^2 / 2).
inline Vec3 tilted_axis(const Vec3& axis, const Vec3& rotation_rad) noexcept {
  if (exactly_zero(rotation_rad)) return axis;
  const Vec3 k = axis + rotation_rad.cross(axis);
  const double n = k.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return axis;
  return k / n;
}

// The tilt wanted, dk = r x k, is given by A and C through least squares on
// the axis's derivatives J = d k / d(A, C) (per rad): (J^T J + l^2 v v^T) dq
// = J^T dk, v the direction of J's smaller singular value s. A tilts the axis about the A line at
// any angle; C only as far as A has tilted the table (|d k / dC| = sin A). The damping l is 0 while
// J's smaller singular value s is at least e = kRotaryDampingStart, and l^2 = e^2 - s^2 below
// (variable damping): C then turns by at most |dk| / e, continuously in the joints, and near A = 0
// a tilt sideways is left out (the shortfall) instead of spinning C. Each turn is clipped to its
// bound. The axis so reached to first order, k* = tilted_axis(k + J dq), is then hit exactly by the
// inverse kinematics (hint: the joints turned by dq), so that without damping or clipping the tool
// axis becomes tilted_axis(k, r).
inline RotaryCorrection rotary_correction(const rt::AcTrtParams& params, const rt::AcJoints& joints,
                                          const rt::ToolPose& pose, const Vec3& rotation_rad,
                                          const JointLimits& limits) noexcept {
  RotaryCorrection rc;
  const Vec3 dk = rotation_rad.cross(pose.axis);
  if (dk.isZero(0.0) || !dk.allFinite()) return rc;
  constexpr double kDegPerRad = 57.29577951308232;
  constexpr double kStepDeg = 1e-3;
  Eigen::Matrix<double, 3, 2> jac;
  for (int q = 0; q < 2; ++q) {
    rt::AcJoints plus = joints, minus = joints;
    (q == 0 ? plus.a_deg : plus.c_deg) += kStepDeg;
    (q == 0 ? minus.a_deg : minus.c_deg) -= kStepDeg;
    jac.col(q) = (rt::forward_ac(params, plus).axis - rt::forward_ac(params, minus).axis) *
                 (kDegPerRad / (2.0 * kStepDeg));
  }
  Eigen::Matrix2d normal = jac.transpose() * jac;
  // Smaller eigenvalue of J^T J: s^2.
  const double half_trace = 0.5 * (normal(0, 0) + normal(1, 1));
  const double half_gap = std::hypot(0.5 * (normal(0, 0) - normal(1, 1)), normal(0, 1));
  const double s2 = half_trace - half_gap;
  constexpr double kE2 = kRotaryDampingStart * kRotaryDampingStart;
  if (s2 < kE2) {
    // Damp along the weak direction only (its unit eigenvector v): the
    // other stays exact.
    Eigen::Vector2d v(normal(0, 1), s2 - normal(0, 0));
    const Eigen::Vector2d w(s2 - normal(1, 1), normal(1, 0));
    if (w.squaredNorm() > v.squaredNorm()) v = w;
    if (!(v.squaredNorm() > 0.0))
      v = normal(0, 0) <= normal(1, 1) ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1);
    v.normalize();
    normal += (kE2 - std::max(s2, 0.0)) * v * v.transpose();
  }
  const Eigen::Vector2d rhs = jac.transpose() * dk;
  // 2 x 2, symmetric, positive definite (damped when nearly singular):
  // Cramer's rule.
  const double det = normal(0, 0) * normal(1, 1) - normal(0, 1) * normal(1, 0);
  double da = (normal(1, 1) * rhs[0] - normal(0, 1) * rhs[1]) / det * kDegPerRad;
  double dc = (normal(0, 0) * rhs[1] - normal(1, 0) * rhs[0]) / det * kDegPerRad;
  // A bound that is NaN, negative or 0 lets the joint not turn.
  auto bound_of = [](double bound) { return bound > 0.0 ? bound : 0.0; };
  auto clip = [&](double& v, double bound) {
    const double b = bound_of(bound);
    const double c = std::clamp(v, -b, b);
    rc.clipped = rc.clipped || c != v;
    v = c;
  };
  clip(da, limits.max_a_correction_deg);
  clip(dc, limits.max_c_correction_deg);
  if (!std::isfinite(da) || !std::isfinite(dc)) return RotaryCorrection{};  // cannot happen
  const Vec3 reached = (pose.axis + jac * Eigen::Vector2d(da, dc) / kDegPerRad).normalized();
  rt::AcJoints hint = joints;
  hint.a_deg += da;
  hint.c_deg += dc;
  const rt::AcIkResult ik = rt::inverse_ac(params, {pose.tcp_mm, reached}, hint);
  if (ik.status == rt::AcIkStatus::kOk || ik.status == rt::AcIkStatus::kSingular) {
    // (Exact, the turns differ from the linear ones at third order; the
    // bounds stay hard.)
    const double ba = bound_of(limits.max_a_correction_deg);
    const double bc = bound_of(limits.max_c_correction_deg);
    da = std::clamp(ik.joints.a_deg - joints.a_deg, -ba, ba);
    dc = std::clamp(ik.joints.c_deg - joints.c_deg, -bc, bc);
  }
  rc.da_deg = da;
  rc.dc_deg = dc;
  rc.shortfall_rad = (tilted_axis(pose.axis, rotation_rad) - reached).norm();
  return rc;
}

// correct_joints() with the orientation correction: A and C turned by
// `rc`, and X Y Z such that the TCP lands on tcp(joints) + correction_mm
// (the forward kinematics is affine in X Y Z, its linear part the table's
// rotation, so one step is exact).
inline rt::AcJoints correct_joints(const rt::AcTrtParams& params, const rt::AcJoints& joints,
                                   const rt::ToolPose& pose, const Vec3& correction_mm,
                                   const RotaryCorrection& rc) noexcept {
  if (rc.da_deg == 0.0 && rc.dc_deg == 0.0)
    return correct_joints(params, joints, pose, correction_mm);
  rt::AcJoints out = joints;
  out.a_deg += rc.da_deg;
  out.c_deg += rc.dc_deg;
  const Vec3 at = rt::forward_ac(params, out).tcp_mm;
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) {
    rt::AcJoints e = out;
    (k == 0 ? e.x_mm : k == 1 ? e.y_mm : e.z_mm) += 1.0;
    m.col(k) = rt::forward_ac(params, e).tcp_mm - at;
  }
  const Vec3 d = m.transpose() * (pose.tcp_mm + correction_mm - at);
  out.x_mm += d.x();
  out.y_mm += d.y();
  out.z_mm += d.z();
  return out;
}

}  // namespace truecut::rt::comp
