// What part.json must say: millimetres, tools that can cut (radius and
// flute length > 0, up to a tool 1 m across and 1 m long, as a machine
// description allows), a known tool kind, and stock within ±1e5 mm (no
// machine is larger than 100 m). read_part_file() applies these to what it
// read, so every command gets them, except that a tool's flute length may
// be absent (0: `truecut field` then takes the table's length); the
// machining needs it (check_part_for_machining). Header only, so that the
// components can use it with truecut_part_file alone.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

#include "truecut/sim/part_file.hpp"

namespace truecut::sim {

inline constexpr double kMaxPartToolRadiusMm = 500.0;   // a tool 1 m across
inline constexpr double kMaxPartToolLengthMm = 1000.0;  // and 1 m long
inline constexpr double kMaxPartCoordinateMm = 1e5;     // no machine is larger than 100 m
inline constexpr const char* kPartToolKinds[] = {"flat_end_mill", "ball_end_mill"};

namespace part_plausibility_detail {

inline std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

inline std::string indexed(const char* key, std::size_t i) {
  return std::string(key) + "[" + std::to_string(i) + "]";
}

// value in (0, max]; a NaN fails too.
inline void require_length(const std::string& file, const std::string& key, double value_mm,
                           double max_mm, const char* why) {
  if (value_mm > 0 && value_mm <= max_mm) return;
  throw PartFileError(file, key,
                      number_text(value_mm) + " mm must be > 0 and at most " + number_text(max_mm) +
                          " mm (" + why + "; check the unit)");
}

}  // namespace part_plausibility_detail

// "units", when given, must be "mm": every length of part.json is read as mm.
inline void check_part_units(const PartFile& p, const std::string& file) {
  if (p.units.empty() || p.units == "mm") return;
  throw PartFileError(file, "units",
                      "'" + p.units + "': part.json lengths are millimetres; only \"mm\" is read");
}

// `flute_length_required` false: a flute length of 0 (the key absent) passes.
inline void check_part_tools(const PartFile& p, const std::string& file,
                             bool flute_length_required = true) {
  namespace d = part_plausibility_detail;
  for (std::size_t i = 0; i < p.metadata.tools.size(); ++i) {
    const PartTool& t = p.metadata.tools[i];
    const std::string key = d::indexed("tools", i);
    d::require_length(file, key + ".radius_mm", t.radius_mm, kMaxPartToolRadiusMm,
                      "a tool of radius 0 cuts nothing; no tool is more than 1 m across");
    if (flute_length_required || t.flute_length_mm != 0)
      d::require_length(file, key + ".flute_length_mm", t.flute_length_mm, kMaxPartToolLengthMm,
                        "the cutter cuts only along its flutes; no tool is more than 1 m long");
    if (!(t.length_mm >= 0 && t.length_mm <= kMaxPartToolLengthMm))
      throw PartFileError(file, key + ".length_mm",
                          d::number_text(t.length_mm) + " mm is outside 0 .. " +
                              d::number_text(kMaxPartToolLengthMm) +
                              " mm (no tool is more than 1 m long; check the unit)");
    if (t.kind.empty()) continue;
    bool known = false;
    for (const char* kind : kPartToolKinds)
      known = known || t.kind == kind;
    if (!known)
      throw PartFileError(
          file, key + ".kind",
          "unknown tool kind '" + t.kind + "'; known: flat_end_mill, ball_end_mill");
  }
}

inline void check_part_stock(const PartFile& p, const std::string& file) {
  namespace d = part_plausibility_detail;
  for (std::size_t i = 0; i < p.metadata.stock.size(); ++i) {
    const StockBox& b = p.metadata.stock[i];
    for (const auto& [name, corner] : {std::pair{"min_mm", &b.min_mm}, {"max_mm", &b.max_mm}})
      for (int a = 0; a < 3; ++a)
        if (!(std::abs((*corner)[a]) <= kMaxPartCoordinateMm))
          throw PartFileError(file, d::indexed("stock", i) + "." + name,
                              d::number_text((*corner)[a]) + " mm is outside ±" +
                                  d::number_text(kMaxPartCoordinateMm) +
                                  " mm (no machine is larger than 100 m; check the unit)");
  }
}

// What read_part_file() checks of everything it read.
inline void check_part_file_sense(const PartFile& p, const std::string& file) {
  check_part_units(p, file);
  check_part_tools(p, file, false);
  check_part_stock(p, file);
}

// All three, a flute length required: what the simulated machining reads
// from part.json.
inline void check_part_for_machining(const PartFile& p, const std::string& file) {
  check_part_units(p, file);
  check_part_tools(p, file);
  check_part_stock(p, file);
}

}  // namespace truecut::sim
