// The oracle: the same programs through LinuxCNC's standalone interpreter
// `rs274` and through `truecut canon` must give the same canonical calls
// (positions, arc centres, feeds, planes, offsets, tools, comments).
//
// rs274 comes from Debian's linuxcnc-uspace package: the installed one, or
// fetched and unpacked at test time by fetch_rs274.sh (rs274_oracle.hpp).
// Without it the tests are skipped with a message saying what to install,
// or fail under TRUECUT_REQUIRE_ORACLES=1.
// LinuxCNC's sample programs are GPL: they are read from that package only.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <vector>

#include "rs274_compare.hpp"
#include "rs274_oracle.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"

namespace truecut::interp::testing {
namespace {

namespace fs = std::filesystem;
using truecut::test::cli_path;
using truecut::test::run_process;
using truecut::test::source_dir;

// Sample programs rs274 runs but truecut rejects on purpose (docs/gcode.md
// lists them). Keyed by "<folder>/<file>".
const std::map<std::string, std::string>& out_of_scope() {
  static const std::map<std::string, std::string> kList = {
      {"ncfiles/lathe_g70_71_demo.ngc", "lathe cycles G70/G71"},
      {"ncfiles/lathe_g7x_face_boring.ngc", "lathe cycles G70-G72"},
      {"ncfiles/lathe_g7x_quadrants.ngc", "lathe cycles G70-G72"},
      {"ncfiles/lathe_pawn.ngc", "lathe radius/diameter mode G7/G8"},
      {"millturn/example.ngc", "lathe radius/diameter mode G7/G8"}};
  return kList;
}

struct Oracle {
  fs::path rs274;  // wrapper script
  fs::path share;  // holds linuxcnc/ncfiles and doc/linuxcnc/examples
  fs::path work;   // tool tables, filtered copies
};

// rs274 once per test process; nullopt (with the reason) when unavailable.
const std::optional<Oracle>& oracle(std::string& why) {
  static const std::optional<Oracle> o = [&]() -> std::optional<Oracle> {
    const auto& found = rs274_oracle(why);
    if (!found) return std::nullopt;
    // ctest runs the tests of this file as parallel processes: each writes
    // its tool tables and filtered copies into a folder of its own.
    Oracle out{found->program, found->share,
               found->program.parent_path() / "work" / std::to_string(getpid())};
    fs::create_directories(out.work);
    // One tool table for both, in inches: rs274 without an INI reads it so,
    // truecut with --tool-units inch.
    std::ofstream inch(out.work / "tools-inch.tbl");
    char line[160];
    for (int t : {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 99, 100}) {
      const double z = 0.1 * t, d = 0.0625 * (t <= 20 ? t : 1), x = t == 2 ? 0.05 : 0.0;
      std::snprintf(line, sizeof line, "T%d P%d X%.6f Z%.6f D%.6f ;tool %d\n", t, t, x, z, d, t);
      inch << line;
    }
    return out;
  }();
  rs274_oracle(why);
  return o;
}

struct Outcome {
  bool rs274_runs = false;
  std::string rs274_error;
  bool truecut_runs = false;
  std::string truecut_error;
  std::optional<std::string> difference;
};

// The 5-axis demos switch kinematics with M428-M430 remaps that need a
// running HAL: those lines are dropped for both interpreters.
fs::path without_kinematics_remaps(const Oracle& o, const fs::path& program) {
  std::ifstream in(program);
  std::string text, line;
  bool dropped = false;
  static const std::regex remap(R"(^\s*[mM]4(28|29|30)\b.*)");
  while (std::getline(in, line)) {
    if (std::regex_match(line, remap)) {
      dropped = true;
      continue;
    }
    text += line + "\n";
  }
  if (!dropped) return program;
  const fs::path copy = o.work / "filtered" / program.parent_path().filename() / program.filename();
  fs::create_directories(copy.parent_path());
  std::ofstream(copy) << text;
  return copy;
}

// With a parameter file (LinuxCNC's .var, in inches as rs274 reads it
// without an INI): rs274 gets a copy, since it writes the file back at exit.
Outcome run_both(const Oracle& o, const fs::path& original,
                 const std::optional<fs::path>& var_file = std::nullopt) {
  const fs::path program = without_kinematics_remaps(o, original);
  const fs::path dir = program.parent_path();
  Outcome out;
  std::vector<std::string> rs274 = {o.rs274.string(), "-g", "-t",
                                    (o.work / "tools-inch.tbl").string()};
  std::vector<std::string> truecut = {cli_path().string(), "canon", "--decimals", "8", "--b-axis",
                                      "--tool-units", "inch", "--tool-table",
                                      (o.work / "tools-inch.tbl").string(),
                                      // rs274 without an INI: a machine in inches,
                                      // where its offset parameters are kept.
                                      "--var-units", "inch"};
  if (var_file) {
    const fs::path copy = o.work / "parameters.var";
    fs::copy_file(*var_file, copy, fs::copy_options::overwrite_existing);
    rs274.insert(rs274.end(), {"-v", copy.string()});
    truecut.insert(truecut.end(), {"--var-file", var_file->string()});
  }
  rs274.push_back(program.filename().string());
  truecut.push_back(program.filename().string());
  auto r = run_process(rs274, dir);
  out.rs274_runs = r.exit_code == 0;
  out.rs274_error = r.err.substr(0, 400);
  auto t = run_process(truecut, dir);
  out.truecut_runs = t.exit_code == 0;
  if (!out.truecut_runs) {
    out.truecut_error = t.err;
    // Bad input: a located message, exit 2 and nothing on stdout.
    static const std::regex located(R"(^[^:]+:\d+:\d+: .+\n$)");
    EXPECT_EQ(t.exit_code, 2) << program;
    EXPECT_TRUE(std::regex_match(t.err, located)) << program << ": " << t.err;
    EXPECT_EQ(t.out, "") << program;
  }
  if (out.rs274_runs && out.truecut_runs)
    out.difference = compare_listings(parse_listing(r.out), parse_listing(t.out));
  return out;
}

// Both interpreters run the program and print the same calls.
void expect_agreement(const Outcome& r, const std::string& what) {
  EXPECT_TRUE(r.rs274_runs) << what << ": rs274 rejects the program: " << r.rs274_error;
  EXPECT_TRUE(r.truecut_runs) << what << ": " << r.truecut_error;
  EXPECT_EQ(r.difference, std::nullopt) << what;
}

std::string key_of(const fs::path& p) {
  return p.parent_path().filename().string() + "/" + p.filename().string();
}

#define REQUIRE_ORACLE(o)      \
  std::string why;             \
  const auto& o = oracle(why); \
  if (!o) TRUECUT_ORACLE_MISSING(rs274_missing(why));

TEST(Rs274Oracle, OwnCorpusMatches) {
  REQUIRE_ORACLE(o);
  int compared = 0;
  for (const auto& p : ngc_programs_under(source_dir() / "tests/interp/corpus")) {
    if (p.filename().string().rfind("sinumerik", 0) == 0) continue;  // not LinuxCNC G-code
    const Outcome r = run_both(*o, p);
    expect_agreement(r, p.string());
    ++compared;
  }
  EXPECT_GE(compared, 6);
}

// Rotated coordinate systems (G10 L2 R, docs/gcode.md): arcs in all planes,
// G91, G92/G52, G53, G10 L20, G28/G30, canned cycles, cutter compensation,
// polar words, M70/M72, a #5230 write, M2; and in inches with XY tool
// offsets, G10 L10/L11, probing and G33.
TEST(Rs274Oracle, RotatedCoordinateSystemsMatch) {
  REQUIRE_ORACLE(o);
  for (const char* name : {"rotated_coordinates.ngc", "rotated_coordinates_inch.ngc"}) {
    const fs::path p = source_dir() / "tests/interp/corpus" / name;
    const Outcome r = run_both(*o, p);
    expect_agreement(r, p.string());
  }
}

// A setup held in the controller's parameter file (--var-file): G55 active
// with a rotation and an A offset, G92 on, the G28/G30 homes, G54 rotated;
// arcs in G17 and G18, a unit change. Without the file the same program
// runs from zero offsets (OwnCorpusMatches).
TEST(Rs274Oracle, ParameterFileSetupMatches) {
  REQUIRE_ORACLE(o);
  const fs::path dir = source_dir() / "tests/interp/corpus";
  const Outcome r =
      run_both(*o, dir / "parameter_file_setup.ngc", dir / "parameter_file_setup.var");
  expect_agreement(r, "parameter_file_setup.ngc with parameter_file_setup.var");
  // G92 offsets in force at the start for any non-zero #5210 (here 3).
  const Outcome g =
      run_both(*o, dir / "parameter_file_setup.ngc", dir / "g92_enabled_any_nonzero.var");
  expect_agreement(g, "parameter_file_setup.ngc with g92_enabled_any_nonzero.var");
  // A parameter file LinuxCNC itself ships (its 9-axis sim configuration:
  // 119 lines, with the U V W columns truecut has no axes for).
  const fs::path shipped =
      o->share / "doc/linuxcnc/examples/sample-configs/sim/qtvcp_screens/sim-9axis.var";
  ASSERT_TRUE(fs::exists(shipped)) << shipped;
  const Outcome s = run_both(*o, dir / "parameter_file_setup.ngc", shipped);
  expect_agreement(s, "parameter_file_setup.ngc with sim-9axis.var");
}

// G5, G5.1, G5.2/G5.3 (docs/gcode.md "Splines G5.x"), in mm and in
// inches: rs274 prints each spline as NURBS_FEED(number of control
// points, ...); the moves after them show where each spline ended.
TEST(Rs274Oracle, SplinesMatch) {
  REQUIRE_ORACLE(o);
  for (const char* name : {"splines.ngc", "splines_inch.ngc"}) {
    const fs::path p = source_dir() / "tests/interp/corpus" / name;
    const Outcome r = run_both(*o, p);
    expect_agreement(r, p.string());
    const auto t =
        run_process({cli_path().string(), "canon", "--tool-units", "inch", "--tool-table",
                     (o->work / "tools-inch.tbl").string(), p.filename().string()},
                    p.parent_path());
    EXPECT_NE(t.out.find("NURBS_FEED(4, ...)"), std::string::npos) << p;
    EXPECT_NE(t.out.find("NURBS_FEED(3, ...)"), std::string::npos) << p;
  }
}

// A number in [lo, hi] from rng's raw output (the random-program cases keep
// their fixed streams).
double uniform_in(std::mt19937& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng()) / static_cast<double>(rng.max()));
}

// Random programs under rotated coordinate systems: G10 L2 R of the active
// and of other systems, G10 L20, G54/G55/G56, G92/G92.1/G52, G53, G28/G30,
// absolute and incremental lines, full and half circles in G17 and G18, a
// canned cycle, and the position read back (#5420, #5421) in between.
TEST(Rs274Oracle, RandomRotatedProgramsAgree) {
  REQUIRE_ORACLE(o);
  const fs::path dir = o->work / "rotation_random";
  fs::create_directories(dir);
  std::mt19937 rng(20261128);
  auto u = [&](double lo, double hi) { return uniform_in(rng, lo, hi); };
  auto pick = [&](unsigned m) { return static_cast<unsigned>(rng() % m); };
  int matched = 0;
  for (int n = 0; n < 60; ++n) {
    std::string text = pick(4) == 0 ? "G20 F20\n" : "G21 F300\n";
    text += "G0 X1 Y2 Z3\n";
    char buf[200];
    const int blocks = 6 + static_cast<int>(pick(10));
    for (int k = 0; k < blocks; ++k) {
      switch (pick(14)) {
        case 0:
        case 1:
          std::snprintf(buf, sizeof buf, "G10 L2 P%u X%.3f Y%.3f R%.3f", pick(4), u(-20, 20),
                        u(-20, 20), u(-180, 180));
          break;
        case 2:
          std::snprintf(buf, sizeof buf, "G10 L2 P%u R%.3f", pick(4), u(-90, 90));
          break;
        case 3: {
          const unsigned w = pick(3);
          std::snprintf(buf, sizeof buf, "G10 L20 P%u%s%s Z%.3f", pick(4),
                        w != 1 ? (" X" + std::to_string(u(-5, 5)).substr(0, 6)).c_str() : "",
                        w != 0 ? (" Y" + std::to_string(u(-5, 5)).substr(0, 6)).c_str() : "",
                        u(1, 5));
          break;
        }
        case 4:
          std::snprintf(buf, sizeof buf, "%s", pick(3) == 0 ? "G54" : pick(2) ? "G55" : "G56");
          break;
        case 5:
          std::snprintf(buf, sizeof buf, "%s",
                        pick(3) == 0 ? "G92.1"
                        : pick(2)    ? "G92 X1.5 Y-2"
                                     : "G52 X-3 Y0.5");
          break;
        case 6:
          std::snprintf(buf, sizeof buf, "G53 G0 X%.3f Y%.3f", u(-10, 10), u(-10, 10));
          break;
        case 7:
          std::snprintf(buf, sizeof buf, "%s", pick(2) ? "G28" : "G30 X1");
          break;
        case 8:
          std::snprintf(buf, sizeof buf, "G%u X%.3f Y%.3f", pick(2), u(-20, 20), u(-20, 20));
          break;
        case 9:
          std::snprintf(buf, sizeof buf, "G91 G1 X%.3f Y%.3f\nG90", u(-5, 5), u(-5, 5));
          break;
        case 10:
          std::snprintf(buf, sizeof buf, "G91 G%u X0 Y0 I%.3f J%.3f\nG90", 2 + pick(2), u(-4, 4),
                        u(-4, 4));
          break;
        case 11:
          std::snprintf(buf, sizeof buf, "G91 G18 G%u X%.3f Z0 I%.3f K0\nG17 G90", 2 + pick(2), 6.0,
                        3.0);
          break;
        case 12:
          std::snprintf(buf, sizeof buf, "G81 X%.3f Y%.3f Z-1 R4\nG80", u(-5, 5), u(-5, 5));
          break;
        default:
          std::snprintf(buf, sizeof buf, "(DEBUG, #5420 #5421 #5230 #5250)");
          break;
      }
      text += std::string(buf) + "\n";
    }
    text += "G0 X0 Y0\nM2\n";
    const fs::path program = dir / ("r" + std::to_string(n) + ".ngc");
    std::ofstream(program) << text;
    const Outcome r = run_both(*o, program);
    ASSERT_EQ(r.rs274_runs, r.truecut_runs)
        << text << "rs274: " << r.rs274_error << "\ntruecut: " << r.truecut_error;
    if (!r.rs274_runs) continue;
    EXPECT_EQ(r.difference, std::nullopt) << text;
    if (!r.difference) ++matched;
  }
  std::printf("random rotated programs: %d of 60 match\n", matched);
  EXPECT_GE(matched, 50) << "too few programs ran";
}

// G95 feed per revolution, G96/G97 constant surface speed (docs/gcode.md):
// SET_FEED_MODE(0, 1), SET_SPINDLE_MODE with D or 1e30, M70/M72, canned
// cycles and G33 under G95, inches.
TEST(Rs274Oracle, FeedPerRevolutionAndSurfaceSpeedMatch) {
  REQUIRE_ORACLE(o);
  for (const char* name : {"feed_per_rev_css.ngc"}) {
    const fs::path p = source_dir() / "tests/interp/corpus" / name;
    const Outcome r = run_both(*o, p);
    expect_agreement(r, p.string());
  }
}

// Each case, after `prefix` and before M2, is refused by rs274 and truecut
// at the same line. Each program's offending line is unique; rs274 prints
// it after its message.
template <size_t N>
void expect_refused_at_the_same_line(const Oracle& o, const std::string& folder,
                                     const std::string& prefix, const char* const (&cases)[N]) {
  const fs::path dir = o.work / folder;
  fs::create_directories(dir);
  int index = 0;
  for (const char* body : cases) {
    const std::string text = prefix + body + "\nM2\n";
    const fs::path program = dir / ("e" + std::to_string(++index) + ".ngc");
    std::ofstream(program) << text;
    const Outcome r = run_both(o, program);
    ASSERT_FALSE(r.rs274_runs) << text << "rs274 runs it";
    ASSERT_FALSE(r.truecut_runs) << text << "truecut runs it";
    // rs274: "...\n<message>\n<the line>\n"; truecut: "<file>:<line>:<col>: <message>".
    std::vector<std::string> err_lines;
    std::istringstream err(r.rs274_error);
    for (std::string l; std::getline(err, l);)
      if (!l.empty()) err_lines.push_back(l);
    ASSERT_FALSE(err_lines.empty()) << text;
    std::vector<std::string> program_lines;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);)
      program_lines.push_back(l);
    const auto at = std::find(program_lines.begin(), program_lines.end(), err_lines.back());
    ASSERT_NE(at, program_lines.end()) << text << r.rs274_error;
    const int rs274_line = static_cast<int>(at - program_lines.begin()) + 1;
    std::smatch m;
    static const std::regex located(R"(^[^:]+:(\d+):\d+: )");
    ASSERT_TRUE(std::regex_search(r.truecut_error, m, located)) << r.truecut_error;
    EXPECT_EQ(std::stoi(m[1]), rs274_line)
        << text << "rs274: " << r.rs274_error << "truecut: " << r.truecut_error;
  }
}

// Cutter radius compensation errors (docs/gcode.md "Cutter radius
// compensation"): rs274 and truecut refuse each program at the same line.
TEST(Rs274Oracle, CutterCompErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "G41 D1 G1 X-4.5 Y-5 (entry too short)",
      "G41 D4 G1 X10 Y0\nG1 X10 Y1\nG1 X0 Y1 (reversed line)",
      "G41 D8 G1 X10 Y0\nG3 X10 Y4 I0 J2 (arc smaller than tool)",
      "G41 D1 G1 X10 Y0\nG40\nG2 X0 Y0 R20 (arc after G40)",
      "G41 D1 G1 X10 Y0\nT2 M6 (tool change)",
      "G41 D1 G1 X10 Y0\nG43 H1 (tool length)",
      "G41 D1 G1 X10 Y0\nG55 (coordinate system)",
      "G41 D1 G1 X10 Y0\nG92 X0 (axis offsets)",
      "G41 D1 G1 X10 Y0\nG10 L2 P1 X1 (active system)",
      "G41 D1 G1 X10 Y0\nG18 (plane)",
      "G41 D1 G1 X10 Y0\nG42 D1 (on when on)",
      "G41 D1 G1 X10 Y0\nG81 X5 R1 Z-1 (cycle)",
      "G41 D1 G1 X10 Y0\nG53 G1 X1 (G53)",
      "G41 D1 G1 X10 Y0\nG28 (home)",
      "G41 D1 G1 X10 Y0\nG64 P0.1 (path mode)",
      "G41 D1 G1 X10 Y0\nG98 (retract mode)",
      "G1 D1 X1 (D alone)",
      "G41.1 G1 X10 (no D)",
      "G41.1 D2 L3 G1 X10 (L out of G18)",
      "G19 G41 D1 G1 X10 (YZ plane)",
      "G41 D1.5 G1 X10 (fraction D)",
      "G41 D25 G1 X10 (unknown tool)",
      "G41 D8 G1 X0 Y0\nG1 X20 Y0\nG3 X20 Y10 R5 (inside arc)\nG1 X0 Y10",
      "G41 D8 G1 X0 Y0\nG3 X20 Y0 R10\nG3 X20 Y2 R1 (small arc)\nG1 X0 Y2",
      "G41 D8 G1 X0 Y0\nG1 X20 Y0\nG3 X30 Y10 R10\nG1 X29 Y10 (arc then back line)",
  };
  expect_refused_at_the_same_line(*o, "comp_errors", "G21 F100 T1 M6\nG0 X-5 Y-5\n", kCases);
}

// Centre-format arcs whose radii differ by more than LinuxCNC's allowance
// (docs/gcode.md "LinuxCNC's regression programs"): refused by both at the
// same line.
TEST(Rs274Oracle, ArcRadiusToleranceErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "G2 X24.03 Y0 I12 J0 (0.03 mm, 0.25 percent)",
      "G2 X6002.9 Y0 I3000 J0 (2.9 mm, under 0.1 percent of 3000 mm)",
      "G20\nG2 X1.003 Y0 I0.5 J0 (0.003 in, 0.6 percent)",
      "G20\nG3 X-0.0031 Y0 I0.5 J0 (0.0031 in, 0.6 percent)",
      "G20\nG2 X600.29 Y0 I300 J0 (0.29 in, under 0.1 percent of 300 in)",
  };
  expect_refused_at_the_same_line(*o, "arc_tolerance", "G21 F100\nG0 X0 Y0 Z0\n", kCases);
}

// Tapping and back boring (docs/gcode.md "Canned cycles"): the programs
// rs274 refuses, refused by truecut at the same line.
TEST(Rs274Oracle, TappingAndBackBoringErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "M5\nG84 X1 Z-3 R2 (spindle stopped)",
      "M3\nG74 X1 Z-3 R2 (clockwise in G74)",
      "M4\nG84 X1 Z-3 R2 (counterclockwise in G84)",
      "M3\nG84 X1 Z-3 R2\nM4\nX2 (counterclockwise in a later G84 block)",
      "M3\nG84 X1 Z-3 (no R)",
      "M3\nG84 X1 R2 (no Z)",
      "M3\nG84 X1 Z3 R2 (R below Z)",
      "M5\nG87 X1 Z-3 R2 I1 J1 K-1 (spindle stopped)",
      "M3\nG87 X1 Z-3 R2 J1 K-1 (no I)",
      "M3\nG87 X1 Z-3 R2 I1 K-1 (no J)",
      "M3\nG87 X1 Z-3 R2 I1 J1 (no K)",
      "M3\nG81 X1 Z-3 R2\nG87 X2 I1 J1 K1 (R of another cycle)",
  };
  expect_refused_at_the_same_line(*o, "tap_errors", "G21 F100 S500\nG0 X-5 Y-5 Z10\n", kCases);
}

// Spindle-synchronised motion and probing (docs/gcode.md): the programs
// rs274 refuses, refused by truecut at the same line.
TEST(Rs274Oracle, SyncMotionAndProbingErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "M3\nG33 Z-3 (no K)",
      "M3\nG33.1 Z-3 K1 F100 (F with G33.1)",
      "M5\nG33 Z-3 K1 (spindle stopped)",
      "M5\nG33.1 Z-3 K1 (spindle stopped in G33.1)",
      "M3\nG33 K1 (no axis word)",
      "M3\nG41.1 D1 G1 X10\nG33 Y-5 K1 (under cutter compensation)",
      "M3\nG33 Z-3 K1\nZ-4 (K does not carry over)",
      "G38.2 Z5 (start is the probe point)",
      "G38.2 Z-3 F0 (zero feed)",
      "G41.1 D1 G1 X10\nG38.2 Y-5 (under cutter compensation)",
      "G38.6 Z-3 (no such probe)",
  };
  expect_refused_at_the_same_line(*o, "sync_errors", "G21 F100 S500\nG0 X-5 Y-5 Z5\n", kCases);
}

// Local offsets, tool table edits, dynamic tool length, M98/M99 (docs/gcode.md):
// the programs rs274 refuses, refused by truecut at the same line.
TEST(Rs274Oracle, OffsetToolAndSubprogramErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "G52 @1 ^2 (polar words)",
      "G0 G52 X1 (with a motion code)",
      "G92 X1 G0 (G92 with a motion code)",
      "G52 X1 R2 (R word)",
      "G52 X1 G10 L2 P1 (two non-modal codes)",
      "G41 D1 G1 X10 Y0\nG52 X1 (under cutter compensation)",
      "G10 L1 P50 Z1 (tool not in the table)",
      "G10 L1 Z1 (no P)",
      "G10 L10 P0 Z1 (P0)",
      "G10 L11 Z1 (L11 without P)",
      "G10 L1 P3 Z1 G0 (with a motion code)",
      "G10 L2 P1 X1 G1 (G10 L2 with a motion code)",
      "G10 L1 P3 Q10 (orientation above 9)",
      "G10 L3 P1 X1 (no such L)",
      "G10 L1 P3 Z1 H2 (H word)",
      "G10 L1 P3 X1 @1 (polar word)",
      "G43.2 Z0.5 (G43.2 without H)",
      "G43.2 H1 Z1 (G43.2 with H and axis words)",
      "G43.1 H1 Z1 (G43.1 with H)",
      "G43.2 H50 (tool not in the table)",
      "G41 D1 G1 X10 Y0\nG43.1 Z1 (G43.1 under cutter compensation)",
      "G1 M98 P100 (M98 with a G code)\nM2\nO100\nG1 X1\nM99",
      "M98 (no P)\nM2\nO100\nG1 X1\nM99",
      "M98 P100 L1.5 (fraction L)\nM2\nO100\nG1 X1\nM99",
      "M98 P100\nM2\nO100\nM98 P100 L-1 (negative L)\nM99",
      "M98 P100\nM2\nO100\nG0 X2 M99 (M99 with a move)",
      "M98 P100\nM2\nO100 G1 X1 (words after the number)\nM99",
      "M98 P100\nM2\nO100\nM98 P100 L1 (recursion)\nM99",
      "G10 L2 P1 R30\nG10 L20 P1 X0 R45 (R with L20)",
      "G10 L2 P1 R30\nG41 D1 G1 X10 Y0\nG10 L2 P0 R10 (the active system turned, comp on)",
      "o400 call [5]\nG0 Z1\no400 sub (met after the call)\nG0 X[#1]\no400 endsub\nM2",
      ("#1 = 0\no10 while [#1 LT 2]\no400 sub (met again in a loop)\nG0 X1\no400 endsub\n"
       "o400 call\n#1 = [#1 + 1]\no10 endwhile\nM2"),
      "#5 = 100.5\no[#5] call (a computed label not whole)\nM2",
      "o1 sub\nG1 X0\no2 sub (nested definition)\nG1 Y0\no2 endsub\no1 endsub\no1 call\nM2",
  };
  expect_refused_at_the_same_line(*o, "offset_errors", "G21 F100 T1 M6\nG0 X-5 Y-5\n", kCases);
}

// G95/G96 (docs/gcode.md): the programs rs274 refuses, refused by truecut
// at the same line.
TEST(Rs274Oracle, FeedAndSpindleModeErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "G96 D2000 (G96 without S)",
      "G97 S500 D100 (D without G96)",
      "G95\nG1 X10 (G95 resets F to 0)",
      "G95 F0.1 S0\nG1 X11 (S0 in G95)",
      "G95 F0.1 S0\nG2 X2 I1 (S0 in G95, arc)",
      "G95 F0.2\nG38.3 Z0 (probing in G95)",
  };
  expect_refused_at_the_same_line(*o, "feed_mode_errors", "G21 F100\nG0 X0 Y0 Z5\nM3 S1000\n",
                                  kCases);
}

// G5, G5.1, G5.2/G5.3 (docs/gcode.md "Splines G5.x"): the programs rs274
// refuses, refused by truecut at the same line.
TEST(Rs274Oracle, SplineErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "G5 I1 X5 Y5 P1 Q1 (I without J)",
      "G5 I1 J1 X5 Y5 P1 (P without Q)",
      "G5 I1 J1 X5 Y5 Q1 (Q without P)",
      "G5 I1 J1 P1 Q1 (no axis word)",
      "G5 I1 J1 X5 Y5 Z1 P1 Q1 (Z word)",
      "G5 I1 J1 X5 Y5 P1 Q1 A3 (A word)",
      "G18 G5 I1 J1 X5 Y5 P1 Q1 (XZ plane)",
      "G19\nG5 I1 J1 X5 Y5 P1 Q1 (YZ plane)",
      "G41.1 D1 G1 X5\nG5 I1 J1 X5 Y5 P1 Q1 (cutter compensation)",
      "G93 G5 I1 J1 X5 Y5 P1 Q1 (inverse time without F)",
      "F0\nG5 I1 J1 X5 Y5 P1 Q1 (zero feed)",
      "G5 I1 J1 X3 P1 Q1 R4 (R word)",
      "G5 I1 J1 X3 P1 Q1 K4 (K word)",
      "G5 I1 J1 X3 P1 Q1 L4 (L word)",
      "G5 I1 J1 X3 P1 Q1\nX4 P1 Q1 (G5 is not modal)",
      "G5.1 I1 X5 Y5 (G5.1 without J)",
      "G5.1 J1 X5 Y5 (G5.1 without I)",
      "G5.1 I1 J0 X3 P1 (P with G5.1)",
      "G5.1 I1 J0 X3 Q1 (Q with G5.1)",
      "G5.1 I1 J1 X5 Y5 Z2 (Z with G5.1)",
      "G5.1 I1 J1 X3\nY3 I1 J2 (G5.1 is not modal)",
      "G5.2 X1 P1\nX2 Y0 P1\nG5.3 (X without Y)",
      "G5.2 Y1 P1\nX2 Y0 P1\nG5.3 (Y without X)",
      "G5.2 X1 Y1 P1\nX2 Y0 (no weight)",
      "G5.2 X1 Y1 P1\nX2 Y0 P0 (zero weight)",
      "G5.2 X1 Y1 P1\nX2 Y0 P-2 (negative weight)",
      "G5.2 X1 Y1 P1\nP3 (P alone after the first block)",
      "F0\nG5.2 X1 Y1 P1 (zero feed)",
      "G5.2 X1 Y1 P1 I1 (I word)",
      "G5.2 X1 Y1 P1 Q1 (Q word)",
      "G5.2 X1 Y1 P1 L2.5 (fraction L)",
      "G5.2 X1 Y1 P1 @2 (polar word)\nG5.3",
      "G5.2 X1 Y1 P1\nX2 Y2 P1 @3 ^45 (polar word later)\nG5.3",
      "G5.2 X1 Y1 P1\nG5.3 (fewer points than the order 3)",
      "G5.2 X1 Y1 P1 L4\nX2 Y0 P1\nG5.3 (fewer points than L4)",
      "G5.2 X1 Y1 P1\nX2 Y0 P1 L5\nX3 Y0 P1\nG5.3 (fewer points than a later L5)",
      "G5.3 (G5.3 without G5.2)",
      "G5.2 X1 Y1 P1\nX2 Y2 P1\nG5.3 X1 (axis word on G5.3)",
      "G5.2 X1 Y1 P1\nX2 Y2 P1\nG5.3\nX5 (axis words after G5.3)",
      "G5 I1 J1 X3 P1 Q1\nG5.3 (G5.3 after G5)",
  };
  expect_refused_at_the_same_line(*o, "spline_errors", "G21 F100\nG0 X0 Y0 Z0\n", kCases);
}

// M62-M68, M19, M48-M53 (docs/gcode.md): the programs rs274
// refuses, refused by truecut at the same line.
TEST(Rs274Oracle, IoCodeErrorsAtTheSameLine) {
  REQUIRE_ORACLE(o);
  static const char* kCases[] = {
      "M62 (no P)",
      "M62 E1 (E without M66-M68)",
      "M67 Q1 (no E)",
      "M66 P1 L1 (wait without a timeout)",
      "M66 P0 L1 Q-1 (negative timeout)",
      "M66 L0 (neither P nor E)",
      "M66 P1 E1 L0 (both P and E)",
      "M66 E2 L4 Q1 (analog input with a wait)",
      "M62 P1 M65 P2 (two output codes)",
      "M68 E0 Q1 M62 P0 (output codes of one group)",
      "M48 M49 (two override codes)",
      "G4 P2 M62 P1 (two P words)",
      "M19 R-10 (angle below 0)",
      "M19 R400 (angle above 360)",
      "M19 M3 (orient and spindle on one line)",
  };
  expect_refused_at_the_same_line(*o, "io_errors", "G21 F100 T1 M6\nG0 X-5 Y-5\n", kCases);
}

// Random profiles under G41/G42 in G17 and G18 (lines, R and I/J/K arcs,
// G0 moves, moves along the tool axis only, the tool table's D or G41.1 D):
// rs274 and truecut must agree on each, call for call or refusing it at the
// same line. The seed is fixed; most random corners are concave, many
// cannot be reached without gouging, which exercises every error path.
TEST(Rs274Oracle, RandomCutterCompProfilesAgree) {
  REQUIRE_ORACLE(o);
  const fs::path dir = o->work / "comp_random";
  fs::create_directories(dir);
  std::mt19937 rng(20261127);
  auto uniform = [&](double lo, double hi) { return uniform_in(rng, lo, hi); };
  int matched = 0, refused = 0;
  for (int n = 0; n < 150; ++n) {
    const bool xz = rng() % 3 == 0;
    const char a = xz ? 'Z' : 'X', b = xz ? 'X' : 'Y';
    const char ia = xz ? 'K' : 'I', ib = xz ? 'I' : 'J';
    const bool left = rng() % 2 == 0;
    char buf[200];
    std::string comp = left ? "G41" : "G42";
    if (rng() % 4 == 0) {
      std::snprintf(buf, sizeof buf, ".1 D%.3f", uniform(-3, 4));  // < 0: the other side
      comp += buf;
    } else {
      comp += " D" + std::to_string(1 + rng() % 4);
    }
    std::string text = std::string("G21 F300 T1 M6\n") + (xz ? "G18" : "G17") + "\nG0 X0 Y0 Z0\n";
    double x = 0, y = 0;
    const int moves = 2 + static_cast<int>(rng() % 6);
    for (int k = 0; k < moves; ++k) {
      const std::string pre = k == 0 ? comp + " " : "";
      const double kind = uniform(0, 1);
      double nx = uniform(-30, 30), ny = uniform(-30, 30);
      // Calls queued behind held moves (feed, spindle, coolant, comments).
      static const char* kExtras[] = {"", "", "", " (note)", " F250", " M8", " S1000 M3"};
      const char* extra = kExtras[rng() % 7];
      if (k > 0 && kind < 0.04) {
        text += "G4 P0.1\n";
        continue;
      }
      if (k > 0 && kind < 0.12) {  // incremental, from the programmed point
        const double dx = std::round(uniform(-15, 15) * 1e3) / 1e3;
        const double dy = std::round(uniform(-15, 15) * 1e3) / 1e3;
        std::snprintf(buf, sizeof buf, "G91 G1 %c%.3f %c%.3f%s\nG90\n", a, dx, b, dy, extra);
        text += buf;
        x += dx;
        y += dy;
        continue;
      }
      if (k > 0 && kind < 0.18) {  // along the tool axis only
        std::snprintf(buf, sizeof buf, "G1 %c%.3f", xz ? 'Y' : 'Z', uniform(-2, 2));
        nx = x, ny = y;
      } else if (kind < 0.25) {
        std::snprintf(buf, sizeof buf, "%sG0 %c%.3f %c%.3f", pre.c_str(), a, nx, b, ny);
      } else if (kind < 0.6) {
        std::snprintf(buf, sizeof buf, "%sG1 %c%.3f %c%.3f", pre.c_str(), a, nx, b, ny);
      } else if (kind < 0.8) {
        const double r = std::max(std::fabs(nx - x), std::fabs(ny - y)) * uniform(0.6, 1.5) + 1;
        std::snprintf(buf, sizeof buf, "%s%s %c%.3f %c%.3f R%.3f", pre.c_str(),
                      rng() % 2 ? "G2" : "G3", a, nx, b, ny, r);
      } else {  // centre form: the end on the circle through the start
        const double cx = x + uniform(-15, 15), cy = y + uniform(-15, 15);
        const double r = std::hypot(x - cx, y - cy), t = uniform(0, 6.283);
        nx = std::round((cx + r * std::cos(t)) * 1e4) / 1e4;
        ny = std::round((cy + r * std::sin(t)) * 1e4) / 1e4;
        std::snprintf(buf, sizeof buf, "%s%s %c%.4f %c%.4f %c%.4f %c%.4f", pre.c_str(),
                      rng() % 2 ? "G2" : "G3", a, nx, b, ny, ia, cx - x, ib, cy - y);
      }
      text += std::string(buf) + extra + "\n";
      x = std::round(nx * 1e3) / 1e3;
      y = std::round(ny * 1e3) / 1e3;
      if (kind >= 0.8) x = nx, y = ny;
    }
    // Exits: a move on the G40 line, G40 alone then a move along the tool
    // axis only (from the programmed point), G40 with one plane word.
    const unsigned exit = rng() % 3;
    if (exit == 0)
      std::snprintf(buf, sizeof buf, "G40 G1 %c%.3f %c%.3f\nM2\n", a, uniform(-40, 40), b,
                    uniform(-40, 40));
    else if (exit == 1)
      std::snprintf(buf, sizeof buf, "G40\nG0 %c5\nM30\n", xz ? 'Y' : 'Z');
    else
      std::snprintf(buf, sizeof buf, "G40 G0 %c%.3f\nM5\nM2\n", a, uniform(-40, 40));
    text += buf;
    const fs::path program = dir / ("r" + std::to_string(n) + ".ngc");
    std::ofstream(program) << text;
    const Outcome r = run_both(*o, program);
    ASSERT_EQ(r.rs274_runs, r.truecut_runs)
        << text << "rs274: " << r.rs274_error << "\ntruecut: " << r.truecut_error;
    if (r.rs274_runs) {
      EXPECT_EQ(r.difference, std::nullopt) << text;
      ++matched;
      continue;
    }
    ++refused;
    std::vector<std::string> err_lines, program_lines;
    std::istringstream err(r.rs274_error), in(text);
    for (std::string l; std::getline(err, l);)
      if (!l.empty()) err_lines.push_back(l);
    for (std::string l; std::getline(in, l);)
      program_lines.push_back(l);
    ASSERT_FALSE(err_lines.empty()) << text;
    const auto at = std::find(program_lines.begin(), program_lines.end(), err_lines.back());
    ASSERT_NE(at, program_lines.end()) << text << r.rs274_error;
    std::smatch m;
    static const std::regex located(R"(^[^:]+:(\d+):\d+: )");
    ASSERT_TRUE(std::regex_search(r.truecut_error, m, located)) << r.truecut_error;
    EXPECT_EQ(std::stoi(m[1]), static_cast<int>(at - program_lines.begin()) + 1)
        << text << "rs274: " << r.rs274_error << "truecut: " << r.truecut_error;
  }
  std::printf("random cutter compensation profiles: %d match, %d refused by both\n", matched,
              refused);
  EXPECT_GE(matched, 75) << "too few programs ran";
}

TEST(Rs274Oracle, FiveAxisDemosMatch) {
  REQUIRE_ORACLE(o);
  const fs::path demos = o->share /
                         "doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis/"
                         "table-rotary-tilting/demos";
  for (const char* name : {"boat-xyzac.ngc", "impeller-7bl-xyzac.ngc"}) {
    const Outcome r = run_both(*o, demos / name);
    ASSERT_TRUE(r.rs274_runs) << name << ": " << r.rs274_error;
    ASSERT_TRUE(r.truecut_runs) << name << ": " << r.truecut_error;
    EXPECT_EQ(r.difference, std::nullopt) << name;
  }
}

TEST(Rs274Oracle, LinuxCncSamplePrograms) {
  REQUIRE_ORACLE(o);
  std::vector<fs::path> programs = ngc_programs_under(o->share / "linuxcnc/ncfiles");
  for (const auto& p : ngc_programs_under(o->share / "doc/linuxcnc/examples"))
    programs.push_back(p);
  int matched = 0, rejected = 0, not_runnable = 0;
  std::set<std::string> seen_out_of_scope;
  for (const auto& p : programs) {
    const Outcome r = run_both(*o, p);
    if (!r.rs274_runs) {
      ++not_runnable;  // needs an INI, a HAL, remaps or user M codes
      continue;
    }
    const auto scope = out_of_scope().find(key_of(p));
    if (!r.truecut_runs) {
      EXPECT_NE(scope, out_of_scope().end())
          << p << " runs in rs274 but truecut rejects it: " << r.truecut_error;
      seen_out_of_scope.insert(key_of(p));
      ++rejected;
      continue;
    }
    EXPECT_EQ(r.difference, std::nullopt) << p;
    if (!r.difference) ++matched;
  }
  std::printf(
      "rs274 oracle: %d sample programs match, %d out of scope, %d not runnable by "
      "rs274 alone\n",
      matched, rejected, not_runnable);
  EXPECT_GE(matched, 150) << "too few sample programs compared";
  for (const auto& [key, reason] : out_of_scope())
    EXPECT_TRUE(seen_out_of_scope.count(key)) << key << " (" << reason << ") is listed as out "
                                              << "of scope but was not rejected";
}

// tools/linuxcnc-regression.sh on a folder laid out like LinuxCNC's
// tests/interp, with programs of this test's own: one line per program,
// classified, and the totals.
TEST(Rs274Oracle, RegressionRunnerClassifiesPrograms) {
  REQUIRE_ORACLE(o);
  const fs::path dir = o->work / "regression";
  fs::remove_all(dir);
  auto write = [&](const std::string& file, const std::string& text) {
    fs::create_directories((dir / file).parent_path());
    std::ofstream(dir / file) << text;
  };
  write("plain/test.ngc", "G21 F100\nG1 X1 Y2\nM2\n");  // no test.sh: rs274 -g test.ngc
  write("nofeed/test.sh", "#!/bin/bash\nrs274 -g prog.ngc | awk '{$1=\"\"; print}'\n");
  write("nofeed/prog.ngc", "G21\nG1 X1\nM2\n");
  // An inch table without an INI, as rs274 reads it: T1 is 0.5 in long.
  write("table/test.sh", "#!/bin/bash\nrs274 -g -t tools.tbl p.ngc\n");
  write("table/tools.tbl", "T1 P1 Z0.5 ;\n");
  write("table/p.ngc", "G21 T1 M6 G43\nG0 Z1\n(debug,#5403)\nM2\n");
  write("ui/test.ngc", "G0 X1\nM2\n");
  write("ui/test-ui.py", "");
  const auto r = run_process({"/bin/bash", (source_dir() / "tools/linuxcnc-regression.sh").string(),
                              "--truecut", cli_path().string(), "--compare",
                              (truecut::test::binary_dir() / "rs274_compare").string(), "--rs274",
                              o->rs274.string(), dir.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("plain/test.ngc: agree\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("nofeed/prog.ngc: both refuse, same line"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("table/p.ngc: agree\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ui: needs a running LinuxCNC"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\nagree: 2\nboth refuse, same line: 1\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("tests not run (need more than a standalone rs274): 1"), std::string::npos)
      << r.out;
}

}  // namespace
}  // namespace truecut::interp::testing
