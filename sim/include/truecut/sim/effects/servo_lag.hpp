// servo_lag: the joint follows its command through the position loop of its
// drive instead of ideally. The dynamic itself is in servo_model.hpp; this is
// the part of it a user tunes (and the diagnosis fits) per axis.
//
//   v_ref = ff1 · Δcmd/T + kv · (cmd − encoder)
//
// At constant speed v in steady state the following error is
// (1 − ff1) · v / kv.
#pragma once

namespace truecut::sim {

struct ServoLagAxis {
  double kv_per_s = 30.0;  // position loop gain, 1/s (1 (m/min)/mm = 16.67 1/s)
  double ff1 = 0.0;        // velocity feed-forward, fraction of the commanded speed
  bool operator==(const ServoLagAxis&) const = default;
};

}  // namespace truecut::sim
