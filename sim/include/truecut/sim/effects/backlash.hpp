// backlash: play between the ballscrew (or worm) and the table. The table is
// dragged by the motor side only when the gap is closed, so after a reversal
// the table stands still until the motor has crossed the play b:
//
//   table ← clamp(table, motor − b/2, motor + b/2)      (play operator)
//
// Moving in + the table lags by b/2, moving in − it leads by b/2: the error
// (true − commanded) steps by b at each reversal. The gap starts centred
// (table = motor). A semi-closed loop's encoder sits on the motor side and
// does not see it.
#pragma once

#include <algorithm>

namespace truecut::sim {

struct BacklashAxis {
  double play = 0.0;  // b, in the joint's unit (mm or deg), >= 0
  bool operator==(const BacklashAxis&) const = default;
};

inline double backlash_table_position(double table, double motor, double play) noexcept {
  const double half = 0.5 * play;
  return std::clamp(table, motor - half, motor + half);
}

}  // namespace truecut::sim
