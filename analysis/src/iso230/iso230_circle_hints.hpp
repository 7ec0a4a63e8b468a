// Ballbar-style reading of a circular test's Fourier components and
// reversal features (docs/iso230.md, "Interpretation hints").
#pragma once

#include <vector>

#include "truecut/analysis/iso230_circular.hpp"

namespace truecut::analysis {

std::vector<CircleHint> circle_hints(const CircularTest& test);

}  // namespace truecut::analysis
