// truecut iso230 --recording REC.csv --out DIR: ISO 230-2 positioning and
// ISO 230-4 circular-test evaluations of a recording (docs/iso230.md).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "measure_options.hpp"
#include "quiet_option.hpp"
#include "truecut/analysis/iso230_report.hpp"
#include "truecut/analysis/recording.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;
using analysis::RecordingError;

const char* kIso230Help =
    "usage: truecut iso230 --recording REC.csv --out DIR [options]\n"
    "\n"
    "Evaluates a recording (docs/formats.md, \"Trace CSV\") by ISO 230-2 (positioning:\n"
    "A, E, M, R, B per axis, targets and approach directions found from standstill\n"
    "windows) and ISO 230-4 (circular test: G, H, F, harmonics and interpretation\n"
    "hints). Deviation = <j>_meas (else <j>_act) - <j>_cmd. Writes DIR/iso230.json and\n"
    "DIR/iso230.html, each atomically; on bad input (exit 2) nothing is written.\n"
    "An EPICS camonitor log (PV DATE TIME VALUE lines) is read as well; map its PVs,\n"
    "e.g. --map x_cmd=IOC:M1-PosSet,x_act=IOC:M1-PosAct. The command may be a target\n"
    "setpoint (jumping to the next target) or a trajectory setpoint: readings start\n"
    "where the measured position comes to rest.\n"
    "\n"
    "options:\n"
    "  --recording FILE          the recording CSV or camonitor log (required)\n"
    "  --out DIR                 output folder (created; required)\n"
    "  --map NAME=SOURCE,...     column map for foreign files (repeatable), e.g.\n"
    "                            x_cmd=X1_CommandPosition,x_act=X1_ActualPosition,t=@index*0.1\n"
    "  --axis J,J                ISO 230-2 on these joints (x y z a c); default: every\n"
    "                            joint with a _cmd and an _act or _meas column, unless\n"
    "                            --circle is given\n"
    "  --circle P,Q              ISO 230-4 circle in the P-Q plane (repeatable)\n"
    "  --radius MM               nominal radius (default: fitted to the commanded circle)\n"
    "  --velocity-threshold V    standstill below V mm/s or deg/s (default 0.01)\n"
    "  --min-dwell S             shortest standstill that is a reading, s (default 0.5)\n"
    "  --target-tol T            commanded positions closer than T are one target (default 0.001)\n"
    "  --min-runs N              approaches per target and direction (default 2)\n"
    "  --quiet                   nothing on stderr but warnings and errors\n"
    "                            (progress is shown on a terminal only)\n"
    "  --help                    this text\n";

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s + ",") {
    if (c == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur += c;
    }
  }
  return out;
}

std::string joint_arg(const std::string& j, const char* option) {
  for (const char* k : analysis::kRecordingJoints)
    if (j == k) return j;
  throw UsageError(std::string(option) + ": '" + j + "' is not a joint (x y z a c)");
}

std::string columns_of(const analysis::Recording& rec) {
  std::string s;
  for (const auto& c : rec.columns)
    s += (s.empty() ? "" : ", ") + c;
  return s;
}

std::string mm(const std::optional<double>& v) {
  if (!v) return "-";
  return rt::format_printf("%.4f", *v);
}

}  // namespace

int cmd_iso230(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"recording", true},
                      {"out", true},
                      {"map", true, true},
                      {"axis", true},
                      {"circle", true, true},
                      {"radius", true},
                      {"velocity-threshold", true},
                      {"min-dwell", true},
                      {"target-tol", true},
                      {"min-runs", true},
                      kQuietOption,
                      {"help", false}});
  if (a.flag("help")) {
    std::fputs(kIso230Help, stdout);
    return kExitOk;
  }
  if (!a.positionals().empty())
    throw UsageError("unexpected argument '" + a.positionals()[0] + "'");
  const auto recording = a.value("recording");
  if (!recording) throw UsageError("--recording FILE is required");
  const auto out_dir = a.value("out");
  if (!out_dir) throw UsageError("--out DIR is required");

  analysis::StandstillOptions standstill;
  standstill.velocity_threshold =
      a.number("velocity-threshold", standstill.velocity_threshold, 1e-12, 1e9);
  standstill.min_dwell_s = a.number("min-dwell", standstill.min_dwell_s, 0, 1e6);
  standstill.target_tolerance = a.number("target-tol", standstill.target_tolerance, 0, 1e6);
  standstill.min_runs = int(a.integer("min-runs", standstill.min_runs, 1, 1000));

  std::vector<std::string> axes;
  if (auto list = a.value("axis"))
    for (const auto& j : split_list(*list)) {
      if (std::find(axes.begin(), axes.end(), j) != axes.end())
        throw UsageError("--axis " + *list + ": joint '" + j + "' is named twice");
      axes.push_back(joint_arg(j, "--axis"));
    }
  std::vector<analysis::CircleOptions> circles;
  for (const auto& spec : a.values("circle")) {
    const auto pq = split_list(spec);
    if (pq.size() != 2 || pq[0] == pq[1])
      throw UsageError("--circle " + spec + ": expected two different joints, e.g. --circle x,y");
    analysis::CircleOptions c;
    c.axis_p = joint_arg(pq[0], "--circle");
    c.axis_q = joint_arg(pq[1], "--circle");
    if (a.value("radius")) c.radius_mm = a.number("radius", 0, 1e-9, 1e9);
    circles.push_back(c);
  }
  if (a.value("radius") && circles.empty()) throw UsageError("--radius needs --circle P,Q");

  for (const char* name : {"iso230.json", "iso230.html"})
    refuse_output_over_input("out", (fs::path(*out_dir) / name).string(), {recording});
  require_writable_folder("out", *out_dir);

  std::string map_text;
  for (const auto& m : a.values("map"))
    map_text += (map_text.empty() ? "" : ",") + m;

  analysis::Iso230Report report;
  report.recording = *recording;
  report.map = map_text;
  report.standstill = standstill;
  try {
    analysis::RecordingOptions options;
    options.map = analysis::parse_column_map(map_text);
    for (const auto& j : axes)
      options.required.push_back(j + "_cmd");
    for (const auto& c : circles)
      for (const auto& j : {c.axis_p, c.axis_q})
        options.required.push_back(j + "_cmd");
    const auto rec = analysis::is_camonitor_log(*recording)
                         ? analysis::read_camonitor(*recording, options)
                         : analysis::read_recording(*recording, options);
    report.rows = rec.rows();
    auto need_measured = [&](const std::string& j) {
      if (!rec.measured(j))
        throw RecordingError(rec.file + ": no column for '" + j + "_act' or '" + j +
                             "_meas' (map one with --map " + j +
                             "_act=COLUMN); available: " + columns_of(rec));
    };
    const bool automatic = axes.empty() && circles.empty();
    if (automatic)
      for (const char* j : analysis::kRecordingJoints)
        if (rec.has(std::string(j) + "_cmd") && rec.measured(j)) axes.push_back(j);
    for (const auto& j : axes) {
      need_measured(j);
      auto result = analysis::evaluate_positioning(rec, j, standstill);
      if (result) {
        report.axes.push_back(std::move(*result));
        continue;
      }
      const std::string reason =
          "no target approached at least " + std::to_string(standstill.min_runs) +
          " times from one direction with a standstill of at least " + mm(standstill.min_dwell_s) +
          " s below " + mm(standstill.velocity_threshold) + "/s";
      if (!automatic) throw RecordingError(rec.file + ": axis " + j + ": " + reason);
      report.skipped.push_back({j, reason});
    }
    for (const auto& c : circles) {
      need_measured(c.axis_p);
      need_measured(c.axis_q);
      report.circles.push_back(analysis::evaluate_circle(rec, c));
    }
    if (report.axes.empty() && report.circles.empty())
      throw RecordingError(rec.file + ": nothing to evaluate: " +
                           (report.skipped.empty()
                                ? std::string("no joint has a _cmd and an _act or _meas column")
                                : report.skipped[0].axis + ": " + report.skipped[0].reason) +
                           " (use --map, --axis or --circle)");
  } catch (const RecordingError& e) {
    std::fprintf(stderr, "truecut iso230: %s\n", e.what());
    return kExitUsage;
  }

  const fs::path dir(*out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir.string() + ": " + ec.message());
  rt::write_files_atomically({{dir / "iso230.json", analysis::iso230_json(report)},
                              {dir / "iso230.html", analysis::iso230_html(report)}});

  for (const auto& ax : report.axes) {
    const char* u = ax.rotary ? "deg" : "mm";
    std::printf("%s: A=%s E=%s M=%s R=%s B=%s %s (%zu targets)\n", ax.joint.c_str(),
                mm(ax.A).c_str(), mm(ax.E).c_str(), mm(ax.M).c_str(), mm(ax.R).c_str(),
                mm(ax.B).c_str(), u, ax.targets.size());
  }
  for (const auto& c : report.circles) {
    std::printf("%s%s circle: G=%s H=%s F=%s mm\n", c.axis_p.c_str(), c.axis_q.c_str(),
                mm(c.G_mm).c_str(), mm(c.H_mm).c_str(), mm(c.F_mm).c_str());
    // A G over less than a full circle is not ISO 230-4's: said where it is read.
    for (const auto& note : c.notes) {
      std::printf("  note: %s\n", note.c_str());
      std::fprintf(stderr, "truecut iso230: WARNING: %s%s circle: %s\n", c.axis_p.c_str(),
                   c.axis_q.c_str(), note.c_str());
    }
  }
  std::printf("wrote %s and %s\n", (dir / "iso230.json").c_str(), (dir / "iso230.html").c_str());
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{
    "iso230", "ISO 230-2 positioning and ISO 230-4 circular test from a recording", cmd_iso230, 80};
}  // namespace

}  // namespace truecut::cli
