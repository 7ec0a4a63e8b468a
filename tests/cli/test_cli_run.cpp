// `truecut run` as a user runs it: exit codes, messages, outputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;

namespace {
ProcessResult run_truecut(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return run_process(args);
}
std::string example(const char* f) {
  return (source_dir() / "examples" / "circle" / f).string();
}
}  // namespace

TEST(CliRun, UsageAndHelp) {
  EXPECT_EQ(2, run_truecut({}).exit_code);
  auto help = run_truecut({"--help"});
  EXPECT_EQ(0, help.exit_code);
  EXPECT_NE(std::string::npos, help.out.find("run"));
  auto run_help = run_truecut({"run", "--help"});
  EXPECT_EQ(0, run_help.exit_code);
  EXPECT_NE(std::string::npos, run_help.out.find("usage: truecut run CONFIG.hal"));
  auto unknown = run_truecut({"frobnicate"});
  EXPECT_EQ(2, unknown.exit_code);
  EXPECT_NE(std::string::npos, unknown.err.find("unknown command 'frobnicate'"));
  auto bad_opt = run_truecut({"run", example("circle.hal"), "--speed", "3"});
  EXPECT_EQ(2, bad_opt.exit_code);
  EXPECT_NE(std::string::npos, bad_opt.err.find("unknown option '--speed'"));
  EXPECT_EQ(2, run_truecut({"run", example("circle.hal"), "--time", "-1"}).exit_code);
  EXPECT_EQ(2, run_truecut({"run", example("circle.hal"), "--cpu", "1"}).exit_code)
      << "--cpu needs --realtime";
}

TEST(CliRun, RunsTheExampleAndWritesTheTrace) {
  auto out = scratch_dir();
  auto r = run_truecut({"run", example("circle.hal"), "--ini", example("circle.ini"), "--time",
                        "0.5", "--out", out.string()});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.out.find("500 cycles"));
  std::string trace = read_file(out / "trace.csv");
  EXPECT_EQ(0u, trace.find("t,x_cmd,x_act,y_cmd,y_act,x_ferr,y_ferr\n"));
  EXPECT_EQ(501, std::count(trace.begin(), trace.end(), '\n'));
  EXPECT_FALSE(std::filesystem::exists(out / "trace.csv.tmp"));
}

TEST(CliRun, WallClockModeRuns) {
  auto out = scratch_dir();
  auto r = run_truecut({"run", example("circle.hal"), "--ini", example("circle.ini"), "--cycles",
                        "50", "--realtime", "--no-mlock", "--out", out.string()});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.out.find("wall clock"));
  EXPECT_NE(std::string::npos, r.out.find("latency"));
}

TEST(CliRun, BadConfigurationGivesFileLineAndNoOutput) {
  auto dir = scratch_dir();
  {
    std::ofstream f(dir / "bad.hal");
    f << "loadrt threads name1=t period1=1000000\n"
         "loadrt recorder file=trace.csv columns=a\n"
         "loadrt siggen\n"
         "net a siggen.0.clock => recorder.0.a\n";
  }
  auto r = run_truecut(
      {"run", (dir / "bad.hal").string(), "--time", "1", "--out", (dir / "out").string()});
  EXPECT_EQ(2, r.exit_code);
  EXPECT_NE(std::string::npos,
            r.err.find("bad.hal:4: type mismatch: pin 'recorder.0.a' is float, signal 'a' is bit"))
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "nothing half-written";
}

TEST(CliRun, MissingFilesAreUsageErrors) {
  auto r = run_truecut({"run", "/nonexistent/x.hal"});
  EXPECT_EQ(2, r.exit_code);
  EXPECT_NE(std::string::npos, r.err.find("/nonexistent/x.hal: no such file"));
  auto i = run_truecut({"run", example("circle.hal"), "--ini", "/nonexistent/m.ini"});
  EXPECT_EQ(2, i.exit_code);
  EXPECT_NE(std::string::npos, i.err.find("/nonexistent/m.ini: cannot open the INI file"));
  auto noini = run_truecut({"run", example("circle.hal"), "--time", "1"});
  EXPECT_EQ(2, noini.exit_code);
  EXPECT_NE(std::string::npos, noini.err.find("circle.hal:10: '[EMCMOT]SERVO_PERIOD' needs an INI"))
      << noini.err;
}

// Issue 23: --dry-run with an --out that did not exist failed, the recorder
// could not create its temporary file there.
TEST(CliRun, DryRunIntoANewFolderLoadsAndLeavesNothing) {
  const auto out = scratch_dir() / "new";
  auto r = run_truecut({"run", example("circle.hal"), "--ini", example("circle.ini"), "--dry-run",
                        "--out", out.string()});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.out.find("configuration loads without error"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

namespace {
// The circle example's recorder, stopped by a SIGINT the test_interrupt
// component raises in the given cycle.
std::filesystem::path interrupted_hal(const std::filesystem::path& dir, int at_cycle) {
  const auto hal = dir / "interrupt.hal";
  std::ofstream(hal) << "loadrt threads name1=t period1=1000000\n"
                        "loadrt siggen\n"
                        "loadrt test_interrupt at="
                     << at_cycle
                     << "\n"
                        "loadrt recorder file=trace.csv columns=s\n"
                        "net s siggen.0.sine => recorder.0.s\n"
                        "addf siggen.0.update t\n"
                        "addf test_interrupt.update t\n"
                        "addf recorder.0.sample t\n";
  return hal;
}
}  // namespace

// Issue 23: `run CONFIG.hal --time 100000` stopped by Ctrl-C exited 0 with
// the trace of the part that ran, as if the run had been done.
TEST(CliRun, ARunInterruptedBeforeItsTimeOrCyclesExits130) {
  const auto dir = scratch_dir();
  const std::string components = test_component_dir().string();
  auto timed = run_truecut({"run", interrupted_hal(dir, 100).string(), "--time", "100000",
                            "--component-path", components, "--out", (dir / "a").string()});
  EXPECT_EQ(130, timed.exit_code) << timed.err;
  EXPECT_NE(std::string::npos,
            timed.err.find("interrupted at 0.100000 s of the 100000.000000 s asked for (--time)"))
      << timed.err;
  const std::string trace = read_file(dir / "a" / "trace.csv");
  EXPECT_EQ(101, std::count(trace.begin(), trace.end(), '\n')) << "the trace up to there";
  auto cycles = run_truecut({"run", interrupted_hal(dir, 10).string(), "--cycles", "1000",
                             "--component-path", components, "--out", (dir / "b").string()});
  EXPECT_EQ(130, cycles.exit_code) << cycles.err;
  EXPECT_NE(std::string::npos, cycles.err.find("interrupted after 10 of the 1000 cycles"))
      << cycles.err;
  // Without --time or --cycles Ctrl-C is how a run ends.
  auto open_ended = run_truecut({"run", interrupted_hal(dir, 10).string(), "--component-path",
                                 components, "--out", (dir / "c").string()});
  EXPECT_EQ(0, open_ended.exit_code) << open_ended.err;
  // Done before the interrupt would have come.
  auto done = run_truecut({"run", interrupted_hal(dir, 100).string(), "--cycles", "50",
                           "--component-path", components, "--out", (dir / "d").string()});
  EXPECT_EQ(0, done.exit_code) << done.err;
}

TEST(CliRun, DryRunChecksWithoutRunning) {
  auto out = scratch_dir();
  auto r = run_truecut({"run", example("circle.hal"), "--ini", example("circle.ini"), "--dry-run",
                        "--show", "--out", out.string()});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.out.find("x.update"));
  EXPECT_NE(std::string::npos, r.out.find("configuration loads without error"));
  EXPECT_TRUE(std::filesystem::is_empty(out));
}

namespace {
// A one-thread HAL that records a siggen output into `file`.
std::filesystem::path recorder_hal(const std::filesystem::path& dir, const std::string& file) {
  const auto hal = dir / "rec.hal";
  std::ofstream f(hal);
  f << "loadrt threads name1=t period1=1000000\n"
       "loadrt siggen\n"
       "loadrt recorder file="
    << file
    << " columns=s\n"
       "addf siggen.0.update t\n"
       "addf recorder.0.sample t\n"
       "net s siggen.0.sine => recorder.0.s\n";
  return hal;
}
}  // namespace

TEST(CliRun, ARecorderWritesOnlyInsideTheOutputFolder) {
  // Issue 23: file=/abs/path and file=../x wrote outside --out, exit 0.
  const auto dir = scratch_dir();
  const auto out = dir / "out";
  const std::string outside_abs = (dir / "abs.csv").string();
  for (const std::string& file : {outside_abs, std::string("../escape.csv")}) {
    auto r = run_truecut(
        {"run", recorder_hal(dir, file).string(), "--time", "0.05", "--out", out.string()});
    EXPECT_EQ(2, r.exit_code) << file << ": " << r.err;
    EXPECT_NE(
        std::string::npos,
        r.err.find("rec.hal:3: loadrt recorder: initialisation failed (Invalid argument): file=" +
                   file + ": outside the output folder"))
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "abs.csv"));
    EXPECT_FALSE(std::filesystem::exists(dir / "escape.csv"));
    EXPECT_FALSE(std::filesystem::exists(dir / "escape.csv.tmp"));
  }
  // /dev/null is the one path outside the folder a recorder may name.
  auto null = run_truecut(
      {"run", recorder_hal(dir, "/dev/null").string(), "--time", "0.05", "--out", out.string()});
  EXPECT_EQ(0, null.exit_code) << null.err;
  // A sub-folder of the output folder is inside it.
  std::filesystem::create_directories(out / "sub");
  auto sub = run_truecut(
      {"run", recorder_hal(dir, "sub/t.csv").string(), "--time", "0.05", "--out", out.string()});
  EXPECT_EQ(0, sub.exit_code) << sub.err;
  EXPECT_TRUE(std::filesystem::exists(out / "sub" / "t.csv"));
}

TEST(CliRun, ARecorderThatCannotCreateItsFileFailsTheLoad) {
  // Issue 23: the recorder reported "cannot create" during the run and the
  // run still exited 0 with no trace.
  const auto dir = scratch_dir();
  auto r = run_truecut({"run", recorder_hal(dir, "no_such_folder/t.csv").string(), "--time", "0.05",
                        "--out", (dir / "out").string()});
  EXPECT_EQ(2, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos,
            r.err.find("rec.hal:3: loadrt recorder: initialisation failed (Invalid argument): "
                       "file=no_such_folder/t.csv: cannot "
                       "create "))
      << r.err;
  EXPECT_NE(std::string::npos, r.err.find("No such file or directory")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out")) << "nothing half-written";
}

namespace {
// The last row of a trace, as numbers.
std::vector<double> last_row(const std::filesystem::path& trace) {
  std::ifstream in(trace);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  std::vector<double> out;
  std::stringstream s(last);
  std::string cell;
  while (std::getline(s, cell, ','))
    out.push_back(std::stod(cell));
  return out;
}
}  // namespace

// The controller's parameter file (--var-file) places the program as on the
// machine: G54 at X+0.25 moves every commanded point by 0.25 mm in X (the
// last one compared here), and an offset beyond the travel is refused
// before anything runs.
TEST(CliRun, ParameterFileOffsetsTheMachinedProgram) {
  const auto dir = scratch_dir();
  const auto part = dir / "part";
  auto p = run_truecut({"part", "implant", "--out", part.string(), "--mesh-edge", "4", "--stepover",
                        "5", "--step-down", "10"});
  ASSERT_EQ(0, p.exit_code) << p.err;
  std::ofstream(dir / "s.var") << "5220 1\n5221 0.25\n";
  std::ofstream(dir / "far.var") << "5221 5000\n";
  const std::vector<std::string> run = {"run", (part / "machine.json").string(),
                                        (part / "program.ngc").string(), "--dexel-spacing", "1"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = run;
    a.insert(a.end(), extra.begin(), extra.end());
    return run_truecut(a);
  };
  auto plain = with({"--out", (dir / "plain").string()});
  ASSERT_EQ(0, plain.exit_code) << plain.err;
  auto shifted =
      with({"--out", (dir / "shifted").string(), "--var-file", (dir / "s.var").string()});
  ASSERT_EQ(0, shifted.exit_code) << shifted.err;
  const auto a = last_row(dir / "plain" / "trace.csv");
  const auto b = last_row(dir / "shifted" / "trace.csv");
  ASSERT_GE(a.size(), 4u);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_NEAR(b[1] - a[1], 0.25, 1e-9);  // x_cmd
  EXPECT_NEAR(b[2], a[2], 1e-9);         // y_cmd
  EXPECT_NEAR(b[3], a[3], 1e-9);         // z_cmd
  EXPECT_NE(read_file(dir / "shifted" / "run.ini").find("PARAMETER_FILE = "), std::string::npos);
  auto far = with({"--out", (dir / "far").string(), "--var-file", (dir / "far.var").string()});
  EXPECT_EQ(2, far.exit_code);
  EXPECT_NE(far.err.find("program.ngc"), std::string::npos) << far.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "far"));
  // --var-units without a file: the machine's units, in which G10 keeps the
  // offset parameters (LinuxCNC's [TRAJ]LINEAR_UNITS). G10 L2 X25.4 under
  // G21 stores 25.4 on a mm machine and 1 on an inch one; the program then
  // goes to X#5221 (mm, G21) in G54: 25.4 + 25.4 against 1 + 25.4.
  std::ofstream(part / "offsets.ngc") << "G21 G90 G17\nG10 L2 P1 X25.4\nG54\nG0 Z50\n"
                                         "G0 X[#5221] Y0\nM30\n";
  const std::vector<std::string> offsets = {"run", (part / "machine.json").string(),
                                            (part / "offsets.ngc").string(), "--dexel-spacing",
                                            "1"};
  auto in_units = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> a = offsets;
    a.insert(a.end(), {"--out", (dir / name).string()});
    a.insert(a.end(), extra.begin(), extra.end());
    auto r = run_truecut(a);
    EXPECT_EQ(0, r.exit_code) << r.err;
    return last_row(dir / name / "trace.csv");
  };
  const auto mm = in_units("mm", {});
  const auto inch = in_units("inch", {"--var-units", "inch"});
  ASSERT_GE(mm.size(), 2u);
  ASSERT_EQ(mm.size(), inch.size());
  EXPECT_NEAR(mm[1] - inch[1], 25.4 - 1.0, 1e-6);  // x_cmd
  EXPECT_NE(read_file(dir / "inch" / "run.ini").find("PARAMETER_UNITS = inch"), std::string::npos);
}
