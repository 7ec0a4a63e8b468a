// Small inline-SVG plots for the self-contained HTML reports.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace truecut::analysis::report {

struct HistogramSeries {
  std::string label;
  std::string colour;  // CSS colour
  std::vector<double> values;
};

// Relative-frequency histogram (percent per bin) of each series, overlaid as
// step lines, over [-range, +range] in `bins` bins; values beyond the range
// go into the outermost bins. Dashed lines mark ±tolerance when > 0.
std::string histogram_svg(const std::vector<HistogramSeries>& series, double range, int bins,
                          double tolerance, const std::string& unit);

struct ProfileSeries {
  std::string label;
  std::string colour;                             // CSS colour
  std::vector<std::pair<double, double>> points;  // (height, value), in height order
};

// Value (horizontal, -range … +range) against height (vertical, low … high)
// of each series as a polyline with dots: a deviation profile along a wall.
// Dashed lines mark ±tolerance when > 0.
std::string profile_svg(const std::vector<ProfileSeries>& series, double low, double high,
                        double range, double tolerance, const std::string& value_unit,
                        const std::string& height_label);

// A horizontal colour bar of deviation_colour() from -limit to +limit.
std::string colour_bar_svg(double limit, double tolerance, const std::string& unit);

// Escapes text for HTML/SVG content.
std::string html_escape(const std::string& text);

}  // namespace truecut::analysis::report
