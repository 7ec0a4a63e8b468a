// --var-file FILE [--var-units mm|inch]: the controller's parameter file
// (LinuxCNC .var), read into the interpreter's starting parameters, so a
// work offset set on the machine (G54…, G92) places the program as it does
// there (interp/parameter_file.hpp).
#pragma once

#include <optional>
#include <string>

#include "args.hpp"
#include "truecut/interp/parameter_file.hpp"

namespace truecut::cli {

inline constexpr const char* kVarFileHelp =
    "  --var-file FILE.var    the controller's parameter file (LinuxCNC's [RS274NGC]\n"
    "                         PARAMETER_FILE): work offsets G54..G59.3 with their rotations,\n"
    "                         the active system #5220, G92 (#5210..), G28/G30 homes\n"
    "  --var-units mm|inch    its length units (default mm; LinuxCNC: [TRAJ]LINEAR_UNITS)\n";

// --OPTION mm|inch (default mm). Throws UsageError for anything else.
interp::LengthUnits length_units_option(const ParsedArgs& a, const std::string& option);

// The parameter file the options name, or nullopt without --var-file.
// Throws UsageError for bad --var-units, interp::GcodeError for the file.
std::optional<interp::ParameterFile> parameter_file_from_args(const ParsedArgs& a);

}  // namespace truecut::cli
