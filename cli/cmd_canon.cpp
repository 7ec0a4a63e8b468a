// truecut canon PROGRAM.ngc: print the canonical machining calls of a G-code
// program in the layout of LinuxCNC's standalone interpreter `rs274`.

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "output_spool.hpp"
#include "parameter_file_args.hpp"
#include "program_budget_args.hpp"
#include "quiet_option.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/operations.hpp"
#include "truecut/interp/planner.hpp"
#include "truecut/interp/rs274_format.hpp"

namespace truecut::cli {
namespace {

const char* kCanonHelp =
    "usage: truecut canon [options] PROGRAM.ngc\n"
    "\n"
    "Interprets an RS274/NGC program (LinuxCNC dialect plus the Sinumerik words\n"
    "TRAORI, TRAFOOF, BSPLINE, CSPLINE) and prints one canonical call per line,\n"
    "laid out like LinuxCNC's `rs274`, e.g.\n"
    "    7 N..... STRAIGHT_FEED(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)\n"
    "Positions are in the work coordinate system and the program's units.\n"
    "Errors are reported as file:line:column: message (exit code 2); nothing is\n"
    "printed on stdout for a program with an error.\n"
    "\n"
    "options:\n"
    "  --tool-table FILE   tool table in LinuxCNC format\n"
    "  --tool-units mm|inch  units of the tool table's offsets and diameters (default mm;\n"
    "                      LinuxCNC's are in [TRAJ]LINEAR_UNITS, rs274's without an INI in inch)\n";
const char* kCanonHelpOptions =
    "  --block-delete      skip lines starting with '/' (switch on)\n"
    "  --b-axis            accept B words (default: the X Y Z A C machine rejects them)\n"
    "  --decimals N        digits after the point (default 4, as rs274)\n"
    "  --annotate          append '; file:line op=NAME tool=T ...' to each call\n"
    "  --operation NAME    print only the moves of CAM operation NAME\n"
    "  --list-operations   print the operation names found in comments\n"
    "  --spline-report     for each BSPLINE/CSPLINE run: contour error Er against the\n"
    "                      programmed polyline before and after node insertion\n"
    "  --spline-tolerance MM  node insertion tolerance (default 0.025, the CAM tolerance)\n"
    "  --quiet             no progress on stderr (shown only on a terminal, after 1 s)\n"
    "  --help              this text\n";

std::string annotation(const std::vector<std::string>& files, const interp::CanonCall& c) {
  const auto& x = c.context;
  std::string s = "  ; " + files[x.file] + ":" + std::to_string(x.line);
  if (!x.operation.empty()) s += " op=" + x.operation;
  s += " tool=" + std::to_string(x.tool);
  if (x.feed_mode == interp::FeedMode::kInverseTime)
    s += " G93 F" + std::to_string(x.inverse_time_f);
  if (x.spline == interp::SplineMode::kBspline) s += " BSPLINE";
  if (x.spline == interp::SplineMode::kCspline) s += " CSPLINE";
  if (x.tcp) s += " TRAORI";
  return s;
}

int print_spline_report(const interp::CanonProgram& program, const ParsedArgs& a) {
  interp::PlannerOptions options;
  options.spline_tolerance_mm = a.number("spline-tolerance", 0.025, 1e-6, 10.0);
  const interp::Plan plan = interp::plan_program(program, options);
  if (plan.splines.empty()) {
    std::printf("no BSPLINE or CSPLINE runs in this program\n");
    return kExitOk;
  }
  std::printf("%6s %-8s %7s %9s %14s %14s %14s\n", "line", "mode", "points", "inserted",
              "Er before mm", "Er after mm", "tolerance mm");
  for (const auto& r : plan.splines)
    std::printf("%6d %-8s %7d %9d %14.6f %14.6f %14.6f%s\n", r.line,
                r.mode == interp::SplineMode::kBspline ? "BSPLINE" : "CSPLINE", r.points,
                r.nodes_inserted, r.error_before_mm, r.error_after_mm, r.tolerance_mm,
                r.within_tolerance() ? "" : "  NOT within tolerance");
  return kExitOk;
}

}  // namespace

int cmd_canon(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"tool-table", true},
                      {"tool-units", true},
                      {"var-file", true},
                      {"var-units", true},
                      {"block-delete", false},
                      {"b-axis", false},
                      {"decimals", true},
                      {"annotate", false},
                      {"operation", true},
                      {"list-operations", false},
                      {"spline-report", false},
                      {"spline-tolerance", true},
                      {"quiet", false},
                      {"max-blocks", true},
                      {"help", false}});
  if (a.flag("help")) {
    std::fputs(
        (std::string(kCanonHelp) + kVarFileHelp + kMaxBlocksHelp + kCanonHelpOptions).c_str(),
        stdout);
    return kExitOk;
  }
  if (a.positionals().size() != 1) throw UsageError("expected one PROGRAM.ngc file");
  const interp::LengthUnits tool_units = length_units_option(a, "tool-units");
  interp::FormatOptions format;
  format.decimals = static_cast<int>(a.integer("decimals", 4, 0, 12));

  // The calls are printed as they are made (into a spool, so a program
  // with an error prints nothing but the error) unless a report needs the
  // whole program: a program of any length in constant memory.
  const bool whole_program = a.flag("list-operations") || a.flag("spline-report");
  const auto only = a.value("operation");
  const bool annotate = a.flag("annotate");
  OutputSpool out;
  int n = 0;
  std::string line;
  interp::CanonProgram program;
  std::set<std::string> operations_seen;  // with --operation, to name a typo
  try {
    interp::InterpreterOptions options;
    if (auto t = a.value("tool-table")) options.tools = interp::ToolTable::load(*t, tool_units);
    if (auto p = parameter_file_from_args(a)) options.parameters = std::move(*p);
    options.block_delete = a.flag("block-delete");
    options.has_b = a.flag("b-axis");
    options.max_blocks = max_blocks_from_args(a);
    if (!whole_program)
      options.on_call = [&](const interp::CanonCall& call, const std::vector<std::string>& files) {
        if (only && operations_seen.size() < 100'000)
          operations_seen.insert(call.context.operation);
        if (only && (call.context.operation != *only || !interp::is_motion(call.op))) return;
        // rs274's columns: the call's number, then the block's N word as
        // written, padded to six characters, or "N....." without one.
        char counter[32];
        std::snprintf(counter, sizeof counter, "%5d N", ++n);
        line = counter;
        const std::string& digits = call.context.block_number;
        if (digits.empty())
          line += "..... ";
        else
          line += digits + std::string(digits.size() < 6 ? 6 - digits.size() : 0, ' ');
        line += interp::format_rs274(call.op, format);
        if (annotate) line += annotation(files, call);
        line += '\n';
        out.append(line);
      };
    // A long program shows the blocks it has run, on a terminal only, once
    // it has taken a second.
    const auto start = std::chrono::steady_clock::now();
    bool shown = false;
    if (progress_shown(a))
      options.progress = [&](std::int64_t blocks) {
        const double s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (s < 1.0) return;
        std::fprintf(stderr, "\rcanon: %lld blocks interpreted (%.0f s)",
                     static_cast<long long>(blocks), s);
        shown = true;
      };
    try {
      program = interp::Interpreter(std::move(options)).run_file(a.positionals()[0]);
    } catch (...) {
      if (shown) std::fputs("\n", stderr);
      throw;
    }
    if (shown) std::fputs("\n", stderr);
  } catch (const interp::GcodeError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitUsage;
  }

  // An operation the program does not have (a typo) would print nothing and
  // look like an operation without moves.
  if (whole_program)
    for (const auto& name : interp::operation_names(program))
      operations_seen.insert(name);
  if (only && !operations_seen.count(*only)) {
    std::string names;
    for (const auto& name : operations_seen)
      if (!name.empty()) names += (names.empty() ? "" : ", ") + name;
    std::fprintf(stderr, "truecut canon: %s has no operation '%s' (its operations: %s)\n",
                 a.positionals()[0].c_str(), only->c_str(),
                 names.empty() ? "none: no (OPERATION: NAME) comment" : names.c_str());
    return kExitUsage;
  }
  if (a.flag("list-operations")) {
    for (const auto& name : interp::operation_names(program))
      std::printf("%s\n", name.c_str());
    return kExitOk;
  }
  if (a.flag("spline-report")) return print_spline_report(program, a);
  out.write_to(stdout);
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{"canon", "print the canonical calls of a G-code program",
                                        cmd_canon, 20};
}  // namespace

}  // namespace truecut::cli
