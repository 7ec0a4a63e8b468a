#include "quiet_option.hpp"

#include <unistd.h>

namespace truecut::cli {

bool progress_shown(const ParsedArgs& a) {
  return !a.flag("quiet") && isatty(STDERR_FILENO) != 0;
}

}  // namespace truecut::cli
