#include "program_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <variant>

#include "truecut/rt/field_file.hpp"
#include "truecut/sim/part_file.hpp"
#include "truecut/sim/part_plausibility.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace truecut::sim::soft_cnc {
namespace {

namespace fs = std::filesystem;

constexpr double kMaxPositionMm = 1e5;  // no machine is larger than 100 m

std::string number_text(double v, const char* format = "%.6g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string where(const interp::CanonProgram& program, const interp::CallContext& ctx) {
  const std::string file =
      ctx.file >= 0 && static_cast<std::size_t>(ctx.file) < program.files.size()
          ? program.files[static_cast<std::size_t>(ctx.file)]
          : std::string("program");
  return file + ":" + std::to_string(ctx.line) + ": ";
}

// The position a motion call moves to (program units), if it is one.
const interp::Axes6* motion_end(const interp::CanonOp& op) {
  if (const auto* m = std::get_if<interp::StraightTraverse>(&op)) return &m->end;
  if (const auto* m = std::get_if<interp::StraightFeed>(&op)) return &m->end;
  if (const auto* m = std::get_if<interp::ArcFeed>(&op)) return &m->end;
  if (const auto* m = std::get_if<interp::NurbsFeed>(&op)) return &m->end;
  if (const auto* m = std::get_if<interp::RigidTap>(&op)) return &m->end;
  if (const auto* m = std::get_if<interp::StraightProbe>(&op)) return &m->end;
  return nullptr;
}

void check_position(const interp::CanonProgram& program, const interp::CallContext& ctx,
                    const interp::Axes6& end) {
  const interp::Axes6 machine = interp::machine_position_mm(end, ctx);
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(machine[a]) <= kMaxPositionMm))
      throw SoftCncInputError(where(program, ctx) + "XYZ"[a] + " " + number_text(machine[a]) +
                              " mm (machine position) is outside ±" + number_text(kMaxPositionMm) +
                              " mm: no machine is larger than 100 m; check the coordinates and "
                              "the units");
}

std::string hours_text(double s) {
  return number_text(s, "%.6g") + " s (" + number_text(s / 3600.0, "%.3g") + " h)";
}

std::pair<int, int> plane_axes(interp::Plane plane) {
  switch (plane) {
    case interp::Plane::kXY:
      return {0, 1};
    case interp::Plane::kXZ:
      return {0, 2};
    case interp::Plane::kYZ:
      return {1, 2};
  }
  return {0, 1};
}

// The shortest time a feed move can take: its length at the programmed feed
// (a lower bound; the planner may only be slower). Arcs count their full
// turns. 0 where the feed is unknown or per revolution.
struct FeedTimeBound {
  interp::Axes6 previous_mm;  // machine position, mm (the start joints at first)
  bool previous_known = false;
  double feed_mm_per_s = 0;

  double seconds(const interp::CanonCall& call) {
    const interp::CallContext& ctx = call.context;
    const double scale = ctx.units == interp::LengthUnits::kInch ? 25.4 : 1.0;
    if (const auto* f = std::get_if<interp::SetFeedRate>(&call.op))
      feed_mm_per_s = ctx.feed_mode == interp::FeedMode::kUnitsPerRevolution
                          ? 0.0
                          : f->units_per_minute * scale / 60.0;
    if (const auto* d = std::get_if<interp::Dwell>(&call.op)) return std::max(0.0, d->seconds);
    const interp::Axes6* end = motion_end(call.op);
    if (!end) return 0;
    const interp::Axes6 to = interp::machine_position_mm(*end, ctx);
    double length_mm = 0;
    if (previous_known) {
      if (const auto* arc = std::get_if<interp::ArcFeed>(&call.op)) {
        // The radius in the arc's plane; the off-plane coordinate of the
        // centre is unused (the end's own here).
        const auto [first, second] = plane_axes(arc->plane);
        interp::Axes6 centre = *end;
        centre[first] = arc->center[first];
        centre[second] = arc->center[second];
        const interp::Axes6 c = interp::machine_position_mm(centre, ctx);
        double r2 = 0;
        for (const int a : {first, second})
          r2 += (previous_mm[a] - c[a]) * (previous_mm[a] - c[a]);
        const double turns = std::max(0, std::abs(arc->rotation) - 1);
        length_mm = turns * 2.0 * 3.14159265358979323846 * std::sqrt(r2);
      } else if (std::holds_alternative<interp::StraightFeed>(call.op)) {
        double d2 = 0;
        for (int a = 0; a < 3; ++a)
          d2 += (to[a] - previous_mm[a]) * (to[a] - previous_mm[a]);
        length_mm = std::sqrt(d2);
      }
    }
    previous_mm = to;
    previous_known = true;
    return feed_mm_per_s > 0 ? length_mm / feed_mm_per_s : 0.0;
  }
};

}  // namespace

void check_program_time_bound(const interp::CanonProgram& program,
                              const std::array<double, 5>& start_joints, double max_s) {
  FeedTimeBound bound;
  for (int a = 0; a < 3; ++a)
    bound.previous_mm[a] = start_joints[static_cast<std::size_t>(a)];
  bound.previous_known = true;
  double t_s = 0;
  for (const interp::CanonCall& call : program.calls) {
    const double dt_s = bound.seconds(call);
    t_s += dt_s;
    if (t_s <= max_s) continue;
    throw SoftCncInputError(
        where(program, call.context) + "the program takes at least " + number_text(t_s, "%.4g") +
        " s by this line (this line alone at least " + number_text(dt_s, "%.4g") +
        " s), more than --max-program-time " + hours_text(max_s) +
        "; check G4 P (seconds), F (mm/min) and an arc's P (turns), or raise "
        "--max-program-time");
  }
}

void check_program_positions(const interp::CanonProgram& program) {
  for (const interp::CanonCall& call : program.calls) {
    if (const interp::Axes6* end = motion_end(call.op)) check_position(program, call.context, *end);
    if (const auto* arc = std::get_if<interp::ArcFeed>(&call.op)) {
      const auto [first, second] = plane_axes(arc->plane);
      interp::Axes6 centre = arc->end;
      centre[first] = arc->center[first];
      centre[second] = arc->center[second];
      check_position(program, call.context, centre);
    }
  }
}

void check_planned_time(const interp::Plan& plan, const std::string& program_name, double max_s) {
  double t_s = 0;
  for (const interp::PlanSegment& s : plan.segments) {
    t_s += s.law.duration_s;
    if (t_s <= max_s) continue;
    throw SoftCncInputError(
        program_name + ":" + std::to_string(s.line) +
        ": the planned program passes --max-program-time " + hours_text(max_s) +
        " at this line (this move or dwell takes " + number_text(s.law.duration_s, "%.1f") +
        " s, the whole program " + number_text(plan.stats.duration_s, "%.1f") +
        " s); check G4 P (seconds) and F (mm/min), or raise --max-program-time");
  }
}

std::map<int32_t, int32_t> cutting_tools(const interp::CanonProgram& program) {
  std::map<int32_t, int32_t> tools;
  bool spindle_on = false;
  for (const interp::CanonCall& call : program.calls) {
    if (std::holds_alternative<interp::StartSpindle>(call.op)) spindle_on = true;
    if (std::holds_alternative<interp::StopSpindle>(call.op)) spindle_on = false;
    const bool feed = std::holds_alternative<interp::StraightFeed>(call.op) ||
                      std::holds_alternative<interp::ArcFeed>(call.op) ||
                      std::holds_alternative<interp::NurbsFeed>(call.op);
    if (feed && spindle_on && call.context.tool > 0)
      tools.emplace(call.context.tool, call.context.line);
  }
  return tools;
}

void check_field_layers(const fs::path& field, const std::map<int32_t, int32_t>& tools,
                        const std::string& program_name) {
  rt::FieldFileHeader header;
  try {
    header = rt::read_field_file_header(field);
  } catch (const rt::FieldFileError& e) {
    throw SoftCncInputError(e.what());
  }
  std::string layers;
  for (const int32_t t : header.tools)
    layers += (layers.empty() ? "" : ", ") + std::to_string(t);
  for (const auto& [tool, line] : tools)
    if (std::find(header.tools.begin(), header.tools.end(), tool) == header.tools.end())
      throw SoftCncInputError(
          field.string() + ": the correction field has no layer for tool " + std::to_string(tool) +
          ", which " + program_name + " cuts with from line " + std::to_string(line) +
          " (the field's layers are for tool " + layers + "); the tool would get no correction");
}

void check_part_tools(const fs::path& part, const fs::path& tool_table,
                      const interp::ToolTable& table, const std::map<int32_t, int32_t>& tools,
                      const std::string& program_name) {
  try {
    const PartFile p = read_part_file(part, kPartTools | kPartStock);
    check_part_for_machining(p, part.string());  // a flute length too
    for (const auto& [tool, line] : tools) {
      const PartTool* t = p.tool(tool);
      if (!t)
        throw PartFileError(part.string(), "tools",
                            "has no tool " + std::to_string(tool) + ", which " + program_name +
                                " cuts with from line " + std::to_string(line) +
                                " (the cutting model would not know its size)");
      const interp::ToolEntry* entry = table.find(tool);
      if (!entry || !(entry->diameter_mm > 0)) continue;
      if (std::abs(entry->diameter_mm - 2 * t->radius_mm) <= 1e-3 + 1e-9) continue;
      std::size_t index = 0;
      while (&p.metadata.tools[index] != t)
        ++index;
      throw PartFileError(
          part.string(), "tools[" + std::to_string(index) + "].radius_mm",
          number_text(t->radius_mm) + " mm, but " + tool_table.string() + " gives tool " +
              std::to_string(tool) + " the diameter D " + number_text(entry->diameter_mm) +
              " mm (radius " + number_text(entry->diameter_mm / 2) +
              " mm): the cutting model cuts with part.json's radius, the program was made for "
              "the table's; make the two files agree");
    }
  } catch (const PartFileError& e) {
    throw SoftCncInputError(e.what());
  }
}

}  // namespace truecut::sim::soft_cnc
