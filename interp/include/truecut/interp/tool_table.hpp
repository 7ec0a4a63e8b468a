// Tool table in LinuxCNC's format: one tool per line,
//   T<number> P<pocket> [X.. Y.. Z.. A.. B.. C.. U.. V.. W..] [D<diameter>]
//   [I.. J.. Q..] [;comment]
// Offsets and diameters are in the machine's length units (LinuxCNC: the
// INI's [TRAJ]LINEAR_UNITS; rs274 without an INI: inch). They are read in
// `units` and stored in mm.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "truecut/interp/canon.hpp"

namespace truecut::interp {

struct ToolEntry {
  int number = 0;
  int pocket = 0;
  Axes6 offset_mm;  // length offsets per axis (Z is the usual one)
  double diameter_mm = 0;
  int orientation = 0;  // Q: a lathe tool's orientation 1-8 (0 or 9: a mill)
  double front_angle_deg = 0, back_angle_deg = 0;  // I, J (lathe tools)
  std::string comment;
};

class ToolTable {
 public:
  // Throws GcodeError with file:line:column on a malformed line.
  static ToolTable load(const std::filesystem::path& file, LengthUnits units = LengthUnits::kMm);
  static ToolTable parse(std::string_view text, const std::string& name,
                         LengthUnits units = LengthUnits::kMm);

  void add(ToolEntry entry);
  const std::vector<ToolEntry>& entries() const { return entries_; }
  const ToolEntry* find(int number) const;
  ToolEntry* find(int number);  // G10 L1/L10/L11 edit the entry
  // 1-based row of the tool in the table, as LinuxCNC numbers its slots.
  std::optional<int> slot_of(int number) const;
  // The units the table was read in: the machine's length units.
  LengthUnits units() const { return units_; }

 private:
  std::vector<ToolEntry> entries_;
  LengthUnits units_ = LengthUnits::kMm;
};

}  // namespace truecut::interp
