#include "truecut/analysis/report/svg_plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "truecut/analysis/report/deviation_image.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::report {
namespace {

// The <svg> element, the plot's frame and the labels of its horizontal
// axis, which runs symmetric from -range to +range.
std::string plot_frame(double W, double H, double left, double top, double pw, double ph,
                       double range) {
  std::string s = "<svg xmlns='http://www.w3.org/2000/svg' width='" + rt::format_printf("%.0f", W) +
                  "' height='" + rt::format_printf("%.0f", H) +
                  "' font-family='sans-serif' font-size='11'>";
  s += "<rect x='" + rt::format_printf("%.1f", left) + "' y='" + rt::format_printf("%.1f", top) +
       "' width='" + rt::format_printf("%.1f", pw) + "' height='" + rt::format_printf("%.1f", ph) +
       "' fill='none' stroke='#888'/>";
  for (int i = -2; i <= 2; ++i) {
    const double v = range * i / 2.0;
    s += "<text x='" + rt::format_printf("%.1f", left + (v + range) / (2 * range) * pw) + "' y='" +
         rt::format_printf("%.1f", top + ph + 14) + "' text-anchor='middle'>" +
         rt::format_printf("%g", v) + "</text>";
  }
  return s;
}

}  // namespace

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string histogram_svg(const std::vector<HistogramSeries>& series, double range, int bins,
                          double tolerance, const std::string& unit) {
  const double W = 560, H = 260, left = 50, right = 10, top = 12, bottom = 40;
  const double pw = W - left - right, ph = H - top - bottom;
  bins = std::max(bins, 2);
  std::vector<std::vector<double>> freq;
  double ymax = 1e-9;
  for (const auto& s : series) {
    std::vector<double> f(bins, 0.0);
    for (double v : s.values) {
      if (!std::isfinite(v)) continue;
      int b = static_cast<int>(std::floor((v + range) / (2 * range) * bins));
      f[std::clamp(b, 0, bins - 1)] += 1.0;
    }
    for (double& x : f)
      x = s.values.empty() ? 0.0 : 100.0 * x / double(s.values.size());
    ymax = std::max(ymax, *std::max_element(f.begin(), f.end()));
    freq.push_back(std::move(f));
  }
  ymax *= 1.1;
  auto X = [&](double v) { return left + (v + range) / (2 * range) * pw; };
  auto Y = [&](double p) { return top + ph - p / ymax * ph; };
  std::string s = plot_frame(W, H, left, top, pw, ph, range);
  for (int i = 0; i <= 4; ++i) {
    const double p = ymax * i / 4.0;
    s += "<text x='" + rt::format_printf("%.1f", left - 4) + "' y='" +
         rt::format_printf("%.1f", Y(p) + 4) + "' text-anchor='end'>" +
         rt::format_printf("%.0f", p) + "</text>";
  }
  s += "<text x='" + rt::format_printf("%.1f", left + pw / 2) + "' y='" +
       rt::format_printf("%.1f", H - 6) + "' text-anchor='middle'>deviation (" + html_escape(unit) +
       ")</text>";
  s += "<text x='12' y='" + rt::format_printf("%.1f", top + ph / 2) +
       "' transform='rotate(-90 12 " + rt::format_printf("%.1f", top + ph / 2) +
       ")' text-anchor='middle'>relative frequency (%)</text>";
  if (tolerance > 0)
    for (double t : {-tolerance, tolerance})
      s += "<line x1='" + rt::format_printf("%.1f", X(t)) + "' x2='" +
           rt::format_printf("%.1f", X(t)) + "' y1='" + rt::format_printf("%.1f", top) + "' y2='" +
           rt::format_printf("%.1f", top + ph) + "' stroke='#444' stroke-dasharray='4 3'/>";
  for (size_t k = 0; k < series.size(); ++k) {
    std::string path;
    for (int b = 0; b < bins; ++b) {
      const double x0 = X(-range + 2 * range * b / bins),
                   x1 = X(-range + 2 * range * (b + 1) / bins);
      path += (b == 0 ? "M" : "L") + rt::format_printf("%.1f", x0) + "," +
              rt::format_printf("%.1f", Y(freq[k][b])) + "L" + rt::format_printf("%.1f", x1) + "," +
              rt::format_printf("%.1f", Y(freq[k][b]));
    }
    s += "<path d='" + path + "' fill='none' stroke='" + html_escape(series[k].colour) +
         "' stroke-width='1.6'/>";
    s += "<rect x='" + rt::format_printf("%.1f", left + 8) + "' y='" +
         rt::format_printf("%.1f", top + 6 + 14.0 * k) + "' width='12' height='3' fill='" +
         html_escape(series[k].colour) + "'/>";
    s += "<text x='" + rt::format_printf("%.1f", left + 24) + "' y='" +
         rt::format_printf("%.1f", top + 10 + 14.0 * k) + "'>" + html_escape(series[k].label) +
         "</text>";
  }
  return s + "</svg>";
}

std::string profile_svg(const std::vector<ProfileSeries>& series, double low, double high,
                        double range, double tolerance, const std::string& value_unit,
                        const std::string& height_label) {
  const double W = 760, H = 320, left = 50, right = 210, top = 12, bottom = 40;
  const double pw = W - left - right, ph = H - top - bottom;
  if (!(high > low)) high = low + 1.0;
  auto X = [&](double v) {
    return left + (std::clamp(v, -range, range) + range) / (2 * range) * pw;
  };
  auto Y = [&](double z) { return top + ph - (z - low) / (high - low) * ph; };
  std::string s = plot_frame(W, H, left, top, pw, ph, range);
  s += "<line x1='" + rt::format_printf("%.1f", X(0)) + "' x2='" + rt::format_printf("%.1f", X(0)) +
       "' y1='" + rt::format_printf("%.1f", top) + "' y2='" + rt::format_printf("%.1f", top + ph) +
       "' stroke='#bbb'/>";
  for (int i = 0; i <= 4; ++i) {
    const double z = low + (high - low) * i / 4.0;
    s += "<text x='" + rt::format_printf("%.1f", left - 4) + "' y='" +
         rt::format_printf("%.1f", Y(z) + 4) + "' text-anchor='end'>" +
         rt::format_printf("%.3g", z) + "</text>";
  }
  s += "<text x='" + rt::format_printf("%.1f", left + pw / 2) + "' y='" +
       rt::format_printf("%.1f", H - 6) + "' text-anchor='middle'>deviation (" +
       html_escape(value_unit) + ")</text>";
  s += "<text x='12' y='" + rt::format_printf("%.1f", top + ph / 2) +
       "' transform='rotate(-90 12 " + rt::format_printf("%.1f", top + ph / 2) +
       ")' text-anchor='middle'>" + html_escape(height_label) + "</text>";
  if (tolerance > 0 && tolerance < range)
    for (double t : {-tolerance, tolerance})
      s += "<line x1='" + rt::format_printf("%.1f", X(t)) + "' x2='" +
           rt::format_printf("%.1f", X(t)) + "' y1='" + rt::format_printf("%.1f", top) + "' y2='" +
           rt::format_printf("%.1f", top + ph) + "' stroke='#444' stroke-dasharray='4 3'/>";
  for (size_t k = 0; k < series.size(); ++k) {
    const std::string colour = html_escape(series[k].colour);
    std::string path;
    for (size_t i = 0; i < series[k].points.size(); ++i) {
      const auto& [z, v] = series[k].points[i];
      path += (i == 0 ? "M" : "L") + rt::format_printf("%.1f", X(v)) + "," +
              rt::format_printf("%.1f", Y(z));
      s += "<circle cx='" + rt::format_printf("%.1f", X(v)) + "' cy='" +
           rt::format_printf("%.1f", Y(z)) + "' r='2.2' fill='" + colour + "'/>";
    }
    if (!path.empty())
      s += "<path d='" + path + "' fill='none' stroke='" + colour + "' stroke-width='1.6'/>";
    // Legend to the right of the plot, clear of the lines.
    s += "<rect x='" + rt::format_printf("%.1f", left + pw + 12) + "' y='" +
         rt::format_printf("%.1f", top + 6 + 14.0 * k) + "' width='12' height='3' fill='" + colour +
         "'/>";
    s += "<text x='" + rt::format_printf("%.1f", left + pw + 28) + "' y='" +
         rt::format_printf("%.1f", top + 10 + 14.0 * k) + "'>" + html_escape(series[k].label) +
         "</text>";
  }
  return s + "</svg>";
}

std::string colour_bar_svg(double limit, double tolerance, const std::string& unit) {
  const double W = 360, H = 46, left = 20, pw = 320;
  std::string s = "<svg xmlns='http://www.w3.org/2000/svg' width='" + rt::format_printf("%.0f", W) +
                  "' height='" + rt::format_printf("%.0f", H) +
                  "' font-family='sans-serif' font-size='11'>";
  const int steps = 64;
  for (int i = 0; i < steps; ++i) {
    const double v = -limit + 2 * limit * (i + 0.5) / steps;
    const auto c = deviation_colour(v, limit);
    s += "<rect x='" + rt::format_printf("%.2f", left + pw * i / steps) + "' y='4' width='" +
         rt::format_printf("%.2f", pw / steps + 0.3) + "' height='16' fill='rgb(" +
         std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]) + ")'/>";
  }
  for (double v : {-limit, 0.0, limit})
    s += "<text x='" + rt::format_printf("%.1f", left + pw * (v + limit) / (2 * limit)) +
         "' y='34' text-anchor='middle'>" + rt::format_printf("%g", v) + "</text>";
  if (tolerance > 0 && tolerance < limit)
    for (double t : {-tolerance, tolerance}) {
      const double x = left + pw * (t + limit) / (2 * limit);
      s += "<line x1='" + rt::format_printf("%.1f", x) + "' x2='" + rt::format_printf("%.1f", x) +
           "' y1='2' y2='22' stroke='#000' stroke-dasharray='3 2'/>";
    }
  s += "<text x='" + rt::format_printf("%.1f", left + pw / 2) + "' y='45' text-anchor='middle'>" +
       html_escape(unit) + (tolerance > 0 ? " (dashed: tolerance)" : "") + "</text>";
  return s + "</svg>";
}

}  // namespace truecut::analysis::report
