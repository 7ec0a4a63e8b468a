// Options, output refusals and steps that `truecut scan`, `truecut cmm` and
// `truecut run --scan/--cmm` share. The same options carry a prefix in
// `truecut run` (`--scan-sigma-um` for scan's `--sigma-um`).
#pragma once

#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

#include "args.hpp"
#include "truecut/offline/mesh.hpp"
#include "truecut/sim/measure/cmm.hpp"
#include "truecut/sim/measure/scanner.hpp"

namespace truecut::cli {

// Outputs are written to NAME.tmp and renamed: never over a device, FIFO or
// folder. UsageError "FILE: exists and is not a regular file; not replaced".
void require_replaceable(const std::string& file);

// true when FILE ends in one of `extensions` (lower-case, with the dot) and
// the mesh writers know the format.
bool has_extension(const std::string& file, std::initializer_list<const char*> extensions);

// --- scanner ---------------------------------------------------------------
struct ScanSettings {
  sim::measure::ScannerOptions options;
  std::string mode = "fringe";    // fringe | laser
  std::string sigma_text = "20";  // as given, for the file comment
  double registration_error_mm = 0;
  double registration_error_deg = 0;
};

// --PREFIXsigma-um, density, mode, max-incidence-deg, registration-error-mm,
// registration-error-deg, seed, normals.
std::vector<OptionSpec> scan_option_specs(const std::string& prefix);
// Parses them (UsageError on a bad value).
ScanSettings scan_settings(const ParsedArgs& a, const std::string& prefix);
// The scan of `mesh` (registration error about the mesh's box centre,
// progress on stderr). Throws std::invalid_argument for an unusable mesh.
sim::measure::ScanResult scan_mesh(const offline::TriangleMesh& mesh, ScanSettings& settings);
// The comment written into the point cloud file.
std::string scan_comment(const ScanSettings& settings);

// --- CMM -------------------------------------------------------------------
struct CmmSettings {
  sim::measure::CmmOptions options;
  double spacing_mm = 1.0;
  std::vector<std::int32_t> surfaces;  // empty: part.json's compensated surfaces
};

// --PREFIXsigma-um, search-mm, seed, spacing, surfaces.
std::vector<OptionSpec> cmm_option_specs(const std::string& prefix);
CmmSettings cmm_settings(const ParsedArgs& a, const std::string& prefix);

// An input that does not fit (part.json for another mesh, an unknown
// surface, no points): exit 2.
struct MeasureInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Nominal points on the selected surfaces of NOMINAL (ids from part.json).
// Throws MeasureInputError, offline::MeshIoError or sim::PartFileError.
std::vector<sim::measure::CmmPoint> cmm_points_on_part(const std::string& nominal_file,
                                                       const std::string& part_file,
                                                       const CmmSettings& settings);

// The per-surface table and the overall row, on stdout, with `indent`.
void print_cmm_table(const std::vector<sim::measure::CmmMeasurement>& measurements,
                     const char* indent = "");

}  // namespace truecut::cli
