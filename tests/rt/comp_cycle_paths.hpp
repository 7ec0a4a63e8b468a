// The four paths of a truecut_comp servo cycle that issue 19 (point 7) has
// counted and timed, each set up in the HAL shim and brought to the state it
// names by a warm-up:
//
//   plain       tcp mode, field faded in, the TCP on a circle inside the grid
//   cross-fade  tcp mode, field B adopted by a reload while field A fades out
//               (fade-time 10 s: every measured cycle is inside the fade)
//   joint       joint mode (forward kinematics, correction, inverse
//               kinematics) with A tilting and C turning every cycle, a
//               field without rotation
//   joint-tilt  the same with a field that also turns the tool (a few
//               mrad): "joint mode with orientation" (rotation shaped, A and
//               C turned by rotary_correction())
//   fault       tcp mode, the TCP outside the field's grid (fault 3), the
//               correction fading out (fade-time 10 s)
//
// The inputs are written straight into a `source` component's pins by
// drive() (no function of its own on the servo thread), so the thread runs
// truecut_comp's update alone. Used by the instruction-count driver
// (comp_cycle_driver.cpp), the no-allocation suite and
// bench/truecut_comp_bench.cpp (which includes this header and
// test_truecut_comp_support.hpp only, without the test support library:
// it passes its own HalOptions).
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "test_truecut_comp_support.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

namespace truecut::test::comp {

enum class CyclePath { kPlain, kCrossFade, kJoint, kJointTilt, kFault };

inline constexpr CyclePath kAllCyclePaths[] = {CyclePath::kPlain, CyclePath::kCrossFade,
                                               CyclePath::kJoint, CyclePath::kJointTilt,
                                               CyclePath::kFault};

inline const char* cycle_path_name(CyclePath p) {
  switch (p) {
    case CyclePath::kPlain:
      return "plain";
    case CyclePath::kCrossFade:
      return "cross-fade";
    case CyclePath::kJoint:
      return "joint";
    case CyclePath::kJointTilt:
      return "joint-tilt";
    case CyclePath::kFault:
      return "fault";
  }
  return "?";
}

inline std::optional<CyclePath> parse_cycle_path(const std::string& text) {
  for (CyclePath p : kAllCyclePaths)
    if (text == cycle_path_name(p)) return p;
  return std::nullopt;
}

// The 80 x 80 x 60 mm field around the origin the paths run in.
inline FieldSpec cycle_path_field(double scale, double rotation_scale = 0.0) {
  FieldSpec s;
  s.origin_mm = {-40.0, -40.0, -30.0};
  s.dims = {17, 17, 13};
  s.scale = scale;
  s.rotation_scale = rotation_scale;
  return s;
}

class CyclePathRig {
 public:
  // Loads the HAL for `path` with its field in `dir` and runs the warm-up
  // that brings it to the path's state. The cross-fade and the fade-out of
  // the fault path take `fade_time_s` (10 s: 10 000 cycles).
  CyclePathRig(CyclePath path, const std::filesystem::path& dir, double fade_time_s = 10.0,
               rt::hal::HalOptions options = hal_options())
      : path_(path), hal_(std::make_unique<rt::hal::Hal>(std::move(options))) {
    const auto file = dir / "cycle_path.tcf";
    const bool joint = path == CyclePath::kJoint || path == CyclePath::kJointTilt;
    write_field(file, cycle_path_field(1.0, path == CyclePath::kJointTilt ? 1.0 : 0.0));
    load_source(*hal_, source_, joint ? 5 : 3);
    std::string text =
        "loadrt threads name1=servo-thread period1=1000000\n"
        "loadrt truecut_comp names=c mode=" +
        std::string(joint ? "joint" : "tcp") + " field=" + file.string() +
        "\nsetp c.enable 1\nsetp c.tool 1\nsetp c.fade-time 0.01\n";
    const char* in[] = {"x", "y", "z", "a", "c"};
    for (std::size_t i = 0; i < source_.pins.size(); ++i)
      text += std::string("net v") + std::to_string(i) + " source.v" + std::to_string(i) +
              " => c." + (joint ? "joint-" : "tcp-") + in[i] + "\n";
    if (joint) text += "setp c.z-rot-point 5\nsetp c.tool-offset 10\n";
    text += "addf c.update servo-thread\n";
    rt::hal::load_hal_text(*hal_, text, "cycle_path.hal");
    ex_ = std::make_unique<rt::hal::Executor>(*hal_);

    cycles(200);  // faded in
    if (path == CyclePath::kCrossFade) {
      // Field B over the same file, read and published by a reload; adopted
      // by the next cycle and cross-faded over 10 s.
      write_field(file, cycle_path_field(-1.5));
      hal_->set_pin_or_param("c.reload", "1");
      cycles(1);
      hal_->run_services();
      hal_->set_pin_or_param("c.fade-time", std::to_string(fade_time_s));
      cycles(20);
    } else if (path == CyclePath::kFault) {
      hal_->set_pin_or_param("c.fade-time", std::to_string(fade_time_s));
      outside_ = true;
      cycles(20);
    }
  }

  // Writes the inputs of cycle `i`: the TCP (or X, Y, Z) on a 20 mm circle,
  // A tilting by +-30 deg, C turning 0.36 deg a cycle; outside the grid
  // (x > 100 mm) on the fault path.
  void drive(uint64_t i) noexcept {
    const double t = double(i) * 1e-3;
    const double w = 2.0 * M_PI * 0.5;
    *source_.pins[0] = (outside_ ? 100.0 : 0.0) + 20.0 * std::cos(w * t);
    *source_.pins[1] = 20.0 * std::sin(w * t);
    *source_.pins[2] = 5.0 * std::sin(0.5 * w * t);
    if (source_.pins.size() == 5) {
      *source_.pins[3] = 30.0 * std::sin(w * t);
      *source_.pins[4] = std::fmod(360.0 * t, 360.0);
    }
  }

  // One servo cycle (inputs, then the thread's functions).
  void cycle() noexcept {
    drive(n_++);
    ex_->step();
  }
  void cycles(uint64_t n) noexcept {
    for (uint64_t i = 0; i < n; ++i)
      cycle();
  }

  // Empty when the component is in the state the path names, else why not.
  std::string check() const {
    const int32_t fault = hal_->get_pin_or_param("c.fault").s;
    const double fade = hal_->get_pin_or_param("c.fade").f;
    const int32_t generation = hal_->get_pin_or_param("c.field-generation").s;
    const bool active = hal_->get_pin_or_param("c.active").b;
    const std::string state = "fault " + std::to_string(fault) + ", fade " + std::to_string(fade) +
                              ", generation " + std::to_string(generation) + ", active " +
                              std::to_string(active);
    bool ok = active;
    switch (path_) {
      case CyclePath::kPlain:
      case CyclePath::kJoint:
        ok = ok && fault == 0 && fade == 1.0 && generation == 1;
        break;
      case CyclePath::kJointTilt:
        ok = ok && fault == 0 && fade == 1.0 && generation == 1 &&
             hal_->get_pin_or_param("c.tilt-mag").f > 0.0;
        break;
      case CyclePath::kCrossFade:
        ok = ok && fault == 0 && fade > 0.0 && fade < 1.0 && generation == 2;
        break;
      case CyclePath::kFault:
        ok = ok && fault == 3 && fade > 0.0 && fade < 1.0;
        break;
    }
    return ok ? std::string() : std::string(cycle_path_name(path_)) + ": " + state;
  }

  rt::hal::Hal& hal() { return *hal_; }
  rt::hal::Executor& executor() { return *ex_; }

 private:
  CyclePath path_;
  Source source_;
  std::unique_ptr<rt::hal::Hal> hal_;
  std::unique_ptr<rt::hal::Executor> ex_;
  bool outside_ = false;
  uint64_t n_ = 0;
};

}  // namespace truecut::test::comp
