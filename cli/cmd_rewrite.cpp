// truecut rewrite IN.ngc --matrix COMP.csv | --field FIELD.tcf --operation NAME ...:
// the G-code rewriting fallback (docs/rewrite.md).
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "parameter_file_args.hpp"
#include "program_budget_args.hpp"
#include "quiet_option.hpp"
#include "stage_progress.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/rewrite.hpp"
#include "truecut/interp/sha256.hpp"
#include "truecut/offline/field_outputs.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/rt/input_file.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;

const char* kRewriteHelp =
    "usage: truecut rewrite IN.ngc (--matrix COMP.csv | --field FIELD.tcf) --operation NAME\n"
    "                       --type peripheral|face|ball --tools TOOLS.tbl --out OUT.ngc [options]\n"
    "\n"
    "Writes the compensation into the program, for controllers that cannot run the\n"
    "real-time module: the moves of operation NAME are densified to --step, each\n"
    "point is shifted by the compensation there (the 3 nearest compensation points\n"
    "of the matrix blended by eqs. 2-5 of the optical-compensation source, or the\n"
    "correction field's layer of the operation's tool) and written as G1 moves with\n"
    "the original feed (G93 F recomputed). Every other line is copied byte for byte;\n"
    "a loop, subroutine call or NURBS block whose feeds cannot be corrected on\n"
    "their own line (they run more than once, or sit in a subroutine file) is\n"
    "written out move by move in its place, with a note saying so.\n"
    "The cutter radius is that of the tool in the spindle (T.. M6): D / 2 in the\n"
    "tool table, as for every other command.\n"
    "OUT and OUT.audit.json (inputs, options, SHA-256 digests, the summary) are\n"
    "written together or not at all. Method, measured results and when to use it\n"
    "rather than the real-time mode: docs/rewrite.md.\n"
    "\n"
    "options:\n"
    "  --matrix FILE        compensation matrix CSV (x,y,z,dx,dy,dz[,valid,surface_id]);\n"
    "                       from truecut field, dx,dy,dz are smoothed and tested\n"
    "  --raw-matrix         matrix mode: read raw_dx,raw_dy,raw_dz instead (the mirror\n"
    "                       of the raw error vectors, scan noise included)\n"
    "  --field FILE         correction field .tcf (instead of --matrix)\n"
    "  --operation NAME     the CAM operation, as in (OPERATION: NAME)\n"
    "  --type T             peripheral (flat end mill, side), face (flat end mill,\n"
    "                       bottom) or ball (ball end mill)\n"
    "  --tools FILE         tool table (LinuxCNC format, mm); the radius of each\n"
    "                       move's cutter is D / 2 of its tool\n"
    "  --tool-radius MM     optional check: the radius you expect; refused (exit 2)\n"
    "                       when it differs from the tool table's\n"
    "  --step MM            densification distance (default 0.5)\n"
    "  --reach MM           farthest compensation point from the cutting edge that\n"
    "                       is used (default: 2 x median point spacing)\n"
    "  --placement P        matrix mode: every-pass (default) averages the blend over\n"
    "                       the cutting part (flank up to the cutting length, or the\n"
    "                       bottom disc), so every pass that sweeps a point takes\n"
    "                       its compensation; tip: the source's 3 points at the tip\n"
    "  --cutting-length MM  every-pass, peripheral: flank length from the tip\n"
    "                       (default: the tool length of G43)\n"
    "  --smooth MM          matrix mode: replace each vector by the Gaussian-weighted\n"
    "                       mean of its surface's vectors within MM (default 0: as\n"
    "                       read); a matrix of raw scan points carries the noise\n"
    "  --surfaces ID,ID     use only compensation points of these surface ids\n"
    "  --machine FILE       machine description JSON: kinematics pivots for moves\n"
    "                       outside TRAORI (default: all pivots 0)\n"
    "  --decimals N         digits after the point in X Y Z A C (default 4 in mm,\n"
    "                       5 in inch blocks)\n"
    "  --rewrite-all        densify every feed move of the operation, also those\n"
    "                       that get no compensation\n"
    "  --max-correction MM  refuse (exit 1, nothing written) when the compensation\n"
    "                       exceeds this (default 0.2, as truecut field)\n"
    "  --force              write although it does, or although no point of the\n"
    "                       operation gets a compensation (recorded in the audit)\n"
    "  --paper denkena      the optical-compensation source's recipe (with --matrix):\n"
    "                       --raw-matrix, --placement tip, --step 0.5, no smoothing;\n"
    "                       options given explicitly still win\n"
    "  --out FILE           the rewritten program\n"
    "  --quiet              no progress on stderr (shown only on a terminal, after 1 s)\n"
    "  --help               this text\n"
    "\n"
    "exit codes: 0 ok, 1 refused (--max-correction) or runtime failure, 2 usage or\n"
    "input error (nothing written on 1 or 2)\n";

std::string read_bytes(const std::string& path, const char* what) {
  try {
    return rt::read_input_file(path, what);
  } catch (const rt::InputFileError& e) {
    throw UsageError(e.what());
  }
}

interp::CutType cut_type(const std::string& s) {
  if (s == "peripheral") return interp::CutType::kPeripheral;
  if (s == "face") return interp::CutType::kFace;
  if (s == "ball") return interp::CutType::kBall;
  throw UsageError("--type '" + s + "': expected peripheral, face or ball");
}

std::vector<std::int32_t> surface_list(const std::string& s) {
  std::vector<std::int32_t> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    errno = 0;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0') throw UsageError("--surfaces: '" + item + "' is not an id");
    // The matrix's surface ids are int32 (docs/formats.md): a larger number
    // would wrap onto another surface.
    if (errno == ERANGE || v < 0 || v > INT32_MAX)
      throw UsageError("--surfaces: " + item + " is outside the surface ids 0.." +
                       std::to_string(INT32_MAX));
    out.push_back(static_cast<std::int32_t>(v));
  }
  return out;
}

// The length of the valid UTF-8 sequence at s[i], or 0 when the byte there
// does not start one (RFC 3629: no overlong forms, no surrogates, <= U+10FFFF).
std::size_t utf8_sequence_length(const std::string& s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  std::size_t n = c < 0x80           ? 1
                  : (c >> 5) == 0x6  ? 2
                  : (c >> 4) == 0xE  ? 3
                  : (c >> 3) == 0x1E ? 4
                                     : 0;
  if (n == 0 || i + n > s.size()) return 0;
  std::uint32_t cp = n == 1 ? c : n == 2 ? c & 0x1F : n == 3 ? c & 0x0F : c & 0x07;
  for (std::size_t k = 1; k < n; ++k) {
    if ((byte(i + k) >> 6) != 0x2) return 0;
    cp = (cp << 6) | (byte(i + k) & 0x3F);
  }
  const std::uint32_t least[5] = {0, 0, 0x80, 0x800, 0x10000};
  if (cp < least[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return n;
}

// A JSON string of the bytes of s (a path or an operation name as the file
// system or the program gives them): valid UTF-8 as it is, and every byte
// that is not as U+FFFD, the replacement character (as the other commands'
// JSON writers do), so the audit is always JSON.
std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const std::size_t n = utf8_sequence_length(s, i);
    if (c == '"' || c == '\\') {
      o += '\\';
      o += static_cast<char>(c);
    } else if (n == 0) {
      o += "\\ufffd";
    } else if (c < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      o += b;
    } else {
      o.append(s, i, n);
      i += n;
      continue;
    }
    ++i;
  }
  return o + "\"";
}

struct Input {
  std::string role, path, sha256;
  size_t bytes = 0;
};

}  // namespace

int cmd_rewrite(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"matrix", true},   {"field", true},          {"operation", true},
                      {"type", true},     {"tool-radius", true},    {"step", true},
                      {"reach", true},    {"surfaces", true},       {"placement", true},
                      {"smooth", true},   {"raw-matrix", false},    {"max-correction", true},
                      {"force", false},   {"cutting-length", true}, {"tools", true},
                      {"machine", true},  {"decimals", true},       {"rewrite-all", false},
                      {"out", true},      {"paper", true},          {"help", false},
                      {"var-file", true}, {"var-units", true},      {"max-blocks", true},
                      {"quiet", false}});
  if (a.flag("help")) {
    std::fputs((std::string(kRewriteHelp) + kVarFileHelp + kMaxBlocksHelp).c_str(), stdout);
    return kExitOk;
  }
  if (a.positionals().size() != 1) throw UsageError("expected one program IN.ngc");
  const std::string in_path = a.positionals()[0];
  const auto matrix_path = a.value("matrix"), field_path = a.value("field");
  if (!matrix_path == !field_path) throw UsageError("give exactly one of --matrix and --field");
  // What only the matrix's neighbour search reads: given with a field it
  // would change nothing and still be recorded in the audit.
  for (const char* matrix_only :
       {"raw-matrix", "placement", "smooth", "surfaces", "reach", "cutting-length"})
    if (a.flag(matrix_only) && !matrix_path)
      throw UsageError(std::string("--") + matrix_only +
                       " goes with --matrix (a --field is looked up at the tool centre, "
                       "without the matrix's neighbour search)");
  // --paper denkena: the optical-compensation source's recipe — its mirror
  // vectors unsmoothed, the 3 points nearest the tool tip, 0.5 mm steps.
  const std::string paper = a.value("paper").value_or("");
  if (!paper.empty() && paper != "denkena")
    throw UsageError("--paper must be denkena, not '" + paper + "'");
  if (!paper.empty() && !matrix_path)
    throw UsageError("--paper denkena goes with --matrix (the source has no field)");
  const bool raw_matrix = a.flag("raw-matrix") || !paper.empty();
  const auto operation = a.value("operation");
  if (!operation) throw UsageError("--operation NAME is required");
  const auto type = a.value("type");
  if (!type) throw UsageError("--type peripheral|face|ball is required");
  const auto tools_path = a.value("tools");
  if (!tools_path)
    throw UsageError("--tools FILE is required (the tool radius is D / 2 of the tool in it)");
  const auto out_path = a.value("out");
  if (!out_path) throw UsageError("--out OUT.ngc is required");
  for (const std::string& written : {*out_path, *out_path + ".audit.json"})
    refuse_output_over_input("out", written, {in_path, matrix_path, field_path, tools_path});

  // OUT and its audit record are written together or not at all; a target
  // that is not a regular file is refused before anything is read.
  const std::string audit_path = *out_path + ".audit.json";
  std::optional<rt::StagedFiles> files;
  try {
    files.emplace(std::vector<fs::path>{*out_path, audit_path}, ".tmp");
  } catch (const rt::FileWriteError& e) {
    throw UsageError(e.what());
  }

  interp::RewriteOptions o;
  o.operation = *operation;
  o.type = cut_type(*type);
  if (a.value("tool-radius")) o.tool_radius_mm = a.number("tool-radius", 0, 0, 1000);
  if (auto s = a.value("step")) {
    char* end = nullptr;
    const double v = std::strtod(s->c_str(), &end);
    if (s->empty() || *end != '\0') throw UsageError("--step '" + *s + "' is not a number");
    if (!(v > 0)) throw UsageError("--step must be > 0 mm (got " + *s + ")");
    o.step_mm = a.number("step", 0.5, 1e-4, 1000);
  }
  o.reach_mm = a.number("reach", 0, 1e-6, 1000);
  o.cutting_length_mm = a.number("cutting-length", 0, 1e-6, 10000);
  o.smoothing_radius_mm = a.number("smooth", 0, 0, 1000);
  if (!paper.empty()) o.placement = interp::MatrixPlacement::kTip;
  if (auto p = a.value("placement")) {
    if (*p == "every-pass")
      o.placement = interp::MatrixPlacement::kEveryPass;
    else if (*p == "tip")
      o.placement = interp::MatrixPlacement::kTip;
    else
      throw UsageError("--placement '" + *p + "': expected every-pass or tip");
  }
  if (auto s = a.value("surfaces")) o.surfaces = surface_list(*s);
  o.decimals = static_cast<int>(a.integer("decimals", 0, 3, 9));
  o.keep_unchanged_moves = !a.flag("rewrite-all");
  o.interpreter.max_blocks = max_blocks_from_args(a);

  std::vector<Input> inputs;
  auto add_input = [&](const std::string& role, const std::string& path, const std::string& bytes) {
    inputs.push_back({role, path, interp::sha256_hex(bytes), bytes.size()});
  };
  const std::string program = read_bytes(in_path, "program");
  add_input("program", in_path, program);

  interp::RewriteResult result;
  try {
    // On a terminal, once it has taken a second; gone (its line ended)
    // before any message of the handlers below.
    StageProgress progress("truecut rewrite", progress_shown(a));
    progress.stage("reading the inputs");
    add_input("tools", *tools_path, read_bytes(*tools_path, "tool table"));
    o.interpreter.tools = interp::ToolTable::load(*tools_path);
    if (auto var = a.value("var-file"))
      add_input("parameters", *var, read_bytes(*var, "parameter file"));
    if (auto p = parameter_file_from_args(a)) o.interpreter.parameters = std::move(*p);
    if (auto m = a.value("machine")) {
      add_input("machine", *m, read_bytes(*m, "machine description"));
      const auto k = sim::read_machine_description(*m).machine.kinematics;
      // The description's pivots and directions; its kinematics hold no tool
      // length or A travel (see KinematicsParams), so those keep rt's defaults.
      o.kinematics = k.ac;
    }
    if (matrix_path) {
      const std::string bytes = read_bytes(*matrix_path, "compensation matrix");
      add_input("matrix", *matrix_path, bytes);
      const auto matrix = interp::parse_compensation_matrix(
          bytes, *matrix_path,
          raw_matrix ? interp::MatrixVectors::kRaw : interp::MatrixVectors::kSmoothed);
      progress.stage("rewriting operation " + o.operation);
      result = interp::rewrite_program(program, in_path, matrix, o);
    } else {
      const std::string bytes = read_bytes(*field_path, "correction field");
      add_input("field", *field_path, bytes);
      const auto field = rt::decode_field_file(bytes, *field_path);
      // A and C turn the table about the machine's pivots: without them the
      // program's X Y Z would follow pivots at 0.
      if (field.field.has_rotation() && !a.value("machine"))
        throw interp::RewriteError(*field_path +
                                   ": the field turns the tool (rotation channels rx ry rz); give "
                                   "--machine MACHINE.json, whose pivots A and C turn about");
      progress.stage("rewriting operation " + o.operation);
      result = interp::rewrite_program(program, in_path, field.field, o);
    }
  } catch (const interp::GcodeError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitUsage;
  } catch (const interp::RewriteError& e) {
    std::fprintf(stderr, "truecut rewrite: %s\n", e.what());
    return kExitUsage;
  } catch (const rt::FieldFileError& e) {
    std::fprintf(stderr, "truecut rewrite: %s\n", e.what());
    return kExitUsage;
  } catch (const sim::MachineDescriptionError& e) {
    std::fprintf(stderr, "truecut rewrite: %s\n", e.what());
    return kExitUsage;
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }

  const interp::RewriteSummary& s = result.summary;
  // A plausibility check of the compensation, as in truecut field: a
  // correction this large on a finished part is a wrong input or unit.
  const double max_correction_mm =
      a.number("max-correction", offline::kFieldMaxCorrectionMm, 0.0, 100.0);
  const bool too_large = s.max_compensation_mm > max_correction_mm;
  const bool none_reached = s.points_compensated == 0;
  const bool forced = too_large || (none_reached && s.points_covered == 0);
  if (too_large && !a.flag("force")) {
    std::fprintf(stderr,
                 "truecut rewrite: the compensation reaches %.4f mm, above --max-correction "
                 "%.4g mm (a wrong matrix, field or unit?); nothing written (--force writes it and "
                 "records that in the audit)\n",
                 s.max_compensation_mm, max_correction_mm);
    return kExitFailure;
  }
  // Nothing of the operation inside what the compensation covers: a matrix
  // or field of another part, frame or unit. Inside a field's grid with no
  // valid node along the moves (surfaces the field did not compensate), the
  // operation simply gets nothing, and is written unchanged with a note.
  if (none_reached && s.points_covered == 0 && !a.flag("force")) {
    std::fprintf(stderr,
                 "truecut rewrite: no point of operation '%s' (%d moves) got a compensation: "
                 "the %s %s does not reach its moves (is it in the program's workpiece frame "
                 "and units? docs/rewrite.md); nothing written (--force writes the program "
                 "unchanged)\n",
                 o.operation.c_str(), s.moves_read, matrix_path ? "matrix" : "field",
                 (matrix_path ? *matrix_path : *field_path).c_str());
    return kExitUsage;
  }
  // The radius of the operation's tool(s), from the tool table.
  std::optional<double> radius_mm;
  bool one_radius = true;
  std::string tools_json, radius_text;
  for (const auto& [tool, r] : s.tool_radii_mm) {
    if (radius_mm && *radius_mm != r) one_radius = false;
    radius_mm = r;
    tools_json += std::string(tools_json.empty() ? "" : ", ") +
                  "{\"tool\": " + std::to_string(tool) +
                  ", \"radius_mm\": " + rt::format_printf("%.17g", r) + "}";
    radius_text += rt::format_printf("%s%g mm (T%d)", radius_text.empty() ? "" : ", ", r, tool);
  }
  if (one_radius && radius_mm) radius_text = rt::format_printf("%g mm", *radius_mm);
  if (!radius_mm) radius_text = "- (no feed move)";
  std::string j = "{\n  \"truecut_rewrite_audit\": 1,\n";
  j += "  \"created\": " + json_string(rt::utc_timestamp_now()) + ",\n";
  j += "  \"frame\": \"workpiece\",\n  \"units\": \"mm\",\n  \"inputs\": [\n";
  for (size_t i = 0; i < inputs.size(); ++i)
    j += "    {\"role\": " + json_string(inputs[i].role) +
         ", \"path\": " + json_string(inputs[i].path) +
         ", \"bytes\": " + std::to_string(inputs[i].bytes) +
         ", \"sha256\": " + json_string(inputs[i].sha256) + "}" +
         (i + 1 < inputs.size() ? ",\n" : "\n");
  j += "  ],\n  \"options\": {\"operation\": " + json_string(o.operation) +
       ", \"type\": " + json_string(interp::to_string(o.type)) + ", \"tool_radius_mm\": " +
       (one_radius && radius_mm ? rt::format_printf("%.17g", *radius_mm) : std::string("null")) +
       ", \"step_mm\": " + rt::format_printf("%.17g", o.step_mm) +
       ", \"reach_mm\": " + rt::format_printf("%.17g", s.reach_mm) +
       ", \"placement\": " + json_string(interp::to_string(o.placement)) +
       ", \"matrix_vectors\": " +
       (matrix_path ? json_string(raw_matrix ? "raw" : "smoothed") : std::string("null")) +
       ", \"paper\": " + (paper.empty() ? std::string("null") : json_string(paper)) +
       ", \"cutting_length_mm\": " + rt::format_printf("%.17g", o.cutting_length_mm) +
       ", \"smoothing_radius_mm\": " + rt::format_printf("%.17g", o.smoothing_radius_mm) +
       ", \"surfaces\": [";
  for (size_t i = 0; i < o.surfaces.size(); ++i)
    j += (i ? ", " : "") + std::to_string(o.surfaces[i]);
  j += "], \"decimals\": " + std::to_string(o.decimals) +
       ", \"rewrite_all\": " + (o.keep_unchanged_moves ? "false" : "true") +
       ", \"max_correction_mm\": " + rt::format_printf("%.17g", max_correction_mm) +
       ", \"forced\": " + (forced ? "true" : "false") + "},\n";
  j += "  \"output\": {\"path\": " + json_string(*out_path) +
       ", \"bytes\": " + std::to_string(result.text.size()) +
       ", \"sha256\": " + json_string(interp::sha256_hex(result.text)) + "},\n";
  j += "  \"summary\": {\"moves_read\": " + std::to_string(s.moves_read) +
       ", \"moves_rewritten\": " + std::to_string(s.moves_rewritten) +
       ", \"moves_kept\": " + std::to_string(s.moves_kept) +
       ", \"holes_rewritten\": " + std::to_string(s.holes_rewritten) +
       ", \"returns_written\": " + std::to_string(s.returns_written) +
       ", \"expansions\": " + std::to_string(s.expansions) +
       ", \"expanded_moves\": " + std::to_string(s.expanded_moves) +
       ", \"expanded_holes\": " + std::to_string(s.expanded_holes) +
       ", \"points_written\": " + std::to_string(s.points_written) +
       ", \"points_compensated\": " + std::to_string(s.points_compensated) +
       ", \"points_covered\": " + std::to_string(s.points_covered) + ", \"blend_points\": [" +
       std::to_string(s.blend_points[0]) + ", " + std::to_string(s.blend_points[1]) + ", " +
       std::to_string(s.blend_points[2]) + ", " + std::to_string(s.blend_points[3]) +
       "], \"max_compensation_mm\": " + rt::format_printf("%.17g", s.max_compensation_mm) +
       ", \"mean_compensation_mm\": " + rt::format_printf("%.17g", s.mean_compensation_mm) +
       ", \"points_rotated\": " + std::to_string(s.points_rotated) +
       ", \"max_rotation_rad\": " + rt::format_printf("%.17g", s.max_rotation_rad) +
       ", \"max_rotation_shortfall_rad\": " +
       rt::format_printf("%.17g", s.max_rotation_shortfall_rad) +
       ", \"lines_in\": " + std::to_string(s.lines_in) +
       ", \"lines_out\": " + std::to_string(s.lines_out) + ", \"tools\": [" + tools_json +
       "]}\n}\n";

  if (too_large)
    std::fprintf(
        stderr, "truecut rewrite: WARNING: compensation %.4f mm above %.4g mm, written (--force)\n",
        s.max_compensation_mm, max_correction_mm);
  if (none_reached)
    std::fprintf(stderr,
                 s.points_covered == 0
                     ? "truecut rewrite: WARNING: no point of the operation got a compensation, "
                       "written unchanged (--force)\n"
                     : "truecut rewrite: note: the field has no valid node along the operation's "
                       "moves (surfaces it did not compensate?): written unchanged\n");
  files->write(0, result.text);
  files->write(1, j);
  files->commit();

  if (matrix_path)
    std::printf(
        "operation %s (%s, R %s, step %g mm, matrix %s, reach %.4g mm, placement %s, "
        "smooth %g mm)\n",
        o.operation.c_str(), interp::to_string(o.type), radius_text.c_str(), o.step_mm,
        matrix_path->c_str(), s.reach_mm, interp::to_string(o.placement), o.smoothing_radius_mm);
  else
    std::printf("operation %s (%s, R %s, step %g mm, field %s)\n", o.operation.c_str(),
                interp::to_string(o.type), radius_text.c_str(), o.step_mm, field_path->c_str());
  std::printf("  moves read            %d\n", s.moves_read);
  std::printf("  moves rewritten       %d\n", s.moves_rewritten);
  std::printf("  moves kept            %d\n", s.moves_kept);
  if (s.holes_rewritten > 0)
    std::printf("  canned-cycle holes    %d (cycles kept, hole and bottom corrected)\n",
                s.holes_rewritten);
  if (s.returns_written > 0)
    std::printf(
        "  returns to the path   %d (G1 back to the original point before the next "
        "operation's feed)\n",
        s.returns_written);
  if (s.expansions > 0)
    std::printf(
        "  written out           %d loops, calls, NURBS blocks or lines as %ld moves, %d "
        "canned-cycle holes among them (see the notes in the program)\n",
        s.expansions, s.expanded_moves, s.expanded_holes);
  std::printf("  points written        %ld\n", s.points_written);
  std::printf("  points compensated    %ld\n", s.points_compensated);
  if (matrix_path)
    std::printf("  blends of 3/2/1 pts   %ld / %ld / %ld, %ld points reached none\n",
                s.blend_points[3], s.blend_points[2], s.blend_points[1], s.blend_points[0]);
  std::printf("  max compensation      %.4f mm\n", s.max_compensation_mm);
  std::printf("  mean compensation     %.4f mm\n", s.mean_compensation_mm);
  if (s.points_rotated > 0)
    std::printf("  tool turned (A, C)    %ld points, up to %.3f mrad, %.3f mrad not given\n",
                s.points_rotated, s.max_rotation_rad * 1e3, s.max_rotation_shortfall_rad * 1e3);
  std::printf("  lines                 %d -> %d\n", s.lines_in, s.lines_out);
  std::printf("wrote %s and %s\n", out_path->c_str(), audit_path.c_str());
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{
    "rewrite", "write the compensation into a G-code program (fallback)", cmd_rewrite, 50};
}  // namespace

}  // namespace truecut::cli
