// diagnosis.html: a self-contained page (inline SVG, no scripts, no
// external resources) with the residual before and after the fit.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "report_text.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"

namespace truecut::analysis::diagnosis {

namespace {

std::string esc(const std::string& s) {
  return report_text::html_escape(s);
}

std::string f(double v, const char* fmt = "%.1f") {
  return report_text::number(v, fmt);
}

struct Series {
  const std::vector<double>* x;
  const std::vector<double>* y;
  const char* colour;
  bool line;
};

// Residuals in µm against x; at most ~1500 points per series (every n-th).
std::string plot(const std::vector<Series>& series, const std::string& xlabel,
                 const std::vector<char>* shade = nullptr,
                 const std::vector<double>* shade_x = nullptr) {
  const double w = 720, h = 240, l = 64, r = 16, t = 12, b = 36;
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (const auto& s : series)
    for (std::size_t i = 0; i < s.x->size(); ++i) {
      xlo = std::min(xlo, (*s.x)[i]), xhi = std::max(xhi, (*s.x)[i]);
      ylo = std::min(ylo, (*s.y)[i] * 1e3), yhi = std::max(yhi, (*s.y)[i] * 1e3);
    }
  if (!(xhi > xlo)) xlo -= 1, xhi += 1;
  if (!(yhi > ylo)) ylo -= 1, yhi += 1;
  const double pad = 0.05 * (yhi - ylo);
  ylo -= pad, yhi += pad;
  auto X = [&](double v) { return l + (v - xlo) / (xhi - xlo) * (w - l - r); };
  auto Y = [&](double v) { return t + (yhi - v) / (yhi - ylo) * (h - t - b); };
  std::string s = report_text::svg_open(w, h);
  if (shade && shade_x) {
    // The held-out block.
    for (std::size_t i = 0; i < shade->size(); ++i)
      if ((*shade)[i]) {
        s += "<rect x=\"" + f(X((*shade_x)[i])) + "\" y=\"" + f(t) + "\" width=\"" +
             f(X(xhi) - X((*shade_x)[i])) + "\" height=\"" + f(h - t - b) +
             "\" fill=\"#f3f0e0\"/><text x=\"" + f(X((*shade_x)[i]) + 4) + "\" y=\"" + f(t + 12) +
             "\" fill=\"#886\">held out</text>";
        break;
      }
  }
  s += report_text::svg_plot_frame(
      {w, h, l, r, t, b, xlo, xhi, ylo, yhi, X, Y, "%.1f", "%.1f", "%.4g", "%.3g"});
  s += "<text x=\"" + f((l + w - r) / 2) + "\" y=\"" + f(h - 4) + "\" text-anchor=\"middle\">" +
       esc(xlabel) + "</text><text x=\"12\" y=\"" + f((t + h - b) / 2) +
       "\" transform=\"rotate(-90 12 " + f((t + h - b) / 2) +
       ")\" text-anchor=\"middle\">residual (µm)</text>";
  for (const auto& se : series) {
    const std::size_t n = se.x->size(), every = std::max<std::size_t>(1, n / 1500);
    if (se.line) {
      std::string pts;
      for (std::size_t i = 0; i < n; i += every)
        pts += f(X((*se.x)[i])) + "," + f(Y((*se.y)[i] * 1e3)) + " ";
      s += "<polyline points=\"" + pts + "\" fill=\"none\" stroke=\"" + se.colour +
           "\" stroke-width=\"0.8\"/>";
    } else {
      std::string d;
      for (std::size_t i = 0; i < n; i += every)
        d += "M" + f(X((*se.x)[i])) + " " + f(Y((*se.y)[i] * 1e3)) + "h0.1";
      s += "<path d=\"" + d + "\" stroke=\"" + se.colour +
           "\" stroke-width=\"2\" stroke-linecap=\"round\" fill=\"none\"/>";
    }
  }
  return s + "</svg>";
}

}  // namespace

std::string diagnosis_html(const DiagnosisResult& r) {
  std::string s = report_text::html_page_head(
      "Diagnosis — " + r.recording, "62em",
      "th{background:#f4f4f4}td.l{text-align:left}section{margin-bottom:2em}"
      ".legend span{margin-right:1.5em}svg{display:block;margin:.3em 0}");
  s += "<h1>Diagnosis (trace mode)</h1><p>recording <code>" + esc(r.recording) + "</code>, " +
       std::to_string(r.rows) + " samples every " + f(r.sample_period_s * 1e3, "%.4g") + " ms" +
       (r.map.empty() ? "" : ", map <code>" + esc(r.map) + "</code>") +
       "; believed model: " + esc(r.believed.name) + "</p>\n";
  s += "<p><b>Verdict:</b> " + esc(r.verdict) + "</p>\n";
  if (!r.glitch_rows.empty()) s += "<p>" + esc(glitch_rows_text(r)) + "</p>\n";
  if (!r.notes.empty()) {
    s += "<ul>";
    for (const auto& n : r.notes)
      s += "<li>" + esc(n) + "</li>";
    s += "</ul>\n";
  }
  s += "<p>Logging delay removed: " + f(r.delay_s * 1e3, "%.4g") + " ms" +
       (r.delay_ci95_s ? " (95 %: " + f(r.delay_ci95_s->first * 1e3, "%.4g") + " .. " +
                             f(r.delay_ci95_s->second * 1e3, "%.4g") + " ms)"
                       : std::string()) +
       (r.delay_note.empty() ? "" : "; " + esc(r.delay_note)) + ". Noise floor " +
       f(r.noise_floor_mm * 1e3, "%.3g") +
       " µm (robust high-pass MAD, at least the recording's resolution).</p>\n";

  s += "<section><h2>Fit</h2><table><tr><th></th><th>samples</th><th>RMS before</th><th>RMS "
       "after</th><th>max before</th><th>max after</th></tr>";
  auto row = [&](const char* name, const FitFigures& fg) {
    s += std::string("<tr><th>") + name + "</th><td>" + std::to_string(fg.samples) + "</td><td>" +
         f(fg.rms_before_mm * 1e3, "%.3g") + " µm</td><td>" + f(fg.rms_after_mm * 1e3, "%.3g") +
         " µm</td><td>" + f(fg.max_before_mm * 1e3, "%.3g") + " µm</td><td>" +
         f(fg.max_after_mm * 1e3, "%.3g") + " µm</td></tr>";
  };
  row("fitted data", r.train);
  if (r.has_heldout)
    row(r.heldout_kind == "file" ? "held-out recording" : "held-out block", r.heldout);
  s += "</table><p>Whiteness of the remaining residual: Ljung–Box Q = " +
       f(r.whiteness.ljung_box_q, "%.1f") + " over " + std::to_string(r.whiteness.lags) +
       " lags, p = " + f(r.whiteness.p_value, "%.3g") +
       (r.whiteness.white ? " (white)" : " (not white)") + "</p></section>\n";

  s += "<section><h2>Explanations</h2>";
  if (r.explanations.empty())
    s += "<p>No candidate effect is selected.</p>";
  else {
    s += "<table><tr><th>effect</th><th>axis</th><th>parameters (95 % interval)</th><th>ΔBIC</th>"
         "<th>RMS of the effect</th></tr>";
    for (const auto& e : r.explanations) {
      std::string ps;
      for (const auto& p : e.parameters)
        ps += esc(p.name) + " = " + f(p.value, "%.5g") +
              (p.fixed ? " (scanned)"
                       : " [" + f(p.ci95_lo, "%.4g") + ", " + f(p.ci95_hi, "%.4g") + "]") +
              "<br>";
      for (const auto& p : e.undetermined)
        ps += esc(p.name) + " not determined: " + f(p.value, "%.5g") + " [" + f(p.ci95_lo, "%.4g") +
              ", " + f(p.ci95_hi, "%.4g") + "]<br>";
      s += "<tr><td class=\"l\">" + esc(e.effect) + "</td><td class=\"l\">" + esc(e.axis) +
           "</td><td class=\"l\">" + ps + "</td><td>" + f(e.delta_bic, "%.1f") + "</td><td>" +
           f(e.rms_effect_mm * 1e3, "%.3g") + " µm</td></tr>";
    }
    s += "</table>";
  }
  if (!r.not_identifiable.empty()) {
    s += "<h3>Not identifiable from these data</h3><ul>";
    for (const auto& n : r.not_identifiable)
      s += "<li><b>" + esc(n.first) + "</b> vs <b>" + esc(n.second) +
           "</b>: " + esc(n.separate_by) + "</li>";
    s += "</ul>";
  }
  if (!r.not_confirmed.empty()) {
    s += "<h3>Not confirmed on the held-out data (left out of the fitted model)</h3><ul>";
    for (const auto& n : r.not_confirmed)
      s += "<li><b>" + esc(n.effect) + (n.axis.empty() ? "" : " " + esc(n.axis)) +
           "</b>: held-out RMS " + f(n.heldout_rms_with_mm * 1e3, "%.3g") + " µm with it, " +
           f(n.heldout_rms_without_mm * 1e3, "%.3g") + " µm without</li>";
    s += "</ul>";
  }
  s += "</section>\n";

  s += "<section><h2>Where the residual is above the noise floor</h2>";
  s += "<table><tr><th>axis</th><th>target</th><th>RMS</th><th>max</th><th>mean</th><th>noise "
       "floor</th><th>standstill noise</th><th>offset removed</th></tr>";
  for (const auto& a : r.axes)
    s += "<tr><td class=\"l\">" + esc(a.axis) + "</td><td class=\"l\">" + esc(a.target) +
         "</td><td>" + f(a.rms_mm * 1e3, "%.3g") + " µm</td><td>" + f(a.max_mm * 1e3, "%.3g") +
         " µm</td><td>" + f(a.mean_mm * 1e3, "%.3g") + " µm</td><td>" +
         f(a.noise_floor_mm * 1e3, "%.3g") + " µm</td><td>" +
         (a.standstill_noise_mm ? f(*a.standstill_noise_mm * 1e3, "%.3g") + " µm" : "–") +
         "</td><td>" + f(a.offset_mm * 1e3, "%.3g") + " µm</td></tr>";
  s += "</table>";
  if (r.mismatch.empty())
    s += "<p>Nowhere.</p>";
  else {
    s += "<table><tr><th>axis</th><th>by</th><th>where</th><th>samples</th><th>RMS</th>"
         "<th>max</th><th>mean</th><th>× floor</th></tr>";
    for (const auto& m : r.mismatch)
      s += "<tr><td class=\"l\">" + esc(m.axis) + "</td><td class=\"l\">" + esc(m.where) +
           "</td><td class=\"l\">" + esc(m.what) + "</td><td>" + std::to_string(m.samples) +
           "</td><td>" + f(m.rms_mm * 1e3, "%.3g") + " µm</td><td>" + f(m.max_mm * 1e3, "%.3g") +
           " µm</td><td>" + f(m.mean_mm * 1e3, "%.3g") + " µm</td><td>" +
           f(m.ratio_to_floor, "%.3g") + "</td></tr>";
    s += "</table>";
  }
  s += "</section>\n";

  s += "<section><h2>Residual plots</h2><p class=\"legend\"><span style=\"color:#999\">■ before "
       "(believed model)</span><span style=\"color:#1f5fbf\">■ after (fitted model)</span></p>";
  for (const auto& se : r.series) {
    s += "<h3>Axis " + esc(se.axis) + "</h3>";
    s += plot({{&se.t_s, &se.before_mm, "#999", true}, {&se.t_s, &se.after_mm, "#1f5fbf", true}},
              "time (s)", &se.heldout, &se.t_s);
    s += plot({{&se.cmd, &se.before_mm, "#999", false}, {&se.cmd, &se.after_mm, "#1f5fbf", false}},
              "commanded position " + se.axis);
    s += plot({{&se.velocity, &se.before_mm, "#999", false},
               {&se.velocity, &se.after_mm, "#1f5fbf", false}},
              "commanded velocity " + se.axis + " (per s)");
  }
  s += "</section>\n";
  return s + "</body></html>\n";
}

}  // namespace truecut::analysis::diagnosis
