// Text helpers shared by the diagnosis reports (trace and surface mode) and
// the ISO 230 report: HTML escaping and numbers for HTML and JSON.
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::report_text {

// &, <, > and " escaped: safe in element text and in attribute values.
inline std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '&')
      o += "&amp;";
    else if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '"')
      o += "&quot;";
    else
      o += c;
  }
  return o;
}

// printf-formatted; "–" when not finite.
inline std::string number(double v, const char* fmt) {
  if (!std::isfinite(v)) return "–";
  return rt::format_printf(fmt, v);
}

// A JSON number, null when not finite (JSON has no NaN or infinity).
inline nlohmann::json json_number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace truecut::analysis::report_text
