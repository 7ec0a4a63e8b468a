// `truecut part` writes a benchmark part that truecut's own interpreter reads.
#include <gtest/gtest.h>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;

TEST(PartCli, WritesAllFilesAndTheProgramInterprets) {
  const auto out = scratch_dir() / "implant";
  auto r = run_process({cli_path().string(), "part", "implant", "--out", out.string(),
                        "--step-down", "4"});
  ASSERT_EQ(0, r.exit_code) << r.err;
  for (const char* f : {"nominal.stl", "program.ngc", "tools.tbl", "part.json"})
    EXPECT_TRUE(std::filesystem::is_regular_file(out / f)) << f;
  auto canon = run_process({cli_path().string(), "canon", "--tool-table",
                            (out / "tools.tbl").string(), "--list-operations",
                            (out / "program.ngc").string()});
  ASSERT_EQ(0, canon.exit_code) << canon.err;
  EXPECT_EQ("SHAFT_TOP_FACE\nSHAFT_PERIPHERAL\n", canon.out);
}

TEST(PartCli, BadArgumentsAreUsageErrorsAndWriteNothing) {
  const auto out = scratch_dir() / "x";
  auto bogus = run_process({cli_path().string(), "part", "bogus", "--out", out.string()});
  EXPECT_EQ(2, bogus.exit_code);
  EXPECT_NE(std::string::npos, bogus.err.find("unknown part 'bogus'"));
  EXPECT_EQ(2, run_process({cli_path().string(), "part", "implant"}).exit_code) << "--out missing";
  EXPECT_EQ(2, run_process({cli_path().string(), "part", "implant", "--out", out.string(),
                            "--stepover", "0"})
                   .exit_code);
  EXPECT_FALSE(std::filesystem::exists(out));
}
