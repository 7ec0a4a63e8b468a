// ISO 230-2 from logs as real controllers write them: an EPICS camonitor log
// (each PV on change, at its own irregular times) whose command is either a
// target setpoint (it jumps at once to the next target and the axis then
// travels there slowly) or a trajectory setpoint (it moves with the axis).
//
// The logs come from a small planted axis written here from the physics,
// independently of the library: a motor moving at constant speed to each
// commanded target, a table coupled to it through a backlash (lost motion)
// of known size, a measuring system with a known positioning deviation
// e(q) (scale error and a periodic pitch error) and noise. The expected
// deviations follow from that model alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/analysis/iso230_positioning.hpp"
#include "truecut/analysis/recording.hpp"

namespace truecut::analysis {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

struct PlantedAxis {
  double speed = 2.0;                               // mm/s, motor speed between targets
  double backlash = 0.006;                          // mm of lost motion between motor and table
  double scale = 4e-5;                              // scale error of the axis (mm/mm)
  double pitch = 0.003;                             // mm, amplitude of the periodic pitch error
  double pitch_period = 23.0;                       // mm
  double noise = 0.0003;                            // mm RMS of the measuring system
  double dwell = 1.5;                               // s at rest before the next target is commanded
  double meas_gap_min = 0.04, meas_gap_max = 0.16;  // s between logged readings
  double quantum = 0;                               // mm, resolution of the reading (0: none)
  double read(double table, double noise) const {
    const double v = table + error(table) + noise;
    return quantum > 0 ? quantum * std::round(v / quantum) : v;
  }
  // Positioning deviation of the table at q (what the reference reads minus q).
  double error(double q) const { return scale * q + pitch * std::sin(2 * kPi * q / pitch_period); }
  // Deviation read at rest at target P after an approach in `direction`: the
  // motor stands at P, the table trails it by half the lost motion.
  double deviation(double P, int direction) const {
    const double q = P - direction * backlash / 2;
    return q + error(q) - P;
  }
};

enum class Command { kTargetSetpoint, kTrajectorySetpoint };

struct Log {
  fs::path file;
  std::vector<double> targets;
};

std::string stamp(double t) {  // seconds after 2024-03-05 10:00:00
  const double day_s = 10 * 3600 + t;
  const int h = int(day_s / 3600), m = int((day_s - h * 3600) / 60);
  const double s = day_s - h * 3600 - m * 60;
  char b[64];
  std::snprintf(b, sizeof b, "2024-03-05 %02d:%02d:%09.6f", h, m, s);
  return b;
}

// ISO 230-2 linear cycle: 5 runs up through the targets, overrun, down
// through them, overrun; written as a camonitor log.
Log write_log(const std::string& name, const PlantedAxis& ax, Command command, unsigned seed) {
  const std::vector<double> targets{2.0, 14.7, 27.3, 39.1, 50.0};
  const double overrun = 2.0;
  std::vector<double> goals;
  goals.push_back(targets.front() - overrun);
  for (int run = 0; run < 5; ++run) {
    for (double P : targets)
      goals.push_back(P);
    goals.push_back(targets.back() + overrun);
    for (std::size_t i = targets.size(); i-- > 0;)
      goals.push_back(targets[i]);
    goals.push_back(targets.front() - overrun);
  }

  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> meas_gap(ax.meas_gap_min, ax.meas_gap_max),
      cmd_gap(0.03, 0.12);
  std::normal_distribution<double> noise(0.0, ax.noise);
  const std::string cmd_pv = "SIM:M1-PosSet", meas_pv = "SIM:Ref-PosAct";
  std::string log;
  auto line = [&](const std::string& pv, double t, double v) {
    char b[160];
    std::snprintf(b, sizeof b, "%-22s %s %.9g  \n", pv.c_str(), stamp(t).c_str(), v);
    log += b;
  };
  // camonitor first prints every PV as of its last change, here long before.
  double motor = goals.front() - 1.0;
  double table = motor - ax.backlash / 2;
  line(cmd_pv, -300.0, motor);
  line("SIM:TestNumber", -400.0, 0);
  line(meas_pv, -0.5, ax.read(table, noise(rng)));

  const double dt = 0.001;
  double t = 0, next_meas = meas_gap(rng), next_cmd = cmd_gap(rng);
  double logged_cmd = motor;
  int test_number = 0;
  auto advance = [&](double goal, double seconds_after_arrival) {
    double rest_until = -1;
    while (true) {
      const double step = std::clamp(goal - motor, -ax.speed * dt, ax.speed * dt);
      motor += step;
      // Lost motion: the table follows only when the motor pushes it.
      table = std::clamp(table, motor - ax.backlash / 2, motor + ax.backlash / 2);
      t += dt;
      if (t >= next_meas) {
        line(meas_pv, t, ax.read(table, noise(rng)));
        next_meas = t + meas_gap(rng);
      }
      if (command == Command::kTrajectorySetpoint && t >= next_cmd) {
        if (motor != logged_cmd) line(cmd_pv, t, motor), logged_cmd = motor;
        next_cmd = t + cmd_gap(rng);
      }
      if (rest_until < 0 && motor == goal) rest_until = t + seconds_after_arrival;
      if (rest_until >= 0 && t >= rest_until) return;
    }
  };
  for (double goal : goals) {
    if (command == Command::kTargetSetpoint) line(cmd_pv, t, goal);
    line("SIM:TestNumber", t, ++test_number);
    advance(goal, ax.dwell);
  }
  const auto p = test::scratch_dir() / name;
  std::ofstream(p, std::ios::binary) << log;
  return {p, targets};
}

RecordingOptions camonitor_map() {
  RecordingOptions o;
  o.map = parse_column_map("x_cmd=SIM:M1-PosSet,x_meas=SIM:Ref-PosAct");
  o.required = {"x_cmd", "x_meas"};
  return o;
}

// Every planted quantity within ±15 % or ±1 µm.
double tolerance(double planted) {
  return std::max(0.15 * std::abs(planted), 0.001);
}

void expect_planted(const AxisPositioning& r, const PlantedAxis& ax,
                    const std::vector<double>& targets) {
  ASSERT_EQ(r.targets.size(), targets.size());
  double planted_B = 0;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const auto& got = r.targets[i];
    // A trajectory setpoint logged 1 ms before its last, sub-threshold step
    // enters the window's command average.
    EXPECT_NEAR(got.target, targets[i], 0.0005);
    ASSERT_TRUE(got.up && got.down);
    EXPECT_EQ(got.up->runs(), 5);
    EXPECT_EQ(got.down->runs(), 5);
    const double up = ax.deviation(targets[i], +1), down = ax.deviation(targets[i], -1);
    EXPECT_NEAR(got.up->mean, up, tolerance(up)) << "target " << targets[i];
    EXPECT_NEAR(got.down->mean, down, tolerance(down)) << "target " << targets[i];
    EXPECT_NEAR(*got.B, up - down, tolerance(up - down)) << "target " << targets[i];
    planted_B = std::max(planted_B, std::abs(up - down));
  }
  ASSERT_TRUE(r.B);
  EXPECT_NEAR(*r.B, planted_B, tolerance(planted_B));
  EXPECT_NEAR(*r.B, ax.backlash, tolerance(ax.backlash));
}

TEST(Iso230Setpoints, CamonitorLogIsRecognisedAndMergedInTimeOrder) {
  const PlantedAxis ax;
  const auto log = write_log("target.log", ax, Command::kTargetSetpoint, 1);
  EXPECT_TRUE(is_camonitor_log(log.file));
  const auto rec = read_camonitor(log.file, camonitor_map());
  ASSERT_GT(rec.rows(), 1000u);
  EXPECT_EQ(rec.t_s.front(), 0.0);
  for (std::size_t k = 1; k < rec.rows(); ++k)
    ASSERT_GT(rec.t_s[k], rec.t_s[k - 1]) << "row " << k;
  // The older first line of the command holds until its first change.
  EXPECT_NEAR(rec.channel("x_cmd").front(), 2.0 - 2.0 - 1.0, 1e-12);
  EXPECT_EQ(rec.columns,
            (std::vector<std::string>{"SIM:M1-PosSet", "SIM:TestNumber", "SIM:Ref-PosAct"}));
}

TEST(Iso230Setpoints, TargetSetpointGivesPlantedBacklashAndDeviations) {
  const PlantedAxis ax;
  const auto log = write_log("target.log", ax, Command::kTargetSetpoint, 2);
  const auto rec = read_camonitor(log.file, camonitor_map());
  const auto r = evaluate_positioning(rec, "x", {});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->measured_channel, "x_meas");
  expect_planted(*r, ax, log.targets);
  bool noted = false;
  for (const auto& n : r->notes)
    noted = noted || n.find("target setpoint") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(Iso230Setpoints, TrajectorySetpointGivesTheSame) {
  const PlantedAxis ax;
  const auto traj = write_log("trajectory.log", ax, Command::kTrajectorySetpoint, 3);
  const auto target = write_log("target.log", ax, Command::kTargetSetpoint, 3);
  const auto r = evaluate_positioning(read_camonitor(traj.file, camonitor_map()), "x", {});
  const auto q = evaluate_positioning(read_camonitor(target.file, camonitor_map()), "x", {});
  ASSERT_TRUE(r && q);
  expect_planted(*r, ax, traj.targets);
  EXPECT_NEAR(*r->B, *q->B, 0.001);
  for (const auto& n : r->notes)
    EXPECT_EQ(n.find("target setpoint"), std::string::npos) << n;
}

TEST(Iso230Setpoints, TwentySeedsThreeMagnitudesBothCommands) {
  // Backlash near the noise floor, medium and large, each with its own pitch
  // error and speed, 20 seeds each, logged both ways.
  for (const auto& [backlash, pitch, speed] :
       {std::tuple{0.0025, 0.001, 1.0}, std::tuple{0.006, 0.003, 2.0},
        std::tuple{0.015, 0.004, 1.0}}) {
    PlantedAxis ax;
    ax.backlash = backlash;
    ax.pitch = pitch;
    ax.speed = speed;
    for (unsigned seed = 100; seed < 120; ++seed)
      for (Command c : {Command::kTargetSetpoint, Command::kTrajectorySetpoint}) {
        const auto log = write_log("sweep.log", ax, c, seed);
        const auto r = evaluate_positioning(read_camonitor(log.file, camonitor_map()), "x", {});
        SCOPED_TRACE("backlash " + std::to_string(backlash) + " seed " + std::to_string(seed) +
                     (c == Command::kTargetSetpoint ? " target" : " trajectory"));
        ASSERT_TRUE(r);
        expect_planted(*r, ax, log.targets);
      }
  }
}

TEST(Iso230Setpoints, SlowQuantisedReadings) {
  // Readings logged only every 0.4–0.6 s and in steps of 0.4 µm, as an
  // encoder PV polled at 2 Hz.
  PlantedAxis ax;
  ax.meas_gap_min = 0.4;
  ax.meas_gap_max = 0.6;
  ax.quantum = 0.0004;
  ax.dwell = 2.0;
  for (Command c : {Command::kTargetSetpoint, Command::kTrajectorySetpoint}) {
    const auto log =
        write_log(c == Command::kTargetSetpoint ? "slow_target.log" : "slow_traj.log", ax, c, 13);
    const auto r = evaluate_positioning(read_camonitor(log.file, camonitor_map()), "x", {});
    ASSERT_TRUE(r);
    expect_planted(*r, ax, log.targets);
  }
}

TEST(Iso230Setpoints, CliReadsCamonitorLog) {
  const PlantedAxis ax;
  const auto log = write_log("target.log", ax, Command::kTargetSetpoint, 4);
  const auto out = test::scratch_dir() / "out";
  auto r = test::run_process({test::cli_path().string(), "iso230", "--recording", log.file.string(),
                              "--map", "x_cmd=SIM:M1-PosSet,x_meas=SIM:Ref-PosAct", "--out",
                              out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::read_file(out / "iso230.json"));
  ASSERT_EQ(j["axes"].size(), 1u);
  EXPECT_NEAR(j["axes"][0]["B_mm"].get<double>(), ax.backlash, tolerance(ax.backlash));
}

TEST(Iso230Setpoints, CamonitorErrorsNameFileAndLine) {
  const auto dir = test::scratch_dir();
  const auto bad = dir / "bad.log";
  std::ofstream(bad, std::ios::binary)
      << "SIM:M1-PosSet  2024-03-05 10:00:00.000000 1  \n"
      << "SIM:Other      2024-03-05 10:00:00.100000 text is fine here\n"
      << "SIM:Ref-PosAct 2024-03-05 10:00:00.200000 abc\n";
  try {
    read_camonitor(bad, camonitor_map());
    FAIL() << "no error";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.log:3: PV 'SIM:Ref-PosAct': value 'abc'"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(bad, std::ios::binary) << "SIM:M1-PosSet  2024-03-05 10:00:00.000000 1\n"
                                       << "SIM:Ref-PosAct 2024-03-05 25:00:00.200000 1\n";
  try {
    read_camonitor(bad, camonitor_map());
    FAIL() << "no error";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.log:2: PV 'SIM:Ref-PosAct': bad time stamp"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(bad, std::ios::binary) << "SIM:M1-PosSet  2024-03-05 10:00:00.000000 1\n";
  try {
    read_camonitor(bad, camonitor_map());
    FAIL() << "no error";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("the log has no PV 'SIM:Ref-PosAct'; PVs in the log: "
                                         "SIM:M1-PosSet"),
              std::string::npos)
        << e.what();
  }
  // A CSV recording is not taken for a camonitor log.
  const auto csv = dir / "rec.csv";
  std::ofstream(csv, std::ios::binary) << "t,x_cmd,x_act\n0,1,1\n";
  EXPECT_FALSE(is_camonitor_log(csv));
}

}  // namespace
}  // namespace truecut::analysis
