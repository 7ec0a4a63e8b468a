// Benchmark parts: nominal geometry (a closed STL in the workpiece frame),
// the CAM program that machines it (LinuxCNC RS274/NGC plus TRAORI/TRAFOOF,
// operations named by `(OPERATION: NAME)` comments) and the metadata the
// compensation chain needs (surfaces, stock, tools), plus the machine each
// part is machined on (machine.json). See docs/parts.md.
#pragma once

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "truecut/offline/mesh.hpp"
#include "truecut/sim/drive_surface.hpp"
#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/part_metadata.hpp"

namespace truecut::sim {

enum class PartId { kImplant, kBenchmark004, kFreeform };

// Every part, in the order of the documentation.
inline constexpr std::array<PartId, 3> kAllParts = {PartId::kImplant, PartId::kBenchmark004,
                                                    PartId::kFreeform};

std::string_view part_name(PartId id);
std::optional<PartId> part_from_name(std::string_view name);

struct BenchmarkPart {
  PartId id = PartId::kImplant;
  PartOptions options;
  offline::TriangleMesh mesh;         // closed, outward normals, mm
  std::vector<int> triangle_surface;  // PartSurface::id of each triangle
  std::string program;                // program.ngc
  PartMetadata metadata;
};

// The PartOptions make_part takes (mm): each from kMinPartOptionMm up to
// its own maximum.
inline constexpr double kMinPartOptionMm = 0.001;
inline constexpr double kMaxMeshEdgeMm = 20.0;
inline constexpr double kMaxStepoverMm = 10.0;
inline constexpr double kMaxPointSpacingMm = 10.0;
inline constexpr double kMaxStepDownMm = 17.0;

// Deterministic: the same id and options give byte-identical outputs.
// Throws std::invalid_argument on a resolution outside those ranges.
BenchmarkPart make_part(PartId id, const PartOptions& options = {});
// The part with its program generated for the adapted geometry `drive`
// instead of the nominal (the nominal mesh and metadata are unchanged).
// Only benchmark004's generator can be driven so far: other parts throw
// std::invalid_argument naming the part.
BenchmarkPart make_part(PartId id, const PartOptions& options, const DriveSurface& drive);

// Tool table in LinuxCNC's format (`T1 P1 D2.000 Z30.000 ;...`).
std::string tool_table_text(const PartMetadata& metadata);
// part.json: metadata, options, per-triangle surface ids, mesh volume.
std::string part_json(const BenchmarkPart& part);

// The machine the part is machined on (docs/parts.md, "Machines"): the
// same 5-axis A/C table-table machine for every part — joint travels that
// contain the program, drives, nominal kinematics with the part's judged
// tool — and, switched on, the part's hidden physics (servo_lag,
// tool_radius_error, rotary_location on the 5-axis part).
MachineDescription part_machine(const BenchmarkPart& part);
// The same machine with every effect off: the model the controller believes.
MachineDescription part_machine_ideal(const BenchmarkPart& part);

// Writes nominal.stl (binary), program.ngc, tools.tbl, part.json,
// machine.json and machine_ideal.json into `dir` (created if missing). Each
// file is written to NAME.tmp and renamed.
void write_part(const BenchmarkPart& part, const std::filesystem::path& dir);

// The free-form surface of the `freeform` part: z = height(x, y) over
// x ∈ [-30, 30], y ∈ [-20, 20] (mm), and its upward unit normal.
double freeform_height_mm(double x_mm, double y_mm);
Eigen::Vector3d freeform_normal(double x_mm, double y_mm);

// Signed volume of a closed mesh (positive when the normals point outwards).
double signed_volume_mm3(const offline::TriangleMesh& mesh);

}  // namespace truecut::sim
