// truecut diagnose --recording REC.csv --out DIR: what the machine does that
// the believed model does not (trace mode), and --surface / --cmm with the
// program that machined the part (surface mode); docs/diagnosis.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "measure_options.hpp"
#include "quiet_option.hpp"
#include "run_support.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"
#include "truecut/analysis/diagnosis/surface.hpp"
#include "truecut/analysis/recording.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/tool_table.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/input_file.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/measure/part_surfaces.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;
namespace dg = analysis::diagnosis;

const char* kDiagnoseHelp =
    "usage: truecut diagnose --recording REC.csv --out DIR [options]\n"
    "       truecut diagnose (--surface SCAN.{stl,ply,xyz} | --cmm CMM.csv) --program P.ngc\n"
    "                        --machine BELIEVED.json --out DIR [options]\n"
    "\n"
    "Re-simulates the recorded commands through the believed machine model, removes\n"
    "a logging delay, locates where the recording differs (above the noise floor),\n"
    "names the missing effects of the machine description (servo_lag, backlash,\n"
    "reversal_spike, pitch_error, thermal_drift, squareness, straightness; with a\n"
    "measured TCP rotary_location and tool_length_error), fits their parameters\n"
    "with 95 % intervals and shows the fit on held-out data. Target per joint:\n"
    "<j>_meas when present, else <j>_act. Writes DIR/diagnosis.json,\n"
    "DIR/fitted_machine.json and DIR/diagnosis.html, each atomically; on bad input\n"
    "(exit 2) nothing is written.\n"
    "\n"
    "options:\n"
    "  --recording FILE        the recording CSV (required)\n"
    "  --out DIR               output folder (created; required)\n"
    "  --map NAME=SOURCE,...   column map for foreign files (repeatable; also used for\n"
    "                          --holdout), e.g. t=@index*0.1,x_cmd=X1_CommandPosition\n"
    "  --machine FILE          believed machine description (default: the ideal\n"
    "                          machine, actual = commanded)\n"
    "  --holdout FILE          a second recording to prove the fit on\n"
    "  --split F               hold out the last fraction F of the recording (default\n"
    "                          0.3 without --holdout; 0: none)\n"
    "  --servo-period S        longest simulated servo period (default 0.001): each\n"
    "                          recorded interval is split into equal sub-steps\n"
    "  --max-servo-periods N   budget: refuse (exit 2) a recording whose re-simulation\n"
    "                          at --servo-period takes more than N servo periods per\n"
    "                          run (default 10000000: 2.8 h of recording at 1 ms)\n"
    "  --command-interpolation cubic|linear\n"
    "                          the command between recorded samples (default cubic:\n"
    "                          monotone, exact for constant accelerations)\n"
    "  --max-delay S           largest logging delay searched (default: 10 samples or\n"
    "                          50 ms, whichever is longer)\n"
    "  --bic-threshold D       BIC gain needed to select an effect (default 10)\n"
    "  --min-effect R          smallest effect selected, RMS over the fitted block in\n"
    "                          units of the noise floor (default 0.1)\n"
    "  --tcp-datum free|known  with tcp_true_x/y/z (a measured tool-centre point): free\n"
    "                          (default) profiles out its constant offset, known takes\n"
    "                          it as absolute in the workpiece frame (rotary_location,\n"
    "                          tool_length_error become candidates)\n"
    "  --tools FILE            tool table (LinuxCNC format): the nominal tool length per\n"
    "                          the recording's `tool` channel, for the TCP comparison\n"
    "                          (default: the description's kinematics.tool)\n"
    "\n"
    "surface mode: re-machines PROGRAM on the believed machine, profiles out the\n"
    "registration, and explains the residual by tool_radius_error, tool_length_error,\n"
    "rotary_location (when the program turns A or C), tool_deflection,\n"
    "workpiece_deflection and squareness (one re-machining per parameter).\n"
    "  --surface FILE          a scan (STL/PLY mesh, PLY/XYZ points), registered by ICP\n"
    "  --cmm FILE              CMM CSV with deviations (as `truecut cmm` writes it)\n"
    "  --program FILE          the program that machined the part (required)\n"
    "  --nominal/--part/--tools  default: beside the program\n"
    "  --split F               held-out region: the last fraction F along the part's\n"
    "                          longest extent (default 0.3)\n"
    "  --candidates LIST       comma-separated effects to test (default: all)\n"
    "  --spacing MM            scan: nominal point spacing (default 0.5)\n"
    "  --work DIR              re-machinings are kept in DIR/runs/ and reused from there\n"
    "                          (default: the --out DIR, so DIR/runs/); on bad input the\n"
    "                          runs this diagnosis made are removed\n"
    "  --component-path DIR    also search DIR for components\n"
    "  --quiet                 nothing on stderr but warnings and errors\n"
    "                          (progress is shown on a terminal only)\n"
    "  --help                  this text\n";

// Input that cannot be diagnosed: the message, exit 2.
// Refuses (UsageError) a recording whose re-simulation would exceed the budget.
void check_servo_budget(const analysis::Recording& rec, double period_s, double budget) {
  const double periods = dg::servo_periods_per_run(rec, period_s);
  if (!(periods > budget)) return;
  const double seconds = rec.rows() > 1 ? rec.t_s.back() - rec.t_s.front() : 0.0;
  throw UsageError(rt::format_printf(
      "%s: re-simulating its %.6g s at --servo-period %g s takes %.3g servo periods per run, more "
      "than --max-servo-periods %.6g (the fit runs each joint hundreds of times); give a longer "
      "--servo-period (default 0.001) or raise --max-servo-periods",
      rec.file.c_str(), seconds, period_s, periods, budget));
}

int bad_input(const std::exception& e) {
  std::fprintf(stderr, "truecut diagnose: %s\n", e.what());
  return kExitUsage;
}

// The three outputs, atomically, then the summary on stdout.
void write_outputs(const std::string& out_dir, const std::string& json,
                   const sim::MachineDescription& fitted, const std::string& html,
                   const std::string& summary) {
  const fs::path dir(out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir.string() + ": " + ec.message());
  rt::write_files_atomically(
      {{dir / "diagnosis.json", json},
       {dir / "fitted_machine.json", sim::format_machine_description(fitted)},
       {dir / "diagnosis.html", html}});
  std::fputs(summary.c_str(), stdout);
  std::printf("wrote %s, %s and %s\n", (dir / "diagnosis.json").c_str(),
              (dir / "fitted_machine.json").c_str(), (dir / "diagnosis.html").c_str());
}

// An input file of surface mode, checked as every reader checks it (a
// regular file within the input budget); a default beside the program names
// the option that gives another.
fs::path existing(const std::optional<std::string>& given, const fs::path& beside, const char* name,
                  const char* what, const char* option) {
  const fs::path p = given ? fs::path(*given) : beside / name;
  try {
    rt::check_input_file(p, what);
  } catch (const rt::InputFileError& e) {
    throw UsageError(std::string(e.what()) +
                     (given ? std::string() : std::string(" (give ") + option + ")"));
  }
  return p;
}

const char* const kOutputFiles[] = {"diagnosis.json", "fitted_machine.json", "diagnosis.html"};

// Every file written into --out DIR against every input (links included):
// `--machine DIR/fitted_machine.json --out DIR`, the natural next
// iteration, replaced the believed model.
void refuse_outputs_over_inputs(const ParsedArgs& a, const std::string& out_dir,
                                const std::vector<std::optional<std::string>>& extra = {}) {
  std::vector<std::optional<std::string>> inputs = extra;
  for (const char* option :
       {"recording", "holdout", "machine", "tools", "surface", "cmm", "program", "nominal", "part"})
    inputs.push_back(a.value(option));
  for (const char* name : kOutputFiles)
    refuse_output_over_input("out", (fs::path(out_dir) / name).string(), inputs);
}

// "tool_radius_error, tool_length_error, ...": what --candidates may name.
std::string known_candidates() {
  std::string names;
  for (const auto& k : dg::surface_candidate_effects())
    names += (names.empty() ? "" : ", ") + k;
  return names;
}

// --candidates LIST, each a surface-mode effect.
std::vector<std::string> candidate_list(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : text + ",") {
    if (ch != ',') {
      cur += ch;
    } else if (!cur.empty()) {
      out.push_back(cur);
      cur.clear();
    }
  }
  const auto& known = dg::surface_candidate_effects();
  for (const auto& c : out)
    if (std::find(known.begin(), known.end(), c) == known.end())
      throw UsageError("--candidates: '" + c +
                       "' is not a surface-mode effect; known: " + known_candidates());
  if (out.empty())
    throw UsageError("--candidates '" + text + "': no effect named; known: " + known_candidates());
  return out;
}

// With --tools: every value of the recording's `tool` channel is a whole
// number the table has (99 or 2.5 used to pass, and such rows got no length).
void check_tool_channel(const analysis::Recording& rec, const std::map<int, double>& table,
                        const std::string& table_file) {
  const auto it = rec.channels.find("tool");
  if (it == rec.channels.end()) return;
  std::string known;
  for (const auto& [tool, length] : table)
    known += (known.empty() ? "" : ", ") + std::to_string(tool);
  for (std::size_t k = 0; k < it->second.size(); ++k) {
    const double v = it->second[k];
    const std::string at = rec.file + ": sample " + std::to_string(k + 1) +
                           " (t = " + rt::format_shortest(rec.t_s[k]) + " s): tool " +
                           rt::format_shortest(v);
    if (v != std::floor(v)) throw dg::DiagnosisError(at + " is not a whole tool number");
    if (!table.count(static_cast<int>(v)))
      throw dg::DiagnosisError(at + " is not in the tool table " + table_file + " (tools " +
                               (known.empty() ? std::string("none") : known) + ")");
  }
}

int surface_mode(const ParsedArgs& a, const std::string& out_dir) {
  const auto program = a.value("program");
  if (!program) throw UsageError("surface mode needs --program FILE.ngc");
  if (!a.value("machine")) throw UsageError("surface mode needs --machine BELIEVED.json");
  if (a.value("holdout")) throw UsageError("surface mode: use --split (a held-out region)");
  dg::SurfaceJob job;
  job.program = existing(program, ".", "", "G-code program", "--program");
  const fs::path beside = job.program.has_parent_path() ? job.program.parent_path() : ".";
  job.nominal = existing(a.value("nominal"), beside, "nominal.stl", "nominal mesh", "--nominal");
  job.part = existing(a.value("part"), beside, "part.json", "part file", "--part");
  job.tools = existing(a.value("tools"), beside, "tools.tbl", "tool table", "--tools");
  job.machine_file = *a.value("machine");
  job.component_path = component_path(a);
  job.work_dir = a.value("work") ? fs::path(*a.value("work")) : fs::path(out_dir);
  dg::SurfaceOptions options;
  options.holdout_fraction = a.number("split", 0.3, 0.0, 0.9);
  options.bic_threshold = a.number("bic-threshold", 10.0, 0.0, 1e6);
  if (const auto c = a.value("candidates")) options.candidates = candidate_list(*c);
  refuse_outputs_over_inputs(a, out_dir,
                             {job.nominal.string(), job.part.string(), job.tools.string()});
  require_writable_folder("out", out_dir);
  if (a.value("work")) require_writable_folder("work", *a.value("work"));
  if (progress_shown(a))
    options.progress = [](const std::string& line) {
      std::fprintf(stderr, "diagnose: %s\n", line.c_str());
    };
  dg::SurfaceDiagnosisResult result;
  try {
    const auto believed = sim::read_machine_description(*a.value("machine"));
    dg::SurfaceMeasurement m;
    if (const auto cmm = a.value("cmm")) {
      m = dg::read_cmm_measurement(*cmm);
    } else {
      const auto nominal = offline::read_stl(job.nominal);
      const auto labels = sim::measure::read_part_surfaces(job.part);
      m = dg::read_scan_measurement(*a.value("surface"), nominal, labels.triangle_surface_ids,
                                    a.number("spacing", 0.5, 0.01, 100.0));
    }
    result = dg::diagnose_surface(m, job, believed, options);
    result.believed_file = *a.value("machine");
  } catch (const sim::MachineDescriptionError& e) {
    return bad_input(e);
  } catch (const dg::DiagnosisError& e) {
    return bad_input(e);
  } catch (const sim::measure::PartFileError& e) {
    return bad_input(e);
  } catch (const offline::MeshIoError& e) {
    return bad_input(e);
  }
  write_outputs(out_dir, dg::surface_diagnosis_json(result), result.fitted,
                dg::surface_diagnosis_html(result), dg::surface_diagnosis_summary(result));
  return kExitOk;
}

}  // namespace

int cmd_diagnose(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"recording", true},
                      {"surface", true},
                      {"cmm", true},
                      {"program", true},
                      {"nominal", true},
                      {"part", true},
                      {"tools", true},
                      {"candidates", true},
                      {"spacing", true},
                      {"work", true},
                      {"component-path", true, true},
                      {"out", true},
                      {"map", true, true},
                      {"machine", true},
                      {"holdout", true},
                      {"split", true},
                      {"servo-period", true},
                      {"max-servo-periods", true},
                      {"command-interpolation", true},
                      {"max-delay", true},
                      {"bic-threshold", true},
                      {"min-effect", true},
                      {"tcp-datum", true},
                      kQuietOption,
                      {"help", false}});
  if (a.flag("help")) {
    std::fputs(kDiagnoseHelp, stdout);
    return kExitOk;
  }
  if (!a.positionals().empty())
    throw UsageError("unexpected argument '" + a.positionals()[0] + "'");
  const auto recording = a.value("recording");
  const int modes =
      int(bool(recording)) + int(bool(a.value("surface"))) + int(bool(a.value("cmm")));
  if (modes > 1) throw UsageError("--recording, --surface and --cmm exclude each other");
  if (modes == 0) throw UsageError("--recording FILE (or --surface / --cmm) is required");
  const auto out_dir = a.value("out");
  if (!out_dir) throw UsageError("--out DIR is required");
  if (!recording) return surface_mode(a, *out_dir);
  const auto holdout = a.value("holdout");
  if (holdout && a.value("split")) throw UsageError("--holdout and --split exclude each other");
  if (holdout) {
    std::error_code ec;
    if (fs::equivalent(*holdout, *recording, ec) && !ec)
      throw UsageError("--holdout " + *holdout + " is the --recording " + *recording +
                       ": a fit proven on its own data proves nothing; give another recording "
                       "or use --split");
  }
  if (a.value("candidates"))
    throw UsageError(
        "--candidates selects the effects of surface mode (--surface or --cmm; "
        "known: " +
        known_candidates() +
        "); trace mode tests every effect of the machine "
        "description");
  refuse_outputs_over_inputs(a, *out_dir);
  require_writable_folder("out", *out_dir);

  dg::DiagnosisOptions options;
  options.holdout_fraction = a.number("split", 0.3, 0.0, 0.9);
  options.max_servo_period_s = a.number("servo-period", 1e-3, 1e-6, 1.0);
  const double max_servo_periods = a.number("max-servo-periods", 1e7, 1.0, 1e12);
  options.max_delay_s = a.number("max-delay", 0.0, 0.0, 1e3);
  if (const auto ci = a.value("command-interpolation")) {
    if (*ci != "cubic" && *ci != "linear")
      throw UsageError("--command-interpolation " + *ci + ": expected cubic or linear");
    options.command_interpolation = *ci == "linear"
                                        ? dg::DiagnosisOptions::CommandInterpolation::kLinear
                                        : dg::DiagnosisOptions::CommandInterpolation::kCubic;
  }
  options.bic_threshold = a.number("bic-threshold", 10.0, 0.0, 1e6);
  options.min_effect_ratio = a.number("min-effect", 0.1, 0.0, 100.0);
  if (const auto d = a.value("tcp-datum")) {
    if (*d != "free" && *d != "known")
      throw UsageError("--tcp-datum " + *d + ": expected free or known");
    options.tcp_datum_known = *d == "known";
  }
  if (const auto t = a.value("tools")) {
    try {
      const auto table = interp::ToolTable::load(*t);
      for (const auto& e : table.entries())
        options.tool_length_mm[e.number] = e.offset_mm.z;
    } catch (const interp::GcodeError& e) {
      throw UsageError(e.what());
    }
  }
  if (progress_shown(a))
    options.progress = [](const std::string& line) {
      std::fprintf(stderr, "diagnose: %s\n", line.c_str());
    };

  std::string map_text;
  for (const auto& m : a.values("map"))
    map_text += (map_text.empty() ? "" : ",") + m;

  dg::DiagnosisResult result;
  try {
    analysis::RecordingOptions ro;
    ro.map = analysis::parse_column_map(map_text);
    if (progress_shown(a)) std::fprintf(stderr, "diagnose: reading %s\n", recording->c_str());
    const auto rec = analysis::read_recording(*recording, ro);
    std::optional<analysis::Recording> held;
    if (holdout) {
      if (progress_shown(a)) std::fprintf(stderr, "diagnose: reading %s\n", holdout->c_str());
      held = analysis::read_recording(*holdout, ro);
    }
    check_servo_budget(rec, options.max_servo_period_s, max_servo_periods);
    if (held) check_servo_budget(*held, options.max_servo_period_s, max_servo_periods);
    if (const auto t = a.value("tools")) {
      check_tool_channel(rec, options.tool_length_mm, *t);
      if (held) check_tool_channel(*held, options.tool_length_mm, *t);
    }
    const auto believed = a.value("machine") ? sim::read_machine_description(*a.value("machine"))
                                             : dg::ideal_machine_for(rec);
    result = dg::diagnose(rec, held ? &*held : nullptr, believed, options);
    result.map = map_text;
  } catch (const analysis::RecordingError& e) {
    return bad_input(e);
  } catch (const sim::MachineDescriptionError& e) {
    return bad_input(e);
  } catch (const dg::DiagnosisError& e) {
    return bad_input(e);
  }

  write_outputs(*out_dir, dg::diagnosis_json(result), result.fitted, dg::diagnosis_html(result),
                dg::diagnosis_summary(result));
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{
    "diagnose",
    "find, name and fit what the machine does that the model does not (recordings, parts)",
    cmd_diagnose, 70};
}  // namespace

}  // namespace truecut::cli
