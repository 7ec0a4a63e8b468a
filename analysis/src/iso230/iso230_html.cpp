// The printable iso230.html page: tables and inline SVG plots, no scripts
// and no external resources.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "diagnosis/report_text.hpp"
#include "truecut/analysis/iso230_report.hpp"

namespace truecut::analysis {
namespace {

std::string esc(const std::string& s) {
  return report_text::html_escape(s);
}

std::string f(double v, const char* fmt = "%.2f") {
  return report_text::number(v, fmt);
}

std::string f(const std::optional<double>& v, double scale, const char* fmt = "%.2f") {
  return v ? f(*v * scale, fmt) : "–";
}

// Deviations are shown in µm (linear) or arcsec (rotary).
struct Unit {
  double scale;
  const char* name;
};
Unit unit_of(const AxisPositioning& a) {
  return a.rotary ? Unit{3600, "″"} : Unit{1000, "µm"};
}

// Linear map of [lo, hi] onto [a, b] pixels.
struct Scale {
  double lo, hi, a, b;
  double operator()(double v) const { return a + (v - lo) / (hi - lo) * (b - a); }
};

std::string positioning_plot(const AxisPositioning& ax) {
  const Unit u = unit_of(ax);
  const double w = 640, h = 300, l = 60, r = 20, t = 20, btm = 40;
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (const auto& tg : ax.targets) {
    xlo = std::min(xlo, tg.target);
    xhi = std::max(xhi, tg.target);
    for (const auto* d : {&tg.up, &tg.down})
      if (*d) {
        ylo = std::min(ylo, ((*d)->mean - 2 * (*d)->s) * u.scale);
        yhi = std::max(yhi, ((*d)->mean + 2 * (*d)->s) * u.scale);
      }
  }
  if (xhi - xlo < 1e-9) xlo -= 1, xhi += 1;
  const double pad = std::max(0.1 * (yhi - ylo), 0.5);
  ylo -= pad, yhi += pad;
  const Scale sx{xlo, xhi, l, w - r}, sy{ylo, yhi, h - btm, t};
  std::string s = report_text::svg_open(w, h);
  s += report_text::svg_plot_frame(
      {w, h, l, r, t, btm, xlo, xhi, ylo, yhi, sx, sy, "%.2f", "%.0f", "%.3g", "%.1f"});
  s += "<text x=\"" + f((l + w - r) / 2) + "\" y=\"" + f(h - 6) +
       "\" text-anchor=\"middle\">target " + ax.joint + " (" + (ax.rotary ? "deg" : "mm") +
       ")</text>";
  s += "<text x=\"12\" y=\"" + f((t + h - btm) / 2) + "\" transform=\"rotate(-90 12 " +
       f((t + h - btm) / 2) + ")\" text-anchor=\"middle\">deviation (" + u.name + ")</text>";
  const struct {
    bool up;
    const char* colour;
    double dx;
  } dirs[] = {{true, "#1f5fbf", -3}, {false, "#c0392b", 3}};
  for (const auto& d : dirs) {
    std::string pts;
    for (const auto& tg : ax.targets) {
      const auto& st = d.up ? tg.up : tg.down;
      if (!st) continue;
      const double x = sx(tg.target) + d.dx;
      pts += f(x) + "," + f(sy(st->mean * u.scale)) + " ";
      s += "<line x1=\"" + f(x) + "\" x2=\"" + f(x) + "\" y1=\"" +
           f(sy((st->mean - 2 * st->s) * u.scale)) + "\" y2=\"" +
           f(sy((st->mean + 2 * st->s) * u.scale)) + "\" stroke=\"" + d.colour + "\"/>";
      s += "<circle cx=\"" + f(x) + "\" cy=\"" + f(sy(st->mean * u.scale)) +
           "\" r=\"2.5\" fill=\"" + d.colour + "\"/>";
    }
    s += "<polyline points=\"" + pts + "\" fill=\"none\" stroke=\"" + d.colour + "\"/>";
  }
  s += "<text x=\"" + f(l + 8) + "\" y=\"" + f(t + 14) + "\" fill=\"#1f5fbf\">↑ x̄ᵢ↑ ± 2sᵢ↑</text>";
  s +=
      "<text x=\"" + f(l + 120) + "\" y=\"" + f(t + 14) + "\" fill=\"#c0392b\">↓ x̄ᵢ↓ ± 2sᵢ↓</text>";
  return s + "</svg>";
}

std::string polar_plot(const CircularTest& c) {
  const double size = 420, mid = size / 2, base = 120, band = 60;  // px
  double peak = 0;
  for (const auto& r : c.runs)
    for (double d : r.deviation_mm)
      peak = std::max(peak, std::abs(d));
  if (peak <= 0) peak = 1e-3;
  const double k = band / peak;  // px per mm of deviation
  std::string s = report_text::svg_open(size, size);
  for (double ring : {-peak, 0.0, peak}) {
    s += "<circle cx=\"" + f(mid) + "\" cy=\"" + f(mid) + "\" r=\"" + f(base + k * ring) +
         "\" fill=\"none\" stroke=\"" + (ring == 0 ? "#888" : "#ddd") + "\"/>";
    s += "<text x=\"" + f(mid + 3) + "\" y=\"" + f(mid - base - k * ring - 2) +
         "\" fill=\"#888\">" + f(ring * 1e3, "%+.1f") + " µm</text>";
  }
  for (int a = 0; a < 360; a += 45) {
    const double rad = a * std::numbers::pi / 180;
    s += "<line x1=\"" + f(mid) + "\" y1=\"" + f(mid) + "\" x2=\"" +
         f(mid + (base + band + 10) * std::cos(rad)) + "\" y2=\"" +
         f(mid - (base + band + 10) * std::sin(rad)) + "\" stroke=\"#eee\"/>";
    s += "<text x=\"" + f(mid + (base + band + 22) * std::cos(rad)) + "\" y=\"" +
         f(mid - (base + band + 22) * std::sin(rad) + 4) + "\" text-anchor=\"middle\">" +
         std::to_string(a) + "°</text>";
  }
  for (const auto& r : c.runs) {
    const char* colour = r.direction == "ccw" ? "#1f5fbf" : "#c0392b";
    std::vector<std::pair<double, double>> pts;
    for (std::size_t i = 0; i < r.angle_deg.size(); ++i)
      pts.push_back({r.angle_deg[i], r.deviation_mm[i]});
    std::sort(pts.begin(), pts.end());
    std::string poly;
    for (const auto& [a, d] : pts) {
      const double rad = a * std::numbers::pi / 180, rr = base + k * d;
      poly += f(mid + rr * std::cos(rad)) + "," + f(mid - rr * std::sin(rad)) + " ";
    }
    s += "<polyline points=\"" + poly + "\" fill=\"none\" stroke=\"" + colour + "\"/>";
  }
  s += "<text x=\"8\" y=\"14\" fill=\"#1f5fbf\">CCW</text><text x=\"8\" y=\"28\" "
       "fill=\"#c0392b\">CW</text>";
  s += "<text x=\"8\" y=\"" + f(size - 8) + "\">+" + c.axis_p + " → right, +" + c.axis_q +
       " ↑; radial scale " + f(band / (peak * 1e3), "%.3g") + " px/µm</text>";
  return s + "</svg>";
}

std::string axis_section(const AxisPositioning& a) {
  const Unit u = unit_of(a);
  const double sc = u.scale;
  std::string s = "<section><h2>ISO 230-2 positioning, axis " + esc(a.joint) + "</h2>";
  s += "<p>measured: <code>" + esc(a.measured_channel) + "</code>; " +
       std::to_string(a.targets.size()) + " targets from " + std::to_string(a.readings) +
       " standstill readings; values in " + u.name + "</p>";
  s += "<table><tr><th></th><th>A</th><th>E</th><th>M</th><th>R</th><th>B</th></tr>";
  s += "<tr><th>bidirectional</th><td>" + f(a.A, sc) + "</td><td>" + f(a.E, sc) + "</td><td>" +
       f(a.M, sc) + "</td><td>" + f(a.R, sc) + "</td><td>" + f(a.B, sc) + "</td></tr>";
  for (const auto& [name, d] : {std::pair{"↑", a.up}, std::pair{"↓", a.down}})
    if (d)
      s += std::string("<tr><th>") + name + "</th><td>" + f(d->A * sc) + "</td><td>" +
           f(d->E * sc) + "</td><td></td><td>" + f(d->R * sc) + "</td><td></td></tr>";
  s += "</table>" + positioning_plot(a);
  s += "<table><tr><th>target</th><th>n↑</th><th>x̄↑</th><th>s↑</th><th>n↓</th><th>x̄↓</th>"
       "<th>s↓</th><th>x̄</th><th>B</th><th>R</th></tr>";
  for (const auto& t : a.targets) {
    s += "<tr><td>" + f(t.target, "%.4f") + "</td>";
    for (const auto* d : {&t.up, &t.down})
      s += *d ? "<td>" + std::to_string((*d)->runs()) + "</td><td>" + f((*d)->mean * sc) +
                    "</td><td>" + f((*d)->s * sc) + "</td>"
              : "<td></td><td>–</td><td>–</td>";
    s += "<td>" + f(t.mean_bidirectional, sc) + "</td><td>" + f(t.B, sc) + "</td><td>" +
         f(t.R, sc) + "</td></tr>";
  }
  s += "</table>";
  for (const auto& n : a.notes)
    s += "<p class=\"note\">" + esc(n) + "</p>";
  return s + "</section>";
}

std::string circle_section(const CircularTest& c) {
  std::string s =
      "<section><h2>ISO 230-4 circular test, " + esc(c.axis_p) + esc(c.axis_q) + " plane</h2>";
  s += "<p>measured: <code>" + esc(c.measured_p) + "</code>, <code>" + esc(c.measured_q) +
       "</code>; nominal radius " + f(c.nominal_radius_mm, "%.4f") + " mm, centre (" +
       f(c.nominal_centre_p_mm, "%.4f") + ", " + f(c.nominal_centre_q_mm, "%.4f") + ") mm</p>";
  s += "<table><tr><th>G</th><th>H</th><th>F max</th><th>F min</th></tr><tr><td>" +
       f(c.G_mm * 1e3) + " µm</td><td>" + (c.H_mm ? f(*c.H_mm * 1e3) + " µm" : "–") + "</td><td>" +
       f(c.F_max_mm * 1e3) + " µm</td><td>" + f(c.F_min_mm * 1e3) + " µm</td></tr></table>";
  s += polar_plot(c);
  s += "<table><tr><th>run</th><th>samples</th><th>swept</th><th>feed</th><th>G</th><th>F max</th>"
       "<th>F min</th><th>noise</th></tr>";
  for (const auto& r : c.runs)
    s += "<tr><td>" + r.direction + "</td><td>" + std::to_string(r.samples) + "</td><td>" +
         f(r.swept_deg, "%.0f") + "°</td><td>" + f(r.feed_mm_per_s * 60, "%.0f") +
         " mm/min</td><td>" + f(r.G_mm * 1e3) + " µm</td><td>" + f(r.F_max_mm * 1e3) +
         " µm</td><td>" + f(r.F_min_mm * 1e3) + " µm</td><td>" + f(r.noise_mm * 1e3) +
         " µm</td></tr>";
  s += "</table>";
  if (!c.harmonics.empty()) {
    s += "<table><tr><th>order</th><th>amplitude</th><th>phase</th></tr>";
    for (const auto& h : c.harmonics)
      s += "<tr><td>" + std::to_string(h.order) + "θ</td><td>" + f(h.amplitude_mm * 1e3) +
           " µm</td><td>" + (h.order ? f(h.phase_deg, "%.1f") + "°" : "") + "</td></tr>";
    s += "</table>";
  }
  if (!c.hints.empty()) {
    s += "<h3>Interpretation</h3><ul>";
    for (const auto& h : c.hints)
      s += "<li><b>" + esc(h.effect) + "</b>: " + esc(h.text) + "</li>";
    s += "</ul>";
  }
  for (const auto& n : c.notes)
    s += "<p class=\"note\">" + esc(n) + "</p>";
  return s + "</section>";
}

}  // namespace

std::string iso230_html(const Iso230Report& r) {
  std::string s = report_text::html_page_head(
      "ISO 230 evaluation — " + r.recording, "60em",
      "section{page-break-inside:avoid;margin-bottom:2em}.note{color:#845}"
      "svg{display:block;margin:.5em 0}@media print{body{max-width:none}}");
  s += "<h1>ISO 230 evaluation</h1><p>recording <code>" + esc(r.recording) + "</code>, " +
       std::to_string(r.rows) + " rows" +
       (r.map.empty() ? "" : ", map <code>" + esc(r.map) + "</code>") + "</p>\n";
  for (const auto& a : r.axes)
    s += axis_section(a) + "\n";
  for (const auto& k : r.skipped)
    s += "<p class=\"note\">axis " + esc(k.axis) + " not evaluated: " + esc(k.reason) + "</p>\n";
  for (const auto& c : r.circles)
    s += circle_section(c) + "\n";
  return s + "</body></html>\n";
}

}  // namespace truecut::analysis
