// tool_geometry: the nominal geometry of the tool in the spindle, looked up
// by tool number in a benchmark part's part.json (the tool list CAM used;
// read with truecut/sim/part_file.hpp).
//
//   loadrt tool_geometry part=PART.json [count=N | names=a,b]
//
// Per instance <i>:
//   in   <i>.tool              tool number in the spindle (s32)
//   out  <i>.radius            nominal radius (mm)
//   out  <i>.corner-radius     nominal corner radius (mm; 0 flat, = radius ball)
//   out  <i>.length            gauge point to tip (mm), as in tools.tbl
//   out  <i>.flute-length      cutting length above the tip (mm)
//   out  <i>.known             (bit) the tool is in the list; otherwise all zero
// Function <i>.update: a bounded search of at most kMaxTools rows.
#include <array>
#include <string>

#include "truecut/rt/component_support.hpp"
#include "truecut/sim/part_file.hpp"
#include "truecut/sim/part_plausibility.hpp"

namespace {

constexpr int kMaxTools = 64;

struct ToolRow {
  int32_t number = 0;
  double radius_mm = 0, corner_radius_mm = 0, length_mm = 0, flute_length_mm = 0;
};

struct Instance {
  std::array<ToolRow, kMaxTools> rows{};
  int count = 0;
  int32_t* tool;
  double* radius;
  double* corner_radius;
  double* length;
  double* flute_length;
  bool* known;
};

void update(void* arg, long) {
  auto& s = *static_cast<Instance*>(arg);
  const ToolRow* row = nullptr;
  for (int i = 0; i < s.count && !row; ++i)
    if (s.rows[i].number == *s.tool) row = &s.rows[i];
  const ToolRow none{};
  const ToolRow& r = row ? *row : none;
  *s.radius = r.radius_mm;
  *s.corner_radius = r.corner_radius_mm;
  *s.length = r.length_mm;
  *s.flute_length = r.flute_length_mm;
  *s.known = row != nullptr;
}

using truecut::rt::hal::component::InitError;

int read_tools(const std::string& file, std::array<ToolRow, kMaxTools>& rows) {
  truecut::sim::PartFile part;
  try {
    part = truecut::sim::read_part_file(file, truecut::sim::kPartTools);
    truecut::sim::check_part_tools(part, file);  // a flute length too
  } catch (const truecut::sim::PartFileError& e) {
    throw InitError(e.what());
  }
  const auto& tools = part.metadata.tools;
  if (tools.size() > kMaxTools)
    throw InitError(file + ": key 'tools': more than " + std::to_string(kMaxTools) + " tools");
  int n = 0;
  for (const truecut::sim::PartTool& t : tools)
    rows[n++] = {t.number, t.radius_mm, t.corner_radius_mm, t.length_mm, t.flute_length_mm};
  return n;
}

}  // namespace

extern "C" TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
                                                          int argc, const char* const* argv,
                                                          void**) {
  using namespace truecut::rt::hal::component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    auto file = args.take("part");
    auto names = instance_names(args, "tool_geometry");
    args.expect_consumed("tool_geometry");
    if (!file) throw InitError("tool_geometry needs part=PART.json (written by truecut part)");
    std::array<ToolRow, kMaxTools> rows{};
    const int count = read_tools(*file, rows);
    for (const auto& n : names) {
      int id = new_component(api, hal, n);
      Builder b(api, hal, id);
      auto* s = b.alloc<Instance>();
      s->rows = rows;
      s->count = count;
      b.pin(n + ".tool", TC_HAL_S32, TC_HAL_IN, &s->tool);
      b.pin(n + ".radius", TC_HAL_FLOAT, TC_HAL_OUT, &s->radius);
      b.pin(n + ".corner-radius", TC_HAL_FLOAT, TC_HAL_OUT, &s->corner_radius);
      b.pin(n + ".length", TC_HAL_FLOAT, TC_HAL_OUT, &s->length);
      b.pin(n + ".flute-length", TC_HAL_FLOAT, TC_HAL_OUT, &s->flute_length);
      b.pin(n + ".known", TC_HAL_BIT, TC_HAL_OUT, &s->known);
      b.funct(n + ".update", update, s);
      api->component_ready(hal, id);
    }
    return 0;
  });
}

extern "C" TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t*, tc_hal_t*, void*) {}
