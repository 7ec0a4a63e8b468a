// `truecut run MACHINE.json PROGRAM.ngc`: the soft-CNC loop of the simulated
// machine, wired by the shipped sim/hal/soft_cnc.hal.
#pragma once

#include <string>
#include <vector>

namespace truecut::cli {

int run_machine(const std::vector<std::string>& argv);

}  // namespace truecut::cli
