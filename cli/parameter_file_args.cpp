#include "parameter_file_args.hpp"

namespace truecut::cli {

std::optional<interp::ParameterFile> parameter_file_from_args(const ParsedArgs& a) {
  interp::LengthUnits units = interp::LengthUnits::kMm;
  if (auto u = a.value("var-units")) {
    if (*u == "inch")
      units = interp::LengthUnits::kInch;
    else if (*u != "mm")
      throw UsageError("--var-units must be mm or inch, not '" + *u + "'");
    if (!a.value("var-file")) throw UsageError("--var-units needs --var-file");
  }
  const auto file = a.value("var-file");
  if (!file) return std::nullopt;
  return interp::ParameterFile::load(*file, units);
}

}  // namespace truecut::cli
