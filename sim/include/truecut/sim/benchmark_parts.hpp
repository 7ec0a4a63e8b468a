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
#include "truecut/sim/machine_description.hpp"

namespace truecut::sim {

enum class PartId { kImplant, kBenchmark004, kFreeform };

// Every part, in the order of the documentation.
inline constexpr std::array<PartId, 3> kAllParts = {PartId::kImplant, PartId::kBenchmark004,
                                                    PartId::kFreeform};

std::string_view part_name(PartId id);
std::optional<PartId> part_from_name(std::string_view name);

// Resolution of the generated mesh and tool paths. The defaults are the
// production settings; tests use coarser values.
struct PartOptions {
  double mesh_edge_mm = 0.5;      // longest edge of a grid cell on any face
  double stepover_mm = 0.5;       // distance between neighbouring passes
  double point_spacing_mm = 0.5;  // distance between points along a curved pass
  double step_down_mm = 1.0;      // axial depth per level (peripheral milling)
};

// Programmed positions are the tool tip: the point on the tool axis at the
// end of the tool (the flat bottom of an end mill, the lowest point of a ball
// mill), in the workpiece frame; TRAORI moves program it directly.
struct PartTool {
  int number = 0;
  std::string kind;  // "flat_end_mill", "ball_end_mill"
  double radius_mm = 0;
  double corner_radius_mm = 0;  // = radius_mm for a ball end mill
  double length_mm = 0;         // gauge point to tool tip (the tool table's Z)
  double flute_length_mm = 0;
  int flutes = 0;
  std::string comment;
};

struct PartSurface {
  int id = 0;
  std::string name;
  std::string kind;         // "plane", "cylinder", "sphere", "freeform"
  bool compensate = false;  // a surface the compensation and the CMM judge
};

struct PartOperation {
  std::string name;  // as in the `(OPERATION: NAME)` comment
  int tool = 0;
  std::string strategy;  // "face", "peripheral", "3-axis", "3+2", "5-axis"
  std::vector<int> surface_ids;
};

// The stock is the union of axis-aligned boxes (min/max corners).
struct StockBox {
  Eigen::Vector3d min_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d max_mm = Eigen::Vector3d::Zero();
};

struct PartMetadata {
  std::string name;
  std::string frame;  // how the workpiece frame sits on the part
  std::string material;
  std::vector<StockBox> stock;
  std::vector<PartTool> tools;
  std::vector<PartSurface> surfaces;
  std::vector<PartOperation> operations;
  // Rotary travel the program assumes (degrees); C is unlimited.
  double a_min_deg = -10.0;
  double a_max_deg = 110.0;
};

struct BenchmarkPart {
  PartId id = PartId::kImplant;
  PartOptions options;
  offline::TriangleMesh mesh;         // closed, outward normals, mm
  std::vector<int> triangle_surface;  // PartSurface::id of each triangle
  std::string program;                // program.ngc
  PartMetadata metadata;
};

// Deterministic: the same id and options give byte-identical outputs.
// Throws std::invalid_argument on a non-positive or absurd resolution.
BenchmarkPart make_part(PartId id, const PartOptions& options = {});

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
