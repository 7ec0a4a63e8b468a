// diagnosis.json (schema in docs/diagnosis.md) and the stdout summary.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "report_text.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::diagnosis {

namespace {

using nlohmann::json;

json num(double v) {
  return report_text::json_number(v);
}

json fit_json(const FitFigures& f) {
  json j = {{"samples", f.samples},
            {"rms_unaligned_mm", num(f.rms_unaligned_mm)},
            {"rms_before_mm", num(f.rms_before_mm)},
            {"rms_after_mm", num(f.rms_after_mm)},
            {"max_before_mm", num(f.max_before_mm)},
            {"max_after_mm", num(f.max_after_mm)},
            {"improvement",
             f.rms_before_mm > 0 ? num(1 - f.rms_after_mm / f.rms_before_mm) : json(nullptr)}};
  json axes = json::object();
  for (const auto& [a, v] : f.per_axis_rms_mm) {
    axes[a] = {{"rms_before_mm", num(v.first)}, {"rms_after_mm", num(v.second)}};
    if (const auto u = f.per_axis_unaligned_rms_mm.find(a); u != f.per_axis_unaligned_rms_mm.end())
      axes[a]["rms_unaligned_mm"] = num(u->second);
  }
  j["per_axis"] = axes;
  return j;
}

}  // namespace

std::string diagnosis_json(const DiagnosisResult& r) {
  json j;
  j["truecut_diagnosis"] = 1;
  j["mode"] = "trace";
  j["recording"] = r.recording;
  j["holdout_recording"] = r.holdout_recording.empty() ? json(nullptr) : json(r.holdout_recording);
  j["map"] = r.map;
  j["rows"] = r.rows;
  j["excluded_samples"] = r.excluded_samples;
  j["glitch_rows"] = json::array();
  for (const auto& g : r.glitch_rows)
    j["glitch_rows"].push_back(
        {{"row", g.row}, {"column", g.column}, {"deviation_mm", num(g.deviation_mm)}});
  j["sample_period_s"] = num(r.sample_period_s);
  j["substeps"] = r.substeps;
  j["delay_s"] = num(r.delay_s);
  j["delay_ci95_s"] = r.delay_ci95_s
                          ? json::array({num(r.delay_ci95_s->first), num(r.delay_ci95_s->second)})
                          : json(nullptr);
  j["delay_note"] = r.delay_note;
  j["noise_floor_mm"] = num(r.noise_floor_mm);
  j["axes"] = json::array();
  for (const auto& a : r.axes)
    j["axes"].push_back({{"axis", a.axis},
                         {"target", a.target},
                         {"samples", a.samples},
                         {"rms_mm", num(a.rms_mm)},
                         {"max_mm", num(a.max_mm)},
                         {"mean_mm", num(a.mean_mm)},
                         {"noise_floor_mm", num(a.noise_floor_mm)},
                         {"resolution_mm", num(a.resolution_mm)},
                         {"interpolation_mm", num(a.interpolation_mm)},
                         {"standstill_noise_mm",
                          a.standstill_noise_mm ? num(*a.standstill_noise_mm) : json(nullptr)},
                         {"offset_mm", num(a.offset_mm)}});
  j["mismatch"] = json::array();
  for (const auto& m : r.mismatch)
    j["mismatch"].push_back({{"axis", m.axis},
                             {"where", m.where},
                             {"what", m.what},
                             {"samples", m.samples},
                             {"rms_mm", num(m.rms_mm)},
                             {"max_mm", num(m.max_mm)},
                             {"mean_mm", num(m.mean_mm)},
                             {"ratio_to_floor", num(m.ratio_to_floor)}});
  j["explanations"] = json::array();
  for (const auto& e : r.explanations) {
    json params = json::object(), ci = json::object(), fixed = json::array(),
         undetermined = json::object();
    for (const auto& p : e.parameters) {
      params[p.name] = num(p.value);
      ci[p.name] = json::array({num(p.ci95_lo), num(p.ci95_hi)});
      if (p.fixed) fixed.push_back(p.name);
    }
    for (const auto& p : e.undetermined)
      undetermined[p.name] = {{"value", num(p.value)},
                              {"ci95", json::array({num(p.ci95_lo), num(p.ci95_hi)})}};
    j["explanations"].push_back(
        {{"effect", e.effect},
         {"axis", e.axis},
         {"parameters", params},
         {"ci95", ci},
         {"fixed", fixed},
         {"undetermined", undetermined},
         {"score", {{"delta_bic", num(e.delta_bic)}, {"rms_effect_mm", num(e.rms_effect_mm)}}},
         {"note", e.note}});
  }
  j["not_identifiable"] = json::array();
  for (const auto& n : r.not_identifiable)
    j["not_identifiable"].push_back({{"first", n.first},
                                     {"second", n.second},
                                     {"correlation", num(n.correlation)},
                                     {"separate_by", n.separate_by}});
  j["not_confirmed"] = json::array();
  for (const auto& n : r.not_confirmed)
    j["not_confirmed"].push_back({{"effect", n.effect},
                                  {"axis", n.axis},
                                  {"heldout_rms_with_mm", num(n.heldout_rms_with_mm)},
                                  {"heldout_rms_without_mm", num(n.heldout_rms_without_mm)}});
  j["candidates_tested"] = r.candidates_tested;
  j["fit"]["train"] = fit_json(r.train);
  j["fit"]["heldout"] = r.has_heldout ? fit_json(r.heldout) : json(nullptr);
  if (r.has_heldout) j["fit"]["heldout"]["kind"] = r.heldout_kind;
  if (r.tcp.present) {
    const auto& t = r.tcp;
    j["tcp"] = {{"target", "tcp_true_x/y/z"},
                {"datum", t.datum_known ? "known" : "free"},
                {"offset_mm", {num(t.offset_mm[0]), num(t.offset_mm[1]), num(t.offset_mm[2])}},
                {"noise_floor_mm",
                 {num(t.noise_floor_mm[0]), num(t.noise_floor_mm[1]), num(t.noise_floor_mm[2])}},
                {"train", fit_json(t.train)},
                {"heldout", t.heldout.samples ? fit_json(t.heldout) : json(nullptr)}};
  } else {
    j["tcp"] = nullptr;
  }
  json ac = json::array();
  for (double v : r.whiteness.autocorrelation)
    ac.push_back(num(v));
  j["whiteness"] = {{"test", "ljung-box"},
                    {"lags", r.whiteness.lags},
                    {"autocorrelation", ac},
                    {"q", num(r.whiteness.ljung_box_q)},
                    {"p_value", num(r.whiteness.p_value)},
                    {"white", r.whiteness.white}};
  j["notes"] = r.notes;
  j["verdict"] = r.verdict;
  return report_text::json_text(j);
}

// "glitch rows: 2 (row 313 x_cmd, ...), left out" or nothing; rows of the
// recording, 0 = the first data row.
std::string glitch_rows_text(const DiagnosisResult& r) {
  if (r.glitch_rows.empty()) return "";
  std::string s = "glitch rows (isolated samples off their neighbours, left out): " +
                  std::to_string(r.glitch_rows.size()) + " (";
  for (std::size_t i = 0; i < r.glitch_rows.size() && i < 20; ++i)
    s += (i ? ", " : "") + std::string("row ") + std::to_string(r.glitch_rows[i].row) + " " +
         r.glitch_rows[i].column + " " + rt::format_printf("%.4g", r.glitch_rows[i].deviation_mm) +
         " mm";
  if (r.glitch_rows.size() > 20) s += ", …";
  return s + ")\n";
}

std::string diagnosis_summary(const DiagnosisResult& r) {
  std::string s = "recording " + r.recording + ": " + std::to_string(r.rows) + " samples every " +
                  rt::format_printf("%.4g", r.sample_period_s * 1e3) + " ms\n";
  s += glitch_rows_text(r);
  s += "logging delay: " + rt::format_printf("%.4g", r.delay_s * 1e3) + " ms";
  if (r.delay_ci95_s)
    s += " (95 % " + rt::format_printf("%.4g", r.delay_ci95_s->first * 1e3) + " .. " +
         rt::format_printf("%.4g", r.delay_ci95_s->second * 1e3) + " ms)";
  s += "\n";
  if (!r.delay_note.empty()) s += "  " + r.delay_note + "\n";
  for (const auto& a : r.axes)
    s += "  " + a.target + ": rms " + rt::format_printf("%.4g", a.rms_mm * 1e3) + " µm, max " +
         rt::format_printf("%.4g", a.max_mm * 1e3) + " µm, noise floor " +
         rt::format_printf("%.4g", a.noise_floor_mm * 1e3) + " µm" +
         (a.resolution_mm > 0
              ? ", recorded in steps of " + rt::format_printf("%.4g", a.resolution_mm * 1e3) + " µm"
              : "") +
         (a.interpolation_mm > 0 ? ", re-simulation between samples uncertain by " +
                                       rt::format_printf("%.4g", a.interpolation_mm * 1e3) + " µm"
                                 : "") +
         "\n";
  if (!r.mismatch.empty()) {
    s += "above the noise floor:\n";
    for (std::size_t i = 0; i < r.mismatch.size() && i < 8; ++i) {
      const auto& m = r.mismatch[i];
      s += "  " + m.axis + " " + m.what + ": rms " + rt::format_printf("%.4g", m.rms_mm * 1e3) +
           " µm (" + rt::format_printf("%.3g", m.ratio_to_floor) + "× floor)\n";
    }
  }
  for (const auto& e : r.explanations) {
    s += "explained: " + e.effect + (e.axis.empty() ? "" : " " + e.axis) + ":";
    for (const auto& p : e.parameters)
      s += " " + p.name + "=" + rt::format_printf("%.4g", p.value) +
           (p.fixed ? ""
                    : " [" + rt::format_printf("%.4g", p.ci95_lo) + ", " +
                          rt::format_printf("%.4g", p.ci95_hi) + "]");
    for (const auto& p : e.undetermined)
      s += " " + p.name + " not determined (" + rt::format_printf("%.4g", p.value) + ", 95 % " +
           rt::format_printf("%.4g", p.ci95_lo) + " .. " + rt::format_printf("%.4g", p.ci95_hi) +
           ")";
    s += " (ΔBIC " + rt::format_printf("%.1f", e.delta_bic) + ")\n";
  }
  for (const auto& n : r.not_identifiable)
    s += "not identifiable: " + n.first + " vs " + n.second + " — " + n.separate_by + "\n";
  for (const auto& n : r.not_confirmed)
    s += "not confirmed on the held-out data (left out): " + n.effect +
         (n.axis.empty() ? "" : " " + n.axis) + ", held-out rms " +
         rt::format_printf("%.4g", n.heldout_rms_with_mm * 1e3) + " µm with it, " +
         rt::format_printf("%.4g", n.heldout_rms_without_mm * 1e3) + " µm without\n";
  s += "fit: rms " + rt::format_printf("%.4g", r.train.rms_unaligned_mm * 1e3) +
       " (delay not removed) → " + rt::format_printf("%.4g", r.train.rms_before_mm * 1e3) + " → " +
       rt::format_printf("%.4g", r.train.rms_after_mm * 1e3) + " µm (fitted data)";
  if (r.has_heldout)
    s += ", " + rt::format_printf("%.4g", r.heldout.rms_unaligned_mm * 1e3) + " → " +
         rt::format_printf("%.4g", r.heldout.rms_before_mm * 1e3) + " → " +
         rt::format_printf("%.4g", r.heldout.rms_after_mm * 1e3) + " µm (held out, " +
         r.heldout_kind + ")";
  if (r.tcp.present) {
    s += "\ntcp (" + std::string(r.tcp.datum_known ? "known datum" : "offset profiled out") +
         "): rms " + rt::format_printf("%.4g", r.tcp.train.rms_before_mm * 1e3) + " → " +
         rt::format_printf("%.4g", r.tcp.train.rms_after_mm * 1e3) + " µm (fitted data)";
    if (r.tcp.heldout.samples)
      s += ", " + rt::format_printf("%.4g", r.tcp.heldout.rms_before_mm * 1e3) + " → " +
           rt::format_printf("%.4g", r.tcp.heldout.rms_after_mm * 1e3) + " µm (held out)";
  }
  s += "\nwhiteness: Ljung–Box Q=" + rt::format_printf("%.1f", r.whiteness.ljung_box_q) +
       " p=" + rt::format_printf("%.3g", r.whiteness.p_value) +
       (r.whiteness.white ? " (white)" : " (not white)") + "\n";
  for (const auto& n : r.notes)
    s += "note: " + n + "\n";
  s += "verdict: " + r.verdict + "\n";
  return s;
}

}  // namespace truecut::analysis::diagnosis
