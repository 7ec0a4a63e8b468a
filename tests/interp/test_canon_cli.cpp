// `truecut canon`: output layout, options, and bad input (exit 2, located
// message, nothing on stdout).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "run_process.hpp"
#include "test_paths.hpp"

namespace truecut::test {
namespace {

std::filesystem::path write(const std::filesystem::path& dir, const std::string& name,
                            const std::string& text) {
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

TEST(CanonCli, PrintsCallsLikeRs274) {
  const auto dir = scratch_dir();
  const auto prog = write(dir, "p.ngc", "G0 X1 Y2 Z3\nG1 X4 F100\nM2\n");
  auto r = run_process({cli_path().string(), "canon", prog.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("    7 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, "
                       "0.0000)\n"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("STRAIGHT_FEED(4.0000, 2.0000"), std::string::npos);
  EXPECT_NE(r.out.find("PROGRAM_END()"), std::string::npos);
}

TEST(CanonCli, ToolTableDecimalsAndAnnotation) {
  const auto dir = scratch_dir();
  const auto tools = write(dir, "t.tbl", "T4 P1 Z12.5\n");
  const auto prog = write(dir, "p.ngc", "(OPERATION: FACE)\nT4 M6 G43\nG0 Z0\nM2\n");
  auto r = run_process({cli_path().string(), "canon", "--tool-table", tools.string(), "--decimals",
                        "6", "--annotate", prog.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("USE_TOOL_LENGTH_OFFSET(0.000000 0.000000 12.500000"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("; " + prog.string() + ":3 op=FACE tool=4"), std::string::npos) << r.out;
  auto ops = run_process({cli_path().string(), "canon", "--tool-table", tools.string(),
                          "--list-operations", prog.string()});
  EXPECT_EQ(ops.out, "FACE\n");
  auto only = run_process({cli_path().string(), "canon", "--tool-table", tools.string(),
                           "--operation", "FACE", prog.string()});
  EXPECT_EQ(only.out,
            "    1 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n");
}

TEST(CanonCli, ParameterFileSetsTheStartingSetup) {
  const auto dir = scratch_dir();
  const auto var = write(dir, "m.var", "5220 2\n5241 4\n5242 -1\n");
  const auto prog = write(dir, "p.ngc", "G0 X1\nM2\n");
  auto r = run_process({cli_path().string(), "canon", "--var-file", var.string(), "--var-units",
                        "inch", prog.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("    2 N..... SET_G5X_OFFSET(2, 101.6000, -25.4000, 0.0000"),
            std::string::npos)
      << r.out;
  const auto bad = write(dir, "bad.var", "5221 1\n5220 1\n");
  auto b = run_process({cli_path().string(), "canon", "--var-file", bad.string(), prog.string()});
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_EQ(b.out, "");
  EXPECT_EQ(b.err.rfind(bad.string() + ":2:1: parameter 5220 after 5221 (line 1)", 0), 0u) << b.err;
  // --var-units alone: the machine's units, where the offset parameters
  // keep their lengths (25.4 mm set in G21 reads 1 on an inch machine).
  const auto g10 = write(dir, "g10.ngc", "G21 G10 L2 P1 X25.4\n(DEBUG,#5221)\nM2\n");
  for (const auto& [machine_units, shown] : std::vector<std::pair<std::string, std::string>>{
           {"inch", "1.000000"}, {"mm", "25.400000"}}) {
    auto units =
        run_process({cli_path().string(), "canon", "--var-units", machine_units, g10.string()});
    ASSERT_EQ(units.exit_code, 0) << units.err;
    EXPECT_NE(units.out.find("MESSAGE(\"" + shown + "\")"), std::string::npos)
        << machine_units << ": " << units.out;
  }
  auto missing = run_process(
      {cli_path().string(), "canon", "--var-file", (dir / "none.var").string(), prog.string()});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find((dir / "none.var").string()), std::string::npos) << missing.err;
}

TEST(CanonCli, BadProgramGivesLocationAndNoOutput) {
  const auto dir = scratch_dir();
  const auto prog = write(dir, "bad.ngc", "G0 X1\nG1 X2 F100\nG2 X3 Y0\nM2\n");
  auto r = run_process({cli_path().string(), "canon", prog.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "") << "no partial output";
  EXPECT_EQ(r.err,
            prog.string() + ":3:1: missing arc data: give R (radius) or I/J (centre offsets)\n");
}

TEST(CanonCli, BinaryFileIsRejected) {
  const auto dir = scratch_dir();
  const auto prog = write(dir, "image.ngc",
                          std::string("\x7f"
                                      "ELF\x02\x01\x01\0\0\0",
                                      10));
  auto r = run_process({cli_path().string(), "canon", prog.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find(prog.string() + ":1:5: not a text file"), std::string::npos) << r.err;
}

TEST(CanonCli, UsageErrors) {
  auto none = run_process({cli_path().string(), "canon"});
  EXPECT_EQ(none.exit_code, 2);
  auto missing = run_process({cli_path().string(), "canon", "/nonexistent/p.ngc"});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("/nonexistent/p.ngc: cannot open the program file"),
            std::string::npos);
  const auto dir = scratch_dir();
  const auto tools = write(dir, "t.tbl", "T1 P1 Zx\n");
  const auto prog = write(dir, "p.ngc", "M2\n");
  auto bad_tools =
      run_process({cli_path().string(), "canon", "--tool-table", tools.string(), prog.string()});
  EXPECT_EQ(bad_tools.exit_code, 2);
  EXPECT_NE(bad_tools.err.find(tools.string() + ":1:7:"), std::string::npos) << bad_tools.err;
  auto help = run_process({cli_path().string(), "canon", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("usage: truecut canon"), std::string::npos);
}

}  // namespace
TEST(CanonCli, SplineReportShowsErBeforeAndAfterNodeInsertion) {
  const auto dir = scratch_dir();
  const auto prog = write(dir, "s.ngc",
                          "G21 G90 G17 G94 F1200\nG0 X0 Y0 Z5\nG1 Z0\nBSPLINE\nX10 Y0\n"
                          "X20 Y8\nX30 Y0\nX40 Y10\nX50 Y0\nCSPLINE\nX60 Y10\nX70 Y0\n"
                          "X80 Y12\nX90 Y0\nG1 X100\nM2\n");
  for (double tol : {0.025, 0.005}) {
    auto r = run_process({cli_path().string(), "canon", "--spline-report", "--spline-tolerance",
                          std::to_string(tol), prog.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::istringstream lines(r.out);
    std::string header, line;
    std::getline(lines, header);
    EXPECT_NE(header.find("Er before mm"), std::string::npos) << r.out;
    int runs = 0;
    while (std::getline(lines, line)) {
      std::istringstream f(line);
      int line_no = 0, points = 0, inserted = 0;
      std::string mode;
      double before = 0, after = 0, tolerance = 0;
      f >> line_no >> mode >> points >> inserted >> before >> after >> tolerance;
      ASSERT_TRUE(f) << line;
      EXPECT_EQ(runs == 0 ? "BSPLINE" : "CSPLINE", mode);
      EXPECT_GT(before, tol) << "the plain spline cuts the corners";
      EXPECT_LE(after, tol) << line;
      EXPECT_GT(inserted, 0);
      EXPECT_NEAR(tol, tolerance, 1e-9);
      ++runs;
    }
    EXPECT_EQ(2, runs) << r.out;
  }
}

// An operation the program does not have (a typo) is refused with the
// program's operations, instead of printing nothing with exit 0.
TEST(CanonCli, AnOperationThatIsNotInTheProgramIsRefused) {
  const auto dir = scratch_dir();
  const auto prog =
      write(dir, "p.ngc", "(OPERATION: ROUGH)\nG0 X1\n(OPERATION: FINISH)\nG1 X2 F100\nM2\n");
  for (const bool list : {false, true}) {
    std::vector<std::string> args = {cli_path().string(), "canon", "--operation", "FINNISH"};
    if (list) args.push_back("--list-operations");
    args.push_back(prog.string());
    auto r = run_process(args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("has no operation 'FINNISH' (its operations: FINISH, ROUGH)"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.out, "");
  }
  auto ok = run_process({cli_path().string(), "canon", "--operation", "FINISH", prog.string()});
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("STRAIGHT_FEED(2.0000"), std::string::npos) << ok.out;
}

// The calls are canon's product: when they cannot all be written (a full
// disk) the command fails.
TEST(CanonCli, OutputThatCannotBeWrittenIsAFailure) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this system";
  const auto dir = scratch_dir();
  std::string text;
  for (int i = 0; i < 5000; ++i)
    text += "G1 X" + std::to_string(i) + " F100\n";
  const auto prog = write(dir, "p.ngc", text + "M2\n");
  auto r = run_process(
      {"/bin/sh", "-c", "\"$0\" canon \"$1\" > /dev/full", cli_path().string(), prog.string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("truecut canon: writing the standard output failed"), std::string::npos)
      << r.err;
}

// The interpreter's block budget stops an endless loop and names the
// option that raises it.
TEST(CanonCli, MaxBlocksStopsAnEndlessLoopAndNamesItsOption) {
  const auto dir = scratch_dir();
  const auto loop = write(dir, "loop.ngc", "#1=0\no1 while [1]\n#1=[#1+1]\no1 endwhile\nM2\n");
  auto r = run_process({cli_path().string(), "canon", "--max-blocks", "1000", loop.string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("more than 1000 blocks executed: an endless loop? (a longer program: "
                       "--max-blocks N)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");
  // A finite loop under the budget runs; the budget must be at least 1.
  const auto finite =
      write(dir, "finite.ngc", "#1=0\no1 while [#1 LT 100]\n#1=[#1+1]\no1 endwhile\nM2\n");
  auto ok = run_process({cli_path().string(), "canon", "--max-blocks", "1000", finite.string()});
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  auto bad = run_process({cli_path().string(), "canon", "--max-blocks", "0", finite.string()});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
}

}  // namespace truecut::test
