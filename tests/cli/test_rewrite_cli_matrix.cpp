// The compensation matrix written by offline's writer is read by the
// rewriter's own reader (interp may not use offline/) to the same doubles,
// and `truecut rewrite` accepts the file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/interp/rewrite_matrix.hpp"
#include "truecut/offline/compensation_matrix.hpp"
#include "truecut/rt/field_file.hpp"

using namespace truecut;
using Eigen::Vector3d;

namespace {

// `truecut rewrite` of the operation FACE of p.ngc (tools t.tbl, out o.ngc),
// with `extra` options.
std::vector<std::string> face_rewrite(const std::vector<std::string>& extra) {
  std::vector<std::string> args = {test::cli_path().string(),
                                   "rewrite",
                                   "p.ngc",
                                   "--operation",
                                   "FACE",
                                   "--type",
                                   "face",
                                   "--tools",
                                   "t.tbl",
                                   "--out",
                                   "o.ngc"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

}  // namespace

TEST(CliRewriteMatrix, OfflineWriterAndRewriteReaderAgreeBitForBit) {
  offline::CompensationMatrix m;
  // Awkward doubles: thirds, tiny magnitudes and the largest a position may
  // have (positions up to 200 times these, within the reader's ±1e5 mm),
  // negative zero, values that need 17 significant digits.
  const double values[] = {1.0 / 3.0,           -2.0 / 7.0, 0.1,  1e-300,
                           -123.45678901234567, 5e-324,     -0.0, 499.99999999999994,
                           0.30000000000000004, 17.0};
  for (int i = 0; i < 200; ++i) {
    const double a = values[i % 10], b = values[(i / 10) % 10], c = values[(i * 7) % 10];
    m.positions_mm.emplace_back(a * (i + 1), b - i, c);
    m.vectors_mm.emplace_back(i % 3 ? 0.0 : c * 1e-3, a * 1e-2, -b * 1e-4);
    m.valid.push_back(i % 5 == 4 ? 0 : 1);
    m.surface_ids.push_back(i % 4);
    if (!m.valid.back()) m.vectors_mm.back() = Vector3d::Zero();
  }
  const auto file = test::scratch_dir() / "comp.csv";
  offline::write_compensation_matrix(file, m, "from the test\nsecond comment line");
  const interp::CompensationMatrixData r = interp::read_compensation_matrix(file);
  ASSERT_EQ(r.size(), m.size());
  for (size_t i = 0; i < m.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      // -0 is written as 0: equal as numbers; everything else bit for bit.
      EXPECT_EQ(r.positions_mm[i][k], m.positions_mm[i][k]) << i;
      EXPECT_EQ(r.vectors_mm[i][k], m.vectors_mm[i][k]) << i;
      if (m.positions_mm[i][k] != 0) {
        EXPECT_EQ(std::signbit(r.positions_mm[i][k]), std::signbit(m.positions_mm[i][k]));
      }
    }
    EXPECT_EQ(r.valid[i], m.valid[i]);
    EXPECT_EQ(r.surface_ids[i], m.surface_ids[i]);
  }
}

// A face 10 x 4 mm at z = 0 whose compensation is dz everywhere (and, when
// given, raw columns of raw_dz beside it), a face-milling operation across
// it at safe height z_safe, and a tool table.
void write_flat_face_case(const std::filesystem::path& dir, double dz, int z_safe,
                          std::optional<double> raw_dz = {}) {
  offline::CompensationMatrix m;
  for (int i = -10; i <= 10; ++i)
    for (int j = -4; j <= 4; ++j) {
      m.positions_mm.emplace_back(0.5 * i, 0.5 * j, 0.0);
      m.vectors_mm.emplace_back(0.0, 0.0, dz);
      if (raw_dz) m.raw_vectors_mm.emplace_back(0.0, 0.0, *raw_dz);
      m.valid.push_back(1);
      m.surface_ids.push_back(1);
    }
  offline::write_compensation_matrix(dir / "comp.csv", m, "flat face");
  std::ofstream(dir / "p.ngc") << "G21 G90 G94\n(OPERATION: FACE)\nT1 M6\nG43 H1\nG0 X-4 Y0 Z"
                               << z_safe << "\nG1 Z0 F100\nG1 X4 F500\nG0 Z" << z_safe + 4
                               << "\nM30\n";
  std::ofstream(dir / "t.tbl") << "T1 P1 D2 Z30\n";
}

TEST(CliRewriteMatrix, RewriteAcceptsTheOfflineMatrix) {
  const auto dir = test::scratch_dir();
  write_flat_face_case(dir, 0.01, 1);
  const auto r = test::run_process(
      {test::cli_path().string(), "rewrite", "p.ngc", "--matrix", "comp.csv", "--operation", "FACE",
       "--type", "face", "--tools", "t.tbl", "--out", "o.ngc"},
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("  max compensation      0.0100 mm"), std::string::npos) << r.out;
  EXPECT_NE(test::read_file(dir / "o.ngc").find("X4.0000 Y0.0000 Z0.0100\nG0 X4 Y0 Z5\n"),
            std::string::npos)
      << test::read_file(dir / "o.ngc");
}

// Issue 24: --paper denkena is the source's recipe — the raw mirror columns,
// the 3 points at the tool tip — recorded in the audit; it needs a matrix.
TEST(CliRewriteMatrix, PaperDenkenaReadsTheRawColumnsAtTheTip) {
  const auto dir = test::scratch_dir();
  write_flat_face_case(dir, 0.01, 1, 0.03);  // raw vectors of 0.03 mm beside the smoothed
  const auto rewrite = [&](const std::vector<std::string>& extra) {
    return test::run_process(face_rewrite(extra), dir);
  };
  auto r = rewrite({"--matrix", "comp.csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(test::read_file(dir / "o.ngc").find("X4.0000 Y0.0000 Z0.0100\n"), std::string::npos);
  EXPECT_NE(test::read_file(dir / "o.ngc.audit.json").find("\"matrix_vectors\": \"smoothed\""),
            std::string::npos);
  r = rewrite({"--matrix", "comp.csv", "--paper", "denkena"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(test::read_file(dir / "o.ngc").find("X4.0000 Y0.0000 Z0.0300\n"), std::string::npos)
      << test::read_file(dir / "o.ngc");
  const std::string audit = test::read_file(dir / "o.ngc.audit.json");
  EXPECT_NE(audit.find("\"placement\": \"tip\""), std::string::npos) << audit;
  EXPECT_NE(audit.find("\"matrix_vectors\": \"raw\""), std::string::npos) << audit;
  EXPECT_NE(audit.find("\"paper\": \"denkena\""), std::string::npos) << audit;
  EXPECT_NE(audit.find("\"step_mm\": 0.5"), std::string::npos) << audit;

  r = rewrite({"--field", "comp.csv", "--paper", "denkena"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--paper denkena goes with --matrix"), std::string::npos) << r.err;
  r = rewrite({"--matrix", "comp.csv", "--paper", "sortino"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--paper must be denkena, not 'sortino'"), std::string::npos) << r.err;
}

// a word; above --max-correction (default 0.2 mm, as truecut field) it is
// refused with exit 1 and nothing written, and --force writes it and says so.
TEST(CliRewriteMatrix, ACompensationAboveMaxCorrectionIsRefusedUnlessForced) {
  const auto dir = test::scratch_dir();
  write_flat_face_case(dir, 5.0, 10);  // 5 mm: a unit mix-up
  std::vector<std::string> args = face_rewrite({"--matrix", "comp.csv"});
  auto r = test::run_process(args, dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("the compensation reaches 5.0000 mm, above --max-correction 0.2 mm"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.ngc"));
  args.push_back("--force");
  r = test::run_process(args, dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("WARNING: compensation 5.0000 mm above 0.2 mm, written (--force)"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "o.ngc"));
}

namespace {

// A face operation cut by T2 (p.ngc, t.tbl) and a field f.tcf whose one
// layer, for `tool`, moves the tool 10 µm up everywhere on a 20 mm cube
// (and turns it by `rotation_rad` when that is not zero).
void write_face_job(const std::filesystem::path& dir, std::int32_t tool,
                    const Vector3d& rotation_rad = Vector3d::Zero()) {
  rt::FieldGrid g;
  g.origin_mm = Vector3d(-10, -10, -10);
  g.spacing_mm = Vector3d(1, 1, 1);
  g.dims = {21, 21, 21};
  rt::FieldLayer layer;
  layer.tool = tool;
  layer.nodes.assign(static_cast<std::size_t>(g.node_count()), rt::FieldNode{0, 0, 0.01, 1});
  if (!rotation_rad.isZero()) layer.rotation_rad.assign(layer.nodes.size(), rotation_rad);
  rt::write_field_file(dir / "f.tcf", rt::CorrectionField(g, {layer}), {"", "test"});
  std::ofstream(dir / "p.ngc") << "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X-4 Y0 Z1\n"
                                  "G1 Z0 F100\nG1 X4 F500\nG0 Z5\nM30\n";
  std::ofstream(dir / "t.tbl") << "T1 P1 D2 Z30\nT2 P2 D4 Z40\n";
}

}  // namespace

TEST(CliRewriteMatrix, FieldWithoutALayerForTheOperationsToolIsRefused) {
  const auto dir = test::scratch_dir();
  write_face_job(dir, 1);
  const auto r = test::run_process(face_rewrite({"--field", "f.tcf"}), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("the correction field has no layer for tool 2 (operation 'FACE')"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.ngc"));
  EXPECT_FALSE(std::filesystem::exists(dir / "o.ngc.audit.json"));
}

// Issue 19: a field that turns the tool needs the machine's pivots (A and C
// turn the table about them); without --machine it is refused, with it the
// rewritten moves carry A and C and the audit counts them.
TEST(CliRewriteMatrix, AFieldThatTurnsTheToolNeedsTheMachine) {
  const auto dir = test::scratch_dir();
  write_face_job(dir, 2, Vector3d(4e-4, 0, 0));
  const auto refused = test::run_process(face_rewrite({"--field", "f.tcf"}), dir);
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("f.tcf: the field turns the tool (rotation channels rx ry rz); give "
                             "--machine MACHINE.json"),
            std::string::npos)
      << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.ngc"));

  const auto made = test::run_process({test::cli_path().string(), "part", "implant", "--out",
                                       (dir / "implant").string(), "--mesh-edge", "1"},
                                      dir);
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const auto r = test::run_process(
      face_rewrite({"--field", "f.tcf", "--machine", "implant/machine.json"}), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string out = test::read_file(dir / "o.ngc");
  EXPECT_NE(out.find(" A-0.0229"), std::string::npos) << out;  // -4e-4 rad in degrees
  const std::string audit = test::read_file(dir / "o.ngc.audit.json");
  EXPECT_NE(audit.find("\"points_rotated\": "), std::string::npos) << audit;
  EXPECT_EQ(audit.find("\"points_rotated\": 0,"), std::string::npos) << audit;
}
