// Tool-centre placement (docs/offline.md, "Tool-centre placement"): for each
// compensation point and each tool, the tool path sample at which that tool
// cuts the point, so that the point's compensation can be stored in the
// tool's field layer where the controller looks it up — at the programmed
// point (the tool tip, the TCP the interpolator hands to the compensation
// component), not at the contact point on the part.
//
// Cutter: a torus-ended cylinder about the tool axis — radius R, corner
// radius r (0: flat end mill, R: ball end mill, between: bull nose), cutting
// length L from the tip. It is the set of points within r of its core, a
// solid cylinder of radius R − r from r to L above the tip, so its signed
// distance is the distance to the core minus r (exact inside and outside).
//
// A sample cuts the point P (nominal normal n) when P lies within
// contact_tolerance_mm of the cutter surface and the cutter's outward normal
// at the nearest surface point is within max_normal_angle_deg of −n (the
// tool touches the face from outside the material). Of all samples of a tool
// that cut P, the one that comes closest (smallest |distance|) is taken — the
// pass that generated the surface there; samples within tie_mm of the
// closest count as equally close. By default (every_generating_pass) the
// point goes to every pass (run of consecutive samples) that reaches it as
// deep as the closest, taking in each pass the sample whose tip is nearest to
// the point: a wall cut in several levels by a long flank is re-cut by every
// level below its own, and the deepest of those levels' corrections sets it
// (docs/offline.md). Without it, the earliest in the program wins (the level
// whose tip lies just below the point).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

#include "truecut/offline/tool_path.hpp"

namespace truecut::offline {

struct ToolShape {
  std::int32_t tool = 0;
  double radius_mm = 0.0;          // R > 0
  double corner_radius_mm = 0.0;   // r in [0, R]
  double cutting_length_mm = 0.0;  // L ≥ r: how far up the axis the tool cuts
};

struct PlacementOptions {
  double contact_tolerance_mm = 0.05;
  double max_normal_angle_deg = 45.0;
  double tie_mm = 1e-3;
  bool every_generating_pass = true;
};

// Signed distance of p from the cutter surface at (tip, unit axis): negative
// inside the cutter; normal = the cutter's outward unit normal at the nearest
// surface point.
struct CutterDistance {
  double distance_mm = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};
CutterDistance cutter_distance(const ToolShape& shape, const Eigen::Vector3d& tip_mm,
                               const Eigen::Vector3d& axis, const Eigen::Vector3d& p_mm);

struct PointPlacement {
  std::uint32_t point = 0;                           // compensation point index
  std::uint32_t sample = 0;                          // ToolPath::samples index
  Eigen::Vector3d tcp_mm = Eigen::Vector3d::Zero();  // the sample's tip: where the layer holds it
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double distance_mm = 0.0;  // cutter distance at that sample (≈ 0 for a finishing pass)
};

struct ToolPlacement {
  std::int32_t tool = 0;
  // Ascending point index; with every_generating_pass a point may appear
  // once per pass, in program order.
  std::vector<PointPlacement> points;
};

struct PlacementResult {
  std::vector<ToolPlacement> tools;  // ascending tool number: every tool with cutting samples
  std::vector<std::uint8_t> cut;     // per point: 1 when some tool cuts it
  std::int64_t uncut_points = 0;
};

// positions/normals: the compensation points (unit normals). Throws
// std::invalid_argument for mismatched sizes, bad options or shapes, or a
// tool on the path without a shape. Deterministic; parallel inside.
PlacementResult place_at_tool_centre(std::span<const Eigen::Vector3d> positions_mm,
                                     std::span<const Eigen::Vector3d> normals, const ToolPath& path,
                                     std::span<const ToolShape> shapes,
                                     const PlacementOptions& options = {});

}  // namespace truecut::offline
