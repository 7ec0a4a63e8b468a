// LinuxCNC's parameter file (the `.var` file of [RS274NGC]PARAMETER_FILE):
// the numbered parameters the controller keeps between runs, among them
// the coordinate systems G54…G59.3 (#5221…), their rotations (#5230, …),
// the active system (#5220), G92 (#5210 enabled, #5211…) and the G28/G30
// homes (#5161…, #5181…). A program run on the machine starts from them, so
// a setup's work offset lives here, not in the program.
//
// Format, as LinuxCNC 2.9 reads it: one parameter per line, its number and
// value separated by white space; anything after the value is ignored; a
// line that does not start with a number (blank, a comment) is skipped. The
// numbers must rise strictly from line to line and lie in 1…5601 (LinuxCNC:
// "Parameter file out of order", "Parameter number out of range"). Where
// LinuxCNC silently skips a line it cannot read after the number (no value,
// a value that is not a number) or truncates a fractional number, truecut
// refuses the file with the line; it also refuses a non-finite value and an
// active system #5220 that is not 1…9 (LinuxCNC falls back to G54).
//
// Lengths are in the machine's units ([TRAJ]LINEAR_UNITS; rs274 without an
// INI: inch); ParameterFile keeps the file's values and its units, and the
// interpreter converts the length parameters to mm when it starts.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <string_view>

#include "truecut/interp/canon.hpp"

namespace truecut::interp {

struct ParameterFile {
  std::map<int, double> values;  // as written in the file
  LengthUnits units = LengthUnits::kMm;

  // Throws GcodeError with file:line on a line it cannot take.
  static ParameterFile load(const std::filesystem::path& file,
                            LengthUnits units = LengthUnits::kMm);
  static ParameterFile parse(std::string_view text, const std::string& name,
                             LengthUnits units = LengthUnits::kMm);
};

}  // namespace truecut::interp
