// Runs a soft-CNC job: writes the wiring and its INI, loads, runs, shuts down.
#include <fstream>
#include <stdexcept>

#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal.hpp"
#include "truecut/rt/hal_file.hpp"
#include "truecut/rt/ini.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace truecut::sim {
namespace {

namespace fs = std::filesystem;

void write_text(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out.flush()) throw std::runtime_error(tmp.string() + ": cannot write");
  }
  fs::rename(tmp, path);
}

struct ProgressHook {
  const SoftCncProgress* callback;
  double program_s;
};

void report_progress(void* user, int64_t time_ns) {
  auto& hook = *static_cast<ProgressHook*>(user);
  (*hook.callback)(double(time_ns) * 1e-9, hook.program_s);
}

}  // namespace

SoftCncResult run_soft_cnc(const SoftCncJob& job, const SoftCncProgress& progress) {
  const MachineDescription machine = read_machine_description(job.machine);
  fs::create_directories(job.out_dir);
  const fs::path hal_file = job.out_dir / "soft_cnc.hal", ini_file = job.out_dir / "run.ini";
  write_text(hal_file, soft_cnc_hal_text());
  write_text(ini_file, soft_cnc_ini_text(job, machine));

  hal::HalOptions options;
  options.component_path = job.component_path;
  options.output_dir = job.out_dir;
  SoftCncResult result;
  hal::Hal h(options);
  const hal::Ini ini = hal::Ini::load(ini_file);
  hal::load_hal_file(h, hal_file, &ini);
  result.program_s = h.get_pin_or_param("planner.program-time").as_double();

  hal::RunLimits limits;
  // The planner stops the run at the program end; the limit only guards a
  // plan that never ends.
  limits.duration_ns = static_cast<int64_t>((result.program_s * 1.5 + 10.0) * 1e9);
  ProgressHook hook{&progress, result.program_s};
  if (progress) {
    limits.progress = report_progress;
    limits.progress_user = &hook;
  }
  hal::Executor executor(h);
  const hal::RunReport report = executor.run_simulated(limits);
  result.simulated_s = double(report.simulated_ns) * 1e-9;
  result.wall_s = report.wall_s;
  result.finished = h.get_pin_or_param("planner.done").as_double() != 0;
  result.limit_fault = h.get_pin_or_param("machine.limit-fault").as_double() != 0;
  return result;  // ~Hal: the recorder and the cutting write their files
}

}  // namespace truecut::sim
