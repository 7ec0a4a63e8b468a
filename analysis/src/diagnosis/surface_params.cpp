// The parameters surface mode fits, as nudges of the machine description.
#include "surface_params.hpp"

#include <cmath>

namespace truecut::analysis::diagnosis {

namespace {

// Compliance 1/k (µm/N) of a deflection effect; 0 when off.
double compliance(bool enabled, double stiffness) {
  return enabled && stiffness > 0 ? 1.0 / stiffness : 0.0;
}

}  // namespace

std::vector<SurfaceParam> surface_params(const sim::MachineParams& believed, bool five_axis) {
  std::vector<SurfaceParam> p;
  const sim::Effects& e = believed.effects;
  p.push_back({"tool_radius_error", "", "radius_mm", 0.02,
               e.tool_radius_error.enabled ? e.tool_radius_error.params.radius_mm : 0.0, false});
  p.push_back({"tool_length_error", "", "length_mm", 0.02,
               e.tool_length_error.enabled ? e.tool_length_error.params.length_mm : 0.0, false});
  if (five_axis) {
    const auto& a = e.rotary_location.params.a;
    const auto& c = e.rotary_location.params.c;
    const bool on = e.rotary_location.enabled;
    p.push_back({"rotary_location", "", "a.e_y0a_um", 20.0, on ? a.e_y0a_um : 0.0, false});
    p.push_back({"rotary_location", "", "a.e_z0a_um", 20.0, on ? a.e_z0a_um : 0.0, false});
    p.push_back({"rotary_location", "", "c.e_x0c_um", 20.0, on ? c.e_x0c_um : 0.0, false});
    p.push_back({"rotary_location", "", "c.e_y0c_um", 20.0, on ? c.e_y0c_um : 0.0, false});
  }
  {
    const double c0 =
        compliance(e.tool_deflection.enabled, e.tool_deflection.params.stiffness_n_per_um);
    p.push_back({"tool_deflection", "", "stiffness_n_per_um", c0 > 0 ? 0.3 * c0 : 5.0, c0, true});
  }
  {
    const double c0 = compliance(e.workpiece_deflection.enabled,
                                 e.workpiece_deflection.params.stiffness_n_per_um);
    p.push_back(
        {"workpiece_deflection", "", "stiffness_n_per_um", c0 > 0 ? 0.3 * c0 : 5.0, c0, true});
  }
  const double sq_step = 200.0;
  p.push_back({"squareness", "xy", "xy_urad", sq_step,
               e.squareness.enabled ? e.squareness.params.xy_urad : 0.0, false});
  p.push_back({"squareness", "yz", "yz_urad", sq_step,
               e.squareness.enabled ? e.squareness.params.yz_urad : 0.0, false});
  p.push_back({"squareness", "zx", "zx_urad", sq_step,
               e.squareness.enabled ? e.squareness.params.zx_urad : 0.0, false});
  return p;
}

void set_surface_param(sim::MachineParams& m, const SurfaceParam& p, double value,
                       const WorkpieceGeometry& geometry) {
  sim::Effects& e = m.effects;
  if (p.effect == "tool_radius_error") {
    e.tool_radius_error.enabled = true;
    e.tool_radius_error.params.radius_mm = value;
  } else if (p.effect == "tool_length_error") {
    e.tool_length_error.enabled = true;
    e.tool_length_error.params.length_mm = value;
  } else if (p.effect == "rotary_location") {
    e.rotary_location.enabled = true;
    auto& a = e.rotary_location.params.a;
    auto& c = e.rotary_location.params.c;
    if (p.key == "a.e_y0a_um") a.e_y0a_um = value;
    if (p.key == "a.e_z0a_um") a.e_z0a_um = value;
    if (p.key == "c.e_x0c_um") c.e_x0c_um = value;
    if (p.key == "c.e_y0c_um") c.e_y0c_um = value;
  } else if (p.effect == "tool_deflection") {
    e.tool_deflection.enabled = value > 0;
    if (value > 0) e.tool_deflection.params.stiffness_n_per_um = 1.0 / value;
  } else if (p.effect == "workpiece_deflection") {
    if (!e.workpiece_deflection.enabled &&
        e.workpiece_deflection.params == sim::WorkpieceDeflectionParams{}) {
      e.workpiece_deflection.params.clamp_point_mm = geometry.clamp_point_mm;
      e.workpiece_deflection.params.axis = {0.0, 0.0, 1.0};
      e.workpiece_deflection.params.reference_length_mm = geometry.reference_length_mm;
    }
    e.workpiece_deflection.enabled = value > 0;
    if (value > 0) e.workpiece_deflection.params.stiffness_n_per_um = 1.0 / value;
  } else if (p.effect == "squareness") {
    e.squareness.enabled = true;
    if (p.key == "xy_urad") e.squareness.params.xy_urad = value;
    if (p.key == "yz_urad") e.squareness.params.yz_urad = value;
    if (p.key == "zx_urad") e.squareness.params.zx_urad = value;
  }
}

std::string surface_group(const SurfaceParam& p) {
  return p.axis.empty() ? p.effect : p.effect + ":" + p.axis;
}

}  // namespace truecut::analysis::diagnosis
