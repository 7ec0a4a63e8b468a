// The option parser every command shares (cli/args.hpp), as a user meets
// it: an empty value, an integer beyond a long, and the range a refused
// number must lie in, written as numbers.
#include <gtest/gtest.h>

#include <fstream>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;

namespace {

std::filesystem::path program() {
  const auto p = scratch_dir() / "p.ngc";
  std::ofstream(p) << "G0 X1\nM2\n";
  return p;
}

}  // namespace

// `--out ""` (an unset shell variable) used to reach the file system as the
// folder "" ("cannot create directories: Invalid argument []").
TEST(CliOptions, AnEmptyValueIsRefused) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"canon", "--tool-table", "", program().string()},
        std::vector<std::string>{"canon", "--tool-table=", program().string()},
        std::vector<std::string>{"part", "implant", "--out", ""}}) {
    std::vector<std::string> argv = args;
    argv.insert(argv.begin(), cli_path().string());
    const ProcessResult r = run_process(argv);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("needs a value, not an empty one"), std::string::npos) << r.err;
  }
}

// strtol saturates beyond a long: 99999999999999999999 read as LONG_MAX
// passed any range ending there.
TEST(CliOptions, AnIntegerBeyondALongIsOutOfRange) {
  const ProcessResult r = run_process(
      {cli_path().string(), "canon", "--max-blocks", "99999999999999999999", program().string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--max-blocks 99999999999999999999 is outside 1..1000000000000"),
            std::string::npos)
      << r.err;
}

// A bound of 1e-4 was written "0.000100", one of 1e-9 "0.000000".
TEST(CliOptions, RangesAreWrittenAsTheNumbersTheyAre) {
  const ProcessResult r = run_process({cli_path().string(), "canon", "--spline-tolerance", "1e-7",
                                       "--spline-report", program().string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--spline-tolerance 1e-7 is outside 1e-06..10"), std::string::npos) << r.err;
}

// 0 stood for each part's default inside `truecut demo`: given on the
// command line it silently meant the default instead of being refused
// (--point-spacing 0 has a meaning of its own: the nominal's vertices).
TEST(CliOptions, DemoSpacingsOfZeroAreRefused) {
  const auto out = scratch_dir() / "demo";
  for (const char* option : {"--mesh-edge", "--stepover", "--cmm-spacing", "--dexel-spacing"}) {
    const ProcessResult r =
        run_process({cli_path().string(), "demo", option, "0", "--out", out.string()});
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
    EXPECT_NE(r.err.find(std::string(option) + " 0 is outside 0.001.."), std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << option;
  }
}
