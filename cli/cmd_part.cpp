// truecut part NAME --out DIR: write a benchmark part (nominal STL, CAM
// program, tool table, metadata, the machine it is machined on).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "quiet_option.hpp"
#include "stage_progress.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/offline/field_outputs.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/program_travel.hpp"

namespace truecut::cli {
namespace {

const char* kPartHelp =
    "usage: truecut part NAME --out DIR [options]\n"
    "\n"
    "Writes a benchmark part into DIR: nominal.stl (binary, mm, workpiece frame),\n"
    "program.ngc (CAM program, operations named in comments), tools.tbl (LinuxCNC\n"
    "tool table), part.json (stock, tools, surfaces, operations), machine.json (the\n"
    "machine with the part's hidden physics) and machine_ideal.json (the same\n"
    "machine, every effect off). Parts:\n"
    "  implant        1.6 mm square shaft, 17 mm cantilever, face (peripheral + face milling)\n"
    "  benchmark004   D100 x 55 mm stepped cylinder with a R20 hemisphere (end and ball\n"
    "                 mills, 3-axis and a 5-axis cap)\n"
    "  freeform       warped 60 x 40 mm surface, ball end mill, 3+2 and TRAORI 5-axis\n"
    "Geometry and operations: docs/parts.md.\n"
    "\n"
    "options:\n"
    "  --out DIR            output folder (created)\n"
    "  --mesh-edge MM       longest mesh edge (default 0.5; 0.001 to 20)\n"
    "  --max-triangles N    budget: refuse (exit 2) a --mesh-edge that would make more\n"
    "                       triangles (default 20000000)\n"
    "  --stepover MM        distance between passes (default 0.5; 0.001 to 10)\n"
    "  --point-spacing MM   distance between points along a curved pass (default 0.5;\n"
    "                       0.001 to 10)\n"
    "  --step-down MM       axial depth per level (default 1.0; 0.001 to 17)\n"
    "  --adapted MESH       generate the program for this adapted geometry (the\n"
    "                       adapted.stl of truecut field, made from this part's\n"
    "                       nominal with the same options): every finishing pass\n"
    "                       placed on the adapted surface, the model-adaptation\n"
    "                       route (benchmark004 only; nominal.stl stays the nominal)\n"
    "  --max-correction MM  with --adapted: refuse (exit 2) an adapted mesh whose vertices\n"
    "                       lie farther than this from the nominal's (default 0.2)\n"
    "  --quiet              no progress on stderr (shown only on a terminal, after 1 s)\n"
    "  --help               this text\n";

// The largest distance between a corner of a nominal facet and the same
// corner of the adapted mesh (the same facets in the same order).
double largest_vertex_move_mm(const offline::TriangleMesh& nominal,
                              const offline::TriangleMesh& adapted) {
  double largest = 0;
  for (std::size_t f = 0; f < nominal.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const double d = (adapted.vertices_mm[adapted.triangles[f][c]] -
                        nominal.vertices_mm[nominal.triangles[f][c]])
                           .norm();
      if (std::isnan(d)) return d;
      largest = std::max(largest, d);
    }
  return largest;
}

}  // namespace

int cmd_part(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"out", true},
                      {"mesh-edge", true},
                      {"max-triangles", true},
                      {"stepover", true},
                      {"point-spacing", true},
                      {"step-down", true},
                      {"adapted", true},
                      {"max-correction", true},
                      {"quiet", false},
                      {"help", false}});
  if (a.flag("help")) {
    std::fputs(kPartHelp, stdout);
    return kExitOk;
  }
  std::string known;
  for (sim::PartId p : sim::kAllParts)
    known += (known.empty() ? "" : ", ") + std::string(sim::part_name(p));
  if (a.positionals().size() != 1) throw UsageError("expected one part NAME (" + known + ")");
  const auto id = sim::part_from_name(a.positionals()[0]);
  if (!id) throw UsageError("unknown part '" + a.positionals()[0] + "' (" + known + ")");
  const auto out = a.value("out");
  if (!out) throw UsageError("--out DIR is required");
  sim::PartOptions opt;
  // The ranges PartOptions takes (benchmark_parts.hpp): a value outside
  // is exit 2 naming the option, not the library's exit 1.
  opt.mesh_edge_mm =
      a.number("mesh-edge", opt.mesh_edge_mm, sim::kMinPartOptionMm, sim::kMaxMeshEdgeMm);
  opt.stepover_mm =
      a.number("stepover", opt.stepover_mm, sim::kMinPartOptionMm, sim::kMaxStepoverMm);
  opt.point_spacing_mm = a.number("point-spacing", opt.point_spacing_mm, sim::kMinPartOptionMm,
                                  sim::kMaxPointSpacingMm);
  opt.step_down_mm =
      a.number("step-down", opt.step_down_mm, sim::kMinPartOptionMm, sim::kMaxStepDownMm);
  const double max_correction_mm =
      a.number("max-correction", offline::kFieldMaxCorrectionMm, 1e-6, 100.0);
  if (a.value("max-correction") && !a.value("adapted"))
    throw UsageError("--max-correction goes with --adapted");
  const double max_triangles = a.number("max-triangles", 20e6, 1.0, 1e12);
  // Budget: the triangle count grows as 1 / mesh-edge²; a mesh at 1 mm
  // (a fraction of a second) tells what the requested edge would give.
  constexpr double kProbeEdgeMm = 1.0;
  if (opt.mesh_edge_mm < kProbeEdgeMm) {
    sim::PartOptions probe = opt;
    probe.mesh_edge_mm = kProbeEdgeMm;
    const double estimate = double(sim::make_part(*id, probe).mesh.triangles.size()) *
                            (kProbeEdgeMm / opt.mesh_edge_mm) * (kProbeEdgeMm / opt.mesh_edge_mm);
    if (estimate > max_triangles)
      throw UsageError(rt::format_printf(
          "--mesh-edge %g mm would make about %.3g triangles (%.3g GB of STL), more than "
          "--max-triangles %.0f; choose a larger --mesh-edge or raise --max-triangles",
          opt.mesh_edge_mm, estimate, estimate * 50e-9, max_triangles));
  }
  std::optional<StageProgress> progress;
  progress.emplace("truecut part", progress_shown(a));
  progress->stage("building the mesh and the program");
  std::optional<sim::BenchmarkPart> driven;
  if (auto adapted_file = a.value("adapted")) {
    if (*id != sim::PartId::kBenchmark004)
      throw UsageError(
          "--adapted: only benchmark004's tool path can be driven by an adapted "
          "geometry so far");
    const sim::BenchmarkPart nominal = sim::make_part(*id, opt);
    // A bad mesh is an input error (exit 2), named by the reader.
    const auto input_error = [](const std::string& message) {
      std::fprintf(stderr, "truecut part: %s\n", message.c_str());
      return kExitUsage;
    };
    offline::TriangleMesh adapted;
    try {
      adapted = offline::read_mesh(*adapted_file);
    } catch (const std::exception& e) {
      return input_error(e.what());
    }
    if (adapted.triangles.size() != nominal.mesh.triangles.size())
      return input_error(rt::format_printf(
          "%s: %zu facets, but the nominal of %s at --mesh-edge %g has %zu: the adapted geometry "
          "must come from this nominal (give the --mesh-edge it was made with)",
          adapted_file->c_str(), adapted.triangles.size(), a.positionals()[0].c_str(),
          opt.mesh_edge_mm, nominal.mesh.triangles.size()));
    const double moved_mm = largest_vertex_move_mm(nominal.mesh, adapted);
    if (!(moved_mm <= max_correction_mm))
      return input_error(rt::format_printf(
          "%s moves the nominal's surface by up to %.4g mm, more than --max-correction %g mm: "
          "an adapted geometry is the nominal moved by its compensation (truecut field keeps "
          "that within its own --max-correction); a wrong file or unit?",
          adapted_file->c_str(), moved_mm, max_correction_mm));
    const sim::DriveSurface drive(nominal.mesh, adapted);
    driven = sim::make_part(*id, opt, drive);
    std::printf("program driven by %s: %zu surface queries, %zu found no facet (offset 0)\n",
                adapted_file->c_str(), drive.queries(), drive.misses());
    if (2 * drive.misses() > drive.queries())
      return input_error(rt::format_printf(
          "%s: %zu of the %zu surface queries (%.0f %%) found no facet within %g mm of the "
          "nominal surface: the program would follow the nominal there; the adapted geometry "
          "does not fit this part",
          adapted_file->c_str(), drive.misses(), drive.queries(),
          100.0 * double(drive.misses()) / double(drive.queries()), sim::DriveSurface::kReachMm));
  }
  const sim::BenchmarkPart part = driven ? std::move(*driven) : sim::make_part(*id, opt);
  progress->stage("checking the program against the travel");
  // The program must stay inside the travel of its machine; a part that does
  // not is a generator bug, reported before anything is written.
  interp::InterpreterOptions io;
  io.tools = interp::ToolTable::parse(sim::tool_table_text(part.metadata), "tools.tbl");
  const sim::MachineDescription machine = sim::part_machine(part);
  const sim::ProgramTravel travel =
      sim::program_travel(interp::Interpreter(io).run_text(part.program, "program.ngc"),
                          machine.machine, "program.ngc");
  if (!travel.inside()) {
    progress.reset();
    std::fprintf(stderr, "truecut part: %s\n", travel.first_excursion->message.c_str());
    return kExitFailure;
  }
  progress->stage("writing the files");
  sim::write_part(part, *out);
  progress.reset();
  std::printf(
      "%s: %zu triangles, %zu program lines -> "
      "%s/{nominal.stl,program.ngc,tools.tbl,part.json,machine.json,machine_ideal.json}\n",
      std::string(sim::part_name(*id)).c_str(), part.mesh.triangles.size(),
      static_cast<size_t>(std::count(part.program.begin(), part.program.end(), '\n')),
      out->c_str());
  std::printf("joints over the program (inside machine.json's travel):");
  for (int j = 0; j < sim::kJointCount; ++j) {
    std::printf(" %c %.1f..%.1f", "XYZAC"[j], travel.min[j], travel.max[j]);
  }
  std::printf("\n");
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{
    "part", "write a benchmark part: nominal STL, CAM program, tools", cmd_part, 5};
}  // namespace

}  // namespace truecut::cli
