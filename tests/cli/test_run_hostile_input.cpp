// `truecut run MACHINE PROGRAM` on input that cannot give the part it
// seems to ask for (issue 23, the hostile-input sweep): a field that
// corrects nothing, part.json tools the cutting model cannot use, a program
// that would run for days, a position no machine reaches, a repeat run that
// wrote into the first run's folder, a cutting model beyond its memory.
// Each is exit 2 naming the file and line or key, with nothing written, or
// a warning where the part is what such a machine makes.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "face_job.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/rt/core/correction_field.hpp"
#include "truecut/rt/field_file.hpp"

using namespace truecut;
using namespace truecut::test;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

ProcessResult run_truecut(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return run_process(args);
}

// A coarse implant with a one-pass program: T2 (flat Ø4, D4 in tools.tbl)
// faces the shaft top; its first cut is on line 8.
class RunHostile : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(scratch_dir());
    const ProcessResult r = run_truecut(coarse_implant_part_args(part()));
    ASSERT_EQ(0, r.exit_code) << r.err;
    std::ofstream(part() / "face.ngc") << kFaceProgram;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path part() { return *dir_ / "part"; }
  static fs::path out(const std::string& name) { return *dir_ / name; }

  // `run machine_ideal.json PROGRAM --out OUT` with `extra`.
  static ProcessResult run(const std::string& out_name, std::vector<std::string> extra,
                           const fs::path& program = part() / "face.ngc") {
    std::vector<std::string> args = {"run",
                                     (part() / "machine_ideal.json").string(),
                                     program.string(),
                                     "--out",
                                     out(out_name).string(),
                                     "--dexel-spacing",
                                     "0.2"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_truecut(args);
  }

  // face.ngc with `line` inserted after line `after` (1-based).
  static fs::path program_with(const std::string& name, int after, const std::string& line) {
    std::ifstream in(part() / "face.ngc");
    std::string text, l;
    for (int n = 1; std::getline(in, l); ++n) {
      text += l + "\n";
      if (n == after) text += line + "\n";
    }
    std::ofstream(part() / name) << text;
    return part() / name;
  }

  static fs::path part_json_with(const std::string& name, const json::json_pointer& at,
                                 const json& value) {
    json p = json::parse(read_file(part() / "part.json"));
    p[at] = value;
    std::ofstream(part() / name) << p.dump(1);
    return part() / name;
  }

  static fs::path* dir_;
};

fs::path* RunHostile::dir_ = nullptr;

// A constant correction of (dx, 0, 0) on a 10 mm grid from `origin`, with
// a layer for each of `tools`.
fs::path field_file(const fs::path& file, const Eigen::Vector3d& origin_mm,
                    const std::vector<int>& tools, double dx_mm) {
  rt::FieldGrid grid;
  grid.origin_mm = origin_mm;
  grid.spacing_mm = Eigen::Vector3d(10, 10, 10);
  grid.dims = {13, 13, 15};
  std::vector<rt::FieldLayer> layers;
  for (const int tool : tools)
    layers.push_back({tool, std::vector<rt::FieldNode>(static_cast<std::size_t>(grid.node_count()),
                                                       rt::FieldNode{dx_mm, 0.0, 0.0, 1.0})});
  rt::write_field_file(file, rt::CorrectionField(grid, std::move(layers)),
                       {"2026-12-01T00:00:00Z", "test_run_hostile_input"});
  return file;
}

void expect_refused(const ProcessResult& r, const std::string& message, const fs::path& out) {
  EXPECT_EQ(2, r.exit_code) << message << "\n" << r.err;
  EXPECT_NE(std::string::npos, r.err.find(message)) << r.err;
  EXPECT_FALSE(fs::exists(out)) << message << ": nothing written";
}

}  // namespace

// Issue 23 (F4): --max-rate 0, a field without the program's tool and a
// field 100 mm from the part all ran with exit 0, no correction and no word.
TEST_F(RunHostile, AFieldThatCannotCorrectTheCutIsRefusedOrReported) {
  const fs::path good = field_file(out("good.tcf"), {-60, -60, -60}, {1, 2}, 0.01);
  expect_refused(run("rate0", {"--field", good.string(), "--max-rate", "0"}),
                 "--max-rate 0 mm/s would hold the field's correction at zero; it must be > 0",
                 out("rate0"));
  const fs::path t9 = field_file(out("t9.tcf"), {-60, -60, -60}, {9}, 0.01);
  expect_refused(run("t9", {"--field", t9.string()}),
                 t9.string() + ": the correction field has no layer for tool 2, which " +
                     (part() / "face.ngc").string() + " cuts with from line 8",
                 out("t9"));

  const fs::path far = field_file(out("far.tcf"), {95, 95, 95}, {1, 2}, 0.01);
  const ProcessResult r = run("far", {"--field", far.string()});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.err.find("WARNING: " + far.string() + " never corrected the cut"))
      << r.err;
  const ProcessResult ok = run("good", {"--field", good.string()});
  ASSERT_EQ(0, ok.exit_code) << ok.err;
  EXPECT_EQ(std::string::npos, ok.err.find("never corrected")) << ok.err;
  EXPECT_NE(std::string::npos, read_file(out("good") / "run.ini").find("TOOLS = 2\n"));
}

// Issue 23 (F7): each of these ran with exit 0 (a radius of 0 left the part
// 0.3 mm oversize, a radius of 3 against the table's D2 cut it 0.5 mm under).
TEST_F(RunHostile, PartJsonToolsUnitsAndStockAreChecked) {
  struct Case {
    std::string pointer;
    json value;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"/tools/1/radius_mm", 0.0, "key 'tools[1].radius_mm': 0 mm must be > 0 and at most 500 mm"},
      {"/tools/1/radius_mm", 1e6, "key 'tools[1].radius_mm': 1e+06 mm must be > 0"},
      {"/tools/1/flute_length_mm", 0.0, "key 'tools[1].flute_length_mm': 0 mm must be > 0"},
      {"/tools/1/kind", "spoon", "key 'tools[1].kind': unknown tool kind 'spoon'"},
      {"/units", "inch", "key 'units': 'inch': part.json lengths are millimetres"},
      {"/stock/0/min_mm/0", -1e30, "key 'stock[0].min_mm': -1e+30 mm is outside ±100000 mm"},
      {"/tools/1/radius_mm", 3.0,
       "key 'tools[1].radius_mm': 3 mm, but " + (part() / "tools.tbl").string() +
           " gives tool 2 the diameter D 4 mm (radius 2 mm)"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string name = "p" + std::to_string(i++);
    const fs::path file = part_json_with(name + ".json", json::json_pointer(c.pointer), c.value);
    expect_refused(run(name, {"--part", file.string()}), file.string() + ": " + c.message,
                   out(name));
  }
}

// Issue 23 (F23): G4 P100000 and a feed of 1e-6 mm/min ran for hours of
// wall time, 1e8 turns of an arc stalled at load without a word.
TEST_F(RunHostile, AProgramBeyondItsBudgetsIsRefusedAtItsLine) {
  // Before planning: a lower bound of the time at the programmed feeds.
  const std::string budget = "more than --max-program-time 86400 s (24 h)";
  const std::vector<std::string> lines = {"G4 P100000", "G1 X1 F0.000001",
                                          "G2 X-5 Y0 I1 J0 P100000000 F600"};
  int i = 0;
  for (const std::string& line : lines) {
    const std::string name = "long" + std::to_string(i++);
    const fs::path program = program_with(name + ".ngc", 8, line);
    const ProcessResult r = run(name, {}, program);
    expect_refused(r, program.string() + ":9: the program takes at least ", out(name));
    EXPECT_NE(std::string::npos, r.err.find(budget)) << r.err;
  }
  const fs::path dwell = program_with("dwell.ngc", 8, "G4 P100");
  expect_refused(run("short_budget", {"--max-program-time", "60"}, dwell),
                 "more than --max-program-time 60 s", out("short_budget"));
  // After planning: the plan's own time (the rapid moves and the
  // accelerations count too; the feed moves alone take 1.3 s).
  expect_refused(
      run("planned", {"--max-program-time", "1.35"}),
      (part() / "face.ngc").string() + ":7: the planned program passes --max-program-time 1.35 s",
      out("planned"));
  expect_refused(run("blocks", {"--max-blocks", "5"}), "more than 5 blocks", out("blocks"));
}

// Issue 23 (F30): G0 X1e300 was reported as "leaves travel [-250, 250] at
// -nan mm".
TEST_F(RunHostile, APositionBeyondAnyMachineIsRefusedAtItsLine) {
  // G-code has no exponent: a 1 and 300 zeros.
  const fs::path program = program_with("far.ngc", 7, "G0 X1" + std::string(300, '0'));
  expect_refused(run("far_x", {}, program),
                 program.string() + ":8: X 1e+300 mm (machine position) is outside ±100000 mm",
                 out("far_x"));
}

// Issue 23 (F30): an input that exists but is no file was "no such file".
TEST_F(RunHostile, InputsThatAreNoFilesAreNamedAsWhatTheyAre) {
  fs::create_directories(out("folder.json"));
  expect_refused(run("dev", {"--part", "/dev/zero"}), "/dev/zero: is not a regular file",
                 out("dev"));
  expect_refused(run("dir", {"--tools", out("folder.json").string()}),
                 out("folder.json").string() + ": is a folder, not a tool table", out("dir"));
  expect_refused(run_truecut({"run", out("folder.json").string(), (part() / "face.ngc").string(),
                              "--out", out("m").string()}),
                 out("folder.json").string() + ": is a folder, not a machine description",
                 out("m"));
  expect_refused(
      run_truecut({"run", "--out", out("m").string(), "/dev/zero", (part() / "face.ngc").string()}),
      "/dev/zero: is not a regular file", out("m"));
}

// Issue 23 (F22): a nominal in µm (17 m across) took 2.8 GB, then
// std::bad_alloc. The estimate is checked before any dexel is made.
TEST_F(RunHostile, ACuttingModelBeyondItsBudgetIsRefused) {
  expect_refused(run("dexels", {"--max-dexels", "1000"}), "more than max-dexels 1000",
                 out("dexels"));
}

// Issue 23 (F18): `run first/soft_cnc.hal --ini first/run.ini --out second`
// wrote machined.stl and machined.ply into first/ (run.ini's absolute
// OUT_DIR), replacing the first run's part.
TEST_F(RunHostile, ARepeatedRunWritesIntoItsOwnOutputFolder) {
  ASSERT_EQ(0, run("first", {}).exit_code);
  const std::string machined = read_file(out("first") / "machined.stl");
  const std::string ini = read_file(out("first") / "run.ini");
  EXPECT_EQ(std::string::npos, ini.find("OUT_DIR")) << ini;
  EXPECT_NE(std::string::npos, ini.find("MAX_BLOCKS = 50000000\n")) << ini;
  EXPECT_NE(std::string::npos, read_file(out("first") / "soft_cnc.hal").find("max-blocks="));
  const ProcessResult again =
      run_truecut({"run", (out("first") / "soft_cnc.hal").string(), "--ini",
                   (out("first") / "run.ini").string(), "--out", out("second").string()});
  ASSERT_EQ(0, again.exit_code) << again.err;
  EXPECT_TRUE(fs::exists(out("second") / "machined.stl"));
  EXPECT_TRUE(fs::exists(out("second") / "trace.csv"));
  EXPECT_EQ(machined, read_file(out("first") / "machined.stl"));

  // A wiring that names another folder absolutely (as earlier run.ini files
  // did) is refused at its loadrt line.
  std::string hal = read_file(out("first") / "soft_cnc.hal");
  const std::string cutting = "loadrt cutting names=cut ";
  hal.replace(hal.find(cutting), cutting.size(), cutting + "out=" + out("first").string() + " ");
  std::ofstream(out("old.hal")) << hal;
  const ProcessResult old =
      run_truecut({"run", out("old.hal").string(), "--ini", (out("first") / "run.ini").string(),
                   "--out", out("third").string()});
  EXPECT_EQ(2, old.exit_code) << old.err;
  EXPECT_NE(std::string::npos,
            old.err.find("out=" + out("first").string() + ": outside the output folder"))
      << old.err;
  EXPECT_EQ(machined, read_file(out("first") / "machined.stl"));
}
