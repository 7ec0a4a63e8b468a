// `truecut diagnose` on hostile input (issue 23, the sweep's findings F1,
// F8, F16, F26, F27, F28, F30 and the low items of diagnose): refused before
// any work with exit 2 and a message naming the file, line or option, and
// nothing left in --out; or, for a name that is not UTF-8, written safely.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_diagnosis_fixtures.hpp"
#include "test_paths.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
using namespace truecut::sim::test;
namespace {

namespace fs = std::filesystem;
using truecut::test::cli_path;
using truecut::test::ProcessResult;
using truecut::test::read_file;
using truecut::test::run_process;
using truecut::test::scratch_dir;

ProcessResult diagnose(std::vector<std::string> args) {
  args.insert(args.begin(), {cli_path().string(), "diagnose"});
  return run_process(args);
}

void write_text(const fs::path& f, const std::string& text) {
  std::ofstream(f, std::ios::binary) << text;
}

// The implant at a coarse mesh: program.ngc, nominal.stl, part.json,
// tools.tbl and machine_ideal.json in DIR/p.
fs::path make_part(const fs::path& dir) {
  const ProcessResult r =
      run_process({cli_path().string(), "part", "implant", "--mesh-edge", "2", "--stepover", "2",
                   "--point-spacing", "2", "--step-down", "4", "--out", (dir / "p").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return dir / "p";
}

// A cmm.csv of 30 points on the +x face of the shaft (x = 0.8), all valid
// (or none); `extra` is appended as line 32.
fs::path cmm_file(const fs::path& file, bool valid = true, const std::string& extra = "") {
  std::string s = "x,y,z,nx,ny,nz,surface,deviation_mm,valid\n";
  for (int i = 0; i < 30; ++i)
    s += "0.8," + std::to_string(-0.5 + 0.03 * i) + "," + std::to_string(1 + 0.5 * i) +
         ",1,0,0,1," + (valid ? "0.01,1\n" : "nan,0\n");
  write_text(file, s + extra);
  return file;
}

// The surface-mode arguments for measurement `cmm` on the part in `p`.
std::vector<std::string> surface_args(const fs::path& p, const fs::path& cmm, const fs::path& out) {
  return {"--cmm",     cmm.string(),
          "--program", (p / "program.ngc").string(),
          "--machine", (p / "machine_ideal.json").string(),
          "--out",     out.string()};
}

// A recording of the X/Y test machine (a second of data).
fs::path recording(const fs::path& file, const std::string& extra_column = "",
                   const std::function<std::string(std::size_t)>& extra = {}) {
  RecordingSpec spec;
  spec.duration_s = 2;
  spec.record_every = 10;
  const Recording rec = make_recording(xy_machine().machine, spec);
  std::ofstream out(file, std::ios::binary);
  out << "t,x_cmd,y_cmd,x_act,y_act" << (extra_column.empty() ? "" : "," + extra_column) << "\n";
  char b[256];
  for (std::size_t k = 0; k < rec.rows(); ++k) {
    std::snprintf(b, sizeof b, "%.6f,%.9f,%.9f,%.9f,%.9f", rec.t_s[k], rec.channels.at("x_cmd")[k],
                  rec.channels.at("y_cmd")[k], rec.channels.at("x_act")[k],
                  rec.channels.at("y_act")[k]);
    out << b << (extra ? "," + extra(k) : "") << "\n";
  }
  return file;
}

}  // namespace

// F1, F26: a CMM file's values were not checked: a point at x = 1e20 mm
// crashed the process in Embree (SIGABRT) after a re-machining, a deviation
// of 1e300 gave "rms inf" with exit 0, a surface of 1e30 was converted with
// int() (undefined behaviour). Each is refused at its line before any work.
TEST(DiagnoseInput, ACmmFileWithImpossibleValuesIsRefusedAtItsLine) {
  const fs::path dir = scratch_dir();
  const fs::path p = make_part(dir);
  struct Case {
    const char* row;
    const char* says;
  };
  const Case cases[] = {
      {"1e20,0,5,1,0,0,1,0.01,1", "c.csv:32: x 1e+20 mm is outside ±1e+05 mm"},
      {"0.8,0,5,1,0,0,1,1e300,1", "c.csv:32: deviation_mm 1e+300 is outside ±100 mm"},
      {"0.8,0,5,1,0,0,1e30,0.01,1", "c.csv:32: surface '1e+30' is not a surface id"},
      {"0.8,0,5,1,0,0,2.5,0.01,1", "c.csv:32: surface '2.5' is not a surface id"},
      {"0.8,0,5,1,0,0,1,0.01,2", "c.csv:32: valid '2' is not 0 or 1"},
  };
  for (const Case& c : cases) {
    const fs::path out = dir / "d";
    const ProcessResult r = diagnose(surface_args(p, cmm_file(dir / "c.csv", true, c.row), out));
    EXPECT_EQ(r.exit_code, 2) << c.row << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("re-machining"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.row;
  }
}

// F26: the CMM reader was a bare ifstream: /dev/zero was read to 2.1 GB, a
// folder was "no points". Both get the common input check.
TEST(DiagnoseInput, ACmmFileThatIsNoRegularFileIsRefused) {
  const fs::path dir = scratch_dir();
  const fs::path p = make_part(dir);
  ProcessResult r = diagnose(surface_args(p, dir, dir / "d"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(dir.string() + ": is a folder, not a CMM file"), std::string::npos) << r.err;
  if (fs::exists("/dev/zero")) {
    r = diagnose(surface_args(p, "/dev/zero", dir / "d"));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("/dev/zero: is not a regular file"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "d"));
}

// F8: --candidates with a typo and a trace-mode effect ran 0 tests and
// still gave a verdict (exit 0).
TEST(DiagnoseInput, UnknownCandidatesAreRefusedNamingTheKnownOnes) {
  const fs::path dir = scratch_dir();
  const fs::path p = make_part(dir);
  std::vector<std::string> args = surface_args(p, cmm_file(dir / "c.csv"), dir / "d");
  args.insert(args.end(), {"--candidates", "tool_radius_eror,backlash"});
  ProcessResult r = diagnose(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--candidates: 'tool_radius_eror' is not a surface-mode effect; known: "
                       "tool_radius_error, tool_length_error, rotary_location, tool_deflection, "
                       "workpiece_deflection, squareness"),
            std::string::npos)
      << r.err;
  args.back() = "tool_radius_error,backlash";
  r = diagnose(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("'backlash' is not a surface-mode effect"), std::string::npos) << r.err;
  // Trace mode has no candidate list.
  r = diagnose({"--recording", recording(dir / "r.csv").string(), "--candidates", "backlash",
                "--out", (dir / "d").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--candidates selects the effects of surface mode"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "d"));
}

// F27: bad input in surface mode left runs/<hash>/ in --out (the help says
// nothing is written); a program leaving the travel was exit 1 naming the
// internal copy runs/<hash>/machine.json; a CMM file without a valid point
// was refused only after a whole re-machining.
TEST(DiagnoseInput, BadInputInSurfaceModeLeavesNothingBehind) {
  const fs::path dir = scratch_dir();
  const fs::path p = make_part(dir);
  std::string program = read_file(p / "program.ngc");
  const std::size_t g54 = program.find("G54\n");
  ASSERT_NE(g54, std::string::npos);
  program.insert(g54 + 4, "G0 X1000\n");
  write_text(p / "travel.ngc", program);
  std::vector<std::string> args = surface_args(p, cmm_file(dir / "c.csv"), dir / "d1");
  args[3] = (p / "travel.ngc").string();
  args.insert(args.end(), {"--nominal", (p / "nominal.stl").string(), "--part",
                           (p / "part.json").string(), "--tools", (p / "tools.tbl").string()});
  ProcessResult r = diagnose(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("joint X leaves travel"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(machine " + (p / "machine_ideal.json").string() + ")"), std::string::npos)
      << r.err;
  const std::size_t error = r.err.find("truecut diagnose: ");
  ASSERT_NE(error, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("runs/", error), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "d1"));

  r = diagnose(surface_args(p, cmm_file(dir / "none.csv", false), dir / "d2"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("none.csv: only 0 of 30 points are measured"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("re-machining"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "d2"));
}

// F16: `--machine DIR/fitted_machine.json --out DIR`, the natural next
// iteration, replaced the believed model it read.
TEST(DiagnoseInput, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  const fs::path dir = scratch_dir();
  fs::create_directories(dir / "d");
  write_machine_description(dir / "d" / "fitted_machine.json", xy_machine());
  const std::string before = read_file(dir / "d" / "fitted_machine.json");
  fs::create_symlink(dir / "d" / "fitted_machine.json", dir / "link.json");
  for (const char* machine : {"d/fitted_machine.json", "link.json"}) {
    const ProcessResult r = diagnose({"--recording", recording(dir / "r.csv").string(), "--machine",
                                      (dir / machine).string(), "--out", (dir / "d").string()});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("is the input " + (dir / machine).string()), std::string::npos) << r.err;
  }
  EXPECT_EQ(read_file(dir / "d" / "fitted_machine.json"), before);
  EXPECT_FALSE(fs::exists(dir / "d" / "diagnosis.json"));
}

// F30: a device given as --part was "/dev/zero not found"; a device given as
// --surface was named twice in the message.
TEST(DiagnoseInput, MessagesSayWhatTheFileIs) {
  if (!fs::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero";
  const fs::path dir = scratch_dir();
  const fs::path p = make_part(dir);
  std::vector<std::string> args = surface_args(p, cmm_file(dir / "c.csv"), dir / "d");
  args.insert(args.end(), {"--part", "/dev/zero"});
  ProcessResult r = diagnose(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/dev/zero: is not a regular file"), std::string::npos) << r.err;
  args = surface_args(p, "/dev/zero", dir / "d");
  args[0] = "--surface";
  r = diagnose(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/dev/zero: is not a regular file"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("/dev/zero"), r.err.rfind("/dev/zero")) << "named twice: " << r.err;
  EXPECT_FALSE(fs::exists(dir / "d"));
}

// Low items: --holdout naming the --recording proves nothing; a `tool`
// channel of 99 (not in --tools) or 2.5 was read silently.
TEST(DiagnoseInput, HoldoutThatIsTheRecordingAndToolsOutsideTheTableAreRefused) {
  const fs::path dir = scratch_dir();
  const std::string rec = recording(dir / "r.csv").string();
  ProcessResult r = diagnose({"--recording", rec, "--holdout", (dir / "." / "r.csv").string(),
                              "--out", (dir / "d").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("is the --recording"), std::string::npos) << r.err;
  write_text(dir / "t.tbl", "T1 P1 D2 Z30\n");
  for (const char* bad : {"99", "2.5"}) {
    const std::string file = recording(dir / "tool.csv", "tool", [&](std::size_t k) {
                               return k == 50 ? bad : "1";
                             }).string();
    r = diagnose(
        {"--recording", file, "--tools", (dir / "t.tbl").string(), "--out", (dir / "d").string()});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("tool.csv: sample 51 (t = "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string("tool ") + bad), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "d"));
}

// F28: a recording named in Latin-1 ("caf\xe9.csv") ended the diagnosis
// after all its work with nlohmann's type_error.316 (exit 1). The name is
// written with U+FFFD for the byte that is not UTF-8.
TEST(DiagnoseInput, ANameThatIsNotUtf8IsWrittenSafely) {
  const fs::path dir = scratch_dir();
  const fs::path rec = recording(dir / "caf\xe9.csv");
  const ProcessResult r = diagnose({"--recording", rec.string(), "--out", (dir / "d").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_file(dir / "d" / "diagnosis.json"));
  const std::string text = j.dump();
  EXPECT_NE(text.find("caf\xef\xbf\xbd.csv"), std::string::npos) << text.substr(0, 400);
}

// The help said --work DIR keeps the runs "(default DIR/runs)" while they
// went to DIR/runs for --work DIR: the help now says where they go.
TEST(DiagnoseInput, TheHelpSaysWhereTheWorkFolderKeepsItsRuns) {
  const ProcessResult r = diagnose({"--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("re-machinings are kept in DIR/runs/"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("(default DIR/runs)"), std::string::npos) << r.out;
}

// An --out that cannot be written was found after all the work.
TEST(DiagnoseInput, AnOutputThatCannotBeWrittenIsRefusedBeforeTheWork) {
  if (!fs::is_directory("/proc/self")) GTEST_SKIP() << "no /proc";
  const fs::path dir = scratch_dir();
  const ProcessResult r = diagnose(
      {"--recording", recording(dir / "r.csv").string(), "--out", "/proc/truecut-diagnosis"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("cannot write in /proc"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("diagnose: reading"), std::string::npos) << r.err;
}

// F23: `--servo-period 1e-6` split each recorded sample into 1000 servo
// periods with no estimate: the diagnosis ran with no end in sight. The
// periods a re-simulation takes are counted from the recording first and
// refused above the budget, naming both options.
TEST(DiagnoseInput, AServoPeriodBeyondTheBudgetIsRefusedBeforeAnyFit) {
  const fs::path dir = scratch_dir();
  const std::string rec = recording(dir / "r.csv").string();
  const fs::path out = dir / "out";
  const ProcessResult r = diagnose({"--recording", rec, "--servo-period", "1e-6",
                                    "--max-servo-periods", "1e6", "--out", out.string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  // 200 samples 10 ms apart: 1.99 s, each interval 10,000 periods of 1 µs.
  EXPECT_NE(r.err.find(rec + ": re-simulating its 1.99 s at --servo-period 1e-06 s takes 1.99e+06 "
                             "servo periods per run, more than --max-servo-periods 1e+06"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out / "diagnosis.json"));
}

}  // namespace truecut::analysis::test
