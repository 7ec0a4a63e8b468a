#include "parameter_file_args.hpp"

namespace truecut::cli {

interp::LengthUnits length_units_option(const ParsedArgs& a, const std::string& option) {
  const auto u = a.value(option);
  if (!u || *u == "mm") return interp::LengthUnits::kMm;
  if (*u == "inch") return interp::LengthUnits::kInch;
  throw UsageError("--" + option + " must be mm or inch, not '" + *u + "'");
}

std::optional<interp::ParameterFile> parameter_file_from_args(const ParsedArgs& a) {
  const interp::LengthUnits units = length_units_option(a, "var-units");
  const auto file = a.value("var-file");
  // Without a file, the machine's units alone: where the offset
  // parameters (#5211.., #5221..) keep their lengths.
  if (!file) {
    if (!a.value("var-units")) return std::nullopt;
    interp::ParameterFile empty;
    empty.units = units;
    return empty;
  }
  return interp::ParameterFile::load(*file, units);
}

}  // namespace truecut::cli
