// The smallest job that cuts: a coarse implant (`truecut part` with these
// arguments) and a one-pass program in which T2 (flat Ø4) faces the shaft
// top at z = 17 (stock up to 17.3); the shaft's sides keep their 0.3 mm.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace truecut::test {

inline std::vector<std::string> coarse_implant_part_args(const std::filesystem::path& out) {
  return {"part",       "implant", "--out",           out.string(), "--mesh-edge", "1",
          "--stepover", "0.8",     "--point-spacing", "1",          "--step-down", "2"};
}

inline constexpr const char* kFaceProgram =
    "%\n"
    "G21 G17 G40 G49 G80 G90 G94\n"
    "G54\n"
    "T2 M6\n"
    "G43 H2\n"
    "S12000 M3\n"
    "G0 X-5 Y0 Z20\n"
    "G1 Z17 F600\n"
    "G1 X5\n"
    "G0 Z20\n"
    "M5 G49 M30\n"
    "%\n";

}  // namespace truecut::test
