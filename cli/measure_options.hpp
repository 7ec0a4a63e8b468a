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

// Refuse (UsageError, before any work) an output that could not be written
// at the end: --OPTION DIR that exists and is not a folder, or in which (or,
// when it does not exist yet, in whose nearest existing parent) no file can
// be created (a read-only place, /proc). A probe file is created and removed
// at once; nothing stays behind.
void require_writable_folder(const std::string& option, const std::string& dir);
// The same for the folder that --OPTION FILE is written in.
void require_writable_file(const std::string& option, const std::string& file);

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
  bool show_progress = false;  // "scan: pose i/n" on stderr
};

// --PREFIXsigma-um, density, mode, max-incidence-deg, registration-error-mm,
// registration-error-deg, seed, normals.
std::vector<OptionSpec> scan_option_specs(const std::string& prefix);
// Parses them (UsageError on a bad value).
ScanSettings scan_settings(const ParsedArgs& a, const std::string& prefix);
// The scan of `mesh` (registration error about the mesh's box centre,
// progress on stderr when settings.show_progress). Throws std::invalid_argument for an unusable
// mesh.
sim::measure::ScanResult scan_mesh(const offline::TriangleMesh& mesh, ScanSettings& settings);
// The comment written into the point cloud file.
std::string scan_comment(const ScanSettings& settings);

// --- CMM -------------------------------------------------------------------
struct CmmSettings {
  sim::measure::CmmOptions options;
  double spacing_mm = 1.0;
  std::vector<std::int32_t> surfaces;  // empty: part.json's compensated surfaces
  // Budget: a sampling or point list of more probes is refused before any
  // is made (each costs about 0.5 KB: two rays, their hits, the result).
  double max_points = 2e6;
  std::string prefix;  // of the options, for messages ("cmm-" in truecut run)
};

// --PREFIXsigma-um, search-mm, seed, spacing, surfaces, max-points.
std::vector<OptionSpec> cmm_option_specs(const std::string& prefix);
CmmSettings cmm_settings(const ParsedArgs& a, const std::string& prefix);

// An input that does not fit (part.json for another mesh, an unknown
// surface, no points): exit 2.
struct MeasureInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Nominal points on the selected surfaces of NOMINAL (ids from part.json).
// Throws MeasureInputError (also when the sampling would make more than
// settings.max_points probes, estimated from the surfaces' area before any
// is made), offline::MeshIoError or sim::PartFileError.
std::vector<sim::measure::CmmPoint> cmm_points_on_part(const std::string& nominal_file,
                                                       const std::string& part_file,
                                                       const CmmSettings& settings);

// Throws MeasureInputError when `points` probes exceed settings.max_points.
void check_probe_budget(std::size_t points, const std::string& source, const CmmSettings& settings);

// Whether some probe found the surface. A report in which every probe
// failed is a failed measurement, not a perfect part: when none did, says so
// on stderr ("COMMAND: none of the N points found the surface of MESH within
// D mm along its normal: no measurement, NOT_WRITTEN (HINT)").
bool some_probe_found_the_surface(const std::vector<sim::measure::CmmMeasurement>& measurements,
                                  const std::string& command, const std::string& mesh_file,
                                  double search_mm, const std::string& not_written,
                                  const std::string& hint);

// The per-surface table and the overall row, on stdout, with `indent`; a
// row without a valid point shows "-" (no measurement), not 0.00.
void print_cmm_table(const std::vector<sim::measure::CmmMeasurement>& measurements,
                     const char* indent = "");

}  // namespace truecut::cli
