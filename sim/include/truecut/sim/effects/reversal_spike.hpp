// reversal_spike: friction in the axis drive train, acting on the joint's
// inertia inside the servo model (servo_model.hpp):
//
//   m · a = F_drive − F_c · sign(v) − B · v          (sliding, v ≠ 0)
//   a = 0 while v = 0 and |F_drive| <= F_c            (sticking)
//
// At a velocity reversal the Coulomb force F_c flips sign; the velocity
// loop's integrator needs time to rebuild the drive force, so the axis
// sticks briefly and the following error shows the quadrant-glitch spike.
// Its height grows with F_c / m and falls with the velocity-loop gains.
// Needs servo_lag on the same axis (friction acts through the servo).
#pragma once

namespace truecut::sim {

struct ReversalSpikeAxis {
  double coulomb = 0.0;  // F_c: N (linear) or N·m (rotary), >= 0
  double viscous = 0.0;  // B: N·s/mm (linear) or N·m·s/deg (rotary), >= 0
  bool operator==(const ReversalSpikeAxis&) const = default;
};

}  // namespace truecut::sim
