// machine_joints' servo function allocates nothing, with every effect on
// (the deflections driven by a turning cutting force).
#include <gtest/gtest.h>

#include <fstream>

#include "alloc_counter.hpp"
#include "test_paths.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::rt::hal;
using namespace truecut::test;

namespace {

const char* kMachine = R"({"truecut_machine": 1,
  "joints": {"x": {"min_mm": -500, "max_mm": 500}, "y": {"min_mm": -500, "max_mm": 500},
             "z": {"min_mm": -500, "max_mm": 500}, "a": {"min_deg": -120, "max_deg": 120},
             "c": {"min_deg": -720, "max_deg": 720}},
  "kinematics": {"type": "xyzac-trt", "x_rot_point_mm": 20, "y_rot_point_mm": -10,
                 "z_rot_point_mm": -200, "y_offset_mm": 5, "z_offset_mm": 50,
                 "tool": {"length_mm": 60, "radius_mm": 4, "corner_radius_mm": 1}},
  "effects": {
    "servo_lag": {"enabled": true, "x": {"kv_per_s": 30, "ff1": 0.8}, "y": {"kv_per_s": 30},
                  "z": {"kv_per_s": 30}, "a": {"kv_per_s": 20}, "c": {"kv_per_s": 20}},
    "backlash": {"enabled": true, "x": {"play_mm": 0.01}, "c": {"play_deg": 0.003}},
    "reversal_spike": {"enabled": true, "x": {"coulomb_n": 150, "viscous_n_s_per_mm": 0.05},
                       "c": {"coulomb_nm": 20}},
    "pitch_error": {"enabled": true, "x": {"scale_um_per_m": 10, "periodic_amplitude_um": 2,
                                            "periodic_period_mm": 10}},
    "thermal_drift": {"enabled": true, "z": {"gain_mm": 0.02, "tau_s": 60,
                                              "driver": "spindle_power",
                                              "reference_power_kw": 10}},
    "squareness": {"enabled": true, "xy_urad": 20, "yz_urad": 10, "zx_urad": 5},
    "straightness": {"enabled": true, "eyx": {"quadratic_um_per_m2": 10}},
    "rotary_location": {"enabled": true,
                        "a": {"e_y0a_um": 5, "e_z0a_um": -3, "e_b0a_urad": 10, "e_c0a_urad": 4,
                              "e_a0a_urad": 20},
                        "c": {"e_x0c_um": 8, "e_y0c_um": 2, "e_a0c_urad": -6, "e_b0c_urad": 9,
                              "e_c0c_urad": 15}},
    "tool_length_error": {"enabled": true, "length_mm": 0.05},
    "tool_radius_error": {"enabled": true, "radius_mm": -0.1, "corner_radius_mm": 0.02},
    "tool_deflection": {"enabled": true, "stiffness_n_per_um": 1.5, "stickout_mm": 20},
    "workpiece_deflection": {"enabled": true, "stiffness_n_per_um": 0.04,
                             "reference_length_mm": 17, "clamp_point_mm": [20, -10, -200],
                             "axis": [0, 0, 1]}}})";

std::string chain(const std::filesystem::path& machine) {
  return "loadrt threads name1=servo-thread period1=1000000\n"
         "loadrt siggen names=p\n"
         "loadrt machine_joints names=m machine=" +
         machine.string() +
         "\nloadrt recorder file=trace.csv columns=x_cmd,x_act,c_act,tx,tcpx,toolk,tdx,wdx\n"
         "setp p.amplitude 40\nsetp p.frequency 2\nsetp m.spindle-power-kw 7\n"
         // The sine also drives a turning cutting force (N) acting 10 mm above
         // the clamp.
         "net xc p.sine => m.x.pos-cmd m.y.pos-cmd recorder.0.x_cmd m.cut-force-x\n"
         "net cc p.cosine => m.c.pos-cmd m.a.pos-cmd m.z.pos-cmd m.cut-force-y\n"
         "net xa m.x.pos-act => recorder.0.x_act\n"
         "net ca m.c.pos-act => recorder.0.c_act\n"
         "net tx m.true-x => recorder.0.tx\n"
         "net tcpx m.true-tcp-x => recorder.0.tcpx\n"
         "net toolk m.true-tool-k => recorder.0.toolk\n"
         "setp m.cut-contact-x 20\nsetp m.cut-contact-y -10\nsetp m.cut-contact-z -190\n"
         "net tdx m.tool-deflection-x => recorder.0.tdx\n"
         "net wdx m.workpiece-deflection-x => recorder.0.wdx\n"
         "addf p.update servo-thread\naddf m.update servo-thread\n"
         "addf recorder.0.sample servo-thread\n";
}

}  // namespace

TEST(MachineNoAlloc, CounterSeesAllocations) {
  EXPECT_EQ(2u, alloc_counter_self_test());
}

TEST(MachineNoAlloc, ServoCyclesAllocateNothing) {
  const auto dir = scratch_dir();
  const auto machine = dir / "m.json";
  std::ofstream(machine) << kMachine;
  HalOptions o;
  o.component_path = {component_dir()};
  o.output_dir = dir;
  Hal hal(o);
  load_hal_text(hal, chain(machine), "chain.hal");
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = 3000;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  auto r = ex.run_simulated(lim);
  EXPECT_EQ(3000u, r.threads[0].cycles);
  EXPECT_EQ(0u, armed_allocations());
  EXPECT_NE(hal.get_pin_or_param("m.x.pos-act").f, hal.get_pin_or_param("m.x.pos-cmd").f)
      << "the effects were running";
  EXPECT_NE(0.0, hal.get_pin_or_param("m.true-tcp-x").f) << "the true pose was computed";
  EXPECT_NE(0.0, hal.get_pin_or_param("m.workpiece-deflection-x").f) << "the part bent";
  EXPECT_NE(0.0, hal.get_pin_or_param("m.tool-deflection-y").f) << "the tool bent";
}
