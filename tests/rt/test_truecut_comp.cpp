// truecut_comp loaded as a shared library through the HAL: pins, exact
// values at grid nodes, joint mode, fault codes, reloads and a field swap
// under a running siggen-driven path.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>

#include "test_truecut_comp_support.hpp"
#include "truecut/rt/core/comp_math.hpp"
#include "truecut/rt/core/joint_mode.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::comp;
using rt::hal::Hal;

namespace {

std::string text(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

double getf(const Hal& h, const std::string& pin) {
  return h.get_pin_or_param(pin).f;
}
int32_t gets32(const Hal& h, const std::string& pin) {
  return h.get_pin_or_param(pin).s;
}
bool getbit(const Hal& h, const std::string& pin) {
  return h.get_pin_or_param(pin).b;
}

// One truecut_comp instance `c` in a servo thread, stepped by hand.
struct Rig {
  Hal hal{hal_options()};
  std::unique_ptr<rt::hal::Executor> ex;

  explicit Rig(const std::string& loadrt_args, const std::string& extra = "") {
    load_hal_text(hal,
                  "loadrt threads name1=servo-thread period1=1000000\n"
                  "loadrt truecut_comp names=c " +
                      loadrt_args + "\naddf c.update servo-thread\n" + extra,
                  "rig.hal");
    ex = std::make_unique<rt::hal::Executor>(hal);
  }
  void set(const std::string& pin, double v) { hal.set_pin_or_param("c." + pin, text(v)); }
  void set(const std::string& pin, const char* v) { hal.set_pin_or_param("c." + pin, v); }
  void set_tcp(const Eigen::Vector3d& p) {
    set("tcp-x", p.x());
    set("tcp-y", p.y());
    set("tcp-z", p.z());
  }
  Eigen::Vector3d corr() const {
    return {getf(hal, "c.corr-x"), getf(hal, "c.corr-y"), getf(hal, "c.corr-z")};
  }
  Eigen::Vector3d tcp_out() const {
    return {getf(hal, "c.tcp-x-out"), getf(hal, "c.tcp-y-out"), getf(hal, "c.tcp-z-out")};
  }
  int32_t fault() const { return gets32(hal, "c.fault"); }
  void run(int cycles) {
    for (int i = 0; i < cycles; ++i)
      ex->step();
  }
};

std::string field_path(const char* name = "field.tcf") {
  return (scratch_dir() / name).string();
}

bool all_outputs_finite(const Hal& h) {
  for (const auto& p : h.pins())
    if (p.owner == "c" && p.dir == rt::hal::PinDir::kOut && p.type == rt::hal::Type::kFloat &&
        !std::isfinite(getf(h, p.name)))
      return false;
  return true;
}

}  // namespace

TEST(TruecutComp, ExportsTheDocumentedPins) {
  Rig r("");
  for (const char* pin : {"enable",
                          "tool",
                          "max-correction",
                          "max-rate",
                          "fade-time",
                          "reload",
                          "swap-inhibit",
                          "tcp-x",
                          "tcp-y",
                          "tcp-z",
                          "axis-i",
                          "axis-j",
                          "axis-k",
                          "tcp-x-out",
                          "tcp-y-out",
                          "tcp-z-out",
                          "axis-i-out",
                          "axis-j-out",
                          "axis-k-out",
                          "corr-x",
                          "corr-y",
                          "corr-z",
                          "corr-mag",
                          "active",
                          "fault",
                          "limited",
                          "fade",
                          "field-generation",
                          "load-errors",
                          "clamp-count",
                          "max-accel",
                          "reset",
                          "max-jerk",
                          "fault-latched",
                          "expect-machine-id",
                          "expect-part-id",
                          "expect-tool-set-id",
                          "field-crc-lo",
                          "field-crc-hi",
                          "field-machine-id",
                          "field-part-id",
                          "field-tool-set-id"})
    EXPECT_TRUE(r.hal.has_pin(std::string("c.") + pin)) << pin;
  EXPECT_TRUE(r.hal.has_function("c.update"));
  EXPECT_EQ(1.0, getf(r.hal, "c.max-correction"));
  EXPECT_EQ(10.0, getf(r.hal, "c.max-rate"));
  EXPECT_EQ(1.0, getf(r.hal, "c.fade-time"));
  EXPECT_EQ(rt::comp::kDefaultMaxAccelMmPerS2, getf(r.hal, "c.max-accel"));
  EXPECT_EQ(rt::comp::kDefaultMaxJerkMmPerS3, getf(r.hal, "c.max-jerk"));
  EXPECT_EQ(1.0, getf(r.hal, "c.axis-k"));
  EXPECT_FALSE(r.hal.has_pin("c.joint-x"));

  Rig j("mode=joint");
  for (const char* pin : {"joint-x", "joint-c", "joint-x-out", "joint-c-out", "x-rot-point",
                          "y-rot-point", "z-rot-point", "y-offset", "z-offset", "tool-offset",
                          "conventional-directions", "a-min", "a-max", "tcp-x-out", "corr-x"})
    EXPECT_TRUE(j.hal.has_pin(std::string("c.") + pin)) << pin;
  EXPECT_FALSE(j.hal.has_pin("c.tcp-x"));
  EXPECT_EQ(-180.0, getf(j.hal, "c.a-min"));
}

TEST(TruecutComp, FieldIdentityIsOnPinsAndAFieldForAnotherMachineIsRefused) {
  // Issue 19, point 5: CRC (two u32 halves) and the ids the field names on
  // pins; expected ids set by the integrator; a mismatch is fault 10
  // (wrong-field) and the field is not applied.
  const rt::CorrectionField field = make_field({});
  rt::FieldFileInfo info{"2026-11-21T00:00:00Z", "truecut_comp test", "mill-2", "part-7", "T1 T2"};
  const auto path = field_path("named.tcf");
  rt::write_field_file(path, field, info);
  const rt::LoadedField loaded = rt::read_field_file(path);
  Rig r("field=" + path);
  r.set("enable", 1.0);
  r.set("tool", 1.0);
  r.run(1);
  auto getu = [&](const char* pin) { return r.hal.get_pin_or_param(std::string("c.") + pin).u; };
  EXPECT_EQ(static_cast<uint32_t>(loaded.crc64), getu("field-crc-lo"));
  EXPECT_EQ(static_cast<uint32_t>(loaded.crc64 >> 32), getu("field-crc-hi"));
  EXPECT_EQ(rt::field_identity_id("mill-2"), getu("field-machine-id"));
  EXPECT_EQ(rt::field_identity_id("part-7"), getu("field-part-id"));
  EXPECT_EQ(rt::field_identity_id("T1 T2"), getu("field-tool-set-id"));
  EXPECT_EQ(1, gets32(r.hal, "c.field-generation"));
  r.run(1500);
  EXPECT_EQ(0, r.fault());
  EXPECT_GT(r.corr().norm(), 0.01);
  // Expecting another machine: the current field fades out, fault 10.
  r.hal.set_pin_or_param("c.expect-machine-id", std::to_string(rt::field_identity_id("mill-3")));
  r.run(1500);
  EXPECT_EQ(10, r.fault());
  EXPECT_EQ(Eigen::Vector3d::Zero(), r.corr());
  // A component expecting mill-3 never applies the mill-2 field.
  Rig other("field=" + path,
            "setp c.expect-machine-id " + std::to_string(rt::field_identity_id("mill-3")) + "\n");
  other.set("enable", 1.0);
  other.set("tool", 1.0);
  for (int i = 0; i < 500; ++i) {
    other.run(1);
    ASSERT_EQ(10, other.fault());
    ASSERT_EQ(Eigen::Vector3d::Zero(), other.corr());
  }
  EXPECT_EQ(0, gets32(other.hal, "c.field-generation"));
  EXPECT_EQ(0u, other.hal.get_pin_or_param("c.field-crc-lo").u);
}

TEST(TruecutComp, RejectsBadLoadArguments) {
  Hal h(hal_options());
  EXPECT_THROW(h.load("truecut_comp", {"mode=world"}), rt::hal::HalError);
  EXPECT_THROW(h.load("truecut_comp", {"field=" + field_path("missing.tcf")}), rt::hal::HalError);
  const auto path = write_field(field_path(), {});
  EXPECT_THROW(h.load("truecut_comp", {"field=" + path.string(), "tools=1,5"}), rt::hal::HalError);
  EXPECT_THROW(h.load("truecut_comp", {"tools=1"}), rt::hal::HalError);
  EXPECT_FALSE(h.has_pin("truecut_comp.0.enable"));
  h.load("truecut_comp", {"field=" + path.string(), "tools=1,2"});
  EXPECT_TRUE(h.has_pin("truecut_comp.0.enable"));
}

TEST(TruecutComp, CorrectionAtGridNodesEqualsTheStoredVectors) {
  const FieldSpec spec;
  const auto path = write_field(field_path(), spec);
  const rt::CorrectionField field = make_field(spec);
  Rig r("field=" + path.string());
  r.set("fade-time", 0.0);
  r.set("max-rate", 1e9);
  r.set("max-accel", 0.0);  // no acceleration limit
  r.set("max-jerk", 0.0);   // nor jerk limit
  r.set("max-correction", 1e3);
  r.set("enable", 1.0);
  const auto& g = field.grid();
  double worst = 0.0;
  for (int32_t tool : spec.tools) {
    r.set("tool", tool);
    const auto nodes = field.nodes(tool);
    for (int32_t k = 0; k < g.dims[2]; ++k)
      for (int32_t j = 0; j < g.dims[1]; ++j)
        for (int32_t i = 0; i < g.dims[0]; ++i) {
          const Eigen::Vector3d p = g.node_position_mm(i, j, k);
          r.set_tcp(p);
          r.run(1);
          const auto& n = nodes[static_cast<std::size_t>(g.index(i, j, k))];
          const Eigen::Vector3d stored(n.dx_mm, n.dy_mm, n.dz_mm);
          worst = std::max(worst, (r.corr() - stored).norm());
          ASSERT_EQ(0, r.fault());
          ASSERT_EQ(r.tcp_out(), p + r.corr());
        }
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(TruecutComp, JointModeCorrectsThroughTheKinematics) {
  FieldSpec spec;
  spec.origin_mm = {-40.0, -40.0, -30.0};
  spec.dims = {17, 17, 13};
  const auto path = write_field(field_path(), spec);
  const rt::CorrectionField field = make_field(spec);
  Rig r("field=" + path.string() + " mode=joint",
        std::string(kJointTestKinematicsHal) +
            "setp c.fade-time 0\nsetp c.max-rate 1e9\nsetp c.max-accel 0\nsetp c.max-jerk 0\n"
            "setp c.tool 1\n");
  const rt::AcTrtParams k = joint_test_kinematics();
  const rt::AcJoints j{3.0, -7.0, 60.0, 25.0, 40.0};
  const char* const* names = kJointInputPins;
  const double v[] = {j.x_mm, j.y_mm, j.z_mm, j.a_deg, j.c_deg};
  for (int i = 0; i < 5; ++i)
    r.set(names[i], v[i]);
  r.run(2);
  for (int i = 0; i < 5; ++i)  // disabled: joints pass through bit for bit
    EXPECT_EQ(v[i], getf(r.hal, std::string("c.") + names[i] + "-out"));
  r.set("enable", 1.0);
  r.run(2);
  const rt::ToolPose in = rt::forward_ac(k, j);
  ASSERT_TRUE(field.inside(in.tcp_mm));
  const Eigen::Vector3d c = field.evaluate(1, in.tcp_mm).correction_mm;
  EXPECT_NEAR(0.0, (r.corr() - c).norm(), 1e-15);
  ASSERT_GT(c.norm(), 0.01);
  rt::AcJoints out;
  out.x_mm = getf(r.hal, "c.joint-x-out");
  out.y_mm = getf(r.hal, "c.joint-y-out");
  out.z_mm = getf(r.hal, "c.joint-z-out");
  out.a_deg = getf(r.hal, "c.joint-a-out");
  out.c_deg = getf(r.hal, "c.joint-c-out");
  EXPECT_EQ(j.a_deg, out.a_deg);
  EXPECT_EQ(j.c_deg, out.c_deg);
  EXPECT_NEAR(0.0, (rt::forward_ac(k, out).tcp_mm - (in.tcp_mm + c)).norm(), 1e-9);
  EXPECT_NEAR(0.0, (r.tcp_out() - (in.tcp_mm + c)).norm(), 1e-12);

  r.set("a-max", 20.0);  // A = 25 is now outside its travel
  r.run(1);
  EXPECT_EQ(7, r.fault());
}

TEST(TruecutComp, EveryFaultHasItsCodeAndFadesWithoutNaN) {
  const auto path = write_field(field_path(), {});
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Every float input is driven by a `source` pin, so NaN can reach it.
  const char* inputs[] = {"tcp-x",  "tcp-y",          "tcp-z",    "axis-i",   "axis-j",
                          "axis-k", "max-correction", "max-rate", "fade-time"};
  struct Case {
    const char* name;
    int32_t code;
    int input;  // index into inputs, or -1 for the tool
    double value;
  };
  const Case cases[] = {
      {"no layer", 2, -1, 7},
      {"outside grid", 3, 0, 500.0},
      {"tcp not finite", 4, 1, kNaN},
      {"axis not finite", 4, 3, kInf},
      {"max-correction not finite", 6, 6, kNaN},
      {"max-rate negative", 6, 7, -1.0},
      {"fade-time not finite", 6, 8, kInf},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Source src;
    Rig r("field=" + path.string(), "setp c.enable 1\nsetp c.tool 1\n");
    load_source(r.hal, src, 9);
    for (int i = 0; i < 9; ++i)
      r.hal.link(std::string("source.v") + std::to_string(i), std::string("s-") + inputs[i]);
    for (int i = 0; i < 9; ++i)
      r.hal.link(std::string("c.") + inputs[i], std::string("s-") + inputs[i]);
    const double initial[] = {1.0, 2.0, 3.0, 0.0, 0.0, 1.0, 1.0, 20.0, 0.05};
    for (int i = 0; i < 9; ++i)
      *src.pins[i] = initial[i];
    r.ex = std::make_unique<rt::hal::Executor>(r.hal);
    r.run(80);
    ASSERT_EQ(0, r.fault());
    const Eigen::Vector3d full = r.corr(), out_before = r.tcp_out();
    ASSERT_GT(full.norm(), 0.05);
    EXPECT_TRUE(getbit(r.hal, "c.active"));
    if (c.input < 0)
      r.set("tool", c.value);
    else
      *src.pins[c.input] = c.value;
    Eigen::Vector3d prev = full;
    double max_step = 0.0;
    for (int i = 0; i < 200; ++i) {
      r.run(1);
      ASSERT_EQ(c.code, r.fault()) << i;
      ASSERT_TRUE(all_outputs_finite(r.hal)) << i;
      max_step = std::max(max_step, (r.corr() - prev).norm());
      prev = r.corr();
    }
    EXPECT_LE(max_step, 20.0 * 1e-3 * (1 + 1e-12));
    // Every fault, a bad max-rate included (the last valid rate is used),
    // brings the correction to zero.
    EXPECT_EQ(Eigen::Vector3d::Zero(), r.corr());
    EXPECT_FALSE(getbit(r.hal, "c.active"));
    if (c.code == 4) {
      EXPECT_EQ(out_before, r.tcp_out()) << "outputs hold while inputs are NaN";
    }
    EXPECT_EQ(c.code == 6 ? 6 : 0, gets32(r.hal, "c.fault-latched"));
    // The fault clears with its cause and the correction fades back in; a
    // bad parameter stays latched until `reset` rises.
    if (c.input < 0)
      r.set("tool", 1.0);
    else
      *src.pins[c.input] = initial[c.input];
    if (c.code == 6) {
      r.run(200);
      EXPECT_EQ(0, r.fault());
      EXPECT_EQ(6, gets32(r.hal, "c.fault-latched"));
      EXPECT_EQ(Eigen::Vector3d::Zero(), r.corr()) << "latched: no correction before reset";
      r.set("reset", 1.0);
      r.run(1);
      r.set("reset", 0.0);
      EXPECT_EQ(0, gets32(r.hal, "c.fault-latched"));
    }
    r.run(200);
    EXPECT_EQ(0, r.fault());
    EXPECT_EQ(full, r.corr());
  }
}

TEST(TruecutComp, NoFieldAndAnOverflowingFieldAreFaults) {
  Rig none("", "setp c.enable 1\n");
  none.run(3);
  EXPECT_EQ(1, none.fault());
  EXPECT_EQ(0, gets32(none.hal, "c.field-generation"));
  none.set("reload", 1.0);  // nothing to reload from: an error, still no field
  none.run(1);
  none.hal.run_services();
  none.run(1);
  EXPECT_EQ(1, gets32(none.hal, "c.load-errors"));
  EXPECT_EQ(1, none.fault());

  rt::FieldGrid g;
  rt::FieldLayer layer;
  layer.tool = 0;
  layer.nodes.assign(8, {1e308, 0.0, 0.0, 1.0});
  layer.nodes[5].dx_mm = -1e308;
  const auto path = field_path("overflow.tcf");
  rt::write_field_file(path, rt::CorrectionField(g, {layer}), {});
  Rig huge("field=" + path, "setp c.enable 1\nsetp c.tcp-x 0.5\nsetp c.tcp-y 0.5\n");
  huge.run(3);
  EXPECT_EQ(5, huge.fault());
  EXPECT_EQ(Eigen::Vector3d::Zero(), huge.corr());
}

namespace {

// siggen drives the TCP around a circle (radius 15 mm, 0.5 Hz) and along z;
// the capture component records corr-x/y/z, tcp-x/y/z and fade each cycle.
struct PathRun {
  Capture cap;
  std::unique_ptr<Hal> hal;
  std::unique_ptr<rt::hal::Executor> ex;

  explicit PathRun(const std::string& field) {
    hal = std::make_unique<Hal>(hal_options());
    load_capture(*hal, cap, 7);
    load_hal_text(*hal,
                  "loadrt threads name1=servo-thread period1=1000000\n"
                  "loadrt siggen names=path,lift\n"
                  "loadrt truecut_comp names=c field=" +
                      field +
                      "\n"
                      "setp path.amplitude 15\nsetp path.frequency 0.5\n"
                      "setp lift.amplitude 4\nsetp lift.frequency 0.3\n"
                      "setp c.enable 1\nsetp c.tool 1\nsetp c.fade-time 0.5\n"
                      "setp c.max-rate 5\n"
                      "net x path.cosine => c.tcp-x capture.c3\n"
                      "net y path.sine => c.tcp-y capture.c4\n"
                      "net z lift.triangle => c.tcp-z capture.c5\n"
                      "net cx c.corr-x => capture.c0\n"
                      "net cy c.corr-y => capture.c1\n"
                      "net cz c.corr-z => capture.c2\n"
                      "net fade c.fade => capture.c6\n"
                      "addf path.update servo-thread\naddf lift.update servo-thread\n"
                      "addf c.update servo-thread\naddf capture.sample servo-thread\n",
                  "path.hal");
    ex = std::make_unique<rt::hal::Executor>(*hal);
    cap.reserve(20000);
  }
  void run(uint64_t cycles) {
    rt::hal::RunLimits lim;
    lim.max_cycles = cycles;
    lim.service_period_ns = 10'000'000;
    ex->run_simulated(lim);
  }
  std::size_t cycles() const { return cap.samples.size() / 7; }
  Eigen::Vector3d at(std::size_t cycle, int first) const {
    const double* s = &cap.samples[cycle * 7 + first];
    return {s[0], s[1], s[2]};
  }
};

// Runs field A, swaps to B (written over the same file) while the path
// runs, then asks for a reload of a corrupt file. Returns the capture.
std::vector<double> swap_scenario(const std::filesystem::path& file, bool check) {
  FieldSpec b_spec;
  b_spec.scale = -2.0;
  write_field(file, {});
  PathRun run(file.string());
  run.run(1500);
  write_field(file, b_spec);
  run.hal->set_pin_or_param("c.reload", "1");
  run.run(3000);
  if (check) {
    EXPECT_EQ(2, gets32(*run.hal, "c.field-generation"));
    EXPECT_EQ(0, gets32(*run.hal, "c.load-errors"));
  }
  { std::ofstream(file, std::ios::binary) << "TRUECUT-FIELD 1\ngarbage\n"; }
  run.hal->set_pin_or_param("c.reload", "0");
  run.run(10);
  run.hal->set_pin_or_param("c.reload", "1");
  run.run(500);
  if (check) {
    EXPECT_EQ(2, gets32(*run.hal, "c.field-generation")) << "a bad file changes nothing";
    EXPECT_EQ(1, gets32(*run.hal, "c.load-errors"));
    EXPECT_EQ(0, gets32(*run.hal, "c.fault"));
    const rt::CorrectionField b = make_field(b_spec);
    double max_step = 0.0;
    for (std::size_t i = 1; i < run.cycles(); ++i)
      max_step = std::max(max_step, (run.at(i, 0) - run.at(i - 1, 0)).norm());
    EXPECT_LE(max_step, 5.0 * 1e-3 * (1 + 1e-12)) << "rate limit x period";
    // After the cross-fade the output is field B at the TCP, exactly.
    const std::size_t last = run.cycles() - 1;
    EXPECT_EQ(b.evaluate(1, run.at(last, 3)).correction_mm, run.at(last, 0));
    // The swap happened mid-run: somewhere between the two fields.
    const rt::CorrectionField a = make_field({});
    const std::size_t mid = 1500 + 250;
    const Eigen::Vector3d ca = a.evaluate(1, run.at(mid, 3)).correction_mm,
                          cb = b.evaluate(1, run.at(mid, 3)).correction_mm;
    EXPECT_GT((run.at(mid, 0) - ca).norm(), 0.1 * (ca - cb).norm());
    EXPECT_GT((run.at(mid, 0) - cb).norm(), 0.1 * (ca - cb).norm());
    EXPECT_EQ(1.0, run.cap.samples[last * 7 + 6]) << "fade complete";
  }
  return run.cap.samples;
}

}  // namespace

TEST(TruecutComp, FieldSwapUnderARunningPathIsSmoothAndDeterministic) {
  const auto file = scratch_dir() / "live.tcf";
  const std::vector<double> first = swap_scenario(file, true);
  const std::vector<double> second = swap_scenario(file, false);
  ASSERT_EQ(first.size(), second.size());
  EXPECT_EQ(0, std::memcmp(first.data(), second.data(), first.size() * sizeof(double)))
      << "same run twice: bit-identical";
}

TEST(TruecutComp, SwapInhibitHoldsTheNewFieldBack) {
  const auto file = scratch_dir() / "held.tcf";
  FieldSpec b_spec;
  b_spec.scale = 2.0;
  write_field(file, {});
  // A 10 ms fade of 0.2 mm needs 5 m/s^2: no acceleration limit here.
  Rig r("field=" + file.string(),
        "setp c.enable 1\nsetp c.tool 1\nsetp c.fade-time 0.01\nsetp c.max-accel 0\nsetp "
        "c.max-jerk 0\n");
  r.set_tcp({0.0, 0.0, 0.0});
  r.run(20);
  write_field(file, b_spec);
  r.set("swap-inhibit", 1.0);
  r.set("reload", 1.0);
  r.run(1);
  r.hal.run_services();  // loads and publishes
  r.run(50);
  EXPECT_EQ(1, gets32(r.hal, "c.field-generation"));
  r.set("swap-inhibit", 0.0);
  r.run(1);
  EXPECT_EQ(2, gets32(r.hal, "c.field-generation"));
  r.run(20);
  EXPECT_EQ(make_field(b_spec).evaluate(1, Eigen::Vector3d::Zero()).correction_mm, r.corr());
}

TEST(TruecutComp, JointModeRespectsSoftLimitsAndPerJointLimits) {
  FieldSpec spec;
  spec.origin_mm = {-40.0, -40.0, -30.0};
  spec.dims = {17, 17, 13};
  spec.scale = 4.0;
  const auto path = write_field(field_path(), spec);
  Rig r("field=" + path.string() + " mode=joint",
        "setp c.x-rot-point 5\nsetp c.y-rot-point -3\nsetp c.z-rot-point 20\n"
        "setp c.z-offset -12\nsetp c.tool-offset 50\nsetp c.fade-time 0.2\nsetp c.tool 1\n");
  for (const char* pin :
       {"joint-x-max-correction", "joint-y-min-limit", "joint-z-max-limit", "joint-clip-count"})
    EXPECT_TRUE(r.hal.has_pin(std::string("c.") + pin)) << pin;
  EXPECT_FALSE(r.hal.has_pin("c.joint-a-max-limit"));
  EXPECT_EQ(0.0, getf(r.hal, "c.joint-x-max-correction"));
  EXPECT_EQ(-rt::comp::kNoSoftLimitMm, getf(r.hal, "c.joint-y-min-limit"));
  EXPECT_EQ(rt::comp::kNoSoftLimitMm, getf(r.hal, "c.joint-z-max-limit"));
  const double cmd[] = {3.0, -7.0, 60.0, 25.0, 40.0};
  const char* names[] = {"joint-x", "joint-y", "joint-z", "joint-a", "joint-c"};
  for (int i = 0; i < 5; ++i)
    r.set(names[i], cmd[i]);
  r.set("enable", 1.0);
  r.run(1000);
  ASSERT_EQ(0, r.fault());
  EXPECT_EQ(0, gets32(r.hal, "c.joint-clip-count"));
  const double dx = getf(r.hal, "c.joint-x-out") - cmd[0];
  const double y_free = getf(r.hal, "c.joint-y-out");
  const double dy = y_free - cmd[1];
  ASSERT_GT(std::abs(dx), 0.05);
  ASSERT_GT(std::abs(dy), 0.05);

  // A soft limit halfway: X stops exactly on it, reported and counted.
  const char* side = dx > 0.0 ? "joint-x-max-limit" : "joint-x-min-limit";
  r.set(side, cmd[0] + 0.5 * dx);
  const double limit = getf(r.hal, std::string("c.") + side);
  r.run(500);
  EXPECT_EQ(limit, getf(r.hal, "c.joint-x-out"));
  EXPECT_EQ(11, r.fault());
  EXPECT_NEAR(y_free, getf(r.hal, "c.joint-y-out"), 1e-9) << "Y keeps its correction";
  const int32_t count = gets32(r.hal, "c.joint-clip-count");
  EXPECT_GE(count, 490);
  r.run(10);
  EXPECT_EQ(count + 10, gets32(r.hal, "c.joint-clip-count"));
  EXPECT_EQ(0, gets32(r.hal, "c.fault-latched")) << "does not latch";

  // A per-joint limit below the field's correction on Y.
  const double m = 0.3 * std::abs(dy);
  r.set("joint-y-max-correction", m);
  const double m_pin = getf(r.hal, "c.joint-y-max-correction");
  for (int i = 0; i < 500; ++i) {
    r.run(1);
    const double y = getf(r.hal, "c.joint-y-out");
    ASSERT_LE(y, cmd[1] + m_pin) << i;
    ASSERT_GE(y, cmd[1] - m_pin) << i;
  }
  EXPECT_EQ(cmd[1] + std::copysign(m_pin, dy), getf(r.hal, "c.joint-y-out"));
  EXPECT_EQ(limit, getf(r.hal, "c.joint-x-out"));
  EXPECT_EQ(11, r.fault());
  EXPECT_TRUE(all_outputs_finite(r.hal));

  // Limits back to their defaults: the full correction returns, the report clears.
  r.set(side, dx > 0.0 ? rt::comp::kNoSoftLimitMm : -rt::comp::kNoSoftLimitMm);
  r.set("joint-y-max-correction", 0.0);
  r.run(1000);
  EXPECT_EQ(0, r.fault());
  EXPECT_NEAR(cmd[0] + dx, getf(r.hal, "c.joint-x-out"), 1e-9);
  EXPECT_NEAR(y_free, getf(r.hal, "c.joint-y-out"), 1e-9);
}
