// Issue 22, point 5: feed moves of the operation that run more than once (a
// loop, a subroutine called twice) or sit in a subroutine file are written
// out move by move in place of the outermost loop or calling line. The
// oracle is the interpreter run on the original program: every feed of the
// operation must come out shifted by the (constant) correction, every other
// move exactly where it was, in the same order.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "oracle.hpp"
#include "rewrite_path_oracle.hpp"
#include "rewrite_test_util.hpp"
#include "rs274_oracle.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/rewrite.hpp"

namespace truecut::interp {
namespace {

namespace fs = std::filesystem;
using V = Eigen::Vector3d;
using testing::expect_same_path_shifted;

std::string rt_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

const char* kTools = "T1 P1 D2 Z35\nT2 P2 D4 Z40\n";

RewriteOptions options(const fs::path& sub_dir = {}) {
  RewriteOptions o;
  o.operation = "POCKET";
  o.type = CutType::kFace;
  o.reach_mm = 1000;  // every point corrected
  o.decimals = 6;
  o.interpreter.tools = ToolTable::parse(kTools, "tools.tbl");
  if (!sub_dir.empty()) o.interpreter.subroutine_path = {sub_dir};
  return o;
}

CompensationMatrixData constant(const V& offset) {
  return testing::plane_matrix(-50, 50, -50, 50, -5, 1, offset);
}

// The program rewritten with the constant correction `offset`: accepted,
// and its moves the original's shifted (expect_same_path_shifted).
void expect_rewritten_shifted(const std::string& program, const V& offset) {
  try {
    const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
    expect_same_path_shifted(program, r.text, options(), offset);
  } catch (const GcodeError& e) {
    ADD_FAILURE() << e.what();
  }
}

// The program written out as one expansion, its moves shifted by `offset`
// (expect_rewritten_shifted), with each of `lines` in the new text.
void expect_one_expansion_with(const std::string& program, const V& offset,
                               std::initializer_list<const char*> lines) {
  expect_rewritten_shifted(program, offset);
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
  EXPECT_EQ(r.summary.expansions, 1) << r.text;
  for (const char* line : lines)
    EXPECT_NE(r.text.find(line), std::string::npos) << line << "\n" << r.text;
}

const std::string kHead = "G21 G17 G90 G94\nT2 M6\nG43 H2\nG0 X0 Y0 Z5\n(OPERATION: POCKET)\n";

TEST(RewriteExpansion, AWhileLoopOfPassesIsWrittenOutCorrected) {
  // Three passes at depths set by a counter, in expressions the in-place
  // rewrite could not keep.
  const std::string program = kHead +
                              "#1 = 1\n"
                              "o100 while [#1 LE 3]\n"
                              "G1 Z[-#1] F100\n"
                              "G1 X10 F300\n"
                              "G1 Y10\n"
                              "G0 Z5\n"
                              "G0 X0 Y0\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "G0 Z20\n"
                              "M30\n";
  const V offset(0.01, -0.02, 0.03);
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
  EXPECT_EQ(r.summary.expansions, 1);
  EXPECT_EQ(r.summary.moves_rewritten, 9);
  EXPECT_EQ(r.text.find("\no100"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("(truecut rewrite: lines 7-14, the loop o100 while ... endwhile"),
            std::string::npos)
      << r.text;
  // The lines around the loop byte for byte.
  EXPECT_EQ(r.text.rfind(kHead + "#1 = 1\n", std::string::npos), r.text.find("G21"));
  EXPECT_NE(r.text.find("\nG0 Z20\nM30\n"), std::string::npos) << r.text;
  expect_same_path_shifted(program, r.text, options(), offset);
}

TEST(RewriteExpansion, ARepeatInIncrementalDistanceEndsInG91AsTheOriginal) {
  // Steps over in G91 inside the loop, and a G91 move after it.
  const std::string program = kHead +
                              "G1 Z-1 F100\n"
                              "o7 repeat [4]\n"
                              "G91 G1 X5 F250\n"
                              "G0 Y2\n"
                              "o7 endrepeat\n"
                              "G0 Z6\n"
                              "G90 G0 Z20\n"
                              "M30\n";
  const V offset(-0.004, 0.0, 0.012);
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
  EXPECT_EQ(r.summary.expansions, 1);
  // The loop's moves are written in G90, then G91 again for the G0 Z6 kept
  // after it (a relative move up from the loop's last point).
  EXPECT_NE(r.text.find("\nG91\nG0 Z6\n"), std::string::npos) << r.text;
  expect_same_path_shifted(program, r.text, options(), offset);
}

// Issue 22 point 5: a loop under a computed label (o[#5] while, o#6 repeat,
// a do ... while and a break under o[...]) ended where the interpreter's run
// of it ended; it was refused ("its end cannot be found"). Written out, it
// gives the moves of the same program under literal labels, line for line
// but for the note naming the loop; the label #5 changes inside the while
// loop, so its closing line could not be read from the text alone.
TEST(RewriteExpansion, LoopsUnderComputedLabelsAreWrittenOutAsUnderLiteralOnes) {
  struct Case {
    std::string computed, literal;
  };
  const std::string head = kHead + "#5 = 100\n#6 = 7\n";
  const std::vector<Case> cases = {
      {"#1 = 1\no[#5] while [#1 LE 3]\nG1 Z[-#1] F100\nG1 X10 F300\n#5 = 100\nG0 Z5\n"
       "G0 X0\n#1 = [#1 + 1]\no[#5] endwhile\n",
       "#1 = 1\no100 while [#1 LE 3]\nG1 Z[-#1] F100\nG1 X10 F300\n#5 = 100\nG0 Z5\n"
       "G0 X0\n#1 = [#1 + 1]\no100 endwhile\n"},
      {"G1 Z-1 F100\no#6 repeat [3]\nG91 G1 X5 F250\nG0 Y2\no#6 endrepeat\nG90\n",
       "G1 Z-1 F100\no7 repeat [3]\nG91 G1 X5 F250\nG0 Y2\no7 endrepeat\nG90\n"},
      {"#2 = 0\no[#6 + 1] do\nG1 X[#2 * 4] Y[#2] F200\n#2 = [#2 + 1]\no[#6 + 1] while [#2 LT 3]\n",
       "#2 = 0\no8 do\nG1 X[#2 * 4] Y[#2] F200\n#2 = [#2 + 1]\no8 while [#2 LT 3]\n"},
      {"#2 = 0\no[#5] while [1]\nG1 X[#2] Y[#2 * 2] F200\n#2 = [#2 + 1]\no[#5] if [#2 GT 2]\n"
       "o[#5] break\no[#5] endif\no[#5] endwhile\n",
       "#2 = 0\no100 while [1]\nG1 X[#2] Y[#2 * 2] F200\n#2 = [#2 + 1]\no101 if [#2 GT 2]\n"
       "o100 break\no101 endif\no100 endwhile\n"},
  };
  const V offset(0.012, -0.007, 0.02);
  for (const Case& c : cases) {
    const std::string computed = head + c.computed + "G0 Z20\nM30\n";
    const std::string literal = head + c.literal + "G0 Z20\nM30\n";
    try {
      const RewriteResult rc = rewrite_program(computed, "p.ngc", constant(offset), options());
      const RewriteResult rl = rewrite_program(literal, "p.ngc", constant(offset), options());
      EXPECT_EQ(rc.summary.expansions, 1) << rc.text;
      EXPECT_EQ(rc.summary.moves_rewritten, rl.summary.moves_rewritten);
      // The same text but for the note's name of the loop.
      std::istringstream a(rc.text), b(rl.text);
      std::string la, lb;
      int line = 0, notes = 0;
      while (std::getline(a, la) && std::getline(b, lb)) {
        ++line;
        if (la.rfind("(truecut rewrite: lines ", 0) == 0) {
          ++notes;
          continue;
        }
        EXPECT_EQ(la, lb) << "line " << line << "\n" << rc.text;
      }
      EXPECT_TRUE(a.eof() || !std::getline(a, la)) << rc.text;
      EXPECT_EQ(notes, 1) << rc.text;
      expect_same_path_shifted(computed, rc.text, options(), offset);
    } catch (const GcodeError& e) {
      ADD_FAILURE() << e.what() << "\n" << computed;
    }
  }
}

TEST(RewriteExpansion, ASubroutineFileCalledTwiceIsWrittenOutAtEachCall) {
  const fs::path dir = truecut::test::scratch_dir();
  std::ofstream(dir / "ring.ngc") << "o<ring> sub\n"
                                     "G0 X#1 Y0\n"
                                     "G1 Z#2 F120\n"
                                     "G3 X-#1 Y0 I-#1 J0 F400\n"
                                     "G3 X#1 Y0 I#1 J0\n"
                                     "G0 Z5\n"
                                     "o<ring> endsub\n"
                                     "M2\n";
  const std::string program =
      kHead + "o<ring> call [8] [-1]\nG4 P0.5\no<ring> call [12] [-2]\n" + "G0 Z20\nM30\n";
  const V offset(0.02, 0.01, -0.015);
  const RewriteOptions o = options(dir);
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), o);
  EXPECT_EQ(r.summary.expansions, 2);
  EXPECT_EQ(r.summary.moves_rewritten, 6);
  EXPECT_EQ(r.text.find("\no<ring> call"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("\nG4 P0.5\n"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("feed moves of operation 'POCKET' in a subroutine file"), std::string::npos)
      << r.text;
  expect_same_path_shifted(program, r.text, o, offset);
}

TEST(RewriteExpansion, ASubroutineOfTheProgramCalledTwiceIsCorrectedAtBothCalls) {
  // Both calls are written out: the definition's lines run twice.
  const std::string program =
      "o<pass> sub\nG1 Z#1 F100\nG1 X10 F300\nG0 Z5\nG0 X0\no<pass> endsub\n" + kHead +
      "o<pass> call [-1]\no<pass> call [-2]\nG0 Z20\nM30\n";
  const V offset(0.0, 0.02, 0.01);
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
  EXPECT_EQ(r.summary.expansions, 2);
  // The definition stays, no longer called.
  EXPECT_NE(r.text.find("o<pass> sub\nG1 Z#1 F100\n"), std::string::npos) << r.text;
  EXPECT_EQ(r.text.find("\no<pass> call"), std::string::npos) << r.text;
  expect_same_path_shifted(program, r.text, options(), offset);
}

// Programs drawn from a seed: loops of each kind, nested, in G90 or G91,
// with calls of a subroutine of the program, back to back, each checked
// against the original's own moves with its own correction.
TEST(RewriteExpansion, DrawnLoopProgramsComeOutShiftedByTheirCorrection) {
  std::mt19937 rng(20261129);
  auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  auto pick = [&](int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); };
  for (int seed = 0; seed < 24; ++seed) {
    std::string p =
        "o<step> sub\nG1 X[#<_cx> + #1] F[#2]\n#<_cx> = [#<_cx> + #1]\no<step> endsub\n" + kHead +
        "#<_cx> = 0\n";
    const int loops = 1 + pick(3);
    for (int l = 0; l < loops; ++l) {
      const int n = 1 + pick(4);
      const std::string label = std::to_string(100 + l);
      const std::string dx = rt_number(uniform(0.5, 6));
      const std::string feed = std::to_string(100 + 50 * pick(6));
      std::string body;
      switch (pick(3)) {
        case 0:
          body = "G1 Z" + rt_number(uniform(-3, 0)) + " F80\no<step> call [" + dx + "] [" + feed +
                 "]\nG0 Z2\n";
          break;
        case 1:
          body = "G91 G1 X" + dx + " Y" + rt_number(uniform(-2, 2)) + " F" + feed + "\nG90\n";
          break;
        default:
          body = "G1 Y" + rt_number(uniform(-8, 8)) + " F" + feed + "\nG2 X[#<_cx> + " + dx +
                 "] Y0 R" + rt_number(uniform(9, 14)) + "\n#<_cx> = [#<_cx> + " + dx + "]\n";
          break;
      }
      if (pick(2) == 0) {
        p += "o" + label + " repeat [" + std::to_string(n) + "]\n" + body + "o" + label +
             " endrepeat\n";
      } else {
        p += "#9 = 0\no" + label + " while [#9 LT " + std::to_string(n) + "]\n" + body +
             "#9 = [#9 + 1]\no" + label + " endwhile\n";
      }
      p += "G90 G0 Z5\nG0 X#<_cx> Y0\n";
    }
    p += "G0 Z20\nM30\n";
    const V offset(uniform(-0.05, 0.05), uniform(-0.05, 0.05), uniform(-0.05, 0.05));
    SCOPED_TRACE("seed " + std::to_string(seed) + "\n" + p);
    expect_rewritten_shifted(p, offset);
  }
}

TEST(RewriteExpansion, ProfilesUnderCutterCompensationInALoopAreWrittenWhereTheToolWent) {
  // Each pass enters G41, goes round a square and leaves with G40; the
  // oracle's moves are those of the compensated tool (the interpreter's).
  const std::string program = kHead +
                              "o5 repeat [3]\n"
                              "G1 Z[-1 * #<_pass>] F100\n"
                              "G41 D2 G1 X5 Y5 F300\n"
                              "X25\nY25\nX5\nY5\n"
                              "G40 G1 X0 Y0\n"
                              "#<_pass> = [#<_pass> + 1]\n"
                              "o5 endrepeat\n"
                              "G0 Z20\nM30\n";
  const std::string with_start = "#<_pass> = 1\n" + program;
  const V offset(0.01, 0.02, -0.01);
  const RewriteResult r = rewrite_program(with_start, "p.ngc", constant(offset), options());
  EXPECT_EQ(r.summary.expansions, 1);
  EXPECT_EQ(r.text.find("G41 D"), std::string::npos) << r.text;
  expect_same_path_shifted(with_start, r.text, options(), offset);
}

TEST(RewriteExpansion, CannedCyclesInALoopAreWrittenOutWithEachHoleCorrected) {
  // A row of G81, G82 (dwell) and G83 (pecks) holes per pass of a loop. As
  // on a cycle line that runs once, each hole moves by the correction: every
  // move of the cycle over the shifted hole, its bottom shifted in depth, the
  // R plane, the pecks above the bottom and the retract height unchanged.
  const std::string program =
      "G21 G17 G90 G94\nT2 M6\nG43 H2\nG0 X0 Y0 Z10\n(OPERATION: POCKET)\n#1 = 0\n"
      "o1 while [#1 LT 3]\n"
      "G98 G81 X[#1 * 10] Y5 Z-3 R2 F100\n"
      "G82 X[#1 * 10] Y15 Z-3 R2 P0.5\n"
      "G83 X[#1 * 10] Y25 Z-5 R2 Q2\n"
      "G80\n"
      "#1 = [#1 + 1]\n"
      "o1 endwhile\n"
      "G0 Z20\nM30\n";
  const V offset(0.02, -0.01, 0.015);
  const RewriteOptions o = options();
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), o);
  EXPECT_EQ(r.summary.expansions, 1);
  EXPECT_EQ(r.summary.expanded_holes, 9);
  EXPECT_NE(r.text.find("\nG4 P0.5\n"), std::string::npos) << r.text;
  const CanonProgram a = Interpreter(o.interpreter).run_text(program, "p.ngc");
  const CanonProgram b = Interpreter(o.interpreter).run_text(r.text, "p.ngc");
  std::vector<std::pair<Axes6, bool>> want, got;  // end, a feed
  std::vector<double> bottoms;                    // the depth of each cycle move's hole
  for (const CanonCall& c : a.calls) {
    if (!is_motion(c.op)) continue;
    const bool feed = !std::holds_alternative<StraightTraverse>(c.op);
    want.push_back(
        {feed ? std::get<StraightFeed>(c.op).end : std::get<StraightTraverse>(c.op).end, feed});
    bottoms.push_back(c.context.canned_cycle == 830 ? -5 : c.context.canned_cycle ? -3 : 1e9);
  }
  for (const CanonCall& c : b.calls) {
    if (!is_motion(c.op)) continue;
    const bool feed = !std::holds_alternative<StraightTraverse>(c.op);
    got.push_back(
        {feed ? std::get<StraightFeed>(c.op).end : std::get<StraightTraverse>(c.op).end, feed});
  }
  ASSERT_EQ(got.size(), want.size()) << r.text;
  for (size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE("move " + std::to_string(i));
    EXPECT_EQ(got[i].second, want[i].second);
    const Axes6& w = want[i].first;
    const Axes6& g = got[i].first;
    if (bottoms[i] > 1e8) {  // not a cycle's: where it went
      EXPECT_NEAR(g.x, w.x, 1e-9);
      EXPECT_NEAR(g.y, w.y, 1e-9);
      EXPECT_NEAR(g.z, w.z, 1e-9);
      continue;
    }
    EXPECT_NEAR(g.x, w.x + offset.x(), 1e-6);
    EXPECT_NEAR(g.y, w.y + offset.y(), 1e-6);
    EXPECT_NEAR(g.z, w.z + (w.z == bottoms[i] ? offset.z() : 0.0), 1e-6);
  }
}

// A rapid right after a corrected point goes back to the original point: on
// its own line when the line can take the point in its words, else (words
// from parameters, a G28, G91) after a G0 back written before the line,
// which is kept; a G53 move is written in the program's coordinates.
TEST(RewriteExpansion, RapidsAfterACorrectedPointLeaveFromTheOriginalPoint) {
  const std::string head =
      "G21 G17 G90 G94\nT2 M6\nG43 H2\nG10 L2 P1 X10 Y-5 Z-20\nG54\n"
      "G0 X0 Y0 Z5\n(OPERATION: POCKET)\nG1 Z-1 F100\nG1 X10 F300\n";
  const V offset(0.03, 0.01, -0.02);
  for (const std::string rapid :
       {"#1 = 7\nG0 Z#1\n", "G53 G0 Z0\n", "G91 G0 Z4\nG90\n", "G28\n", "G0 Z[2 + 3]\n"}) {
    const std::string program = head + rapid + "G0 X-3\nM30\n";
    SCOPED_TRACE(program);
    expect_rewritten_shifted(program, offset);
  }
}

TEST(RewriteExpansion, SpindleAndCoolantInALoopSwitchWhereTheyDidInTheOriginal) {
  const std::string program = kHead +
                              "#1 = 0\n"
                              "o100 while [#1 lt 3]\n"
                              "S[1000 + 100 * #1] M3\n"
                              "M8\n"
                              "G1 Z-1 F100\n"
                              "M7\n"
                              "G1 X[10 + #1] F300\n"
                              "M9\n"
                              "G96 D2000 S100 M4\n"
                              "G1 Y4\n"
                              "G97 S500\n"
                              "M5\n"
                              "G0 Z5\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "M8\n"
                              "M30\n";
  expect_rewritten_shifted(program, V(0.02, -0.01, 0.015));
  const RewriteResult r =
      rewrite_program(program, "p.ngc", constant(V(0.02, -0.01, 0.015)), options());
  EXPECT_EQ(r.summary.expansions, 1) << r.text;
}

// G93 inside a loop: every written feed line carries its F, the pieces of a
// move its share of the move's time; feed-mode words switch where they did.
TEST(RewriteExpansion, InverseTimeFeedsInALoopKeepEachMovesTime) {
  const std::string switched_inside = kHead +
                                      "#1 = 0\n"
                                      "o100 while [#1 lt 2]\n"
                                      "G93\n"
                                      "G1 Z-1 F2\n"
                                      "G1 X[10 + #1] Y3 F4\n"
                                      "G2 X[20 + #1] Y3 I5 J0 F1.5\n"
                                      "G94\n"
                                      "G1 X0 F300\n"
                                      "G0 Z5\n"
                                      "#1 = [#1 + 1]\n"
                                      "o100 endwhile\n"
                                      "M30\n";
  expect_rewritten_shifted(switched_inside, V(0.02, -0.01, 0.015));
  const std::string in_force_before = kHead +
                                      "G93\n"
                                      "o1 repeat [3]\n"
                                      "G91 G1 X4 Y1 Z-0.5 F[60 / 0.333]\n"
                                      "G90\n"
                                      "o1 endrepeat\n"
                                      "G1 X0 Y0 F3\n"
                                      "G94 G0 Z5\n"
                                      "M30\n";
  expect_rewritten_shifted(in_force_before, V(-0.01, 0.03, 0.005));
}

// G33 inside a loop or alone: each threading move stays one G33 line with
// its K (a G33 waits for the spindle's index pulse, so pieces would restart
// the thread), its end corrected.
TEST(RewriteExpansion, ThreadingMovesInALoopStayOneG33LineEach) {
  const std::string program = kHead +
                              "S400 M3\n"
                              "#1 = 0\n"
                              "o100 while [#1 lt 3]\n"
                              "G0 X[-1 - 0.1 * #1] Z1\n"
                              "G33 Z-20 K1.5\n"
                              "G0 X5\n"
                              "G0 Z1\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "M30\n";
  const V offset(0.02, -0.01, 0.015);
  expect_rewritten_shifted(program, offset);
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
  size_t g33_lines = 0;
  for (size_t at = r.text.find("G33 "); at != std::string::npos; at = r.text.find("G33 ", at + 1)) {
    ++g33_lines;
    const size_t eol = r.text.find('\n', at);
    EXPECT_NE(r.text.substr(at, eol - at).find(" K1.5"), std::string::npos) << r.text;
  }
  EXPECT_EQ(g33_lines, 3u) << r.text;

  // Outside a loop the G33 line is written out the same way.
  const std::string once = kHead + "S400 M3\nG0 X-1 Z1\nG33 Z-20 K1.5\nG0 X5\nM30\n";
  expect_rewritten_shifted(once, offset);
  const RewriteResult r1 = rewrite_program(once, "p.ngc", constant(offset), options());
  EXPECT_EQ(r1.summary.expansions, 1) << r1.text;
  EXPECT_NE(r1.text.find("G33 X-0.980000 Y-0.010000 Z-19.985000 K1.5"), std::string::npos)
      << r1.text;
}

// Outputs, override switches, optional stops, spindle orient and log lines
// inside a loop: each written where it came among the moves (M62/M63 and
// M67 before the move they go with), as the calls of the original
// (issue 22 point 5; before, the rewrite refused the loop).
TEST(RewriteExpansion, OutputsOverridesStopsAndLogsInALoopComeWhereTheyDid) {
  const std::string program = kHead +
                              "(LOGOPEN,holes.txt)\n"
                              "#1 = 0\n"
                              "o100 while [#1 lt 3]\n"
                              "M62 P1\n"
                              "G1 Z-1 F100\n"
                              "M63 P1\n"
                              "M50 P0\n"
                              "M67 E2 Q[2.5 * #1]\n"
                              "G1 X[10 + #1] F300\n"
                              "M64 P3\n"
                              "M68 E0 Q-1.25\n"
                              "(LOG,pass #1 at x #5420)\n"
                              "M1\n"
                              "M51 P0\n"
                              "M52 P1\n"
                              "M53 P0\n"
                              "G1 Y4\n"
                              "M65 P3 M48\n"
                              "M5\n"
                              "M19 R[90 + #1] P1 Q2\n"
                              "G0 Z5\n"
                              "M19 Q0.5\n"
                              "S1000 M3\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "(LOGCLOSE)\n"
                              "M30\n";
  const V offset(0.02, -0.01, 0.015);
  expect_one_expansion_with(program, offset,
                            {"M62 P1\nG1 X0.020000 Y-0.010000 Z4.515000 F100", "M67 E2 Q5\n",
                             "M68 E0 Q-1.25\n", "(LOG,pass 2.000000 at x 12.000000)\n",
                             "M19 R92 P1 Q2\n", "M19 Q0.5\n", "M50 P1\nM51 P1\n"});
}

// A grid of parts from one subroutine, each under its own G52 local offset,
// and a G92 set at a position inside a loop: each offset is written as the
// G52 that gives it, and the moves after it in that frame (issue 22 point 5).
TEST(RewriteExpansion, LocalOffsetsInALoopAreWrittenAsTheG52TheyGive) {
  const std::string grid = kHead +
                           "o<part> sub\n"
                           "G0 X0 Y0\n"
                           "G1 Z-1 F100\n"
                           "G1 X6 F300\n"
                           "G2 X6 Y6 I0 J3\n"
                           "G0 Z5\n"
                           "o<part> endsub\n"
                           "#1 = 0\n"
                           "o100 while [#1 lt 3]\n"
                           "G52 X[#1 * 20] Y[#1 * 5]\n"
                           "o<part> call\n"
                           "#1 = [#1 + 1]\n"
                           "o100 endwhile\n"
                           "G52 X0 Y0\n"
                           "G0 X1 Y1\n"
                           "M30\n";
  const V offset(0.02, -0.01, 0.015);
  expect_one_expansion_with(grid, offset, {"G52 X40 Y10 Z0 A0 C0\n"});

  const std::string g92 = kHead +
                          "o100 repeat [2]\n"
                          "G0 X0 Y0\n"
                          "G92 X-15 Y0\n"
                          "G1 Z-1 F100\n"
                          "G1 X-5 F300\n"
                          "G0 Z5\n"
                          "G92.1\n"
                          "G0 X10\n"
                          "G92 X0\n"
                          "G1 X3\n"
                          "G92.2\n"
                          "o100 endrepeat\n"
                          "G0 X0 Y0\n"
                          "M30\n";
  expect_rewritten_shifted(g92, offset);
}

// Fixtures in a loop: each pass selects its work offset (G55, G56 set with
// G10 L2 before the loop, one of them rotated), sets the one in use again
// with G10 L2 and G10 L20, and switches units; each is written where it
// came (issue 22 point 5).
TEST(RewriteExpansion, WorkOffsetsAndUnitsInALoopAreWrittenWhereTheyCame) {
  const V offset(0.02, -0.01, 0.015);
  const std::string program = kHead +
                              "G10 L2 P2 X40 Y0 Z0\n"
                              "G10 L2 P3 X80 Y5 Z-1 R10\n"
                              "#1 = 0\n"
                              "o100 while [#1 lt 3]\n"
                              "o101 if [#1 eq 1]\n"
                              "G55\n"
                              "o101 elseif [#1 eq 2]\n"
                              "G56\n"
                              "o101 endif\n"
                              "G0 X0 Y0\n"
                              "G1 Z-1 F100\n"
                              "G1 X6 F300\n"
                              "G10 L2 P0 X[40 + #1] Y1 R[2 * #1]\n"
                              "G1 Y3\n"
                              "G10 L20 P0 Z4\n"
                              "G0 Z5\n"
                              "G20\n"
                              "G0 X0.1\n"
                              "G21\n"
                              "G54\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "G0 X0 Y0\n"
                              "M30\n";
  expect_one_expansion_with(program, offset,
                            {"\nG55\n", "\nG56\n", "\nG10 L2 P3 X42 Y1 Z-1 A0 C0 R4\n", "\nG20\n"});
}

// G10 L2 and L20 of systems not in use inside a loop, each pass then cutting
// in the system it set (and the one set last selected again after the loop):
// the interpreter's COMMENT carries the origin each G10 gave, written as the
// G10 L2 that gives it (issue 22 point 5; these were refused before).
TEST(RewriteExpansion, OriginsOfSystemsNotInUseSetInALoopAreWrittenAsG10L2) {
  const V offset(0.02, -0.01, 0.015);
  const std::string program = kHead +
                              "#1 = 0\n"
                              "o100 while [#1 lt 2]\n"
                              "G10 L2 P4 X[30 * #1 + 10] Y2 R[5 * #1]\n"
                              "G0 X3 Y4\n"
                              "G10 L20 P5 X1 Y[#1]\n"
                              "G57\n"
                              "G0 X0 Y0\n"
                              "G1 Z-1 F100\n"
                              "G1 X6 F300\n"
                              "G0 Z5\n"
                              "G58\n"
                              "G1 X2 Y2 F300\n"
                              "G54\n"
                              "G0 X0 Y0\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "G58\n"
                              "G0 X1 Y1\n"
                              "G54\n"
                              "M30\n";
  // Second pass: G54 origin 0, tool at G54 (3, 4) when G10 L20 P5 X1 Y1
  // puts G58's origin at (2, 3).
  expect_one_expansion_with(
      program, offset,
      {"\nG10 L2 P4 X40 Y2 Z0 A0 C0 R5\n", "\nG10 L2 P5 X2 Y3 Z", "\nG57\n", "\nG58\n"});
}

// Two tools in turn inside a loop, with G43, G43.1, G43.2 and G49: the
// changes and offsets written where they came, each tool's feeds corrected
// with its own length offset in force (issue 22 point 5).
TEST(RewriteExpansion, ToolChangesAndLengthOffsetsInALoopAreWrittenWhereTheyCame) {
  const std::string program = kHead +
                              "o100 repeat [2]\n"
                              "T1 M6\n"
                              "G43 H1\n"
                              "S8000 M3\n"
                              "G0 X0 Y0 Z5\n"
                              "G1 Z-1 F100\n"
                              "G1 X6 F300\n"
                              "G0 Z5\n"
                              "T2 M6\n"
                              "G43 H2\n"
                              "G43.1 Z41.5\n"
                              "M3\n"
                              "G1 Z-1 F100\n"
                              "G1 Y6 F300\n"
                              "G43.2 H1\n"
                              "G0 Z80\n"
                              "G49\n"
                              "M61 Q2\n"
                              "G43 H0\n"
                              "G0 Z5\n"
                              "o100 endrepeat\n"
                              "M30\n";
  const V offset(0.02, -0.01, 0.015);
  expect_one_expansion_with(
      program, offset,
      {"\nT1\nM6\nG43.1 X0 Y0 Z35 A0 C0\n", "\nG43.1 X0 Y0 Z41.5 A0 C0\n",
       "\nG43.1 X0 Y0 Z76.5 A0 C0\n", "\nG49\nM61 Q2\nG43.1 X0 Y0 Z40 A0 C0\n"});
}

TEST(RewriteExpansion, WhatAnExpansionCannotWriteIsRefusedNamingTheLoop) {
  const std::string output = kHead +
                             "o1 repeat [2]\n"
                             "G1 Z-1 F100\n"
                             "G38.2 Z-10 F50\n"
                             "G0 Z5\n"
                             "o1 endrepeat\n"
                             "M30\n";
  try {
    rewrite_program(output, "bad.ngc", constant(V(0.01, 0, 0)), options());
    ADD_FAILURE() << "no error";
  } catch (const GcodeError& e) {
    EXPECT_EQ(e.where().line, 8) << e.what();
    const std::string msg = e.what();
    EXPECT_NE(msg.find("inside the loop o1 repeat ... endrepeat (lines 6-10)"), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("run more than once"), std::string::npos) << msg;
  }
}

// The switches a canned cycle makes itself, in a loop: G84/G74 tapping turns
// the feed and speed overrides off and reverses the spindle at the bottom,
// G88 stops the spindle and the program there. Written out as the M50/M51,
// M5/M3/M4, G4 and M0 lines that make the same calls, between the same
// moves, each hole corrected at its bottom (issue 22 point 5; before, the
// rewrite refused the loop). rs274 runs the rewritten program to the same
// calls but for the holes.
TEST(RewriteExpansion, TappingAndManualBoringInALoopSwitchAsTheCycleDid) {
  const std::string program = kHead +
                              "#1 = 0\n"
                              "o100 while [#1 lt 2]\n"
                              "S500 M3\n"
                              "G98 G84 X[#1 * 10] Y5 Z-3 R1 F250\n"
                              "G80\n"
                              "S400 M4\n"
                              "G99 G74 X[#1 * 10] Y15 Z-4 R1 F200\n"
                              "G80\n"
                              "S300 M3\n"
                              "G88 X[#1 * 10] Y25 Z-2 R1 P0.5 F100\n"
                              "G80\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "G0 Z20\n"
                              "M30\n";
  const V offset(0.02, -0.01, 0.015);
  expect_one_expansion_with(
      program, offset,
      {"M50 P0\nM51 P0\nG1 X0.020000 Y4.990000 Z-2.985000 F250\nM5\nM4\nG4 P0\n",
       "M5\nM3\nM50 P1\nM51 P1\n", "G4 P0.5\nM5\nM0\nM3\n"});
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
  EXPECT_EQ(r.summary.expanded_holes, 6) << r.text;

  std::string why;
  const auto& rs274 = testing::rs274_oracle(why);
  if (!rs274) TRUECUT_ORACLE_MISSING(testing::rs274_missing(why));
  const fs::path dir =
      truecut::test::binary_dir() / "rewrite-expansion-tapping" / std::to_string(::getpid());
  fs::create_directories(dir);
  std::ofstream(dir / "tools.tbl") << kTools;
  std::ofstream(dir / "original.ngc") << program;
  std::ofstream(dir / "rewritten.ngc") << r.text;
  // rs274's calls but for the positions of moves (and comments, which the
  // rewrite adds), as "NAME(args)".
  auto switches = [&](const char* file) {
    const auto run = truecut::test::run_process(
        {rs274->program.string(), "-g", "-t", (dir / "tools.tbl").string(), std::string(file)},
        dir);
    EXPECT_EQ(run.exit_code, 0) << file << ": " << run.err;
    std::vector<std::string> out;
    std::istringstream in(run.out);
    std::string line, feed;
    while (std::getline(in, line)) {
      const size_t at = line.find("N..... ");
      if (at == std::string::npos) continue;
      std::string call = line.substr(at + 7);
      if (call.rfind("COMMENT", 0) == 0) continue;
      // The feed goes with the move (the rewrite writes F on the move's line).
      if (call.rfind("SET_FEED_RATE", 0) == 0) {
        feed = call;
        continue;
      }
      if (call.rfind("STRAIGHT_FEED", 0) == 0) call = "STRAIGHT_FEED at " + feed;
      if (call.rfind("STRAIGHT_TRAVERSE", 0) == 0) call = "STRAIGHT_TRAVERSE";
      out.push_back(call);
    }
    return out;
  };
  const std::vector<std::string> want = switches("original.ngc");
  EXPECT_EQ(std::count(want.begin(), want.end(), "PROGRAM_STOP()"), 2);
  EXPECT_EQ(std::count(want.begin(), want.end(), "DISABLE_FEED_OVERRIDE()"), 4);
  EXPECT_EQ(switches("rewritten.ngc"), want) << r.text;
}

// G87 in a loop, under M3: its moves written out, the hole corrected at its
// back-bore height K (the top of its feeds), the entry beside the hole
// shifted with it, and its spindle orients as the M19 R0 P2 that makes the
// same ORIENT_SPINDLE call (issue 22 point 5; before, refused).
TEST(RewriteExpansion, BackBoringInALoopIsWrittenOutCorrectedAtItsBackBoreHeight) {
  const std::string program = kHead +
                              "S800 M3\n"
                              "#1 = 0\n"
                              "o100 while [#1 lt 2]\n"
                              "G98 G87 X[#1 * 10] Y5 Z-8 R2 I1.5 J0 K-3 F100\n"
                              "G80\n"
                              "#1 = [#1 + 1]\n"
                              "o100 endwhile\n"
                              "G0 Z20\n"
                              "M30\n";
  const V offset(0.02, -0.01, 0.015);
  expect_one_expansion_with(
      program, offset,
      {"G0 X1.520000 Y4.990000 Z2.000000\nM5\nM19 R0 P2\n",
       "G0 X0.020000 Y4.990000 Z-8.000000\nM3\nG1 X0.020000 Y4.990000 Z-2.985000 F100\n"
       "G1 X0.020000 Y4.990000 Z-8.000000\nM5\nM19 R0 P2\n"});
  const RewriteResult r = rewrite_program(program, "p.ngc", constant(offset), options());
  EXPECT_EQ(r.summary.expanded_holes, 2) << r.text;
}

}  // namespace
}  // namespace truecut::interp
