// The joint servo (servo_lag on): textbook following error, stability over
// the usual servo periods, acceleration limit, encoder quantisation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "machine_fixtures.hpp"
#include "test_names.hpp"

using namespace truecut::sim;
using namespace truecut::sim::test;

class ServoPeriods : public ::testing::TestWithParam<double> {};

TEST_P(ServoPeriods, SteadyStateFollowingErrorIsVelocityOverKv) {
  const double period = GetParam();
  const double v = 100.0;  // mm/s
  MachineParams m = ideal_params();
  enable_servo_lag(m, kX, 25.0);
  enable_servo_lag(m, kY, 25.0, 0.6);
  const int cycles = int(std::lround(3.0 / period));
  auto tr = run(m, period, cycles, [&](double t) {
    MachineInputs in;
    in.pos_cmd[kX] = in.pos_cmd[kY] = v * t;
    return in;
  });
  const auto& last = tr.out.back();
  EXPECT_NEAR(v / 25.0, last.f_error[kX], 1e-9);
  EXPECT_NEAR(v / 25.0, tr.in.back().pos_cmd[kX] - last.pos_act[kX], 1e-9);
  EXPECT_NEAR((1.0 - 0.6) * v / 25.0, last.f_error[kY], 1e-9) << "ff1 removes its share";
  EXPECT_NEAR(v, last.vel_act[kX], 1e-7);
  EXPECT_EQ(0.0, last.f_error[kZ]) << "joints without servo_lag stay ideal";
}

INSTANTIATE_TEST_SUITE_P(Periods, ServoPeriods, ::testing::Values(125e-6, 250e-6, 500e-6, 1e-3),
                         [](const ::testing::TestParamInfo<double>& info) {  // e.g. "125us"
                           return std::to_string(std::lround(info.param * 1e6)) + "us";
                         });

TEST(Servo, StepResponseIsStableAndTheSameForEveryPeriod) {
  MachineParams m = ideal_params();
  enable_servo_lag(m, kX, 40.0);
  // Reference: the encoder every 1 ms with a 125 µs servo period.
  auto step = [](double) { return on_x(1.0); };
  std::vector<std::vector<double>> at_ms;
  for (double period : {125e-6, 250e-6, 500e-6, 1e-3}) {
    const int per_ms = int(std::lround(1e-3 / period));
    MachineModel model(m);
    MachineState st;
    MachineOutputs out;
    model.step(st, on_x(0.0), period, out);  // starts at 0
    std::vector<double> samples;
    double peak = 0.0;
    for (int k = 1; k <= 1000 * per_ms; ++k) {
      model.step(st, step(k * period), period, out);
      peak = std::max(peak, out.pos_act[kX]);
      if (k % per_ms == 0) samples.push_back(out.pos_act[kX]);
    }
    EXPECT_LT(peak, 1.001) << "period " << period << ": overshoot";
    EXPECT_NEAR(1.0, out.pos_act[kX], 1e-6) << "period " << period << ": settles";
    at_ms.push_back(samples);
  }
  // The position loop is sampled at the servo period, as in a real drive:
  // a longer period delays it by the difference, which moves a first-order
  // lag of rate Kv by less than Kv·ΔT of the step. The velocity loop runs on
  // the same 25 µs sub-steps whatever the period.
  const double periods[] = {125e-6, 250e-6, 500e-6, 1e-3};
  for (size_t p = 1; p < at_ms.size(); ++p) {
    double worst = 0.0;
    for (size_t i = 0; i < at_ms[0].size(); ++i)
      worst = std::max(worst, std::abs(at_ms[p][i] - at_ms[0][i]));
    EXPECT_LT(worst, 40.0 * (periods[p] - periods[0]) * 1.0) << "period " << periods[p];
  }
}

TEST(Servo, AccelerationLimitHolds) {
  MachineParams m = ideal_params();
  enable_servo_lag(m, kX, 40.0);
  m.joints[kX].drive.max_accel = 2000.0;
  const double period = 1e-3;
  auto tr = run(m, period, 1500, [](double t) { return on_x(t > 0.0 ? 10.0 : 0.0); });
  double worst = 0.0;
  for (size_t k = 1; k < tr.out.size(); ++k)
    worst = std::max(worst, std::abs(tr.out[k].vel_act[kX] - tr.out[k - 1].vel_act[kX]) / period);
  EXPECT_LE(worst, 2000.0 * (1 + 1e-9));
  EXPECT_GT(worst, 1800.0) << "the step must actually hit the limit";
  EXPECT_NEAR(10.0, tr.out.back().pos_act[kX], 1e-3);
}

TEST(Servo, EncoderQuantisesWhatTheLoopSees) {
  MachineParams m = ideal_params();
  enable_servo_lag(m, kX, 40.0);
  m.joints[kX].drive.encoder_resolution = 0.001;
  auto tr = run(m, 1e-3, 800, [](double t) { return on_x(3.3 * std::sin(7.0 * t)); });
  bool moved_between_counts = false;
  for (const auto& o : tr.out) {
    EXPECT_NEAR(0.0, std::remainder(o.pos_act[kX], 0.001), 1e-12);
    EXPECT_LE(std::abs(o.pos_act[kX] - o.pos_true[kX]), 0.0005 + 1e-12);
    moved_between_counts |= std::abs(o.pos_act[kX] - o.pos_true[kX]) > 1e-5;
  }
  EXPECT_TRUE(moved_between_counts);
}

TEST(Servo, RotaryJointFollowsInDegrees) {
  MachineParams m = ideal_params();
  enable_servo_lag(m, kC, 20.0);
  const double w = 90.0;  // deg/s
  auto tr = run(m, 1e-3, 3000, [&](double t) {
    MachineInputs in;
    in.pos_cmd[kC] = w * t;
    return in;
  });
  EXPECT_NEAR(w / 20.0, tr.out.back().f_error[kC], 1e-9);
}

TEST(Servo, SubstepsAreBoundedAndCoverThePeriod) {
  EXPECT_EQ(5, servo_substeps(125e-6));
  EXPECT_EQ(40, servo_substeps(1e-3));
  EXPECT_EQ(1, servo_substeps(0.0));
  EXPECT_EQ(4096, servo_substeps(10.0));
}
