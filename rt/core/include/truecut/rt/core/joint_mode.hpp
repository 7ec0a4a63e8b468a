// Joint-space mode of truecut_comp: joints -> forward kinematics -> TCP,
// and the corrected TCP -> inverse kinematics -> joints. Pure functions.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

#include <array>

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

}  // namespace truecut::rt::comp
