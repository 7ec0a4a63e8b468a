// --quiet and progress, alike for every command: progress (how far the work
// is) goes to stderr on a terminal only; --quiet leaves nothing on stderr but
// warnings and errors.
#pragma once

#include "args.hpp"

namespace truecut::cli {

inline const OptionSpec kQuietOption{"quiet", false};

// Whether to show progress: stderr is a terminal and --quiet was not given.
bool progress_shown(const ParsedArgs& a);

}  // namespace truecut::cli
