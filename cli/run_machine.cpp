// truecut run MACHINE.json PROGRAM.ngc --out DIR: machine a part on the
// simulated machine (sim/include/truecut/sim/soft_cnc.hpp).
#include "run_machine.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>

#include "parameter_file_args.hpp"
#include "quiet_option.hpp"
#include "run_measure.hpp"
#include "run_support.hpp"
#include "stage_progress.hpp"
#include "truecut/rt/hal_file.hpp"
#include "truecut/rt/input_file.hpp"
#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/soft_cnc.hpp"
#include "truecut/sim/soft_cnc_outputs.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;

const char* kHelp =
    "usage: truecut run MACHINE.json PROGRAM.ngc --out DIR [options]\n"
    "\n"
    "Machines PROGRAM on the simulated 5-axis A/C machine MACHINE (a machine\n"
    "description, docs/formats.md) in simulated time (or, with --realtime, against\n"
    "the wall clock): interpreter/planner ->\n"
    "truecut_comp -> machine joints with their physics -> cutting -> recorder.\n"
    "DIR receives soft_cnc.hal and run.ini (the exact wiring and settings used;\n"
    "`truecut run DIR/soft_cnc.hal --ini DIR/run.ini --out DIR` repeats the run),\n"
    "machined.stl and machined.ply (the machined surface) and trace.csv (t,\n"
    "<j>_cmd, <j>_act, feed, spindle_power, line, tool, true TCP).\n"
    "\n"
    "The part is found beside the program, as `truecut part` writes it\n"
    "(nominal.stl, part.json, tools.tbl), unless given:\n"
    "  --nominal FILE.stl     nominal part: where the cutting model's dexels sit\n"
    "  --part FILE.json       part.json: stock and tools\n"
    "  --tools FILE.tbl       LinuxCNC tool table\n";
const char* kHelpOptions =
    "options:\n"
    "  --out DIR              output folder (created)\n"
    "  --field FILE.tcf       correction field for truecut_comp (real-time compensation)\n"
    "  --max-correction MM    truecut_comp magnitude limit (default 0.5)\n"
    "  --max-rate MM_PER_S    truecut_comp rate limit (default 5)\n"
    "  --fade-time S          truecut_comp fade in/out (default 0.2)\n"
    "  --period-us US         servo period (default 1000)\n"
    "  --dexel-spacing MM     cutting model's surface sampling (default 0.1)\n"
    "  --cut-threads N        threads that cut (default 0: one per CPU; same result for any)\n"
    "  --record-every N       record every N-th cycle (default 1)\n"
    "  --max-dexels N         cutting model's size limit (default 10000000, at most 50000000)\n"
    "  --max-blocks N         blocks the interpreter may execute (default 50000000)\n"
    "  --max-program-time S   longest planned program, s (default 86400: 24 h)\n"
    "  --component-path DIR   also search DIR for components (repeatable)\n"
    "  --realtime             run against the wall clock instead of simulated time\n"
    "                         (same outputs; prints cycle timing and overruns)\n"
    "  --cpu N                with --realtime: pin the servo thread to CPU N\n"
    "  --fifo PRIO            with --realtime: SCHED_FIFO priority 1..99 when permitted\n"
    "  --quiet                nothing on stderr but warnings and errors\n"
    "                         (progress is shown on a terminal only)\n"
    "  --help                 this text\n"
    "measuring the machined part after the run (FILE relative to DIR):\n"
    "  --scan FILE            virtual optical scan (as truecut scan): .ply, .xyz, .txt, .csv\n"
    "  --scan-sigma-um S      and its options --scan-seed, --scan-density, --scan-mode,\n"
    "                         --scan-max-incidence-deg, --scan-normals,\n"
    "                         --scan-registration-error-mm, --scan-registration-error-deg\n"
    "  --cmm FILE             virtual CMM on the part's compensated surfaces (as truecut cmm\n"
    "                         --nominal --part): CSV\n"
    "  --cmm-sigma-um S       and --cmm-seed, --cmm-spacing, --cmm-surfaces, --cmm-search-mm,\n"
    "                         --cmm-max-points\n";

// An input file that must be there: a missing one, a folder or a device
// each named as what it is (rt/input_file.hpp).
fs::path input_file(const fs::path& p, const char* what, const std::string& hint = {}) {
  try {
    rt::check_input_file(p, what);
  } catch (const rt::InputFileError& e) {
    throw UsageError(e.what() + hint);
  }
  return p;
}

fs::path existing(const std::optional<std::string>& given, const fs::path& beside,
                  const char* default_name, const char* option, const char* what) {
  const fs::path p = given ? fs::path(*given) : beside / default_name;
  return input_file(
      p, what,
      given ? std::string() : std::string(" (looked beside the program; give ") + option + ")");
}

// A rate or magnitude limit of truecut_comp: at 0 the field is never applied.
double comp_limit(const ParsedArgs& a, const char* option, double fallback, double max,
                  const char* unit) {
  const double v = a.number(option, fallback, 0.0, max);
  if (v > 0) return v;
  throw UsageError(std::string("--") + option + " 0 " + unit +
                   " would hold the field's correction at zero; it must be > 0 (up to " +
                   std::to_string(static_cast<int>(max)) + ")");
}

// Every file the run reads, for the outputs to be checked against.
std::vector<fs::path> job_inputs(const sim::SoftCncJob& job) {
  std::vector<fs::path> inputs = {job.machine, job.program, job.nominal, job.part, job.tools};
  if (job.field) inputs.push_back(*job.field);
  if (job.parameters) inputs.push_back(*job.parameters);
  return inputs;
}

// The run's own outputs must not replace what it reads (`--out` the part's
// folder with `--nominal` named machined.stl, say).
void refuse_outputs_over_inputs(const sim::SoftCncJob& job) {
  for (const char* name : sim::kSoftCncOutputs) {
    // The field's copy (for swaps) over the field itself is the same bytes.
    if (name == sim::kFieldCopy) continue;
    for (const fs::path& input : job_inputs(job)) {
      std::error_code ec;
      if (fs::equivalent(job.out_dir / name, input, ec) && !ec)
        throw UsageError("--out " + job.out_dir.string() + ": the run writes " + name +
                         " there, which is the input " + input.string() +
                         "; choose another folder");
    }
  }
}

// A field that corrected nothing of the cut: at every service point at
// which the tool cut, the correction was zero.
void warn_if_never_corrected(const sim::SoftCncJob& job, const sim::SoftCncResult& r) {
  if (!job.field || r.cutting_samples == 0 || r.corrected_cutting_samples > 0) return;
  std::fprintf(stderr,
               "truecut run: WARNING: %s never corrected the cut: the correction was zero "
               "whenever the tool cut (%lld checks, every 10 ms); does the field's grid cover "
               "the part, and is it the field for this part?\n",
               job.field->string().c_str(), static_cast<long long>(r.cutting_samples));
}

}  // namespace

int run_machine(const std::vector<std::string>& argv) {
  std::vector<OptionSpec> specs = run_measure_option_specs();
  specs.insert(specs.end(), {{"out", true},
                             {"nominal", true},
                             {"part", true},
                             {"tools", true},
                             {"var-file", true},
                             {"var-units", true},
                             {"field", true},
                             {"max-correction", true},
                             {"max-rate", true},
                             {"fade-time", true},
                             {"period-us", true},
                             {"dexel-spacing", true},
                             {"cut-threads", true},
                             {"record-every", true},
                             {"max-blocks", true},
                             {"max-dexels", true},
                             {"max-program-time", true},
                             {"component-path", true, true},
                             {"realtime", false},
                             {"cpu", true},
                             {"fifo", true},
                             kQuietOption,
                             {"help", false}});
  ParsedArgs a(argv, specs);
  if (a.flag("help")) {
    std::fputs((std::string(kHelp) + kVarFileHelp + kHelpOptions).c_str(), stdout);
    return kExitOk;
  }
  if (a.positionals().size() != 2) throw UsageError("expected MACHINE.json PROGRAM.ngc");
  const auto out = a.value("out");
  if (!out) throw UsageError("--out DIR is required");
  sim::SoftCncJob job;
  job.machine = input_file(a.positionals()[0], "machine description");
  job.program = input_file(a.positionals()[1], "program file");
  const fs::path beside = job.program.has_parent_path() ? job.program.parent_path() : ".";
  job.nominal = existing(a.value("nominal"), beside, "nominal.stl", "--nominal", "nominal mesh");
  job.part = existing(a.value("part"), beside, "part.json", "--part", "part file");
  job.tools = existing(a.value("tools"), beside, "tools.tbl", "--tools", "tool table");
  if (auto f = a.value("field")) job.field = input_file(*f, "correction field");
  if (auto v = a.value("var-file")) job.parameters = input_file(*v, "parameter file");
  job.parameters_in_inches = length_units_option(a, "var-units") == interp::LengthUnits::kInch;
  job.out_dir = *out;
  job.period_us = a.number("period-us", 1000.0, 50.0, 100000.0);
  job.dexel_spacing_mm = a.number("dexel-spacing", 0.1, 0.01, 5.0);
  job.max_dexels = static_cast<std::size_t>(
      a.integer("max-dexels", static_cast<long>(sim::cutting::kDefaultMaxDexels), 1,
                static_cast<long>(sim::cutting::kMaxDexels)));
  job.cut_threads = static_cast<int>(a.integer("cut-threads", 0, 0, 256));
  job.record_every = a.integer("record-every", 1, 1, 1000000);
  job.max_correction_mm = comp_limit(a, "max-correction", sim::kSoftCncMaxCorrectionMm, 10.0, "mm");
  job.max_rate_mm_per_s = comp_limit(a, "max-rate", 5.0, 1000.0, "mm/s");
  job.max_blocks = a.integer("max-blocks", 50'000'000, 1, 1'000'000'000'000L);
  job.max_program_time_s =
      a.number("max-program-time", sim::kSoftCncMaxProgramTimeS, 1.0, 365.0 * 24 * 3600);
  job.fade_time_s = a.number("fade-time", 0.2, 0.0, 60.0);
  job.component_path = component_path(a);
  job.wall_clock = a.flag("realtime");
  if (!job.wall_clock && (a.value("cpu") || a.value("fifo")))
    throw UsageError("--cpu and --fifo need --realtime");
  job.wall_clock_options.cpu = static_cast<int>(a.integer("cpu", -1, 0, 1023));
  job.wall_clock_options.fifo_priority = static_cast<int>(a.integer("fifo", 0, 1, 99));
  refuse_outputs_over_inputs(job);
  RunMeasurement measure =
      prepare_run_measurement(a, job.out_dir, job.nominal, job.part, job_inputs(job));

  Progress progress;
  const bool show_progress = progress_shown(a);
  job.show_info_messages = !a.flag("quiet");
  sim::SoftCncResult r;
  try {
    if (!a.flag("quiet"))
      std::fprintf(stderr, "machining %s on %s\n", job.program.string().c_str(),
                   job.machine.string().c_str());
    // Before the first cycle: interpreting, checking and planning the
    // program, building the cutting model (a long program takes a minute).
    std::optional<StageProgress> loading;
    loading.emplace("truecut run", show_progress);
    loading->stage("reading, checking and planning the program");
    // Messages (the cutting model's at load, the outputs' at the end) go
    // below the progress line, not into it; the mutex because a component
    // may write from another thread.
    std::mutex line_mutex;
    bool run_line_open = false;
    if (show_progress)
      job.message_sink = [&](const std::string& line) {
        std::lock_guard<std::mutex> lock(line_mutex);
        if (loading) {
          loading->message(line);
          return;
        }
        if (run_line_open) std::fputs("\n", stderr);
        run_line_open = false;
        std::fputs(line.c_str(), stderr);
      };
    r = sim::run_soft_cnc(job, [&](double t_s, double program_s) {
      if (!show_progress) return;
      std::lock_guard<std::mutex> lock(line_mutex);
      loading.reset();
      progress.total_ns = static_cast<int64_t>(program_s * 1e9);
      const int64_t before = progress.last_ns;
      print_progress(&progress, static_cast<int64_t>(t_s * 1e9));
      run_line_open = run_line_open || progress.last_ns != before;
    });
    if (run_line_open) std::fputs("\n", stderr);
  } catch (const sim::MachineDescriptionError& e) {
    std::fprintf(stderr, "truecut run: %s\n", e.what());
    return kExitUsage;
  } catch (const sim::SoftCncInputError& e) {
    std::fprintf(stderr, "truecut run: %s\n", e.what());
    return kExitUsage;
  } catch (const rt::hal::HalFileError& e) {
    std::fprintf(stderr, "truecut run: %s\n", e.what());
    return kExitUsage;
  }
  if (r.output_errors > 0) {
    std::fprintf(stderr,
                 "truecut run: %d output file(s) could not be written in full (see above)\n",
                 r.output_errors);
    return kExitFailure;
  }
  if (!r.finished) {
    std::fprintf(stderr, "truecut run: the program did not reach its end\n");
    return kExitFailure;
  }
  if (r.limit_fault) {
    // The planned path was checked before machining; what still leaves the
    // travel is the correction field or the servo loops.
    std::fprintf(stderr,
                 "truecut run: %s:%d: a joint command left the machine's travel while "
                 "machining (seen at this line; the planned path stays inside it)\n",
                 job.program.string().c_str(), r.limit_fault_line);
    return kExitFailure;
  }
  std::printf("truecut run %s %s\n", job.machine.string().c_str(), job.program.string().c_str());
  std::printf("  time        %.3f s machined in %.3f s wall (%.1fx real time)\n", r.simulated_s,
              r.wall_s, r.wall_s > 0 ? r.simulated_s / r.wall_s : 0.0);
  const double command_s = r.load_wall_s + r.wall_s + r.unload_wall_s;
  std::printf(
      "  stages      %.3f s checking, planning and loading, %.3f s machining, %.3f s writing the "
      "outputs: %.3f s (%.1fx real time)\n",
      r.load_wall_s, r.wall_s, r.unload_wall_s, command_s,
      command_s > 0 ? r.simulated_s / command_s : 0.0);
  if (job.wall_clock) {
    for (const auto& note : r.report.notes)
      std::printf("  realtime    %s\n", note.c_str());
    for (const auto& t : r.report.threads)
      std::printf(
          "  %-11s %llu cycles of %lld us, %llu overruns; latency median %.1f us, p99 %.1f us, "
          "max %.1f us; compute median %.1f us, max %.1f us\n",
          t.name.c_str(), static_cast<unsigned long long>(t.cycles),
          static_cast<long long>(t.period_ns / 1000), static_cast<unsigned long long>(t.overruns),
          double(t.latency.percentile_ns(0.5)) * 1e-3, double(t.latency.percentile_ns(0.99)) * 1e-3,
          double(t.latency.max_ns()) * 1e-3, double(t.compute.percentile_ns(0.5)) * 1e-3,
          double(t.compute.max_ns()) * 1e-3);
  }
  if (job.field)
    std::printf("  correction  max %.4g mm: limited in %d cycles\n", job.max_correction_mm,
                r.clamped_cycles);
  warn_if_never_corrected(job, r);
  if (r.clamped_cycles > 0)
    std::fprintf(stderr,
                 "truecut run: WARNING: --max-correction %.4g mm limited the field's correction "
                 "in %d servo cycles: the part got less correction than %s asks for; raise "
                 "--max-correction or check the field\n",
                 job.max_correction_mm, r.clamped_cycles, job.field->string().c_str());
  std::printf("  output      %s/{machined.stl,machined.ply,trace.csv,soft_cnc.hal,run.ini}\n",
              job.out_dir.string().c_str());
  if (!measure_machined_part(measure, job.out_dir / sim::kMachinedStl)) return kExitFailure;
  return kExitOk;
}

}  // namespace truecut::cli
