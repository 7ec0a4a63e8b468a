// The result of `truecut iso230` and its two renderings: iso230.json
// (schema in docs/iso230.md) and a self-contained printable HTML page.
#pragma once

#include <string>
#include <vector>

#include "truecut/analysis/iso230_circular.hpp"
#include "truecut/analysis/iso230_positioning.hpp"

namespace truecut::analysis {

struct SkippedAxis {
  std::string axis;
  std::string reason;
};

struct Iso230Report {
  std::string recording;  // file name as given
  std::size_t rows = 0;
  std::string map;  // the --map text, empty when none
  StandstillOptions standstill;
  std::vector<AxisPositioning> axes;
  std::vector<SkippedAxis> skipped;
  std::vector<CircularTest> circles;
};

std::string iso230_json(const Iso230Report& report);
std::string iso230_html(const Iso230Report& report);

}  // namespace truecut::analysis
