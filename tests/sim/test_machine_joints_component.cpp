// The machine_joints HAL component: loads a machine description, runs the
// joint model per servo cycle, reports bad files with file and key.
#include <gtest/gtest.h>

#include <fstream>

#include "test_paths.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"
#include "truecut/sim/machine_model.hpp"

using namespace truecut::rt::hal;

namespace {

HalOptions opts(const std::filesystem::path& out) {
  HalOptions o;
  o.component_path = {truecut::test::component_dir()};
  o.output_dir = out;
  return o;
}

std::filesystem::path write(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file) << text;
  return file;
}

const char* kLagOnX = R"({"truecut_machine": 1,
  "joints": {"x": {"min_mm": -1000, "max_mm": 1000, "drive": {"encoder_resolution_mm": 0}},
             "y": {"min_mm": -1000, "max_mm": 1000}, "z": {"min_mm": -1000, "max_mm": 1000}},
  "effects": {"servo_lag": {"enabled": true, "x": {"kv_per_s": 25}},
              "backlash": {"enabled": true, "y": {"play_mm": 0.01}},
              "squareness": {"enabled": true, "xy_urad": 100}}})";

const char* kTrunnion = R"({"truecut_machine": 1,
  "joints": {"x": {"min_mm": -1000, "max_mm": 1000}, "y": {"min_mm": -1000, "max_mm": 1000},
             "z": {"min_mm": -1000, "max_mm": 1000}, "a": {"min_deg": -120, "max_deg": 120},
             "c": {"min_deg": -720, "max_deg": 720}},
  "kinematics": {"type": "xyzac-trt", "x_rot_point_mm": 120, "y_rot_point_mm": -40,
                 "z_rot_point_mm": -250, "y_offset_mm": 30, "z_offset_mm": 60,
                 "tool": {"length_mm": 80, "radius_mm": 3, "corner_radius_mm": 3}},
  "effects": {"rotary_location": {"enabled": true, "c": {"e_x0c_um": 20, "e_a0c_urad": 50}},
              "tool_length_error": {"enabled": true, "length_mm": 0.1},
              "tool_radius_error": {"enabled": true, "radius_mm": -0.1}}})";

void run_cycles(Hal& hal, uint64_t n) {
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = n;
  ex.run_simulated(lim);
}

}  // namespace

TEST(MachineJoints, FollowsWithLagAndReportsTrueTablePosition) {
  auto dir = truecut::test::scratch_dir();
  auto machine = write(dir / "m.json", kLagOnX);
  Hal hal(opts(dir));
  // siggen's sawtooth with amplitude 1000 at 0.05 Hz ramps at 100 mm/s.
  load_hal_text(hal,
                "loadrt threads name1=servo period1=1000000\nloadrt siggen\n"
                "loadrt machine_joints names=m machine=" +
                    machine.string() +
                    "\nsetp siggen.0.amplitude 1000\nsetp siggen.0.frequency 0.05\n"
                    "net xc siggen.0.sawtooth => m.x.pos-cmd m.y.pos-cmd\n"
                    "addf siggen.0.update servo\naddf m.update servo\n",
                "m.hal");
  run_cycles(hal, 2000);
  EXPECT_NEAR(100.0 / 25.0, hal.get_pin_or_param("m.x.f-error").f, 1e-9);
  const double x_act = hal.get_pin_or_param("m.x.pos-act").f;
  EXPECT_NEAR(100.0, hal.get_pin_or_param("m.x.vel-act").f, 1e-9);
  EXPECT_EQ(x_act, hal.get_pin_or_param("m.x.pos-true").f);
  // y (ideal drive) moves in +: its table lags by half the play.
  const double y_cmd = hal.get_pin_or_param("m.y.pos-cmd").f;
  EXPECT_EQ(y_cmd, hal.get_pin_or_param("m.y.pos-act").f);
  EXPECT_NEAR(y_cmd - 0.005, hal.get_pin_or_param("m.y.pos-true").f, 1e-12);
  EXPECT_NEAR(x_act + 100e-6 * (y_cmd - 0.005), hal.get_pin_or_param("m.true-x").f, 1e-12);
  EXPECT_FALSE(hal.get_pin_or_param("m.fault").b);
  EXPECT_FALSE(hal.get_pin_or_param("m.limit-fault").b);
}

TEST(MachineJoints, BadDescriptionFailsTheLoadNamingFileAndKey) {
  auto dir = truecut::test::scratch_dir();
  std::string bad = kLagOnX;
  bad.replace(bad.find("0.01"), 4, "-0.01");
  auto file = write(dir / "bad.json", bad);
  Hal hal(opts(dir));
  try {
    hal.load("machine_joints", {"machine=" + file.string()});
    FAIL() << "loaded";
  } catch (const HalError& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find(
                                     file.string() + ": effects.backlash.y.play_mm: must be >= 0"))
        << e.what();
  }
  EXPECT_FALSE(hal.has_pin("machine_joints.0.x.pos-cmd")) << "a failed load leaves nothing";
  EXPECT_THROW(hal.load("machine_joints", {}), HalError);
  EXPECT_THROW(hal.load("machine_joints", {"machine=" + file.string(), "kv=3"}), HalError);
}

TEST(MachineJoints, RunsAreByteForByteRepeatable) {
  auto dir = truecut::test::scratch_dir();
  auto demo = truecut::test::source_dir() / "examples/machines/demo_3axis.json";
  std::string traces[2];
  for (int run = 0; run < 2; ++run) {
    auto out = dir / ("run" + std::to_string(run));
    std::filesystem::create_directories(out);
    {
      Hal hal(opts(out));
      load_hal_text(hal,
                    "loadrt threads name1=servo period1=250000\nloadrt siggen count=2\n"
                    "loadrt machine_joints names=m machine=" +
                        demo.string() +
                        "\nloadrt recorder file=trace.csv "
                        "columns=x_cmd,x_act,y_cmd,y_act,tx,ty,tz\n"
                        "setp siggen.0.amplitude 50\nsetp siggen.0.frequency 0.7\n"
                        "setp siggen.1.amplitude 30\nsetp siggen.1.frequency 1.1\n"
                        "setp m.spindle-power-kw 8\n"
                        "net xc siggen.0.sine => m.x.pos-cmd recorder.0.x_cmd\n"
                        "net yc siggen.1.triangle => m.y.pos-cmd recorder.0.y_cmd\n"
                        "net xa m.x.pos-act => recorder.0.x_act\n"
                        "net ya m.y.pos-act => recorder.0.y_act\n"
                        "net tx m.true-x => recorder.0.tx\nnet ty m.true-y => recorder.0.ty\n"
                        "net tz m.true-z => recorder.0.tz\n"
                        "addf siggen.0.update servo\naddf siggen.1.update servo\n"
                        "addf m.update servo\naddf recorder.0.sample servo\n",
                    "d.hal");
      run_cycles(hal, 8000);
    }
    traces[run] = truecut::test::read_file(out / "trace.csv");
  }
  EXPECT_GT(traces[0].size(), 8000u * 7);
  EXPECT_EQ(traces[0], traces[1]);
}

TEST(MachineJoints, OutputsTheTruePoseInTheWorkpieceFrame) {
  auto dir = truecut::test::scratch_dir();
  auto machine = write(dir / "m.json", kTrunnion);
  Hal hal(opts(dir));
  load_hal_text(hal,
                "loadrt threads name1=servo period1=1000000\n"
                "loadrt machine_joints names=m machine=" +
                    machine.string() +
                    "\nsetp m.x.pos-cmd 150\nsetp m.y.pos-cmd 20\nsetp m.z.pos-cmd -90\n"
                    "setp m.a.pos-cmd 35\nsetp m.c.pos-cmd 200\naddf m.update servo\n",
                "m.hal");
  run_cycles(hal, 3);
  using namespace truecut::sim;
  const auto description = read_machine_description(machine);
  MachineModel model(description.machine);
  MachineState state;
  MachineInputs in;
  in.pos_cmd = {150.0, 20.0, -90.0, 35.0, 200.0};
  MachineOutputs out;
  model.step(state, in, 1e-3, out);
  const char* tcp[] = {"m.true-tcp-x", "m.true-tcp-y", "m.true-tcp-z"};
  const char* axis[] = {"m.true-tool-i", "m.true-tool-j", "m.true-tool-k"};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(out.tcp_true[i], hal.get_pin_or_param(tcp[i]).f) << tcp[i];
    EXPECT_EQ(out.tool_axis_true[i], hal.get_pin_or_param(axis[i]).f) << axis[i];
  }
  // Not the pose the controller believes in: 0.1 mm of tool and 20 µm of C
  // axis offset.
  const auto nominal = truecut::rt::forward_ac(nominal_ac_params(description.machine),
                                               {150.0, 20.0, -90.0, 35.0, 200.0});
  const Eigen::Vector3d got(out.tcp_true.data());
  EXPECT_GT((got - nominal.tcp_mm).norm(), 0.05);
  EXPECT_LT((got - nominal.tcp_mm).norm(), 0.15);
  EXPECT_NEAR(1.0, Eigen::Vector3d(out.tool_axis_true.data()).norm(), 1e-15);
  EXPECT_DOUBLE_EQ(80.1, hal.get_pin_or_param("m.true-tool-length").f);
  EXPECT_DOUBLE_EQ(2.9, hal.get_pin_or_param("m.true-tool-radius").f);
  EXPECT_DOUBLE_EQ(2.9, hal.get_pin_or_param("m.true-tool-corner-radius").f);
}
