// Runs a soft-CNC job: writes the wiring and its INI, loads, runs, shuts down.
#include <algorithm>
#include <chrono>
#include <future>
#include <memory>
#include <stdexcept>
#include <vector>

#include "program_checks.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/tool_table.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal.hpp"
#include "truecut/rt/hal_file.hpp"
#include "truecut/rt/ini.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"
#include "truecut/sim/program_travel.hpp"
#include "truecut/sim/soft_cnc.hpp"
#include "truecut/sim/soft_cnc_outputs.hpp"

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
  int64_t cutting_samples = 0;    // service points at which the tool cut
  int64_t corrected_samples = 0;  // ... with a correction other than zero
};

// Whether the field ever corrected the cut (sampled at the service points).
void sample_correction(ServiceHook& hook) {
  if (!hook.hal->get_pin_or_param("cut.engaged").b) return;
  ++hook.cutting_samples;
  if (hook.hal->get_pin_or_param("comp.corr-mag").as_double() > 0) ++hook.corrected_samples;
}

void on_service(void* user, int64_t time_ns) {
  auto& hook = *static_cast<ServiceHook*>(user);
  const double t_s = double(time_ns) * 1e-9;
  if (hook.limit_fault_line == 0 && hook.hal->get_pin_or_param("machine.limit-fault").b)
    hook.limit_fault_line = std::max<int32_t>(1, hook.hal->get_pin_or_param("planner.line").s);
  if (!hook.field_file.empty()) sample_correction(hook);
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

// The program as the planner component will interpret it, checked before
// anything is written: positions no machine reaches, a duration beyond the
// job's budget, and the tools it cuts with against the field, part.json and
// the tool table (program_checks.hpp). The planned path's own checks
// (check_planned_path) follow.
struct CheckedProgram {
  interp::CanonProgram canon;
  std::vector<int32_t> cutting_tools;  // the field must have their layers
};

CheckedProgram check_program(const SoftCncJob& job, const MachineDescription& machine) {
  try {
    interp::InterpreterOptions io;
    io.tools = interp::ToolTable::load(job.tools);
    io.max_blocks = job.max_blocks;
    const interp::LengthUnits units =
        job.parameters_in_inches ? interp::LengthUnits::kInch : interp::LengthUnits::kMm;
    io.parameters.units = units;  // as the planner component: units with or without a file
    if (job.parameters) io.parameters = interp::ParameterFile::load(*job.parameters, units);
    CheckedProgram checked{interp::Interpreter(io).run_file(job.program), {}};
    soft_cnc::check_program_positions(checked.canon);
    const interp::PlannerOptions planner = soft_cnc_planner_options(job, machine);
    soft_cnc::check_program_time_bound(checked.canon, planner.start_joints, job.max_program_time_s);
    const auto tools = soft_cnc::cutting_tools(checked.canon);
    soft_cnc::check_part_tools(job.part, job.tools, io.tools, tools, job.program.string());
    if (job.field) soft_cnc::check_field_layers(*job.field, tools, job.program.string());
    for (const auto& [tool, line] : tools)
      checked.cutting_tools.push_back(tool);
    return checked;
  } catch (const interp::GcodeError& e) {
    throw SoftCncInputError(e.what());
  }
}

// The planned program: its duration against the job's budget, and its path
// against the machine's travel.
void check_planned_path(const SoftCncJob& job, const MachineDescription& machine,
                        const interp::CanonProgram& canon) {
  try {
    const interp::Plan plan = interp::plan_program(canon, soft_cnc_planner_options(job, machine));
    soft_cnc::check_planned_time(plan, job.program.string(), job.max_program_time_s);
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
  const auto start = std::chrono::steady_clock::now();
  auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  const MachineDescription machine = read_machine_description(given.machine);
  if (!given.field_swaps.empty() && !given.field)
    throw std::runtime_error("field swaps need a field to start with");
  for (const auto& swap : given.field_swaps)
    if (!fs::is_regular_file(swap.field))
      throw std::runtime_error(swap.field.string() + ": no such file (field swap)");
  const CheckedProgram checked = check_program(given, machine);
  // Planning the program for the travel check takes as long as the planner
  // component's own planning at load (half a second of the free-form's
  // run): the two run side by side. A load the check then refuses is
  // unloaded before any cycle has run, so the components write nothing
  // (cycles_ran in hal_abi.h), and the wiring is removed as after a refused
  // load.
  std::future<void> path_check =
      std::async(std::launch::async, [&] { check_planned_path(given, machine, checked.canon); });
  const bool dir_created = !fs::exists(given.out_dir);
  SoftCncJob job = given;
  const fs::path hal_file = job.out_dir / kSoftCncHal, ini_file = job.out_dir / kRunIni;
  std::vector<fs::path> written;
  // The wiring and its INI belong to the run's outputs: a run ended by a
  // signal removes them as it removes trace.csv.tmp.
  std::vector<std::unique_ptr<rt::PendingFile>> interrupted_removes;
  rt::hal::HalOptions options;
  options.component_path = job.component_path;
  options.output_dir = job.out_dir;
  options.show_info_messages = job.show_info_messages;
  options.message_sink = job.message_sink;
  SoftCncResult result;
  rt::hal::Hal h(options);
  try {
    try {
      fs::create_directories(given.out_dir);
      if (!job.field_swaps.empty()) {
        job.field = job.out_dir / kFieldCopy;
        written.push_back(*job.field);
        rt::copy_file_atomically(*given.field, *job.field);
      }
      written.push_back(hal_file);
      rt::write_file_atomically(hal_file, soft_cnc_hal_text());
      written.push_back(ini_file);
      rt::write_file_atomically(ini_file, soft_cnc_ini_text(job, machine, checked.cutting_tools));
      for (const fs::path& f : written)
        interrupted_removes.push_back(std::make_unique<rt::PendingFile>(f));
      const rt::hal::Ini ini = rt::hal::Ini::load(ini_file);
      rt::hal::load_hal_file(h, hal_file, &ini);
    } catch (...) {
      // The check's refusal comes first: it would have been met before
      // anything was loaded.
      path_check.get();
      throw;
    }
    path_check.get();
  } catch (const rt::hal::HalFileError& e) {
    // A component refused the job (its message names the file and key);
    // the wiring file it points to is removed with the rest.
    h.unload();
    remove_written(written, job.out_dir, dir_created);
    throw SoftCncInputError(e.message());
  } catch (...) {
    h.unload();
    remove_written(written, job.out_dir, dir_created);
    throw;
  }
  result.program_s = h.get_pin_or_param("planner.program-time").as_double();
  result.load_wall_s = seconds_since(start);

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
  result.cutting_samples = hook.cutting_samples;
  result.corrected_cutting_samples = hook.corrected_samples;
  const auto unload_start = std::chrono::steady_clock::now();
  result.output_errors = h.unload();  // the recorder and the cutting write their files
  result.unload_wall_s = seconds_since(unload_start);
  return result;
}

}  // namespace truecut::sim
