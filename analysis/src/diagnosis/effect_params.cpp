#include "effect_params.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace truecut::analysis::diagnosis {

std::string play_key(int joint) {
  return sim::joint_kind(joint) == sim::JointKind::kLinear ? "play_mm" : "play_deg";
}
std::string coulomb_key(int joint) {
  return sim::joint_kind(joint) == sim::JointKind::kLinear ? "coulomb_n" : "coulomb_nm";
}

void enable_effect(sim::MachineParams& p, const std::string& effect, int j) {
  sim::Effects& fx = p.effects;
  if (effect == "servo_lag") {
    fx.servo_lag.enabled = true;
    if (!fx.servo_lag.axes[j]) fx.servo_lag.axes[j] = sim::ServoLagAxis{30.0, 0.0};
  } else if (effect == "backlash") {
    fx.backlash.enabled = true;
    if (!fx.backlash.axes[j]) fx.backlash.axes[j] = sim::BacklashAxis{0.0};
  } else if (effect == "reversal_spike") {
    fx.reversal_spike.enabled = true;
    if (!fx.reversal_spike.axes[j]) fx.reversal_spike.axes[j] = sim::ReversalSpikeAxis{0.0, 0.0};
  } else if (effect == "pitch_error") {
    fx.pitch_error.enabled = true;
    if (!fx.pitch_error.axes[j]) fx.pitch_error.axes[j] = sim::PitchErrorAxis{};
  } else if (effect == "thermal_drift") {
    fx.thermal_drift.enabled = true;
    if (!fx.thermal_drift.axes[j]) {
      sim::ThermalDriftAxis t;
      t.gain_mm = 0.0;
      fx.thermal_drift.axes[j] = t;
    }
  } else if (effect == "squareness") {
    fx.squareness.enabled = true;
  } else if (effect == "straightness") {
    fx.straightness.enabled = true;
  }
}

void disable_effect(sim::MachineParams& p, const std::string& effect, int j) {
  sim::Effects& fx = p.effects;
  auto drop = [j](auto& e) {
    e.axes[j].reset();
    e.enabled = std::any_of(e.axes.begin(), e.axes.end(), [](const auto& a) { return bool(a); });
  };
  if (effect == "servo_lag") drop(fx.servo_lag);
  if (effect == "backlash") drop(fx.backlash);
  if (effect == "reversal_spike") drop(fx.reversal_spike);
  if (effect == "pitch_error") drop(fx.pitch_error);
  if (effect == "thermal_drift") drop(fx.thermal_drift);
  if (effect == "squareness") fx.squareness.enabled = false;
  if (effect == "straightness") fx.straightness.enabled = false;
}

double* param_ptr(sim::MachineParams& p, const std::string& effect, int j, const std::string& key) {
  sim::Effects& fx = p.effects;
  if (effect == "squareness") {
    if (key == "xy_urad") return &fx.squareness.params.xy_urad;
    if (key == "yz_urad") return &fx.squareness.params.yz_urad;
    if (key == "zx_urad") return &fx.squareness.params.zx_urad;
    return nullptr;
  }
  if (effect == "straightness") {
    // "eyx.quadratic_um_per_m2", "eyx.cubic_um_per_m3", "eyx.reference_mm"
    const auto dot = key.find('.');
    if (dot == std::string::npos) return nullptr;
    for (int i = 0; i < sim::kStraightnessCount; ++i) {
      auto& c = fx.straightness.params.components[i];
      if (key.compare(0, dot, sim::kStraightnessNames[i]) != 0 || !c) continue;
      if (key.substr(dot + 1) == "quadratic_um_per_m2") return &c->quadratic_um_per_m2;
      if (key.substr(dot + 1) == "cubic_um_per_m3") return &c->cubic_um_per_m3;
      if (key.substr(dot + 1) == "reference_mm") return &c->reference_mm;
    }
    return nullptr;
  }
  if (j < 0 || j >= sim::kJointCount) return nullptr;
  if (effect == "servo_lag" && fx.servo_lag.axes[j]) {
    auto& a = *fx.servo_lag.axes[j];
    if (key == "kv_per_s") return &a.kv_per_s;
    if (key == "ff1") return &a.ff1;
  }
  if (effect == "backlash" && fx.backlash.axes[j] && key == play_key(j))
    return &fx.backlash.axes[j]->play;
  if (effect == "reversal_spike" && fx.reversal_spike.axes[j] && key == coulomb_key(j))
    return &fx.reversal_spike.axes[j]->coulomb;
  if (effect == "pitch_error" && fx.pitch_error.axes[j]) {
    auto& a = *fx.pitch_error.axes[j];
    if (key == "scale_um_per_m") return &a.scale_um_per_m;
    if (key == "reference_mm") return &a.reference_mm;
    if (key == "periodic_amplitude_um") return &a.periodic_amplitude_um;
    if (key == "periodic_period_mm") return &a.periodic_period_mm;
    if (key == "periodic_phase_deg") return &a.periodic_phase_deg;
  }
  if (effect == "thermal_drift" && fx.thermal_drift.axes[j]) {
    auto& a = *fx.thermal_drift.axes[j];
    if (key == "gain_mm") return &a.gain_mm;
    if (key == "tau_s") return &a.tau_s;
  }
  return nullptr;
}

double clamp_param(const std::string& key, double v) {
  if (key == "kv_per_s") return std::clamp(v, 0.5, 1000.0);
  if (key == "ff1") return std::clamp(v, 0.0, 1.5);
  if (key == "tau_s") return std::max(v, 1e-3);
  if (key == "periodic_period_mm") return std::max(v, 0.01);
  if (key.rfind("play_", 0) == 0 || key.rfind("coulomb_", 0) == 0) return std::max(v, 0.0);
  return v;
}

double param_step(const std::string& key, double v) {
  const double a = std::abs(v);
  if (key == "kv_per_s") return std::max(1e-3 * a, 1e-3);
  if (key == "ff1") return 1e-3;
  if (key.rfind("play_", 0) == 0) return std::max(1e-3 * a, 1e-5);
  if (key.rfind("coulomb_", 0) == 0) return std::max(1e-2 * a, 0.5);
  if (key == "scale_um_per_m") return std::max(1e-3 * a, 0.1);
  if (key == "periodic_amplitude_um") return std::max(1e-3 * a, 0.02);
  if (key == "periodic_phase_deg") return 0.2;
  if (key == "periodic_period_mm") return std::max(1e-4 * a, 1e-5);
  if (key == "gain_mm") return std::max(1e-3 * a, 1e-5);
  if (key == "tau_s") return std::max(1e-3 * a, 1e-3);
  if (key.find("quadratic_um_per_m2") != std::string::npos ||
      key.find("cubic_um_per_m3") != std::string::npos)
    return std::max(1e-3 * a, 1.0);
  return std::max(1e-3 * a, 0.1);  // µrad
}

std::string separation_hint(const std::string& a, const std::string& b) {
  auto has = [&](const char* x, const char* y) { return (a == x && b == y) || (a == y && b == x); };
  if (has("backlash", "reversal_spike"))
    return "a dwell after each reversal separates them: backlash stays as a step of b while the "
           "axis stands still, the friction spike decays";
  if (has("logging_delay", "servo_lag"))
    return "a step command or a sharp reversal, or a dwell after a move: a logging delay shifts "
           "the whole response, a servo lag rounds it and settles exponentially with 1/Kv";
  if (has("servo_lag", "backlash"))
    return "moves at two different feeds: servo lag scales with the speed, backlash does not";
  if (has("straightness", "squareness") || has("straightness", "pitch_error"))
    return "moves of the axis at several fixed positions of the other axes, and travel "
           "covering more of the axis: a bow is quadratic, squareness and pitch are linear";
  if (has("squareness", "servo_lag"))
    return "the same path run at two feeds (a lag scales with the speed, squareness with the "
           "position) or an external measurement of the true position (_meas)";
  if (has("tool_length_error", "rotary_location"))
    return "measurements at two or more A angles: a tool-length error moves along the tool "
           "axis, which turns with A; an A-axis-line offset moves with the table";
  if (has("pitch_error", "squareness"))
    return "moves of one axis with the other axis at several fixed positions";
  if (has("pitch_error", "thermal_drift"))
    return "repeated moves over the same positions spread over time (or a warm-up at standstill)";
  if (has("thermal_drift", "squareness") || has("thermal_drift", "servo_lag"))
    return "repeating the same path at the start and at the end of the recording";
  if (has("pitch_error", "servo_lag"))
    return "the same positions approached at different speeds and at standstill";
  return "a path that moves the two signatures independently (other speeds, other positions, "
         "dwells)";
}

}  // namespace truecut::analysis::diagnosis
