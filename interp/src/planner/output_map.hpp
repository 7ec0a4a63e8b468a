// From a point of the planning space to what the servo cycle reports: joints
// and the tool pose in the workpiece frame. In joint space the point is the
// joints (rotaries scaled); in TCP mode it is (TCP, scaled A, C), the tool
// axis follows from A and C and the joints from inverse_ac with the
// previous joints as hint (continuous C, no spin at A = 0).
#pragma once

#include "truecut/interp/plan_segment.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"

namespace truecut::interp::plan {

struct MappedPoint {
  rt::AcJoints joints;
  rt::ToolPose pose;
};

inline rt::ToolPose pose_of(const rt::AcTrtParams& kin, double a_deg, double c_deg,
                            const Vec5& p) noexcept {
  rt::ToolPose pose = rt::forward_ac(kin, rt::AcJoints{0, 0, 0, a_deg, c_deg});
  pose.tcp_mm = {p[0], p[1], p[2]};
  return pose;
}

inline MappedPoint map_point(bool tcp, const rt::AcTrtParams& kin, double weight, const Vec5& p,
                             const rt::AcJoints& hint) noexcept {
  MappedPoint m;
  const double a = p[3] / weight, c = p[4] / weight;
  if (!tcp) {
    m.joints = {p[0], p[1], p[2], a, c};
    m.pose = rt::forward_ac(kin, m.joints);
    return m;
  }
  m.pose = pose_of(kin, a, c, p);
  // The hint carries the interpolated angles so the inverse picks their
  // branch; C stays exactly where interpolation put it at the singularity.
  rt::AcJoints h = hint;
  h.a_deg = a;
  h.c_deg = c;
  m.joints = rt::inverse_ac(kin, m.pose, h).joints;
  return m;
}

}  // namespace truecut::interp::plan
