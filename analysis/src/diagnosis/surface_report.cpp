// Surface mode: diagnosis.json, the HTML page and the stdout summary.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "report_text.hpp"
#include "truecut/analysis/diagnosis/surface.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::diagnosis {

namespace {

using nlohmann::json;

json num(double v) {
  return report_text::json_number(v);
}

json fit_json(const SurfaceFit& f) {
  return {{"points", f.points},
          {"rms_before_mm", num(f.rms_before_mm)},
          {"rms_after_mm", num(f.rms_after_mm)},
          {"max_before_mm", num(f.max_before_mm)},
          {"max_after_mm", num(f.max_after_mm)},
          {"improvement",
           f.rms_before_mm > 0 ? num(1 - f.rms_after_mm / f.rms_before_mm) : json(nullptr)}};
}

std::string esc(const std::string& s) {
  return report_text::html_escape(s);
}

}  // namespace

std::string surface_diagnosis_json(const SurfaceDiagnosisResult& r) {
  json j;
  j["truecut_diagnosis"] = 1;
  j["mode"] = "surface";
  j["measurement"] = r.measurement;
  j["measurement_kind"] = r.kind;
  j["program"] = r.program;
  j["points"] = r.points;
  j["valid_points"] = r.valid_points;
  json reg = {{"translation_mm",
               {num(r.registration_translation_mm.x()), num(r.registration_translation_mm.y()),
                num(r.registration_translation_mm.z())}},
              {"rotation_urad",
               {num(r.registration_rotation_urad.x()), num(r.registration_rotation_urad.y()),
                num(r.registration_rotation_urad.z())}},
              {"about_mm", {r.centroid_mm.x(), r.centroid_mm.y(), r.centroid_mm.z()}},
              {"scan_to_nominal", nullptr}};
  if (r.scan_to_nominal) {
    json m = json::array();
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 4; ++k)
        m.push_back(r.scan_to_nominal->matrix()(i, k));
    reg["scan_to_nominal"] = m;
    reg["icp_rms_before_mm"] = num(r.icp_rms_before_mm);
    reg["icp_rms_after_mm"] = num(r.icp_rms_after_mm);
  }
  j["registration"] = reg;
  j["noise_floor_mm"] = num(r.noise_floor_mm);
  json mm = json::array();
  for (const auto& g : r.mismatch)
    mm.push_back({{"where", g.where},
                  {"what", g.what},
                  {"points", g.points},
                  {"rms_mm", num(g.rms_mm)},
                  {"mean_mm", num(g.mean_mm)},
                  {"max_mm", num(g.max_mm)},
                  {"ratio_to_floor", num(g.ratio_to_floor)}});
  j["mismatch"] = mm;
  j["unmeasured_surfaces"] = r.unmeasured_surfaces;
  json ex = json::array();
  for (const auto& e : r.explanations) {
    json p = json::object(), ci = json::object();
    for (const auto& q : e.parameters) {
      p[q.name] = num(q.value);
      ci[q.name] = {num(q.ci95_lo), num(q.ci95_hi)};
    }
    ex.push_back(
        {{"effect", e.effect},
         {"axis", e.axis.empty() ? json(nullptr) : json(e.axis)},
         {"parameters", p},
         {"ci95", ci},
         {"score", {{"delta_bic", num(e.delta_bic)}, {"rms_effect_mm", num(e.rms_effect_mm)}}},
         {"note", e.note}});
  }
  j["explanations"] = ex;
  json ni = json::array();
  for (const auto& n : r.not_identifiable)
    ni.push_back({{"first", n.first},
                  {"second", n.second},
                  {"correlation", num(n.correlation)},
                  {"separate_by", n.separate_by}});
  j["not_identifiable"] = ni;
  j["candidates_tested"] = r.candidates_tested;
  j["resimulations"] = r.resimulations;
  j["gauss_newton"] = {{"iterations", r.gauss_newton_iterations},
                       {"converged", r.gauss_newton_converged}};
  json heldout = nullptr;
  if (r.has_heldout) {
    heldout = fit_json(r.heldout);
    heldout["kind"] = r.heldout_kind;
  }
  j["fit"] = {{"train", fit_json(r.train)}, {"heldout", heldout}};
  j["verdict"] = r.verdict;
  return report_text::json_text(j);
}

std::string surface_diagnosis_summary(const SurfaceDiagnosisResult& r) {
  std::ostringstream o;
  o << "measurement " << r.measurement << " (" << r.kind << "): " << r.valid_points << " of "
    << r.points << " points compared\n";
  if (r.scan_to_nominal)
    o << "scan registered by ICP: rms " << rt::format_printf("%.4g", r.icp_rms_before_mm * 1e3)
      << " -> " << rt::format_printf("%.4g", r.icp_rms_after_mm * 1e3) << " µm\n";
  o << "registration profiled out: translation ("
    << rt::format_printf("%.3g", r.registration_translation_mm.x() * 1e3) << ", "
    << rt::format_printf("%.3g", r.registration_translation_mm.y() * 1e3) << ", "
    << rt::format_printf("%.3g", r.registration_translation_mm.z() * 1e3) << ") µm, rotation ("
    << rt::format_printf("%.3g", r.registration_rotation_urad.x()) << ", "
    << rt::format_printf("%.3g", r.registration_rotation_urad.y()) << ", "
    << rt::format_printf("%.3g", r.registration_rotation_urad.z()) << ") µrad\n";
  o << "noise floor " << rt::format_printf("%.4g", r.noise_floor_mm * 1e3) << " µm; "
    << r.resimulations << " re-machinings\n";
  for (const auto& u : r.unmeasured_surfaces)
    o << "not measured (no valid point): " << u << "\n";
  if (!r.mismatch.empty()) o << "above the noise floor:\n";
  for (const auto& g : r.mismatch)
    // "surface 3 (shaft_y_pos)" names its kind already ("surface surface 3" before).
    o << "  " << (g.what.rfind(g.where + " ", 0) == 0 ? g.what : g.where + " " + g.what) << ": rms "
      << rt::format_printf("%.4g", g.rms_mm * 1e3) << " µm, mean "
      << rt::format_printf("%.4g", g.mean_mm * 1e3) << " µm ("
      << rt::format_printf("%.3g", g.ratio_to_floor) << "× floor)\n";
  for (const auto& e : r.explanations) {
    o << "found " << e.effect << (e.axis.empty() ? "" : ":" + e.axis) << ":";
    for (const auto& p : e.parameters)
      o << " " << p.name << "=" << rt::format_printf("%.5g", p.value) << " ["
        << rt::format_printf("%.5g", p.ci95_lo) << ", " << rt::format_printf("%.5g", p.ci95_hi)
        << "]";
    o << " (ΔBIC " << rt::format_printf("%.1f", e.delta_bic) << ")";
    if (!e.note.empty()) o << "; " << e.note;
    o << "\n";
  }
  if (r.gauss_newton_iterations > 0)
    o << "parameters fitted by " << r.gauss_newton_iterations << " Gauss-Newton iteration"
      << (r.gauss_newton_iterations > 1 ? "s" : "")
      << (r.gauss_newton_converged ? " (converged)" : " (not converged: last step above se/5)")
      << "\n";
  for (const auto& n : r.not_identifiable)
    o << "not identifiable: " << n.first << " vs " << n.second << " (correlation "
      << rt::format_printf("%.3f", n.correlation) << ") — " << n.separate_by << "\n";
  o << "fit: rms " << rt::format_printf("%.4g", r.train.rms_before_mm * 1e3) << " -> "
    << rt::format_printf("%.4g", r.train.rms_after_mm * 1e3) << " µm (fitted region)";
  if (r.has_heldout)
    o << ", " << rt::format_printf("%.4g", r.heldout.rms_before_mm * 1e3) << " -> "
      << rt::format_printf("%.4g", r.heldout.rms_after_mm * 1e3) << " µm (held out, "
      << r.heldout_kind << ")";
  o << "\nverdict: " << r.verdict << "\n";
  return o.str();
}

std::string surface_diagnosis_html(const SurfaceDiagnosisResult& r) {
  std::ostringstream h;
  h << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>truecut diagnosis (surface)"
       "</title><style>body{font-family:sans-serif;max-width:1000px;margin:auto}"
       "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px}</style>"
       "</head><body><h1>Surface diagnosis</h1><pre>"
    << esc(surface_diagnosis_summary(r)) << "</pre>";
  // Residual before / after against the coordinate along the held-out split
  // (the longest extent), one panel each.
  int axis = 0;
  {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const auto& p : r.position_mm)
      lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    if (!r.position_mm.empty()) (hi - lo).maxCoeff(&axis);
  }
  double xmin = 1e300, xmax = -1e300, ymax = 1e-9;
  for (std::size_t i = 0; i < r.position_mm.size(); ++i) {
    xmin = std::min(xmin, r.position_mm[i][axis]);
    xmax = std::max(xmax, r.position_mm[i][axis]);
    ymax = std::max({ymax, std::abs(r.before_mm[i]), std::abs(r.after_mm[i])});
  }
  if (!(xmax > xmin)) xmax = xmin + 1;
  const int w = 900, hgt = 220;
  for (int panel = 0; panel < 2; ++panel) {
    const auto& v = panel == 0 ? r.before_mm : r.after_mm;
    h << "<h2>Residual " << (panel == 0 ? "before" : "after") << " the fit against "
      << "xyz"[axis] << " (held-out points red; ±" << rt::format_printf("%.3g", ymax * 1e3)
      << " µm full scale)</h2><svg width=\"" << w << "\" height=\"" << hgt
      << "\" xmlns=\"http://www.w3.org/2000/svg\"><rect width=\"" << w << "\" height=\"" << hgt
      << "\" fill=\"white\" stroke=\"#999\"/><line x1=\"0\" y1=\"" << hgt / 2 << "\" x2=\"" << w
      << "\" y2=\"" << hgt / 2 << "\" stroke=\"#ccc\"/>";
    for (std::size_t i = 0; i < v.size(); ++i) {
      const double x = (r.position_mm[i][axis] - xmin) / (xmax - xmin) * (w - 10) + 5;
      const double y = hgt / 2.0 - v[i] / ymax * (hgt / 2.0 - 5);
      h << "<circle cx=\"" << rt::format_printf("%.1f", x) << "\" cy=\""
        << rt::format_printf("%.1f", y) << "\" r=\"1.2\" fill=\""
        << (r.is_heldout[i] ? "#c33" : "#36c") << "\"/>";
    }
    h << "</svg>";
  }
  h << "<h2>Located regions</h2><table><tr><th>where</th><th>what</th><th>points</th>"
       "<th>rms µm</th><th>mean µm</th><th>× floor</th></tr>";
  for (const auto& g : r.mismatch)
    h << "<tr><td>" << esc(g.where) << "</td><td>" << esc(g.what) << "</td><td>" << g.points
      << "</td><td>" << rt::format_printf("%.3g", g.rms_mm * 1e3) << "</td><td>"
      << rt::format_printf("%.3g", g.mean_mm * 1e3) << "</td><td>"
      << rt::format_printf("%.3g", g.ratio_to_floor) << "</td></tr>";
  h << "</table></body></html>\n";
  return h.str();
}

}  // namespace truecut::analysis::diagnosis
