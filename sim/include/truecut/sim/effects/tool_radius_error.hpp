// tool_radius_error: the real cutter's radius (and corner radius) differ
// from the ones the program was computed for. The spindle and the TCP do
// not move; the cutting stage removes material with the true tool
// (TrueTool in true_tool_pose.hpp), so every surface the tool's side or
// corner forms moves by the difference along its normal.
//
//   r_true   = r + Δr
//   r_c,true = r_true                 for a ball end mill (nominal r_c = r > 0)
//   r_c,true = r_c + Δr_c             otherwise (flat: r_c = 0, bull-nose)
//
// The model-adaptation source's concealed error — CAM told a tool 0.2 mm
// larger in diameter than the real one — is Δr = −0.1 mm.
#pragma once

namespace truecut::sim {

struct ToolRadiusErrorParams {
  double radius_mm = 0.0;         // Δr = real − nominal radius
  double corner_radius_mm = 0.0;  // Δr_c, not for a ball end mill (its corner follows Δr)
  bool operator==(const ToolRadiusErrorParams&) const = default;
};

}  // namespace truecut::sim
