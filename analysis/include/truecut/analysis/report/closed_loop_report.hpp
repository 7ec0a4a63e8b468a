// The closed-loop demo's self-contained HTML report (one file, no network):
// per part, deviation colour maps of the machined surface for every stage,
// relative-frequency histograms of the CMM deviations, per-surface tables
// against the tolerance, a slice of the correction field and the audit
// record. Every figure comes from the files the demo's steps wrote.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "truecut/sim/measure/cmm.hpp"

namespace truecut::analysis::report {

struct ReportSurface {
  int id = 0;
  std::string name;
  bool compensate = false;
};

struct ReportStage {
  std::string key;    // uncompensated, realtime, rewrite, realtime_2
  std::string title;  // for people
  std::filesystem::path machined_stl;
  std::vector<sim::measure::CmmMeasurement> cmm;
};

struct ReportPart {
  std::string name;
  std::filesystem::path nominal_stl;
  std::vector<int> triangle_surface_ids;  // per nominal triangle
  std::vector<ReportSurface> surfaces;
  std::vector<ReportStage> stages;  // the first is the reference (uncompensated)
  std::filesystem::path field_tcf;  // the first iteration's field
  std::string audit_json;           // its audit record
  std::string commands;             // the steps, as a shell script
};

struct ReportOptions {
  std::string title = "truecut closed-loop demo";
  double tolerance_um = 20.0;  // drawn on histograms and colour bars
  double scanner_sigma_um = 20.0;
};

// The HTML text. Throws when a machined mesh or the field cannot be read.
std::string closed_loop_html(const std::vector<ReportPart>& parts, const ReportOptions& options);

// Per-surface deviation statistics of the judged surfaces plus "all judged".
std::vector<sim::measure::SurfaceDeviationStats> judged_statistics(
    const std::vector<sim::measure::CmmMeasurement>& cmm,
    const std::vector<ReportSurface>& surfaces);

}  // namespace truecut::analysis::report
