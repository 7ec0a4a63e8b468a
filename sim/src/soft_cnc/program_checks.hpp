// The checks of a soft-CNC job's program before it is machined (besides the
// travel check, program_travel.hpp): positions no machine reaches, a
// planned duration beyond the job's budget, the tools it cuts with against
// the correction field, part.json and the tool table. Each throws
// SoftCncInputError naming the file and line or key.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/planner.hpp"
#include "truecut/interp/tool_table.hpp"

namespace truecut::sim::soft_cnc {

// Positions of X, Y, Z beyond ±1e5 mm or not finite (a move to X 1e300 was
// reported as "leaves travel at -nan mm"), before anything is planned.
void check_program_positions(const interp::CanonProgram& program);

// Before planning, a lower bound of the duration (dwells, and feed moves at
// their programmed feed, arcs with all their turns) against `max_s`: an arc
// of 1e8 turns was planned as 1.9 s and then sampled for minutes by the
// travel check.
void check_program_time_bound(const interp::CanonProgram& program,
                              const std::array<double, 5>& start_joints, double max_s);

// The planned duration against `max_s`: refused at the line where the plan
// passes it (G4 P100000 or F0.000001 ran for hours before).
void check_planned_time(const interp::Plan& plan, const std::string& program_name, double max_s);

// The tools (> 0) the program feeds with while the spindle turns, each with
// the first line it cuts at.
std::map<int32_t, int32_t> cutting_tools(const interp::CanonProgram& program);

// The correction field must have a layer for each of them.
void check_field_layers(const std::filesystem::path& field, const std::map<int32_t, int32_t>& tools,
                        const std::string& program_name);

// part.json must be plausible (part_plausibility.hpp), list each of them,
// and give the radius the tool table's diameter gives (within its 0.001 mm).
void check_part_tools(const std::filesystem::path& part, const std::filesystem::path& tool_table,
                      const interp::ToolTable& table, const std::map<int32_t, int32_t>& tools,
                      const std::string& program_name);

}  // namespace truecut::sim::soft_cnc
