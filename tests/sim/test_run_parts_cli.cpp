// `truecut run MACHINE.json PROGRAM.ngc --out DIR --scan --cmm` machines each
// benchmark part (coarse) on its machine with all twelve physics effects on
// at once, records the trace, scans and probes the result, repeats a run bit
// for bit, and refuses bad input (machine file, program, travel, part file)
// with exit 2, the file and key or line, and nothing written.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/machine_description.hpp"

namespace {

namespace fs = std::filesystem;
using namespace truecut::test;
using nlohmann::json;
using truecut::sim::PartId;

// Every effect of docs/machine-model.md, switched on, on every joint it can
// act on (sizes of a machine in fair order; the deflections stiff enough
// that the coarse test cuts stay within the dexel model's stock).
const char* kAllEffects = R"({
  "servo_lag": {"enabled": true, "x": {"kv_per_s": 30, "ff1": 0.95}, "y": {"kv_per_s": 28,
      "ff1": 0.93}, "z": {"kv_per_s": 33, "ff1": 0.95}, "a": {"kv_per_s": 25, "ff1": 0.9},
      "c": {"kv_per_s": 25, "ff1": 0.9}},
  "backlash": {"enabled": true, "x": {"play_mm": 0.004}, "y": {"play_mm": 0.003},
      "z": {"play_mm": 0.002}, "a": {"play_deg": 0.001}, "c": {"play_deg": 0.001}},
  "reversal_spike": {"enabled": true, "x": {"coulomb_n": 100, "viscous_n_s_per_mm": 0.01},
      "y": {"coulomb_n": 120}, "z": {"coulomb_n": 80}, "a": {"coulomb_nm": 5},
      "c": {"coulomb_nm": 3, "viscous_nm_s_per_deg": 0.001}},
  "pitch_error": {"enabled": true,
      "x": {"scale_um_per_m": 15, "periodic_amplitude_um": 1.5, "periodic_period_mm": 10},
      "y": {"scale_um_per_m": -10, "reference_mm": 20},
      "z": {"periodic_amplitude_um": 2, "periodic_period_mm": 16, "periodic_phase_deg": 30}},
  "thermal_drift": {"enabled": true, "x": {"gain_mm": 0.01, "tau_s": 120},
      "z": {"gain_mm": -0.02, "tau_s": 60, "driver": "spindle_power", "reference_power_kw": 1}},
  "squareness": {"enabled": true, "xy_urad": 20, "yz_urad": -15, "zx_urad": 10},
  "straightness": {"enabled": true, "eyx": {"quadratic_um_per_m2": 20},
      "ezy": {"cubic_um_per_m3": 30, "reference_mm": 10}},
  "rotary_location": {"enabled": true,
      "a": {"e_y0a_um": 8, "e_z0a_um": -5, "e_b0a_urad": 10, "e_c0a_urad": 15, "e_a0a_urad": 20},
      "c": {"e_x0c_um": 10, "e_y0c_um": -6, "e_a0c_urad": 12, "e_b0c_urad": -8,
            "e_c0c_urad": 25}},
  "tool_length_error": {"enabled": true, "length_mm": 0.01},
  "tool_radius_error": {"enabled": true, "radius_mm": -0.02},
  "tool_deflection": {"enabled": true, "stiffness_n_per_um": 1.0, "stickout_mm": 20},
  "workpiece_deflection": {"enabled": true, "stiffness_n_per_um": 0.5,
      "reference_length_mm": 20, "clamp_point_mm": [0, 0, 0], "axis": [0, 0, 1]}
})";

const char* kTraceHeader =
    "t,x_cmd,y_cmd,z_cmd,a_cmd,c_cmd,x_act,y_act,z_act,a_act,c_act,feed,spindle_power,line,tool,"
    "tcp_true_x,tcp_true_y,tcp_true_z";

ProcessResult truecut(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return run_process(args);
}

// The program without the operations named (from their marker to the next).
std::string without_operations(const std::string& program, const std::vector<std::string>& ops) {
  std::istringstream in(program);
  std::string out, line;
  bool skipping = false;
  while (std::getline(in, line)) {
    if (line.rfind("(OPERATION: ", 0) == 0) {
      skipping = false;
      for (const auto& op : ops)
        skipping = skipping || line == "(OPERATION: " + op + ")";
    }
    if (!skipping) out += line + "\n";
  }
  return out;
}

struct Job {
  fs::path dir;      // the part's files
  fs::path machine;  // machine_all.json
  fs::path program;
};

// The part at a coarse resolution, its machine with every effect on, and a
// program short enough for a test: the part's own, except benchmark004,
// whose walls and step faces (minutes of machining) are left out; its two
// ball operations keep the 3-axis rings and the continuous 5-axis cap.
Job make_job(PartId id, const fs::path& root) {
  truecut::sim::PartOptions o;
  o.mesh_edge_mm = 4;
  o.stepover_mm = 5;
  o.point_spacing_mm = 5;
  o.step_down_mm = 10;
  const truecut::sim::BenchmarkPart part = truecut::sim::make_part(id, o);
  Job job;
  job.dir = root / std::string(truecut::sim::part_name(id));
  truecut::sim::write_part(part, job.dir);
  json machine = json::parse(read_file(job.dir / "machine.json"));
  machine["effects"] = json::parse(kAllEffects);
  job.machine = job.dir / "machine_all.json";
  std::ofstream(job.machine) << machine.dump(1);
  job.program = job.dir / "program.ngc";
  if (id == PartId::kBenchmark004) {
    job.program = job.dir / "ball_operations.ngc";
    std::ofstream(job.program) << without_operations(part.program, {"WALLS", "STEP_FACES"});
  }
  return job;
}

std::vector<std::string> run_args(const Job& job, const fs::path& out) {
  return {"run",
          job.machine.string(),
          job.program.string(),
          "--out",
          out.string(),
          "--dexel-spacing",
          "1",
          "--scan",
          "scan.ply",
          "--scan-density",
          "1",
          "--cmm",
          "cmm.csv",
          "--cmm-spacing",
          "4"};
}

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string c; std::getline(row, c, ',');)
      cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

class RunPart : public ::testing::TestWithParam<PartId> {};

TEST_P(RunPart, AllEffectsOnMachinesRecordsScansAndProbes) {
  const Job job = make_job(GetParam(), scratch_dir());
  const auto description = truecut::sim::read_machine_description(job.machine);
  const auto& fx = description.machine.effects;
  for (const bool on :
       {fx.servo_lag.enabled, fx.backlash.enabled, fx.reversal_spike.enabled,
        fx.pitch_error.enabled, fx.thermal_drift.enabled, fx.squareness.enabled,
        fx.straightness.enabled, fx.rotary_location.enabled, fx.tool_length_error.enabled,
        fx.tool_radius_error.enabled, fx.tool_deflection.enabled, fx.workpiece_deflection.enabled})
    ASSERT_TRUE(on);

  const fs::path out = job.dir / "run";
  const ProcessResult r = truecut(run_args(job, out));
  ASSERT_EQ(0, r.exit_code) << r.err;
  for (const char* f : {"machined.stl", "machined.ply", "trace.csv", "scan.ply", "cmm.csv",
                        "soft_cnc.hal", "run.ini"})
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;

  // The trace: every column of docs/soft-cnc.md, one row per cycle, the
  // program's lines and tools, the servo lag between command and encoder,
  // the spindle loaded by the cut, the true TCP away from the commanded one.
  const auto rows = csv_rows(read_file(out / "trace.csv"));
  ASSERT_GT(rows.size(), 1000u);
  std::string header;
  for (const auto& c : rows[0])
    header += (header.empty() ? "" : ",") + c;
  ASSERT_EQ(kTraceHeader, header);
  std::set<int> tools;
  int max_line = 0;
  double max_lag_mm = 0, max_power_kw = 0, max_feed = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(18u, rows[i].size()) << "row " << i;
    EXPECT_NEAR(0.001 * double(i - 1), std::stod(rows[i][0]), 1e-9) << "row " << i;
    for (int j = 0; j < 3; ++j)
      max_lag_mm =
          std::max(max_lag_mm, std::abs(std::stod(rows[i][1 + j]) - std::stod(rows[i][6 + j])));
    max_feed = std::max(max_feed, std::stod(rows[i][11]));
    max_power_kw = std::max(max_power_kw, std::stod(rows[i][12]));
    max_line = std::max(max_line, std::stoi(rows[i][13]));
    tools.insert(std::stoi(rows[i][14]));
  }
  std::size_t program_lines = 0;
  {
    std::istringstream p(read_file(job.program));
    for (std::string l; std::getline(p, l);)
      ++program_lines;
  }
  EXPECT_GT(max_line, 10);
  EXPECT_LE(max_line, static_cast<int>(program_lines));
  EXPECT_GT(max_lag_mm, 0.005) << "servo lag of the linear joints";
  EXPECT_GT(max_feed, 1.0);
  EXPECT_GT(max_power_kw, 0.0) << "the cut loads the spindle";
  EXPECT_FALSE(tools.empty());

  // The run's stages: before the loop, the loop (the "machined in" time),
  // the outputs; they add up to the total printed.
  {
    const auto at = r.out.find("  stages      ");
    ASSERT_NE(std::string::npos, at) << r.out;
    double load_s = -1, loop_s = -1, write_s = -1, all_s = -1;
    ASSERT_EQ(4, std::sscanf(r.out.c_str() + at,
                             "  stages %lf s checking, planning and loading, %lf s machining, "
                             "%lf s writing the outputs: %lf s",
                             &load_s, &loop_s, &write_s, &all_s))
        << r.out.substr(at, 200);
    EXPECT_GT(load_s, 0);
    EXPECT_GT(write_s, 0);
    const auto time_at = r.out.find(" machined in ");
    ASSERT_NE(std::string::npos, time_at) << r.out;
    double machined_s = -1;
    ASSERT_EQ(1, std::sscanf(r.out.c_str() + time_at, " machined in %lf s", &machined_s));
    EXPECT_EQ(machined_s, loop_s) << "the loop's time is the \"machined in\" one";
    EXPECT_NEAR(load_s + loop_s + write_s, all_s, 0.0021);
  }

  // Scan and CMM.
  EXPECT_NE(std::string::npos, r.out.find(" points (sigma 20 um, seed 1) -> ")) << r.out;
  const auto cmm = csv_rows(read_file(out / "cmm.csv"));
  ASSERT_GT(cmm.size(), 10u);
  EXPECT_EQ("valid", cmm[0].back());
  std::size_t valid = 0;
  for (std::size_t i = 1; i < cmm.size(); ++i)
    valid += cmm[i].back() == "1";
  EXPECT_GT(valid, (cmm.size() - 1) / 2);
}

INSTANTIATE_TEST_SUITE_P(
    Parts, RunPart, ::testing::Values(PartId::kImplant, PartId::kBenchmark004, PartId::kFreeform),
    [](const auto& info) { return std::string(truecut::sim::part_name(info.param)); });

// The 5-axis part with every effect on, the cutting force feeding the
// deflections back, twice: the same bytes in every file.
TEST(RunPartRepeat, TwoRunsGiveIdenticalFiles) {
  const Job job = make_job(PartId::kFreeform, scratch_dir());
  ASSERT_EQ(0, truecut(run_args(job, job.dir / "one")).exit_code);
  ASSERT_EQ(0, truecut(run_args(job, job.dir / "two")).exit_code);
  for (const char* f : {"trace.csv", "machined.stl", "machined.ply", "scan.ply", "cmm.csv"}) {
    const std::string a = read_file(job.dir / "one" / f), b = read_file(job.dir / "two" / f);
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_TRUE(a == b) << f << " differs between two identical runs";
  }
}

TEST(RunPartBadInput, ExitTwoNamingFileAndKeyOrLineWithNothingWritten) {
  const Job job = make_job(PartId::kImplant, scratch_dir());
  const fs::path out = job.dir / "run";
  const std::string program = read_file(job.dir / "program.ngc");
  auto machine_with = [&](const std::string& name, const std::string& pointer, const json& v) {
    json m = json::parse(read_file(job.machine));
    m[json::json_pointer(pointer)] = v;
    std::ofstream(job.dir / name) << m.dump(1);
    return (job.dir / name).string();
  };
  auto program_with = [&](const std::string& name, const std::string& after,
                          const std::string& line) {
    std::string text = program;
    const auto at = text.find(after);
    EXPECT_NE(std::string::npos, at) << after;
    text.insert(text.find('\n', at) + 1, line + "\n");
    std::ofstream(job.dir / name) << text;
    return (job.dir / name).string();
  };
  // The line number the inserted line gets.
  auto line_of = [&](const std::string& after) {
    const auto at = program.find(after);
    return 2 + std::count(program.begin(), program.begin() + static_cast<long>(at), '\n');
  };
  const fs::path bad_part = job.dir / "bad_part";
  fs::create_directories(bad_part);
  for (const char* f : {"nominal.stl", "tools.tbl", "program.ngc"})
    fs::copy_file(job.dir / f, bad_part / f);
  json part = json::parse(read_file(job.dir / "part.json"));
  part["tools"][0]["radius_mm"] = -1;
  std::ofstream(bad_part / "part.json") << part.dump(1);

  struct Case {
    std::string machine, program, message;
  };
  const std::string machine = job.machine.string(), good = job.program.string();
  const std::vector<Case> cases = {
      {machine_with("m1.json", "/effects/backlsh", json::object()), good,
       "m1.json: effects.backlsh: unknown effect; known: servo_lag"},
      {machine_with("m2.json", "/effects/servo_lag/x/kv", 30), good,
       "m2.json: effects.servo_lag.x.kv: unknown parameter; known: kv_per_s, ff1"},
      {machine_with("m3.json", "/effects/thermal_drift/z/tau_s", -60), good,
       "m3.json: effects.thermal_drift.z.tau_s: must be > 0"},
      {machine_with("m4.json", "/joints/x/drive", json{{"vel_integral_time_s", -0.01}}), good,
       "m4.json: joints.x.drive.vel_integral_time_s: must be > 0"},
      {machine, program_with("p1.ngc", "G43 H1", "G0 X400"),
       "p1.ngc:" + std::to_string(line_of("G43 H1")) + ": joint X leaves travel [-250, 250] at "},
      {machine, program_with("p2.ngc", "G43 H1", "G1 X0 F100 Q"),
       "p2.ngc:" + std::to_string(line_of("G43 H1")) + ":"},
      {machine, (bad_part / "program.ngc").string(), "part.json: key 'tools[0].radius_mm'"},
  };
  for (const Case& c : cases) {
    const ProcessResult r =
        truecut({"run", c.machine, c.program, "--out", out.string(), "--dexel-spacing", "1"});
    EXPECT_EQ(2, r.exit_code) << c.message << "\n" << r.err;
    EXPECT_NE(std::string::npos, r.err.find(c.message)) << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.message << ": nothing written";
  }
  // The travel check plans beside the wiring's load: when the load fails
  // too (the cutting model over --max-dexels), the travel's refusal is the
  // one reported, as when the check ran first.
  const ProcessResult both = truecut({"run", machine, cases[4].program, "--out", out.string(),
                                      "--dexel-spacing", "1", "--max-dexels", "1"});
  EXPECT_EQ(2, both.exit_code) << both.err;
  EXPECT_NE(std::string::npos, both.err.find(cases[4].message)) << both.err;
  EXPECT_EQ(std::string::npos, both.err.find("max-dexels 1")) << both.err;
  EXPECT_FALSE(fs::exists(out)) << "nothing written";
  // The load alone failing is reported as before.
  const ProcessResult load = truecut(
      {"run", machine, good, "--out", out.string(), "--dexel-spacing", "1", "--max-dexels", "1"});
  EXPECT_EQ(2, load.exit_code) << load.err;
  EXPECT_NE(std::string::npos, load.err.find("more than max-dexels 1")) << load.err;
  EXPECT_FALSE(fs::exists(out)) << "nothing written";
}

}  // namespace
