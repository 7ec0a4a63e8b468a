// `truecut run MACHINE PROGRAM --field F` says when max-correction limited the
// field (issue 23: the correction was clamped without a word and the run
// exited 0 as if the part had got the whole field).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/rt/core/correction_field.hpp"
#include "truecut/rt/field_file.hpp"

using namespace truecut;
using namespace truecut::test;
namespace fs = std::filesystem;

namespace {

// A constant correction of (dx, 0, 0) over the implant's work volume for
// its two tools.
void write_constant_field(const fs::path& file, double dx_mm) {
  rt::FieldGrid grid;
  grid.origin_mm = Eigen::Vector3d(-60, -60, -60);
  grid.spacing_mm = Eigen::Vector3d(10, 10, 10);
  grid.dims = {13, 13, 15};
  std::vector<rt::FieldLayer> layers;
  for (const int tool : {1, 2})
    layers.push_back({tool, std::vector<rt::FieldNode>(static_cast<std::size_t>(grid.node_count()),
                                                       rt::FieldNode{dx_mm, 0.0, 0.0, 1.0})});
  rt::write_field_file(file, rt::CorrectionField(grid, std::move(layers)),
                       {"2026-11-27T00:00:00Z", "test_run_field_clamp"});
}

}  // namespace

TEST(RunFieldClamp, ACorrectionLimitedByMaxCorrectionIsReported) {
  const fs::path dir = scratch_dir();
  ASSERT_EQ(0, run_process({cli_path().string(), "part", "implant", "--out", (dir / "p").string()})
                   .exit_code);
  write_constant_field(dir / "f.tcf", 0.02);
  const ProcessResult r =
      run_process({cli_path().string(), "run", (dir / "p" / "machine.json").string(),
                   (dir / "p" / "program.ngc").string(), "--field", (dir / "f.tcf").string(),
                   "--max-correction", "0.005", "--out", (dir / "r").string()});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos,
            r.err.find("WARNING: --max-correction 0.005 mm limited the field's correction in "))
      << r.err;
  EXPECT_NE(std::string::npos, r.out.find("  correction  max 0.005 mm: limited in ")) << r.out;
  EXPECT_EQ(std::string::npos, r.out.find("limited in 0 cycles")) << r.out;
}
