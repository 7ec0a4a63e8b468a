// What part.json holds besides the mesh (docs/parts.md): resolution options,
// stock, tools, surfaces, operations and rotary travel of a benchmark part.
// Free of the mesh and machine types so that small readers (the tool_geometry
// component) can use it.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace truecut::sim {

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

}  // namespace truecut::sim
