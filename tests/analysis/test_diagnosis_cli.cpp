// truecut diagnose: outputs, exit codes, and a run on the public UMich data.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_process.hpp"
#include "test_diagnosis_fixtures.hpp"
#include "test_paths.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
using namespace truecut::sim::test;
namespace {

namespace fs = std::filesystem;
using truecut::test::cli_path;
using truecut::test::data_dir;
using truecut::test::read_file;
using truecut::test::run_process;
using truecut::test::scratch_dir;

// A recording with foreign column names (read through --map).
fs::path write_csv(const Recording& rec, const fs::path& file) {
  std::ofstream out(file, std::ios::binary);
  out << "Time,XC,YC,XM,YM,Comment\n";
  char b[256];
  for (std::size_t k = 0; k < rec.rows(); ++k) {
    std::snprintf(b, sizeof b, "%.6f,%.9f,%.9f,%.9f,%.9f,row %zu\n", rec.t_s[k],
                  rec.channels.at("x_cmd")[k], rec.channels.at("y_cmd")[k],
                  rec.channels.at("x_meas")[k], rec.channels.at("y_meas")[k], k);
    out << b;
  }
  return file;
}

std::vector<std::string> files_in(const fs::path& dir) {
  std::vector<std::string> names;
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir))
      names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

const char* kMap = "t=Time,x_cmd=XC,y_cmd=YC,x_meas=XM,y_meas=YM";

TEST(DiagnosisCli, FindsPlantedBacklashAndWritesThreeFiles) {
  const auto dir = scratch_dir();
  MachineDescription believed = xy_machine();
  enable_servo_lag(believed.machine, kX, 40.0, 0.9);
  enable_servo_lag(believed.machine, kY, 35.0, 0.8);
  write_machine_description(dir / "believed.json", believed);
  MachineDescription truth = believed;
  truth.machine.effects.backlash.enabled = true;
  truth.machine.effects.backlash.axes[kX] = BacklashAxis{0.004};
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  spec.duration_s = 8;
  const auto csv = write_csv(make_recording(truth.machine, spec), dir / "rec.csv");
  const auto out = dir / "out";
  auto r = run_process({cli_path().string(), "diagnose", "--recording", csv.string(), "--map", kMap,
                        "--machine", (dir / "believed.json").string(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("explained: backlash x"), std::string::npos) << r.out;
  EXPECT_EQ(r.err.find("diagnose: "), std::string::npos) << r.err;  // progress: on a terminal only
  EXPECT_EQ(files_in(out),
            (std::vector<std::string>{"diagnosis.html", "diagnosis.json", "fitted_machine.json"}));
  const auto j = nlohmann::json::parse(read_file(out / "diagnosis.json"));
  ASSERT_EQ(j["explanations"].size(), 1u) << j.dump(2);
  const auto& e = j["explanations"][0];
  EXPECT_EQ(e["effect"], "backlash");
  EXPECT_EQ(e["axis"], "x");
  EXPECT_NEAR(e["parameters"]["play_mm"].get<double>(), 0.004, 0.0006);
  EXPECT_LE(e["ci95"]["play_mm"][0].get<double>(), e["parameters"]["play_mm"].get<double>());
  for (const char* k : {"rms_before_mm", "rms_after_mm"}) {
    EXPECT_TRUE(j["fit"]["train"][k].is_number());
    EXPECT_TRUE(j["fit"]["heldout"][k].is_number());
  }
  EXPECT_LT(j["fit"]["heldout"]["rms_after_mm"].get<double>(),
            j["fit"]["heldout"]["rms_before_mm"].get<double>());
  EXPECT_TRUE(j["not_identifiable"].is_array());
  EXPECT_TRUE(j["mismatch"].is_array());
  EXPECT_TRUE(j["delay_s"].is_number());
  EXPECT_TRUE(j["noise_floor_mm"].is_number());
  const auto fitted = read_machine_description(out / "fitted_machine.json");
  ASSERT_TRUE(fitted.machine.effects.backlash.active(kX));
  EXPECT_EQ(fitted.machine.effects.servo_lag, believed.machine.effects.servo_lag);
  const auto html = read_file(out / "diagnosis.html");
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org/2000/svg"));
}

// A tracker's columns (TrackerX/Y/Z) mapped to the TCP channels; the tool
// length (80 mm, T7) from a tool table by the `tool` channel.
TEST(DiagnosisCli, MeasuredTcpThroughTheMapFindsTheToolLength) {
  const auto dir = scratch_dir();
  MachineDescription believed = trunnion_with_servo();
  MachineDescription truth = believed;
  truth.machine.effects.tool_length_error.enabled = true;
  truth.machine.effects.tool_length_error.params.length_mm = 0.015;
  // The believed description's own tool is wrong: the table's must be used.
  believed.machine.kinematics.tool.length_mm = 50.0;
  write_machine_description(dir / "believed.json", believed);
  const Recording rec = five_axis_recording(truth.machine, 31);
  {
    std::ofstream out(dir / "rec.csv", std::ios::binary);
    out << "t,x_cmd,y_cmd,z_cmd,a_cmd,c_cmd,x_act,y_act,z_act,a_act,c_act,tool,TrackerX,TrackerY,"
           "TrackerZ\n";
    char b[64];
    for (std::size_t k = 0; k < rec.rows(); ++k) {
      std::snprintf(b, sizeof b, "%.6f", rec.t_s[k]);
      out << b;
      for (const char* kind : {"_cmd", "_act"})
        for (const char* j : {"x", "y", "z", "a", "c"}) {
          std::snprintf(b, sizeof b, ",%.9f", rec.channels.at(std::string(j) + kind)[k]);
          out << b;
        }
      out << ",7";
      for (const char* c : {"x", "y", "z"}) {
        std::snprintf(b, sizeof b, ",%.9f", rec.channels.at(std::string("tcp_true_") + c)[k]);
        out << b;
      }
      out << "\n";
    }
  }
  std::ofstream(dir / "tools.tbl") << "T7 P1 D10.000 Z80.000 ;probe\n";
  const auto out = dir / "out";
  auto r =
      run_process({cli_path().string(), "diagnose", "--recording", (dir / "rec.csv").string(),
                   "--map", "tcp_true_x=TrackerX,tcp_true_y=TrackerY,tcp_true_z=TrackerZ",
                   "--machine", (dir / "believed.json").string(), "--tools",
                   (dir / "tools.tbl").string(), "--tcp-datum", "known", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_file(out / "diagnosis.json"));
  ASSERT_TRUE(j["tcp"].is_object()) << j.dump(2);
  EXPECT_EQ(j["tcp"]["datum"], "known");
  EXPECT_LT(j["tcp"]["heldout"]["rms_after_mm"].get<double>(),
            0.5 * j["tcp"]["heldout"]["rms_before_mm"].get<double>());
  bool found = false;
  for (const auto& e : j["explanations"])
    if (e["effect"] == "tool_length_error") {
      found = true;
      EXPECT_LE(e["ci95"]["length_mm"][0].get<double>(), 0.015) << e.dump();
      EXPECT_GE(e["ci95"]["length_mm"][1].get<double>(), 0.015) << e.dump();
    }
  EXPECT_TRUE(found) << r.out;
  const auto fitted = read_machine_description(out / "fitted_machine.json");
  EXPECT_TRUE(fitted.machine.effects.tool_length_error.enabled);
  auto bad =
      run_process({cli_path().string(), "diagnose", "--recording", (dir / "rec.csv").string(),
                   "--tcp-datum", "maybe", "--out", (dir / "out2").string()});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
}

TEST(DiagnosisCli, BadInputExitsTwoAndWritesNothing) {
  const auto dir = scratch_dir();
  std::ofstream(dir / "bad.csv") << "t,x_cmd\n0,1\n0.1,2\n";
  const auto out = dir / "out";
  auto r = run_process({cli_path().string(), "diagnose", "--recording", (dir / "bad.csv").string(),
                        "--out", out.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.csv"), std::string::npos) << r.err;
  EXPECT_TRUE(files_in(out).empty());
  r = run_process({cli_path().string(), "diagnose", "--out", out.string()});
  EXPECT_EQ(r.exit_code, 2);
  r = run_process({cli_path().string(), "diagnose", "--recording", (dir / "bad.csv").string(),
                   "--map", "x_act=Nope", "--out", out.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("Nope"), std::string::npos) << r.err;
}

// The UMich rows the data set's README calls reliable (X1_ActualPosition
// not 198, feed not 50: the others are home blocks and rapids spliced in),
// written as a plain recording with the original time (row × 0.1 s).
fs::path umich_reliable_rows(int experiment, const fs::path& out) {
  char name[32];
  std::snprintf(name, sizeof name, "experiment_%02d.csv", experiment);
  RecordingOptions o;
  o.map = parse_column_map(
      "t=@index*0.1,x_cmd=X1_CommandPosition,x_act=X1_ActualPosition,y_cmd=Y1_CommandPosition,"
      "y_act=Y1_ActualPosition,z_cmd=Z1_CommandPosition,z_act=Z1_ActualPosition,"
      "feed=M1_CURRENT_FEEDRATE");
  const Recording rec = read_recording(data_dir() / "umich_cnc_mill" / name, o);
  std::ofstream f(out, std::ios::binary);
  f << "t,x_cmd,x_act,y_cmd,y_act,z_cmd,z_act\n";
  const char* cols[] = {"x_cmd", "x_act", "y_cmd", "y_act", "z_cmd", "z_act"};
  for (std::size_t k = 0; k < rec.rows(); ++k) {
    if (rec.channel("x_act")[k] == 198.0 || rec.channel("feed")[k] == 50.0) continue;
    f << rec.t_s[k];
    for (const char* c : cols)
      f << "," << rec.channel(c)[k];
    f << "\n";
  }
  return out;
}

// The delay of z_act behind z_cmd by least squares, written here: z_cmd read
// at t − d (linear between samples) against z_act, the mean removed, over
// the rows whose neighbours are reliable rows 0.1 s apart; d on a 0.1 ms grid.
double z_delay_least_squares(const fs::path& reliable_csv) {
  RecordingOptions o;
  const Recording rec = read_recording(reliable_csv, o);
  const auto &t = rec.t_s, &c = rec.channel("z_cmd"), &a = rec.channel("z_act");
  std::vector<std::size_t> use;
  for (std::size_t k = 1; k + 1 < t.size(); ++k)
    if (std::abs(t[k] - t[k - 1] - 0.1) < 1e-6 && std::abs(t[k + 1] - t[k] - 0.1) < 1e-6)
      use.push_back(k);
  double best_d = 0, best = INFINITY;
  for (int i = -500; i <= 500; ++i) {
    const double d = i * 1e-4, f = std::abs(d) / 0.1;
    double s = 0, ss = 0;
    for (std::size_t k : use) {
      const double p = d >= 0 ? c[k] - f * (c[k] - c[k - 1]) : c[k] + f * (c[k + 1] - c[k]);
      s += a[k] - p, ss += (a[k] - p) * (a[k] - p);
    }
    const double rss = ss - s * s / double(use.size());
    if (rss < best) best = rss, best_d = d;
  }
  return best_d;
}

// Issue 18: z lags its command on the UMich mill. Fitted on experiment 1,
// the lag the diagnosis removes matches the one measured here, and it
// lowers the z error on experiment 7, which the fit did not see, by at
// least 25 % (reliable rows of both).
TEST(DiagnosisCli, UmichZLagFoundAndItLowersTheZErrorOnAnotherExperiment) {
  const fs::path dir = scratch_dir();
  const fs::path train = umich_reliable_rows(1, dir / "exp01.csv");
  const fs::path held = umich_reliable_rows(7, dir / "exp07.csv");
  const double d_z = z_delay_least_squares(train);
  EXPECT_GT(d_z, 0.003);  // the issue: 3 to 9 ms
  EXPECT_LT(d_z, 0.012);
  const auto out = dir / "out";
  auto r = run_process({cli_path().string(), "diagnose", "--recording", train.string(), "--holdout",
                        held.string(), "--servo-period", "0.01", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_file(out / "diagnosis.json"));
  // The lag of z in the fitted model: the logging delay plus the steady lag
  // (1 − ff1)/Kv of a servo_lag selected on z.
  double lag_z = j["delay_s"].get<double>();
  for (const auto& e : j["explanations"])
    if (e["effect"] == "servo_lag" && e["axis"] == "z")
      lag_z += (1 - e["parameters"].value("ff1", 0.0)) / e["parameters"]["kv_per_s"].get<double>();
  EXPECT_NEAR(lag_z, d_z, 0.2 * d_z) << r.out;
  ASSERT_TRUE(j["fit"]["heldout"].is_object());
  EXPECT_EQ(j["fit"]["heldout"]["kind"], "file");
  const auto& z = j["fit"]["heldout"]["per_axis"]["z"];
  EXPECT_LE(z["rms_after_mm"].get<double>(), 0.75 * z["rms_unaligned_mm"].get<double>()) << r.out;
}

TEST(DiagnosisCli, UmichExperimentRunsAndHeldOutDoesNotGetWorse) {
  const auto data = data_dir() / "umich_cnc_mill" / "experiment_01.csv";
  ASSERT_TRUE(fs::is_regular_file(data)) << data << " is missing (data/ is part of the repository)";
  const auto out = scratch_dir() / "out";
  auto r = run_process(
      {cli_path().string(), "diagnose", "--recording", data.string(), "--map",
       "t=@index*0.1,x_cmd=X1_CommandPosition,x_act=X1_ActualPosition,y_cmd=Y1_CommandPosition,"
       "y_act=Y1_ActualPosition,z_cmd=Z1_CommandPosition,z_act=Z1_ActualPosition,"
       "line=M1_sequence_number",
       "--servo-period", "0.01", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_file(out / "diagnosis.json"));
  EXPECT_EQ(j["rows"], 1055);
  EXPECT_EQ(j["axes"].size(), 3u);
  ASSERT_TRUE(j["fit"]["heldout"].is_object());
  EXPECT_EQ(j["fit"]["heldout"]["kind"], "split");
  const double before = j["fit"]["heldout"]["rms_before_mm"].get<double>();
  const double after = j["fit"]["heldout"]["rms_after_mm"].get<double>();
  EXPECT_GT(before, 0.0);
  EXPECT_LE(after, before * (1 + 1e-12));
  EXPECT_LE(j["fit"]["heldout"]["rms_before_mm"].get<double>(),
            j["fit"]["heldout"]["rms_unaligned_mm"].get<double>() * (1 + 1e-12));
  for (const auto& e : j["explanations"]) {
    EXPECT_TRUE(e["effect"].is_string());
    EXPECT_TRUE(e["parameters"].is_object());
    EXPECT_TRUE(e["ci95"].is_object());
  }
  EXPECT_NO_THROW(read_machine_description(out / "fitted_machine.json"));
}

}  // namespace
}  // namespace truecut::analysis::test
