// Runs a soft-CNC job: writes the wiring and its INI, loads, runs, shuts down.
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/tool_table.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal.hpp"
#include "truecut/rt/hal_file.hpp"
#include "truecut/rt/ini.hpp"
#include "truecut/sim/program_travel.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace truecut::sim {
namespace {

namespace fs = std::filesystem;

// Runs at every service point on the non-real-time side: the progress
// report and the field swaps (file replaced, then a reload pulse: raised at
// one service point, lowered at the next).
struct ServiceHook {
  const SoftCncProgress* callback;
  double program_s;
  rt::hal::Hal* hal;
  const std::vector<SoftCncFieldSwap>* swaps;
  fs::path field_file;
  std::size_t next_swap = 0;
  bool reload_high = false;
  int32_t limit_fault_line = 0;
};

void on_service(void* user, int64_t time_ns) {
  auto& hook = *static_cast<ServiceHook*>(user);
  const double t_s = double(time_ns) * 1e-9;
  if (hook.limit_fault_line == 0 && hook.hal->get_pin_or_param("machine.limit-fault").b)
    hook.limit_fault_line = std::max<int32_t>(1, hook.hal->get_pin_or_param("planner.line").s);
  if (hook.reload_high) {
    hook.hal->set_pin_or_param("comp.reload", "0");
    hook.reload_high = false;
  } else if (hook.next_swap < hook.swaps->size() && t_s >= (*hook.swaps)[hook.next_swap].time_s) {
    rt::copy_file_atomically((*hook.swaps)[hook.next_swap].field, hook.field_file);
    hook.hal->set_pin_or_param("comp.reload", "1");
    hook.reload_high = true;
    ++hook.next_swap;
  }
  if (*hook.callback) (*hook.callback)(t_s, hook.program_s);
}

// The program as the planner component will interpret and plan it, checked
// against the machine's travel before anything is written.
void check_program(const SoftCncJob& job, const MachineDescription& machine) {
  try {
    interp::InterpreterOptions io;
    io.tools = interp::ToolTable::load(job.tools);
    const interp::LengthUnits units =
        job.parameters_in_inches ? interp::LengthUnits::kInch : interp::LengthUnits::kMm;
    io.parameters.units = units;  // as the planner component: units with or without a file
    if (job.parameters) io.parameters = interp::ParameterFile::load(*job.parameters, units);
    const interp::Plan plan = interp::plan_program(interp::Interpreter(io).run_file(job.program),
                                                   soft_cnc_planner_options(job, machine));
    const ProgramTravel travel = program_travel(plan, machine.machine, job.program.string());
    if (!travel.inside())
      throw SoftCncInputError(travel.first_excursion->message + " (machine " +
                              job.machine.string() + ")");
  } catch (const interp::GcodeError& e) {
    throw SoftCncInputError(e.what());
  }
}

// Removes what a job that failed to load wrote: its files, and out_dir if
// the job created it and it is empty again.
void remove_written(const std::vector<fs::path>& files, const fs::path& dir, bool dir_created) {
  std::error_code ec;
  for (const auto& f : files)
    fs::remove(f, ec);
  if (dir_created && fs::is_empty(dir, ec)) fs::remove(dir, ec);
}

}  // namespace

SoftCncResult run_soft_cnc(const SoftCncJob& given, const SoftCncProgress& progress) {
  const MachineDescription machine = read_machine_description(given.machine);
  if (!given.field_swaps.empty() && !given.field)
    throw std::runtime_error("field swaps need a field to start with");
  for (const auto& swap : given.field_swaps)
    if (!fs::is_regular_file(swap.field))
      throw std::runtime_error(swap.field.string() + ": no such file (field swap)");
  check_program(given, machine);
  const bool dir_created = !fs::exists(given.out_dir);
  fs::create_directories(given.out_dir);
  SoftCncJob job = given;
  const fs::path hal_file = job.out_dir / "soft_cnc.hal", ini_file = job.out_dir / "run.ini";
  std::vector<fs::path> written;
  rt::hal::HalOptions options;
  options.component_path = job.component_path;
  options.output_dir = job.out_dir;
  SoftCncResult result;
  rt::hal::Hal h(options);
  try {
    if (!job.field_swaps.empty()) {
      job.field = job.out_dir / "field.tcf";
      written.push_back(*job.field);
      rt::copy_file_atomically(*given.field, *job.field);
    }
    written.push_back(hal_file);
    rt::write_file_atomically(hal_file, soft_cnc_hal_text());
    written.push_back(ini_file);
    rt::write_file_atomically(ini_file, soft_cnc_ini_text(job, machine));
    const rt::hal::Ini ini = rt::hal::Ini::load(ini_file);
    rt::hal::load_hal_file(h, hal_file, &ini);
  } catch (const rt::hal::HalFileError& e) {
    // A component refused the job (its message names the file and key);
    // the wiring file it points to is removed with the rest.
    remove_written(written, job.out_dir, dir_created);
    throw SoftCncInputError(e.message());
  } catch (...) {
    remove_written(written, job.out_dir, dir_created);
    throw;
  }
  result.program_s = h.get_pin_or_param("planner.program-time").as_double();

  rt::hal::RunLimits limits;
  // The planner stops the run at the program end; the limit only guards a
  // plan that never ends.
  limits.duration_ns = static_cast<int64_t>((result.program_s * 1.5 + 10.0) * 1e9);
  ServiceHook hook{&progress, result.program_s, &h, &job.field_swaps,
                   job.field ? *job.field : fs::path()};
  limits.progress = on_service;  // also notes the line of a limit fault
  limits.progress_user = &hook;
  limits.cycle_probe = job.cycle_probe;
  limits.cycle_probe_user = job.cycle_probe_user;
  rt::hal::Executor executor(h);
  result.report = job.wall_clock ? executor.run_wall_clock(limits, job.wall_clock_options)
                                 : executor.run_simulated(limits);
  result.simulated_s = double(result.report.simulated_ns) * 1e-9;
  result.wall_s = result.report.wall_s;
  result.finished = h.get_pin_or_param("planner.done").as_double() != 0;
  result.limit_fault = h.get_pin_or_param("machine.limit-fault").as_double() != 0;
  result.limit_fault_line = hook.limit_fault_line;
  result.field_generation = h.get_pin_or_param("comp.field-generation").s;
  result.field_load_errors = h.get_pin_or_param("comp.load-errors").s;
  result.clamped_cycles = h.get_pin_or_param("comp.clamp-count").s;
  result.output_errors = h.unload();  // the recorder and the cutting write their files
  return result;
}

}  // namespace truecut::sim
