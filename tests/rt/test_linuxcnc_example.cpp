// examples/linuxcnc/: a simulated 5-axis A/C table-table machine
// (xyzac-trt-kins) in LinuxCNC with truecut_comp in joint mode between
// motion and the drives, and a 3-axis mill with the component driving
// LinuxCNC's external offsets, each run headless (run_program.py as the
// display): the part program runs to the end with the field applied. Needs what
// test_linuxcnc_module needs (linuxcnc_support.hpp); skipped otherwise,
// failed under TRUECUT_REQUIRE_ORACLES=1.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "linuxcnc_support.hpp"
#include "oracle.hpp"
#include "test_truecut_comp_support.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::comp;

namespace {

struct ExampleRun {
  ProcessResult r;
  std::string log;
  double max_corr = -1.0;
};

// Runs the shipped configuration `ini` of examples/linuxcnc/ headless with
// a synthetic field; checks that the program ran to the end and a
// correction was applied.
ExampleRun run_example(const std::string& ini, const std::string& program) {
  ExampleRun run;
  // The configuration, as shipped, in a folder LinuxCNC (running as nobody)
  // may write in; the field where [TRUECUT]FIELD names it.
  const auto work = scratch_dir() / "config";
  std::filesystem::create_directories(work);
  for (const auto& e : std::filesystem::directory_iterator(source_dir() / "examples/linuxcnc"))
    if (e.path().extension() != ".md") std::filesystem::copy(e.path(), work / e.path().filename());
  FieldSpec spec;  // covers the program's moves, tools 1 and 2
  spec.origin_mm = {-40.0, -40.0, -30.0};
  spec.dims = {17, 17, 13};
  write_field(work / "field.tcf", spec);
  for (const auto& e : std::filesystem::directory_iterator(work))
    ::chmod(e.path().c_str(), e.path().extension() == ".py" ? 0777 : 0666);
  ::chmod(work.c_str(), 0777);

  // -r: LinuxCNC's output to stdout/stderr instead of files in /tmp.
  run.r = run_linuxcnc_private(work, {"linuxcnc", "-r", ini});
  run.log = "exit " + std::to_string(run.r.exit_code) + "\nstdout:\n" + run.r.out + "\nstderr:\n" +
            run.r.err;
  EXPECT_EQ(0, run.r.exit_code) << run.log;
  EXPECT_NE(std::string::npos, run.r.out.find(program + ": finished")) << run.log;
  // The field was taken into use once, no reload failed, and a correction
  // was applied (run_program.py watches tc.corr-mag during the run).
  const auto at = run.r.out.find("truecut_comp: field-generation 1, load-errors 0, max corr-mag ");
  EXPECT_NE(std::string::npos, at) << run.log;
  if (at == std::string::npos) return run;
  std::printf("%s\n", run.r.out.substr(at, run.r.out.find('\n', at) - at).c_str());
  EXPECT_EQ(1, std::sscanf(run.r.out.c_str() + at,
                           "truecut_comp: field-generation 1, load-errors 0, "
                           "max corr-mag %lf",
                           &run.max_corr))
      << run.log;
  EXPECT_GT(run.max_corr, 0.01) << run.log;
  EXPECT_LE(run.max_corr, 0.5) << "max-correction in the HAL file\n" << run.log;
  return run;
}

// The value after `prefix` on a line of run_program.py's output.
double value_after(const ExampleRun& run, const std::string& prefix) {
  const auto at = run.r.out.find(prefix);
  if (at == std::string::npos) {
    ADD_FAILURE() << "no '" << prefix << "'\n" << run.log;
    return std::nan("");
  }
  std::printf("%s\n", run.r.out.substr(at, run.r.out.find('\n', at) - at).c_str());
  return std::strtod(run.r.out.c_str() + at + prefix.size(), nullptr);
}

}  // namespace

TEST(LinuxcncExample, XyzacTrtRunsAPartProgramToTheEndWithTheFieldApplied) {
  if (const std::string missing = linuxcnc_missing(); !missing.empty())
    TRUECUT_ORACLE_MISSING(missing);
  const ExampleRun run = run_example("xyzac-trt-truecut.ini", "part.ngc");
  // The feedback wiring takes each joint's correction off the drive's
  // position, so motion sees its own command come back: no following error
  // from the correction (the simulated drive follows its command exactly).
  EXPECT_LT(value_after(run, "motion: max |f-error| of X, Y, Z "), 1e-6) << run.log;
}

// The stock route: the same component in TCP mode drives LinuxCNC's
// external offsets of a 3-axis trivkins mill; motion applies them, and once
// the machine stands the offset equals the correction to the count (10 nm).
TEST(LinuxcncExample, XyzExternalOffsetsApplyTheFieldThroughMotion) {
  if (const std::string missing = linuxcnc_missing(); !missing.empty())
    TRUECUT_ORACLE_MISSING(missing);
  const ExampleRun run = run_example("xyz-eoffset-truecut.ini", "part-xyz.ngc");
  const std::string prefix = "external offsets: max |eoffset| ";
  const auto at = run.r.out.find(prefix);
  ASSERT_NE(std::string::npos, at) << run.log;
  std::printf("%s\n", run.r.out.substr(at, run.r.out.find('\n', at) - at).c_str());
  double max_x, max_y, max_z, dx, dy, dz;
  ASSERT_EQ(6, std::sscanf(run.r.out.c_str() + at,
                           "external offsets: max |eoffset| X %lf Y %lf Z %lf mm; standing at the "
                           "end, eoffset - corr X %lf Y %lf Z %lf",
                           &max_x, &max_y, &max_z, &dx, &dy, &dz))
      << run.log;
  EXPECT_GT(std::max({max_x, max_y, max_z}), 0.01) << "motion applied the correction\n" << run.log;
  constexpr double kCountMm = 1e-5;  // axis.L.eoffset-scale in the HAL file
  for (double d : {dx, dy, dz})
    EXPECT_LE(std::abs(d), kCountMm) << "within a count of the correction\n" << run.log;
}
