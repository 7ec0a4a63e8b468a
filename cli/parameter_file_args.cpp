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
  if (a.value("var-units") && !a.value("var-file"))
    throw UsageError("--var-units needs --var-file");
  const auto file = a.value("var-file");
  if (!file) return std::nullopt;
  return interp::ParameterFile::load(*file, units);
}

}  // namespace truecut::cli
