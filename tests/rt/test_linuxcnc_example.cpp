// examples/linuxcnc/: a simulated 5-axis A/C table-table machine
// (xyzac-trt-kins) in LinuxCNC with truecut_comp in joint mode between
// motion and the drives, run headless (run_program.py as the display): the
// part program runs to the end with the field applied. Needs what
// test_linuxcnc_module needs (linuxcnc_support.hpp); skipped otherwise,
// failed under TRUECUT_REQUIRE_ORACLES=1.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "linuxcnc_support.hpp"
#include "oracle.hpp"
#include "test_truecut_comp_support.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::comp;

TEST(LinuxcncExample, XyzacTrtRunsAPartProgramToTheEndWithTheFieldApplied) {
  if (const std::string missing = linuxcnc_missing(); !missing.empty())
    TRUECUT_ORACLE_MISSING(missing);
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
  const ProcessResult r = run_linuxcnc_private(work, {"linuxcnc", "-r", "xyzac-trt-truecut.ini"});
  const std::string log =
      "exit " + std::to_string(r.exit_code) + "\nstdout:\n" + r.out + "\nstderr:\n" + r.err;
  EXPECT_EQ(0, r.exit_code) << log;
  EXPECT_NE(std::string::npos, r.out.find("part.ngc: finished")) << log;
  // The field was taken into use once, no reload failed, and a correction
  // was applied (run_program.py watches tc.corr-mag during the run).
  const auto at = r.out.find("truecut_comp: field-generation 1, load-errors 0, max corr-mag ");
  ASSERT_NE(std::string::npos, at) << log;
  std::printf("%s\n", r.out.substr(at, r.out.find('\n', at) - at).c_str());
  double max_corr = 0.0;
  ASSERT_EQ(1, std::sscanf(r.out.c_str() + at,
                           "truecut_comp: field-generation 1, load-errors 0, "
                           "max corr-mag %lf",
                           &max_corr))
      << log;
  EXPECT_GT(max_corr, 0.01) << log;
  EXPECT_LE(max_corr, 0.5) << "max-correction in the HAL file\n" << log;

  // The feedback wiring takes each joint's correction off the drive's
  // position, so motion sees its own command come back: no following error
  // from the correction (the simulated drive follows its command exactly).
  const auto fe = r.out.find("motion: max |f-error| of X, Y, Z ");
  ASSERT_NE(std::string::npos, fe) << log;
  std::printf("%s\n", r.out.substr(fe, r.out.find('\n', fe) - fe).c_str());
  double max_ferror = -1.0;
  ASSERT_EQ(1, std::sscanf(r.out.c_str() + fe, "motion: max |f-error| of X, Y, Z %lf", &max_ferror))
      << log;
  EXPECT_LT(max_ferror, 1e-6) << log;
}
