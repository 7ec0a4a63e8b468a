// Issue 22, point 5, judged on programs the rewrite was not written for:
// LinuxCNC 2.9's sample programs, read from the Debian package at test time
// (installed, or fetched by fetch_rs274.sh; they are GPL and never copied
// in). Each program that makes feed moves is made one operation ("ALL",
// with T1 M6 put first so that a tool is in the spindle) and rewritten with
// a constant correction. The oracle is the interpreter run on the original
// (rewrite_path_oracle.hpp): every feed comes out shifted, every rapid
// where it was, the spindle and coolant where they switched. What the
// rewrite refuses it must refuse by name, at a line; at least 90 % of the
// programs must be rewritten (the target for LinuxCNC's programs).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "oracle.hpp"
#include "rewrite_path_oracle.hpp"
#include "rewrite_test_util.hpp"
#include "rs274_oracle.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/rewrite.hpp"

namespace truecut::interp {
namespace {

namespace fs = std::filesystem;
using V = Eigen::Vector3d;

std::vector<fs::path> sample_programs(const fs::path& share) {
  std::vector<fs::path> out = testing::ngc_programs_under(share / "linuxcnc/ncfiles");
  for (const fs::path& p : testing::ngc_programs_under(share / "doc/linuxcnc/examples"))
    out.push_back(p);
  return out;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The whole program as operation ALL with tool 1 in the spindle: the two
// lines go first, after a leading '%' line when there is one.
std::string as_one_operation(const std::string& text) {
  const std::string head = "(OPERATION: ALL)\nT1 M6\n";
  size_t start = text.find_first_not_of(" \t\r\n");
  if (start != std::string::npos && text[start] == '%') {
    const size_t eol = text.find('\n', start);
    if (eol == std::string::npos) return text + "\n" + head;
    return text.substr(0, eol + 1) + head + text.substr(eol + 1);
  }
  return head + text;
}

std::string tool_table() {
  std::string t;
  for (int k = 0; k <= 200; ++k)
    t += "T" + std::to_string(k) + " P" + std::to_string(k) + " D1 ;\n";
  return t;
}

bool makes_feed_moves(const CanonProgram& p) {
  return std::any_of(p.calls.begin(), p.calls.end(), [](const CanonCall& c) {
    return std::holds_alternative<StraightFeed>(c.op) || std::holds_alternative<ArcFeed>(c.op) ||
           std::holds_alternative<NurbsFeed>(c.op);
  });
}

constexpr double kSpacing_mm = 10, kReach_mm = 12;

// The end of a straight move or arc (a spline's stays within its control
// points, which these moves reach); nullptr for other calls.
const Axes6* end_of_move(const CanonOp& op) {
  if (const auto* t = std::get_if<StraightTraverse>(&op)) return &t->end;
  if (const auto* f = std::get_if<StraightFeed>(&op)) return &f->end;
  if (const auto* a = std::get_if<ArcFeed>(&op)) return &a->end;
  return nullptr;
}

// The correction `offset_mm` on a grid over where the program's moves go
// (machine mm, 20 mm around them), every kSpacing_mm: each tool point has
// grid points within kReach_mm (half a cell's diagonal is 8.7 mm), so the
// correction is the same everywhere and the oracle knows it without the
// model. When A or C turn, the rewrite looks the tool up in the part's
// frame: the grid then fills the ball the moves reach.
CompensationMatrixData constant_matrix_around(const CanonProgram& program, const V& offset_mm) {
  V lo = V::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double reach = 0;
  bool turns = false;
  for (const CanonCall& c : program.calls) {
    const Axes6* end = end_of_move(c.op);
    if (!end) continue;
    const V p = testing::machine_xyz_mm(*end, c.context);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    reach = std::max(reach, p.norm());
    turns = turns || end->a != 0 || end->c != 0;
  }
  if (turns) lo = V::Constant(-reach), hi = V::Constant(reach);
  lo.array() -= 20;
  hi.array() += 20;
  CompensationMatrixData m;
  for (double z = lo.z(); z <= hi.z() + kSpacing_mm; z += kSpacing_mm)
    m = testing::plane_matrix(lo.x(), hi.x() + kSpacing_mm, lo.y(), hi.y() + kSpacing_mm, z,
                              kSpacing_mm, offset_mm, std::move(m));
  return m;
}

// The correction is a shift of the tip in the workpiece's frame, which turns
// with the table: in machine axes it stays the same only along the axes the
// program does not turn about. A turns about X, C (on A) about Z: a program
// that turns A only is corrected along X, C only along Z, both: not at all
// (the written-out lines must then make exactly the original's moves).
V correction_for(const CanonProgram& program) {
  bool turns_a = false, turns_c = false;
  for (const CanonCall& c : program.calls)
    if (const Axes6* end = end_of_move(c.op)) {
      turns_a = turns_a || end->a != 0;
      turns_c = turns_c || end->c != 0;
    }
  if (turns_a && turns_c) return V::Zero();
  if (turns_a) return V(0.013, 0, 0);
  if (turns_c) return V(0, 0, 0.008);
  return V(0.013, -0.021, 0.008);
}

TEST(RewriteLinuxCncSamples, ProgramsComeOutShiftedOrAreRefusedByName) {
  std::string why;
  const auto& linuxcnc = testing::rs274_oracle(why);
  if (!linuxcnc) TRUECUT_ORACLE_MISSING(testing::rs274_missing(why));
  const std::vector<fs::path> programs = sample_programs(linuxcnc->share);

  int runnable = 0, rewritten = 0;
  std::vector<std::string> refused;
  for (const fs::path& path : programs) {
    RewriteOptions o;
    o.operation = "ALL";
    o.type = CutType::kFace;
    o.reach_mm = kReach_mm;
    o.decimals = 6;
    o.interpreter.tools = ToolTable::parse(tool_table(), "tools.tbl");
    o.interpreter.subroutine_path = {path.parent_path()};
    const std::string name = path.string();
    const std::string program = as_one_operation(read_text(path));
    CompensationMatrixData matrix;
    V offset_mm;
    try {
      const CanonProgram original = Interpreter(o.interpreter).run_text(program, name);
      if (!makes_feed_moves(original)) continue;
      offset_mm = correction_for(original);
      matrix = constant_matrix_around(original, offset_mm);
    } catch (const GcodeError&) {
      continue;  // a lathe program, a B axis, user M codes: the interpreter's suites
    }
    ++runnable;
    SCOPED_TRACE(name);
    RewriteResult r;
    try {
      r = rewrite_program(program, name, matrix, o);
    } catch (const GcodeError& e) {
      EXPECT_GT(e.where().line, 0) << e.what();
      refused.push_back(path.filename().string() + ": " + e.what());
      continue;
    }
    ++rewritten;
    testing::expect_same_path_shifted(program, r.text, o, offset_mm, name);
  }
  std::printf("LinuxCNC sample programs with feed moves: %d, rewritten %d, refused %zu\n", runnable,
              rewritten, refused.size());
  for (const std::string& line : refused)
    std::printf("  refused %s\n", line.c_str());
  // LinuxCNC 2.9 ships 29 such programs (2026-11): fewer means the folders
  // were not read.
  EXPECT_GE(runnable, 20) << "too few sample programs read from " << linuxcnc->share;
  EXPECT_GE(rewritten, 0.9 * runnable);
}

}  // namespace
}  // namespace truecut::interp
