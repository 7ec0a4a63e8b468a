// Named access to the fitted parameters of the machine description's
// effects: the diagnosis fits parameters by their description keys.
#pragma once

#include <string>

#include "truecut/sim/machine_description.hpp"

namespace truecut::analysis::diagnosis {

// Switches `effect` on for `joint` (-1 for the global effects), creating
// the joint's entry with neutral values when it has none.
void enable_effect(sim::MachineParams& params, const std::string& effect, int joint);
// Removes the joint's entry (or switches a global effect off).
void disable_effect(sim::MachineParams& params, const std::string& effect, int joint);
// The parameter `key` of the (enabled) effect; null when unknown.
double* param_ptr(sim::MachineParams& params, const std::string& effect, int joint,
                  const std::string& key);
// Keeps a parameter inside its physical range.
double clamp_param(const std::string& key, double value);
// A finite-difference step for the parameter at `value`.
double param_step(const std::string& key, double value);
// The key of the joint-unit parameters: play_mm / play_deg, coulomb_n / coulomb_nm.
std::string play_key(int joint);
std::string coulomb_key(int joint);

// What motion or measurement tells two candidates apart ("effect" names).
std::string separation_hint(const std::string& a, const std::string& b);

}  // namespace truecut::analysis::diagnosis
