// Text helpers shared by the diagnosis reports (trace and surface mode) and
// the ISO 230 report: HTML escaping, numbers for HTML and JSON, the page
// head and the frame of an inline SVG plot.
#pragma once

#include <cmath>
#include <functional>
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

// The start of a self-contained report page, up to and including <body>:
// `title` (escaped here), the body `max_width` (CSS length), the common
// rules for text and tables, then the page's own CSS rules `extra_css`.
inline std::string html_page_head(const std::string& title, const std::string& max_width,
                                  const std::string& extra_css) {
  return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
         html_escape(title) + "</title><style>body{font-family:sans-serif;max-width:" + max_width +
         ";margin:1em auto;color:#222}table{border-collapse:collapse;margin:.5em "
         "0}td,th{border:1px "
         "solid #bbb;padding:2px 6px;text-align:right}" +
         extra_css + "</style></head><body>\n";
}

// The opening <svg> tag of a w x h pixel plot.
inline std::string svg_open(double w, double h) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + number(w, "%.0f") + "\" height=\"" +
         number(h, "%.0f") + "\" font-size=\"11\">";
}

// The frame of a plot of w x h pixels with margins l r t b: its box, 5
// labelled ticks on each axis over [xlo, xhi] and [ylo, yhi], and a line at
// y = 0 when 0 is inside. x_px and y_px map data to pixels.
struct PlotFrame {
  double w, h, l, r, t, b;
  double xlo, xhi, ylo, yhi;
  std::function<double(double)> x_px, y_px;
  const char* px_format;      // pixel positions of ticks, labels and the 0 line
  const char* box_format;     // the box's position and size
  const char* x_tick_format;  // tick labels
  const char* y_tick_format;
};

inline std::string svg_plot_frame(const PlotFrame& p) {
  auto px = [&](double v) { return number(v, p.px_format); };
  auto box = [&](double v) { return number(v, p.box_format); };
  std::string s = "<rect x=\"" + box(p.l) + "\" y=\"" + box(p.t) + "\" width=\"" +
                  box(p.w - p.l - p.r) + "\" height=\"" + box(p.h - p.t - p.b) +
                  "\" fill=\"none\" stroke=\"#888\"/>";
  for (int i = 0; i <= 4; ++i) {
    const double yv = p.ylo + (p.yhi - p.ylo) * i / 4, xv = p.xlo + (p.xhi - p.xlo) * i / 4;
    s += "<text x=\"" + px(p.l - 4) + "\" y=\"" + px(p.y_px(yv) + 4) + "\" text-anchor=\"end\">" +
         number(yv, p.y_tick_format) + "</text>";
    s += "<text x=\"" + px(p.x_px(xv)) + "\" y=\"" + px(p.h - p.b + 14) +
         "\" text-anchor=\"middle\">" + number(xv, p.x_tick_format) + "</text>";
  }
  if (p.ylo < 0 && p.yhi > 0)
    s += "<line x1=\"" + px(p.l) + "\" x2=\"" + px(p.w - p.r) + "\" y1=\"" + px(p.y_px(0)) +
         "\" y2=\"" + px(p.y_px(0)) + "\" stroke=\"#ccc\"/>";
  return s;
}

// A JSON number, null when not finite (JSON has no NaN or infinity).
inline nlohmann::json json_number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

// The document as indented JSON text. A string that is not UTF-8 (a Latin-1
// file name, an operation name from a program in another encoding) has each
// invalid byte replaced by U+FFFD: the report is written, and names the
// input as nearly as UTF-8 can; nlohmann's default threw type_error.316
// after all the work.
template <class Json>
std::string json_text(const Json& j) {
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

// `s` with each byte that is not UTF-8 replaced by U+FFFD, as json_text
// writes it: for a name that goes into JSON through another writer (the
// fitted machine's name, which carries the recording's file name).
inline std::string utf8_safe(const std::string& s) {
  return nlohmann::json::parse(
             nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace))
      .get<std::string>();
}

}  // namespace truecut::analysis::report_text
