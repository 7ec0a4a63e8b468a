#include "truecut/interp/parameter_file.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>

#include "source_text.hpp"
#include "system_parameters.hpp"
#include "truecut/interp/error.hpp"

namespace truecut::interp {

namespace {

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

// Where the parameter is an offset or a stored position (G28/G30 homes,
// G92, the coordinate systems with their rotation), whether it holds an
// angle (A B C, R) or a length (X Y Z U V W); nullopt for other parameters.
enum class OffsetKind { kNone, kLength, kAngle };
OffsetKind offset_kind(long number) {
  const auto axis_kind = [](long k) {  // 1..9: X Y Z A B C U V W
    return k >= 4 && k <= 6 ? OffsetKind::kAngle : OffsetKind::kLength;
  };
  for (long first : {5161L, 5181L, 5211L})
    if (number >= first && number < first + 9) return axis_kind(number - first + 1);
  if (number >= 5221 && number < 5221 + 9 * 20) {
    const long k = (number - 5221) % 20 + 1;  // 1..9 axes, 10 the XY rotation R
    if (k <= 9) return axis_kind(k);
    if (k == 10) return OffsetKind::kAngle;
  }
  return OffsetKind::kNone;
}

}  // namespace

ParameterFile ParameterFile::parse(std::string_view text, const std::string& name,
                                   LengthUnits units) {
  ParameterFile out;
  out.units = units;
  // LinuxCNC skips a line that starts with anything but a number, so an
  // editor's byte-order mark would silently drop the first parameter.
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF")
    throw GcodeError({name, 1, 1},
                     "the file starts with a UTF-8 byte-order mark: LinuxCNC would skip its first "
                     "line and the value on it; save the file without it");
  const SourceFile src = source_from_text(text, name);
  int previous = 0;
  int previous_line = 0;
  for (size_t li = 0; li < src.lines.size(); ++li) {
    const int line = static_cast<int>(li) + 1;
    const std::string& s = src.lines[li];
    size_t i = 0;
    while (i < s.size() && is_blank(s[i]))
      ++i;
    const bool sign = i < s.size() && (s[i] == '-' || s[i] == '+');
    const size_t digits = i + (sign ? 1 : 0);
    if (digits >= s.size() || !std::isdigit(static_cast<unsigned char>(s[digits])))
      continue;  // blank or a comment: LinuxCNC skips it too
    size_t end = digits;
    while (end < s.size() && std::isdigit(static_cast<unsigned char>(s[end])))
      ++end;
    const int column = static_cast<int>(i) + 1;
    if (end < s.size() && !is_blank(s[end]))
      throw GcodeError({name, line, column},
                       "parameter number '" + s.substr(i, end + 1 - i) +
                           "...' is not a whole number followed by white space");
    const std::string number_text = s.substr(i, end - i);
    const long number = end - digits > 6 ? 999999 : std::strtol(number_text.c_str(), nullptr, 10);
    if ((sign && s[i] == '-') || number < 1 || number >= Parameters::kCount)
      throw GcodeError({name, line, column},
                       "parameter number " + number_text + " out of range 1..5601");
    size_t v = end;
    while (v < s.size() && is_blank(s[v]))
      ++v;
    size_t v_end = v;
    while (v_end < s.size() && !is_blank(s[v_end]))
      ++v_end;
    const std::string value_text = s.substr(v, v_end - v);
    if (value_text.empty())
      throw GcodeError({name, line, column}, "parameter " + number_text + " has no value");
    char* stop = nullptr;
    const double value = std::strtod(value_text.c_str(), &stop);
    if (stop != value_text.c_str() + value_text.size() || !std::isfinite(value))
      throw GcodeError(
          {name, line, static_cast<int>(v) + 1},
          "parameter " + number_text + ": '" + value_text + "' is not a finite number");
    if (number <= previous)
      throw GcodeError({name, line, column},
                       "parameter " + number_text + " after " + std::to_string(previous) +
                           " (line " + std::to_string(previous_line) +
                           "): the numbers must rise from line to line, as LinuxCNC requires "
                           "(\"Parameter file out of order\")");
    if (number == kCoordSystemIndex && (value != std::floor(value) || value < 1 || value > 9))
      throw GcodeError({name, line, static_cast<int>(v) + 1},
                       "parameter 5220 (the active coordinate system) must be 1..9 (G54..G59.3), "
                       "got " +
                           value_text);
    // No machine is larger than 100 m: an offset beyond it is a unit or
    // typing mistake that would surface later as a misleading program error
    // (a 1e300 mm G54 made "zero-radius arc" of the program's first arc).
    const OffsetKind kind = offset_kind(number);
    const double limit = kind == OffsetKind::kAngle    ? 1e6
                         : units == LengthUnits::kInch ? 1e5 / 25.4
                                                       : 1e5;
    const char* unit = kind == OffsetKind::kAngle    ? "deg"
                       : units == LengthUnits::kInch ? "inch"
                                                     : "mm";
    if (kind != OffsetKind::kNone && std::abs(value) > limit)
      throw GcodeError(
          {name, line, static_cast<int>(v) + 1},
          "parameter " + number_text + ": " + value_text + " " + unit +
              " is outside the offsets a machine can have (" +
              (kind == OffsetKind::kAngle
                   ? std::string("±1e6 deg")
                   : std::string(units == LengthUnits::kInch ? "±3937 inch" : "±1e5 mm")) +
              ": no machine is larger than 100 m)");
    out.values[static_cast<int>(number)] = value;
    previous = static_cast<int>(number);
    previous_line = line;
  }
  return out;
}

ParameterFile ParameterFile::load(const std::filesystem::path& file, LengthUnits units) {
  return parse(read_located_file(file, "parameter file"), file.string(), units);
}

}  // namespace truecut::interp
