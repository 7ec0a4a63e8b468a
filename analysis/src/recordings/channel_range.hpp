// The values a recorded channel may take (internal to the recording readers).
#pragma once

#include <string>

namespace truecut::analysis::detail {

// "" when `value` (in the channel's unit) is physically possible, otherwise
// what is wrong with it: "1e+154 mm is outside -1e+05 .. 1e+05 (…)".
std::string implausible_value(const std::string& channel, double value);

}  // namespace truecut::analysis::detail
