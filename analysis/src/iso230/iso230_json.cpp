// iso230.json: lengths carry _mm (x y z) or _deg (a c) in their key.
#include <nlohmann/json.hpp>

#include "diagnosis/report_text.hpp"
#include "truecut/analysis/iso230_report.hpp"

namespace truecut::analysis {
namespace {

using nlohmann::ordered_json;

ordered_json opt(const std::optional<double>& v) {
  return v ? ordered_json(*v) : ordered_json(nullptr);
}

ordered_json direction(const DirectionStats& d, const std::string& u) {
  return {{"runs", d.runs()},
          {"deviations" + u, d.deviations},
          {"mean" + u, d.mean},
          {"s" + u, d.s},
          {"R" + u, d.R}};
}

ordered_json axis_json(const AxisPositioning& a) {
  const std::string u = a.rotary ? "_deg" : "_mm";
  ordered_json j;
  j["axis"] = a.joint;
  j["unit"] = a.rotary ? "deg" : "mm";
  j["measured"] = a.measured_channel;
  j["readings"] = a.readings;
  j["bidirectional"] = a.A.has_value();
  j["A" + u] = opt(a.A);
  j["E" + u] = opt(a.E);
  j["M" + u] = opt(a.M);
  j["R" + u] = opt(a.R);
  j["B" + u] = opt(a.B);
  j["B_mean" + u] = opt(a.B_mean);
  for (const auto& [name, d] : {std::pair{"up", a.up}, std::pair{"down", a.down}}) {
    j["A_" + std::string(name) + u] = d ? ordered_json(d->A) : ordered_json(nullptr);
    j["E_" + std::string(name) + u] = d ? ordered_json(d->E) : ordered_json(nullptr);
    j["R_" + std::string(name) + u] = d ? ordered_json(d->R) : ordered_json(nullptr);
  }
  ordered_json positions = ordered_json::array();
  for (const auto& t : a.targets) {
    ordered_json p;
    p["target" + u] = t.target;
    p["up"] = t.up ? direction(*t.up, u) : ordered_json(nullptr);
    p["down"] = t.down ? direction(*t.down, u) : ordered_json(nullptr);
    p["mean" + u] = opt(t.mean_bidirectional);
    p["B" + u] = opt(t.B);
    p["R" + u] = opt(t.R);
    positions.push_back(p);
  }
  j["positions"] = positions;
  j["notes"] = a.notes;
  return j;
}

ordered_json harmonics_json(const std::vector<Harmonic>& hs) {
  ordered_json out = ordered_json::array();
  for (const auto& h : hs)
    out.push_back({{"order", h.order},
                   {"amplitude_mm", h.amplitude_mm},
                   {"phase_deg", h.phase_deg},
                   {"cos_mm", h.cos_mm},
                   {"sin_mm", h.sin_mm}});
  return out;
}

ordered_json circle_json(const CircularTest& c) {
  ordered_json j;
  j["axes"] = {c.axis_p, c.axis_q};
  j["measured"] = {c.measured_p, c.measured_q};
  j["nominal"] = {{"centre_mm", {c.nominal_centre_p_mm, c.nominal_centre_q_mm}},
                  {"radius_mm", c.nominal_radius_mm}};
  j["G_mm"] = c.G_mm;
  j["H_mm"] = opt(c.H_mm);
  j["F_mm"] = c.F_mm;
  j["F_max_mm"] = c.F_max_mm;
  j["F_min_mm"] = c.F_min_mm;
  ordered_json runs = ordered_json::array();
  for (const auto& r : c.runs) {
    ordered_json rev = ordered_json::array();
    for (const auto& f : r.reversals)
      rev.push_back({{"angle_deg", f.angle_deg},
                     {"axis", f.reversing_axis},
                     {"spike_mm", f.spike_mm},
                     {"step_mm", f.step_mm}});
    runs.push_back({{"direction", r.direction},
                    {"samples", r.samples},
                    {"swept_deg", r.swept_deg},
                    {"feed_mm_per_s", r.feed_mm_per_s},
                    {"centre_mm", {r.centre_p_mm, r.centre_q_mm}},
                    {"fitted_radius_mm", r.fitted_radius_mm},
                    {"G_mm", r.G_mm},
                    {"F_max_mm", r.F_max_mm},
                    {"F_min_mm", r.F_min_mm},
                    {"noise_mm", r.noise_mm},
                    {"harmonics", harmonics_json(r.harmonics)},
                    {"reversals", rev}});
  }
  j["runs"] = runs;
  j["harmonics"] = harmonics_json(c.harmonics);
  ordered_json hints = ordered_json::array();
  for (const auto& h : c.hints)
    hints.push_back({{"effect", h.effect},
                     {"axis", h.axis.empty() ? ordered_json(nullptr) : ordered_json(h.axis)},
                     {"value", h.value},
                     {"unit", h.unit},
                     {"text", h.text}});
  j["hints"] = hints;
  j["notes"] = c.notes;
  return j;
}

}  // namespace

std::string iso230_json(const Iso230Report& r) {
  ordered_json j;
  j["format"] = "truecut-iso230";
  j["version"] = 1;
  j["recording"] = r.recording;
  j["rows"] = r.rows;
  j["map"] = r.map.empty() ? ordered_json(nullptr) : ordered_json(r.map);
  j["standstill"] = {{"velocity_threshold_per_s", r.standstill.velocity_threshold},
                     {"min_dwell_s", r.standstill.min_dwell_s},
                     {"target_tolerance", r.standstill.target_tolerance},
                     {"settle_fraction", r.standstill.settle_fraction},
                     {"min_runs", r.standstill.min_runs}};
  j["axes"] = ordered_json::array();
  for (const auto& a : r.axes)
    j["axes"].push_back(axis_json(a));
  j["skipped_axes"] = ordered_json::array();
  for (const auto& s : r.skipped)
    j["skipped_axes"].push_back({{"axis", s.axis}, {"reason", s.reason}});
  j["circles"] = ordered_json::array();
  for (const auto& c : r.circles)
    j["circles"].push_back(circle_json(c));
  return report_text::json_text(j);
}

}  // namespace truecut::analysis
