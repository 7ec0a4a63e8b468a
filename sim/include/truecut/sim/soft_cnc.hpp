// The soft-CNC loop of the simulated machine, as `truecut run MACHINE.json
// PROGRAM.ngc` and the closed-loop demo run it: the shipped wiring
// sim/hal/soft_cnc.hal (interpreter/planner -> truecut_comp -> tool geometry
// -> machine joints -> cutting -> recorder) with a run.ini written for the
// job, in simulated time or, on request, against the wall clock.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "truecut/interp/planner.hpp"
#include "truecut/offline/field_outputs.hpp"
#include "truecut/rt/comp.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::sim {

// A field taken into use while the program runs: at the first service point
// at or after time_s (simulated time, or wall time since the start in
// wall-clock mode), `field` replaces the file truecut_comp reads and
// comp.reload is pulsed; the component cross-fades to it over the fade time.
struct SoftCncFieldSwap {
  double time_s = 0.0;
  std::filesystem::path field;
};

// truecut_comp's magnitude limit in a simulated run, unless --max-correction
// says otherwise. It overrides rt::comp::kDefaultMaxCorrectionMm: above the
// largest correction `truecut field` writes (offline::kFieldMaxCorrectionMm),
// so it never clips a field that passed that check, and below the
// component's default, so that a wrong field moves the simulated tool less.
inline constexpr double kSoftCncMaxCorrectionMm = 0.5;
static_assert(kSoftCncMaxCorrectionMm >= offline::kFieldMaxCorrectionMm &&
              kSoftCncMaxCorrectionMm <= rt::comp::kDefaultMaxCorrectionMm);

// The planned program may take at most this long unless
// --max-program-time says otherwise: 24 h of machining, above any job of
// the benchmark parts (benchmark004 takes 37 minutes).
inline constexpr double kSoftCncMaxProgramTimeS = 24.0 * 3600.0;

struct SoftCncJob {
  std::filesystem::path machine;  // machine description (JSON)
  std::filesystem::path program;  // G-code
  std::filesystem::path nominal;  // nominal part STL: where the cutting model's dexels sit
  std::filesystem::path part;     // part.json: stock and tools
  std::filesystem::path tools;    // LinuxCNC tool table
  // The controller's parameter file (LinuxCNC .var: work offsets, G92,
  // homes) the program starts from, and whether its lengths are in inches.
  std::optional<std::filesystem::path> parameters;
  bool parameters_in_inches = false;
  std::optional<std::filesystem::path> field;  // correction field for truecut_comp
  std::filesystem::path out_dir;
  double period_us = 1000.0;
  double dexel_spacing_mm = 0.1;  // the cutting model's surface sampling (docs/cutting.md)
  std::size_t max_dexels = cutting::kDefaultMaxDexels;  // the cutting model's size budget
  int cut_threads = 0;  // threads that cut (0: one per hardware thread); same result for any
  long record_every = 1;
  double max_correction_mm = kSoftCncMaxCorrectionMm;  // truecut_comp's limit
  double max_rate_mm_per_s = 5.0;
  double fade_time_s = 0.2;
  // Budgets of the interpreter (blocks executed: an endless loop) and of
  // the planned program (a dwell or feed off by orders of magnitude runs
  // for days): refused at load, naming the line.
  std::int64_t max_blocks = 50'000'000;  // InterpreterOptions::max_blocks
  double max_program_time_s = kSoftCncMaxProgramTimeS;
  std::vector<std::filesystem::path> component_path;  // where the components' .so are
  bool show_info_messages = true;  // components' info messages on stderr (false: --quiet)
  std::function<void(const std::string& line)> message_sink;  // HalOptions::message_sink

  // Field swaps in time order; they need `field`. With swaps the component
  // reads out_dir/field.tcf, a copy of `field` that each swap replaces.
  std::vector<SoftCncFieldSwap> field_swaps;
  // Wall-clock mode: the servo thread sleeps to real deadlines with
  // `wall_clock_options` (CPU pinning, SCHED_FIFO, spin); the outputs are the
  // same as in simulated time, only the timing statistics differ.
  bool wall_clock = false;
  rt::hal::WallClockOptions wall_clock_options;
  // RunLimits::cycle_probe, for tests that watch the servo cycles.
  void (*cycle_probe)(void* user, int phase) = nullptr;
  void* cycle_probe_user = nullptr;
};

struct SoftCncResult {
  double program_s = 0.0;    // planned duration of the program
  double simulated_s = 0.0;  // time the loop ran
  double wall_s = 0.0;       // of the loop
  // Wall time before the loop (reading and checking the inputs, planning,
  // loading the wiring: the cutting model's build among it) and after it
  // (the components' exits: the machined mesh and the files written).
  double load_wall_s = 0.0;
  double unload_wall_s = 0.0;
  bool finished = false;         // the planner reached the program end
  bool limit_fault = false;      // a joint command left the machine's travel
  int32_t limit_fault_line = 0;  // program line at the service point (10 ms) that first saw it
  int32_t field_generation = 0;  // fields truecut_comp took into use
  int32_t field_load_errors = 0;
  // Cycles in which max-correction limited the field's correction
  // (comp.clamp-count): the part got less correction than the field asked.
  int32_t clamped_cycles = 0;
  // With a field: the service points (every 10 ms) at which the tool cut,
  // and those at which the field's correction was not zero. None of the
  // second with some of the first: the field corrected nothing of the cut
  // (a grid away from the part, a zero field).
  int64_t cutting_samples = 0;
  int64_t corrected_cutting_samples = 0;
  // Errors the components reported while writing their files at the end
  // (machined.stl, trace.csv: a full disk, a folder gone); messages on stderr.
  int32_t output_errors = 0;
  rt::hal::RunReport report;  // cycles, overruns, compute time and latency, notes
};

// Bad input, found before the machine runs: the program or the tool table
// does not interpret, the program cannot be planned, moves beyond any
// machine, takes longer than max_program_time_s, its planned path leaves
// the machine's travel, it cuts with a tool the field has no layer for or
// part.json does not describe (or describes with another radius than the
// tool table), or a component refuses its files. The
// message names the file and line or key, e.g.
// "part/program.ngc:123: joint z leaves travel [-50, 350] at 362.5 mm".
class SoftCncInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The shipped wiring, compiled in (sim/hal/soft_cnc.hal).
const std::string& soft_cnc_hal_text();
// The run.ini the wiring reads for this job (absolute paths of the inputs;
// the outputs go into the folder the run is given, --out). `field_tools`:
// the tools truecut_comp must find a layer for (tools=).
std::string soft_cnc_ini_text(const SoftCncJob& job, const MachineDescription& machine,
                              const std::vector<int32_t>& field_tools = {});

// A job for a part folder as `truecut part` writes it: its `machine` file,
// its `program`, and its nominal.stl, part.json and tools.tbl; the outputs
// go to out_dir. The other fields keep their defaults.
SoftCncJob part_folder_job(const std::filesystem::path& part_dir,
                           const std::filesystem::path& out_dir,
                           const std::string& machine = "machine.json",
                           const std::string& program = "program.ngc");

// The options the wiring gives interp_planner for this job (run.ini's
// [KINS], START and SERVO_PERIOD_NS): what run_soft_cnc plans the program
// with to check the travel before it machines.
interp::PlannerOptions soft_cnc_planner_options(const SoftCncJob& job,
                                                const MachineDescription& machine);

// Called on the non-real-time side with the simulated time reached and the
// program's planned duration.
using SoftCncProgress = std::function<void(double time_s, double program_s)>;

// Checks the job, writes soft_cnc.hal and run.ini into job.out_dir, loads
// them and runs until the program ends. The HAL shuts down before this
// returns, so machined.stl, machined.ply and trace.csv are in out_dir.
// Throws, with nothing written (and out_dir not created): MachineDescriptionError
// (bad machine file), SoftCncInputError (bad program or tool table, a path
// outside the travel, or a component refusing the job, e.g. a bad part.json:
// the message names the file and key; the files written for it are removed
// again) and std::runtime_error.
SoftCncResult run_soft_cnc(const SoftCncJob& job, const SoftCncProgress& progress = {});

}  // namespace truecut::sim
