// `truecut run MACHINE PROGRAM --scan FILE --cmm FILE`: the machined part
// measured right after the run, with the virtual scanner (as `truecut scan`)
// and the virtual CMM (as `truecut cmm --nominal --part`).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "args.hpp"
#include "measure_options.hpp"

namespace truecut::cli {

struct RunMeasurement {
  std::optional<std::filesystem::path> scan_file;  // point cloud
  std::optional<std::filesystem::path> cmm_file;   // cmm.csv
  ScanSettings scan;
  CmmSettings cmm;
  std::vector<sim::measure::CmmPoint> cmm_points;  // on the nominal part
  bool show_progress = false;                      // on a terminal, without --quiet
};

// --scan, --cmm and their --scan-*/--cmm-* options.
std::vector<OptionSpec> run_measure_option_specs();

// Everything checked before the run, so that a bad option or input is exit 2
// with nothing written: option values, output names (inside out_dir: no
// absolute path, no '..'; never a run output, one of `inputs`, a device or
// FIFO), the CMM's points from `nominal` and `part`. Throws UsageError.
RunMeasurement prepare_run_measurement(const ParsedArgs& a, const std::filesystem::path& out_dir,
                                       const std::filesystem::path& nominal,
                                       const std::filesystem::path& part,
                                       const std::vector<std::filesystem::path>& inputs);

// After the run: scans and/or probes `machined_stl`, writes the files and
// prints a summary. Returns false (message on stderr) when the scanner
// measured no point.
bool measure_machined_part(RunMeasurement& m, const std::filesystem::path& machined_stl);

}  // namespace truecut::cli
