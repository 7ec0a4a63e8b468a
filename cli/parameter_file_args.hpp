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
    "  --var-units mm|inch    the machine's length units (default mm; LinuxCNC:\n"
    "                         [TRAJ]LINEAR_UNITS): the parameter file's, and those the\n"
    "                         offset parameters #5161.., #5211.., #5221.. keep\n"
    "                         under G20 and G21 alike\n";

// --OPTION mm|inch (default mm). Throws UsageError for anything else.
interp::LengthUnits length_units_option(const ParsedArgs& a, const std::string& option);

// The parameter file the options name (without --var-file but with
// --var-units: an empty one in those units), or nullopt without either.
// Throws UsageError for bad --var-units, interp::GcodeError for the file.
std::optional<interp::ParameterFile> parameter_file_from_args(const ParsedArgs& a);

}  // namespace truecut::cli
