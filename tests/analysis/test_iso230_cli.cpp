// truecut iso230: outputs, exit codes and messages.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_process.hpp"
#include "test_paths.hpp"

namespace truecut::test {
namespace {

namespace fs = std::filesystem;

// Two targets, three runs each way, deviations known (µm):
// 10 ↑ {2,4,6} ↓ {-1,0,1}; 20 ↑ {5,5,5} ↓ {1,3,5} → A 10, E 5, M 2, R 10, B 4.
fs::path positioning_recording(const fs::path& dir) {
  const double dev[2][2][3] = {{{2, 4, 6}, {-1, 0, 1}}, {{5, 5, 5}, {1, 3, 5}}};
  std::string csv = "t,x_cmd,x_act,feed\n";
  double t = 0, pos = 5;
  auto sample = [&](double cmd, double d_um) {
    char b[160];
    std::snprintf(b, sizeof b, "%.6f,%.6f,%.6f,1000\n", t, cmd, cmd + d_um * 1e-3);
    csv += b;
    t += 0.1;
  };
  auto go = [&](double to, double d_um) {
    for (int k = 1; k <= 4; ++k)
      sample(pos + (to - pos) * k / 4, 0);
    pos = to;
    for (int k = 0; k < 20; ++k)
      sample(pos, d_um);
  };
  for (int run = 0; run < 3; ++run) {
    go(10, dev[0][0][run]);
    go(20, dev[1][0][run]);
    for (int k = 1; k <= 4; ++k)
      sample(20 + k, 0);
    pos = 24;
    go(20, dev[1][1][run]);
    go(10, dev[0][1][run]);
    for (int k = 1; k <= 4; ++k)
      sample(10 - k, 0);
    pos = 6;
  }
  auto p = dir / "positioning.csv";
  std::ofstream(p, std::ios::binary) << csv;
  return p;
}

fs::path circle_recording(const fs::path& dir) {
  std::string csv = "time_s,X,Y,Xm,Ym\r\n";
  for (int k = 0; k <= 7200; ++k) {
    const double th = (k <= 3600 ? k : 7200 - k) * 2 * M_PI / 3600;
    const double r = 50 + 0.003 * std::cos(2 * (th - M_PI / 4));
    char b[200];
    std::snprintf(b, sizeof b, "%.4f,%.9f,%.9f,%.9f,%.9f\r\n", k * 0.001, 50 * std::cos(th),
                  50 * std::sin(th), r * std::cos(th), r * std::sin(th));
    csv += b;
  }
  auto p = dir / "circle.csv";
  std::ofstream(p, std::ios::binary) << csv;
  return p;
}

std::vector<std::string> files_in(const fs::path& dir) {
  std::vector<std::string> names;
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir))
      names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(Iso230Cli, PositioningWritesJsonAndHtml) {
  const auto dir = scratch_dir();
  const auto rec = positioning_recording(dir);
  const auto out = dir / "out";
  auto r = run_process(
      {cli_path().string(), "iso230", "--recording", rec.string(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("x: A=0.0100 E=0.0050 M=0.0020 R=0.0100 B=0.0040 mm"), std::string::npos)
      << r.out;
  EXPECT_EQ(files_in(out), (std::vector<std::string>{"iso230.html", "iso230.json"}));
  const auto j = nlohmann::json::parse(read_file(out / "iso230.json"));
  ASSERT_EQ(j["axes"].size(), 1u);
  const auto& x = j["axes"][0];
  EXPECT_EQ(x["axis"], "x");
  EXPECT_NEAR(x["A_mm"].get<double>(), 0.010, 1e-6);
  EXPECT_NEAR(x["E_mm"].get<double>(), 0.005, 1e-6);
  EXPECT_NEAR(x["M_mm"].get<double>(), 0.002, 1e-6);
  EXPECT_NEAR(x["R_mm"].get<double>(), 0.010, 1e-6);
  EXPECT_NEAR(x["B_mm"].get<double>(), 0.004, 1e-6);
  ASSERT_EQ(x["positions"].size(), 2u);
  EXPECT_NEAR(x["positions"][0]["up"]["s_mm"].get<double>(), 0.002, 1e-6);
  EXPECT_EQ(x["positions"][1]["down"]["runs"], 3);
  const auto html = read_file(out / "iso230.html");
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http://"),
            html.find("http://www.w3.org/2000/svg"));  // no external resources
}

TEST(Iso230Cli, CircleThroughMapWithCrlf) {
  const auto dir = scratch_dir();
  const auto rec = circle_recording(dir);
  const auto out = dir / "out";
  auto r = run_process({cli_path().string(), "iso230", "--recording", rec.string(), "--map",
                        "t=time_s,x_cmd=X,y_cmd=Y", "--map", "x_meas=Xm,y_meas=Ym", "--circle",
                        "x,y", "--radius", "50", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_file(out / "iso230.json"));
  EXPECT_TRUE(j["axes"].empty());
  ASSERT_EQ(j["circles"].size(), 1u);
  const auto& c = j["circles"][0];
  EXPECT_NEAR(c["G_mm"].get<double>(), 0.006, 2e-5);
  EXPECT_NEAR(c["F_max_mm"].get<double>(), 0.003, 2e-5);
  EXPECT_NEAR(c["H_mm"].get<double>(), 0.0, 2e-5);
  EXPECT_NEAR(c["harmonics"][2]["amplitude_mm"].get<double>(), 0.003, 2e-5);
  EXPECT_EQ(c["hints"][0]["effect"], "squareness");
}

TEST(Iso230Cli, UmichThroughMap) {
  const auto out = scratch_dir() / "out";
  auto r = run_process({cli_path().string(), "iso230", "--recording",
                        (data_dir() / "umich_cnc_mill" / "experiment_12.csv").string(), "--map",
                        "t=@index*0.1,x_cmd=X1_CommandPosition,x_act=X1_ActualPosition", "--out",
                        out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_file(out / "iso230.json"));
  EXPECT_EQ(j["rows"], 2276);
}

TEST(Iso230Cli, BadInputExitsTwoAndWritesNothing) {
  const auto dir = scratch_dir();
  const auto rec = positioning_recording(dir);
  const auto out = dir / "out";
  auto run = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {cli_path().string(), "iso230"});
    return run_process(args);
  };

  auto r = run({"--out", out.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--recording FILE is required"), std::string::npos) << r.err;

  r = run({"--recording", rec.string(), "--out", out.string(), "--axis", "y"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(rec.string() + ":1: no column for 'y_cmd'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("available: t, x_cmd, x_act, feed"), std::string::npos) << r.err;

  r = run({"--recording", rec.string(), "--out", out.string(), "--axis", "q"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("'q' is not a joint"), std::string::npos) << r.err;

  r = run({"--recording", rec.string(), "--out", out.string(), "--map", "x_act"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--map item 'x_act' is not NAME=COLUMN"), std::string::npos) << r.err;

  r = run({"--recording", rec.string(), "--out", out.string(), "--min-runs", "4"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nothing to evaluate"), std::string::npos) << r.err;

  auto text = read_file(rec);
  const auto at = text.find('\n', text.find('\n', text.find('\n') + 1) + 1);  // end of line 3
  text.insert(at, "x");
  auto bad = dir / "bad.csv";
  std::ofstream(bad, std::ios::binary) << text;
  r = run({"--recording", bad.string(), "--out", out.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad.string() + ":3: column 4 'feed': '1000x' is not a finite number"),
            std::string::npos)
      << r.err;

  r = run({"--recording", (dir / "missing.csv").string(), "--out", out.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("cannot open"), std::string::npos) << r.err;

  EXPECT_TRUE(files_in(out).empty());
}

// Issue 23 (sweep F28): a recording named in Latin-1 ended iso230 after all
// its work with nlohmann's type_error.316 (exit 1, no file named). The name
// is written with U+FFFD for the byte that is not UTF-8.
TEST(Iso230Cli, ANameThatIsNotUtf8IsWrittenSafely) {
  const auto dir = scratch_dir();
  const fs::path latin1 = dir / "caf\xe9.csv";
  fs::rename(positioning_recording(dir), latin1);
  const auto out = dir / "out";
  const auto r = run_process(
      {cli_path().string(), "iso230", "--recording", latin1.string(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_file(out / "iso230.json"));
  EXPECT_NE(j.dump().find("caf\xef\xbf\xbd.csv"), std::string::npos) << j.dump().substr(0, 300);
}

// Issue 23 (sweep, low): --axis x,x was accepted; a circle of 180° gave G
// with exit 0 and said "less than a full circle" only in the JSON.
TEST(Iso230Cli, AnAxisTwiceIsRefusedAndAPartialCircleIsSaid) {
  const auto dir = scratch_dir();
  const auto out = dir / "out";
  auto r =
      run_process({cli_path().string(), "iso230", "--recording",
                   positioning_recording(dir).string(), "--axis", "x,x", "--out", out.string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--axis x,x: joint 'x' is named twice"), std::string::npos) << r.err;
  EXPECT_TRUE(files_in(out).empty());

  std::string csv = "t,x_cmd,y_cmd,x_act,y_act\n";
  for (int k = 0; k <= 1800; ++k) {  // half a circle, counter-clockwise
    const double th = k * M_PI / 1800;
    char b[200];
    std::snprintf(b, sizeof b, "%.4f,%.9f,%.9f,%.9f,%.9f\n", k * 0.001, 50 * std::cos(th),
                  50 * std::sin(th), 50.002 * std::cos(th), 50.002 * std::sin(th));
    csv += b;
  }
  std::ofstream(dir / "half.csv", std::ios::binary) << csv;
  r = run_process({cli_path().string(), "iso230", "--recording", (dir / "half.csv").string(),
                   "--circle", "x,y", "--radius", "50", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("  note: ccw run covers 1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("°, less than a full circle"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("WARNING: xy circle: ccw run covers 1"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace truecut::test
