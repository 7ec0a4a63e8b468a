// Ballbar-style reading of a circular test's Fourier components and
// reversal features (docs/iso230.md, "Interpretation hints").
#pragma once

#include <vector>

#include "truecut/sim/iso230_circular.hpp"

namespace truecut::sim {

std::vector<CircleHint> circle_hints(const CircularTest& test);

}  // namespace truecut::sim
