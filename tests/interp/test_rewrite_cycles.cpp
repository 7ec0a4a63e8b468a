// truecut::interp::rewrite_program on canned cycles (issue 22, point 5): a
// cycle line of the rewritten operation keeps its cycle, with its hole and
// bottom written where the correction at the bottom puts them; the cycle's
// later lines outside the operation, which would take X Y Z from it, drill
// where they did. The expected holes are the test's own arithmetic: the
// programmed hole plus the vector planted around it.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "rewrite_test_util.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/rewrite.hpp"

namespace truecut::interp {
namespace {

using V = Eigen::Vector3d;

const char* kProgram =
    "G21 G17 G90 G94\n"
    "T2 M6\n"
    "G43 H2\n"
    "S1000 M3\n"
    "G0 X0 Y0 Z10\n"
    "(OPERATION: HOLES)\n"
    "G98 G81 X10 Y5 Z-3 R2 F100 (first hole)\n"
    "X20\n"
    "G83 X30 Y15 Z-6 R2 Q1.5\n"
    "(OPERATION: OTHER)\n"
    "Y25\n"
    "G80\n"
    "G0 Z20\n"
    "M30\n";

struct Hole {
  V programmed;  // X Y and the bottom Z as programmed
  V shift;       // planted around it
};

// Compensation points in a small cluster around each hole's bottom, all with
// the hole's vector: whichever points the blend takes, it gives that vector.
CompensationMatrixData clusters(const std::vector<Hole>& holes) {
  CompensationMatrixData m;
  for (const Hole& h : holes) {
    const V& c = h.programmed;
    m = testing::plane_matrix(c.x() - 0.4, c.x() + 0.4, c.y() - 0.4, c.y() + 0.4, c.z(), 0.2,
                              h.shift, std::move(m));
  }
  return m;
}

RewriteOptions options() {
  RewriteOptions o;
  o.operation = "HOLES";
  o.type = CutType::kBall;
  o.interpreter.tools = ToolTable::parse("T2 P2 D0.001 Z40\n", "tools.tbl");
  o.reach_mm = 1.0;
  o.decimals = 6;
  return o;
}

// The deepest feed of each line that makes feeds: the hole's bottom.
std::map<int, Axes6> bottoms(const std::string& text) {
  const CanonProgram p = Interpreter(options().interpreter).run_text(text, "p.ngc");
  std::map<int, Axes6> out;
  for (const CanonCall& c : p.calls)
    if (const auto* f = std::get_if<StraightFeed>(&c.op)) {
      auto it = out.find(c.context.line);
      if (it == out.end() || f->end.z < it->second.z) out[c.context.line] = f->end;
    }
  return out;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start < text.size()) {
    const size_t end = text.find('\n', start);
    lines.push_back(text.substr(start, end - start));
    start = end == std::string::npos ? text.size() : end + 1;
  }
  return lines;
}

TEST(RewriteCycles, HolesOfTheOperationMoveByTheirCorrectionAndKeepTheirCycle) {
  const std::vector<Hole> holes = {{V(10, 5, -3), V(0.02, -0.01, 0.015)},
                                   {V(20, 5, -3), V(-0.03, 0.02, -0.01)},
                                   {V(30, 15, -6), V(0.01, 0.04, 0.025)}};
  // Planted far from the holes of the other operation: (30, 25) gets nothing.
  const RewriteResult r = rewrite_program(kProgram, "p.ngc", clusters(holes), options());
  EXPECT_EQ(r.summary.holes_rewritten, 3);
  EXPECT_NE(r.text.find("(truecut rewrite: canned cycles kept: 3 cycle lines"), std::string::npos)
      << r.text;

  const auto before = bottoms(kProgram);
  const auto after = bottoms(r.text);
  const auto out = lines_of(r.text);
  // Output line numbers are one more (the header comment).
  const int hole_lines[] = {7, 8, 9};
  for (int k = 0; k < 3; ++k) {
    const int line = hole_lines[k];
    ASSERT_TRUE(after.count(line + 1)) << r.text;
    const Axes6& got = after.at(line + 1);
    const V want = holes[k].programmed + holes[k].shift;
    EXPECT_NEAR(got.x, want.x(), 1e-9) << "hole " << k << "\n" << r.text;
    EXPECT_NEAR(got.y, want.y(), 1e-9) << "hole " << k;
    EXPECT_NEAR(got.z, want.z(), 1e-9) << "hole " << k;
    // The line is still a cycle line with its R (and Q, F, comment).
    const std::string& text = out.at(line);
    EXPECT_TRUE(text.find("G81") != std::string::npos || text.find("G83") != std::string::npos ||
                k == 1)
        << text;
    EXPECT_EQ(text.find("G1"), std::string::npos) << text;
  }
  EXPECT_NE(out.at(7).find("R2 F100 X10.020000 Y4.990000 Z-2.985000 (first hole)"),
            std::string::npos)
      << out.at(7);
  EXPECT_NE(out.at(9).find("Q1.5"), std::string::npos) << out.at(9);
  // Y25, outside the operation, continues G83 but took X and Z from the
  // corrected line: written with its own, it drills where it did.
  EXPECT_EQ(out.at(11), "X30 Y25 Z-6");  // shortest exact decimals
  ASSERT_TRUE(after.count(12)) << r.text;
  const Axes6& other = after.at(12);
  const Axes6& was = before.at(11);
  EXPECT_EQ(other.x, was.x);
  EXPECT_EQ(other.y, was.y);
  EXPECT_EQ(other.z, was.z);
  EXPECT_EQ(was.x, 30.0);
  EXPECT_EQ(was.y, 25.0);
  EXPECT_EQ(was.z, -6.0);
}

TEST(RewriteCycles, AnUncorrectedCycleIsCopied) {
  const std::vector<Hole> far = {{V(100, 100, -3), V(0.02, 0, 0)}};
  const RewriteResult r = rewrite_program(kProgram, "p.ngc", clusters(far), options());
  EXPECT_EQ(r.text, kProgram);
  EXPECT_EQ(r.summary.holes_rewritten, 0);
}

TEST(RewriteCycles, AHoleInG18IsCorrectedAlongY) {
  const char* prog =
      "G21 G18 G90 G94\nT2 M6\nG43 H2\nS1000 M3\nG0 X0 Y10 Z0\n(OPERATION: HOLES)\n"
      "G98 G81 X4 Z6 Y-2 R3 F100\nG80\nG0 Y20\nM30\n";
  const std::vector<Hole> holes = {{V(4, -2, 6), V(0.01, -0.02, 0.03)}};
  const RewriteResult r = rewrite_program(prog, "p.ngc", clusters(holes), options());
  EXPECT_EQ(r.summary.holes_rewritten, 1);
  const CanonProgram p = Interpreter(options().interpreter).run_text(r.text, "p.ngc");
  int feeds = 0;
  for (const CanonCall& c : p.calls)
    if (const auto* f = std::get_if<StraightFeed>(&c.op)) {
      if (f->end.y > 0) continue;  // the G98 return is a rapid; feeds go down to Y
      ++feeds;
      EXPECT_NEAR(f->end.x, 4.01, 1e-9) << r.text;
      EXPECT_NEAR(f->end.y, -2.02, 1e-9) << r.text;
      EXPECT_NEAR(f->end.z, 6.03, 1e-9) << r.text;
    }
  EXPECT_EQ(feeds, 1) << r.text;
}

// The next operation's retract after the last, corrected hole (found by
// fuzzing the rewrite): it names only Z, so it is written with X Y Z and
// goes where the original went, not above the corrected hole.
TEST(RewriteCycles, TheNextOperationsRetractReturnsToTheOriginalHole) {
  const std::string prog =
      "G21 G17 G90 G94\nT2 M6\nG43 H2\nS1000 M3\nG0 X0 Y0 Z10\n(OPERATION: HOLES)\n"
      "G99 G81 X10 Y5 Z-3 R2 F100\nG80\n(OPERATION: REST)\nG0 Z20\nM30\n";
  const std::vector<Hole> holes = {{V(10, 5, -3), V(0.02, -0.01, 0.015)}};
  const RewriteResult r = rewrite_program(prog, "p.ngc", clusters(holes), options());
  EXPECT_EQ(r.summary.holes_rewritten, 1);
  EXPECT_EQ(r.summary.rapids_rewritten, 1);
  const CanonProgram p = Interpreter(options().interpreter).run_text(r.text, "p.ngc");
  const auto* last = std::get_if<StraightTraverse>(&p.calls.back().op);
  for (auto it = p.calls.rbegin(); !last && it != p.calls.rend(); ++it)
    last = std::get_if<StraightTraverse>(&it->op);
  ASSERT_NE(last, nullptr) << r.text;
  EXPECT_EQ(last->end.x, 10) << r.text;
  EXPECT_EQ(last->end.y, 5) << r.text;
  EXPECT_EQ(last->end.z, 20) << r.text;
}

void expect_refused(const std::string& prog, int line, const std::string& message) {
  const std::vector<Hole> holes = {{V(10, 5, -3), V(0.02, 0, 0)}, {V(20, 5, -3), V(0.02, 0, 0)}};
  try {
    rewrite_program(prog, "p.ngc", clusters(holes), options());
    FAIL() << "accepted:\n" << prog;
  } catch (const GcodeError& e) {
    EXPECT_EQ(e.where().line, line) << e.what();
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

// A cycle in G91, with an expression or in polar coordinates cannot be
// kept, corrected, on its line: it is written out as its moves (test_rewrite_expansion.cpp), the
// hole corrected.
TEST(RewriteCycles, CyclesThatCannotBeKeptAreWrittenOutOrRefusedByName) {
  const std::string head =
      "G21 G17 G90 G94\nT2 M6\nG43 H2\nS1000 M3\nG0 X0 Y0 Z10\n(OPERATION: HOLES)\n";
  const std::vector<Hole> holes = {{V(10, 5, -3), V(0.02, 0, 0)}, {V(20, 5, -3), V(0.02, 0, 0)}};
  for (const std::string line :
       {"G91 G98 G81 X10 Y5 Z-5 R-8 F100\nG90 G80\n", "G98 G81 X10 Y5 Z[-3] R2 F100\nG80\n",
        "G98 G81 @11.18033988749895 ^26.56505117707799 Z-3 R2 F100\nG80\n"}) {
    const RewriteResult r =
        rewrite_program(head + line + "M30\n", "p.ngc", clusters(holes), options());
    EXPECT_EQ(r.summary.expansions, 1) << r.text;
    EXPECT_EQ(r.summary.expanded_holes, 1) << r.text;
    EXPECT_EQ(r.summary.holes_rewritten, 0) << r.text;
    // The bottom of the hole (10, 5, -3) moved by the vector planted there.
    EXPECT_NE(r.text.find("G1 X10.020000 Y5.000000 Z-3.000000"), std::string::npos) << r.text;
  }
  expect_refused(head + "G18 G98 G87 X10 Z5 Y-3 R2 I1 K0 J-1 F100\nG80\nM30\n", 7,
                 "G87 (back boring) outside G17");
  // In a loop, G87 under M4 orients the spindle with CANON_DIRECTION 3,
  // which no M19 makes.
  expect_refused(
      "G21 G17 G90 G94\nT2 M6\nG43 H2\nS1000 M4\nG0 X0 Y0 Z10\n(OPERATION: HOLES)\n"
      "#1 = 0\no1 while [#1 LT 2]\nG98 G87 X[10 + #1 * 10] Y5 Z-5 R2 I1 J0 K-3 F100\n"
      "G80\n#1 = [#1 + 1]\no1 endwhile\nM30\n",
      9, "ORIENT_SPINDLE(..., 3) has no M19 form");
}

// The feeds of each G87 line, in order, as the interpreter runs `text`.
std::map<int, std::vector<Axes6>> feeds_by_line(const std::string& text) {
  const CanonProgram p = Interpreter(options().interpreter).run_text(text, "p.ngc");
  std::map<int, std::vector<Axes6>> out;
  for (const CanonCall& c : p.calls)
    if (const auto* f = std::get_if<StraightFeed>(&c.op))
      if (c.context.canned_cycle == 870) out[c.context.line].push_back(f->end);
  return out;
}

// G87 back bores upwards from below the part (Z) to K, entering beside the
// hole (I J): the cut is at K, so the correction planted there moves the
// hole in X Y and K by it, while Z, where the tool waits below the part, and
// the entry offset stay (issue 22 point 5; before, G87 was refused).
TEST(RewriteCycles, BackBoringIsCorrectedAtItsBackBoreHeight) {
  const std::string program =
      "G21 G17 G90 G94\nT2 M6\nG43 H2\nS1000 M3\nG0 X0 Y0 Z10\n(OPERATION: HOLES)\n"
      "G98 G87 X10 Y5 Z-8 R2 I1.5 J-0.5 K-3 F100 (back bore)\n"
      "X20\n"
      "G80\nG0 Z20\nM30\n";
  // Planted at each hole's back-bore point (X Y K); nothing at Z.
  const std::vector<Hole> holes = {{V(10, 5, -3), V(0.02, -0.01, 0.015)},
                                   {V(20, 5, -3), V(-0.03, 0.02, -0.01)}};
  const RewriteResult r = rewrite_program(program, "p.ngc", clusters(holes), options());
  EXPECT_EQ(r.summary.holes_rewritten, 2) << r.text;
  EXPECT_EQ(r.summary.expansions, 0) << r.text;
  EXPECT_NE(r.text.find("; G87 with the hole and back-bore height X Y K the correction at K "
                        "gives, Z kept)"),
            std::string::npos)
      << r.text;
  const auto out = lines_of(r.text);
  EXPECT_NE(out.at(7).find("G98 G87 R2 I1.5 J-0.5 F100 X10.020000 Y4.990000 Z-8 K-2.985000 "
                           "(back bore)"),
            std::string::npos)
      << out.at(7);
  const auto before = feeds_by_line(program);
  const auto after = feeds_by_line(r.text);
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE("hole " + std::to_string(k));
    const int line = 7 + k;
    ASSERT_EQ(before.at(line).size(), 2u);
    ASSERT_EQ(after.at(line + 1).size(), 2u) << r.text;
    const V& c = holes[k].programmed;
    const V& d = holes[k].shift;
    // Up to K, then down to Z, both over the shifted hole.
    const Axes6& up = after.at(line + 1)[0];
    const Axes6& down = after.at(line + 1)[1];
    EXPECT_NEAR(up.x, c.x() + d.x(), 1e-9);
    EXPECT_NEAR(up.y, c.y() + d.y(), 1e-9);
    EXPECT_NEAR(up.z, c.z() + d.z(), 1e-9);
    EXPECT_NEAR(down.x, c.x() + d.x(), 1e-9);
    EXPECT_NEAR(down.y, c.y() + d.y(), 1e-9);
    EXPECT_EQ(down.z, -8.0);
    EXPECT_EQ(before.at(line)[0].z, -3.0);
  }
  // The entry beside the hole keeps its offset from the hole.
  const CanonProgram p = Interpreter(options().interpreter).run_text(r.text, "p.ngc");
  int offset_entries = 0;
  for (const CanonCall& c : p.calls)
    if (const auto* t = std::get_if<StraightTraverse>(&c.op))
      if (c.context.line == 8 && std::fabs(t->end.z + 8) < 1e-12 &&
          std::fabs(t->end.x - 11.52) < 1e-9) {
        EXPECT_NEAR(t->end.y, 4.49, 1e-9);
        ++offset_entries;
      }
  EXPECT_EQ(offset_entries, 2) << r.text;  // down beside the hole, and out again
}

}  // namespace
}  // namespace truecut::interp
