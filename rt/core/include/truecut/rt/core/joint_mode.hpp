// Joint-space mode of truecut_comp: joints -> forward kinematics -> TCP,
// and the corrected TCP -> inverse kinematics -> joints. Pure functions.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

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
