// One builder per benchmark part (internal to the parts generator).
#pragma once

#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/drive_surface.hpp"

namespace truecut::sim::parts {

class ProgramWriter;

BenchmarkPart make_implant(const PartOptions& options);
// drive: the passes follow this adapted geometry instead of the nominal.
BenchmarkPart make_benchmark004(const PartOptions& options, const DriveSurface* drive = nullptr);
BenchmarkPart make_freeform(const PartOptions& options);

// Program preamble (units, plane, modes) and tool change with length offset.
void start_program(ProgramWriter& w, const PartMetadata& m);
void change_tool(ProgramWriter& w, const PartTool& tool, double rpm);
void end_program(ProgramWriter& w);

}  // namespace truecut::sim::parts
