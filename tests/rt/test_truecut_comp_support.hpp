// Shared by the truecut_comp suites: synthetic fields, HAL set-up, and a
// capture component that copies pins into preallocated memory each cycle.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "test_paths.hpp"
#include "truecut/rt/core/correction_field.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/rt/hal.hpp"

namespace truecut::test::comp {

// The stored vector of the synthetic field at a node position (mm).
inline Eigen::Vector3d synthetic_vector(int32_t tool, double scale, const Eigen::Vector3d& p) {
  const double t = tool;
  return scale * Eigen::Vector3d(0.10 * std::sin(0.11 * p.x() + 0.7 * t) + 0.02 * t,
                                 0.08 * std::cos(0.13 * p.y() - 0.5 * t),
                                 0.05 * std::sin(0.07 * (p.x() + p.y() + p.z()) + t));
}

// The stored tool rotation (rad) of the synthetic field at a node position
// (mm): a few mrad, varying smoothly.
inline Eigen::Vector3d synthetic_rotation(int32_t tool, double scale, const Eigen::Vector3d& p) {
  const double t = tool;
  return scale * Eigen::Vector3d(2e-3 * std::sin(0.09 * p.y() + 0.3 * t),
                                 -1.5e-3 * std::cos(0.12 * p.x() - 0.4 * t),
                                 1e-3 * std::sin(0.05 * p.z() + t));
}

// The A/C table-table kinematics the joint-mode tests use (pivots off the
// origin, a tool length), and the same as `setp` lines for an instance `c`.
inline rt::AcTrtParams joint_test_kinematics() {
  rt::AcTrtParams k;
  k.x_rot_point_mm = 5;
  k.y_rot_point_mm = -3;
  k.z_rot_point_mm = 20;
  k.z_offset_mm = -12;
  k.tool_length_mm = 50;
  return k;
}
inline constexpr const char* kJointTestKinematicsHal =
    "setp c.x-rot-point 5\nsetp c.y-rot-point -3\nsetp c.z-rot-point 20\n"
    "setp c.z-offset -12\nsetp c.tool-offset 50\n";

// The joint inputs of an instance `c` (x y z mm, a c deg).
inline constexpr const char* kJointInputPins[] = {"joint-x", "joint-y", "joint-z", "joint-a",
                                                  "joint-c"};

struct FieldSpec {
  std::vector<int32_t> tools{1, 2};
  double scale = 1.0;  // multiplies every vector
  // Weight 0 on the two outermost node layers, 1 inside: the correction goes
  // to zero smoothly before the grid ends.
  bool fading_border = false;
  Eigen::Vector3d origin_mm{-20.0, -20.0, -10.0};
  std::array<int32_t, 3> dims{9, 9, 5};
  double spacing_mm = 5.0;
  rt::FieldInterpolation interpolation = rt::FieldInterpolation::kTricubicBspline;
  // Multiplies every synthetic_rotation(); 0: the field has no rotation.
  double rotation_scale = 0.0;
};

inline rt::CorrectionField make_field(const FieldSpec& spec) {
  rt::FieldGrid g;
  g.origin_mm = spec.origin_mm;
  g.spacing_mm = Eigen::Vector3d::Constant(spec.spacing_mm);
  g.dims = spec.dims;
  std::vector<rt::FieldLayer> layers;
  for (int32_t tool : spec.tools) {
    rt::FieldLayer l;
    l.tool = tool;
    l.nodes.resize(static_cast<std::size_t>(g.node_count()));
    for (int32_t k = 0; k < g.dims[2]; ++k)
      for (int32_t j = 0; j < g.dims[1]; ++j)
        for (int32_t i = 0; i < g.dims[0]; ++i) {
          const Eigen::Vector3d v = synthetic_vector(tool, spec.scale, g.node_position_mm(i, j, k));
          auto& n = l.nodes[static_cast<std::size_t>(g.index(i, j, k))];
          n = {v.x(), v.y(), v.z(), 1.0};
          if (spec.rotation_scale != 0.0) {
            if (l.rotation_rad.empty()) l.rotation_rad.resize(l.nodes.size());
            l.rotation_rad[static_cast<std::size_t>(g.index(i, j, k))] =
                synthetic_rotation(tool, spec.rotation_scale, g.node_position_mm(i, j, k));
          }
          if (spec.fading_border) {
            auto edge = [](int32_t a, int32_t d) { return a < 2 || a > d - 3; };
            if (edge(i, g.dims[0]) || edge(j, g.dims[1]) || edge(k, g.dims[2])) n.weight = 0.0;
          }
        }
    layers.push_back(std::move(l));
  }
  return rt::CorrectionField(g, std::move(layers), spec.interpolation);
}

inline std::filesystem::path write_field(const std::filesystem::path& path, const FieldSpec& spec) {
  rt::write_field_file(path, make_field(spec), {"2026-11-21T00:00:00Z", "truecut_comp test"});
  return path;
}

inline rt::hal::HalOptions hal_options() {
  rt::hal::HalOptions o;
  o.component_path = {component_dir()};
  o.output_dir = scratch_dir();
  return o;
}

// A test component `capture` with float in pins c0..c(n-1) and function
// capture.sample, which appends their values to `samples` (reserved up front,
// so the cycle never allocates; stops at capacity).
struct Capture {
  std::vector<double*> pins;
  std::vector<double> samples;
  std::size_t capacity = 0;
  void reserve(std::size_t cycles) {
    capacity = cycles * pins.size();
    samples.clear();
    samples.reserve(capacity);
  }
};

inline Capture*& capture_slot() {
  static Capture* slot = nullptr;
  return slot;
}

inline void capture_sample(void* arg, long) {
  auto& c = *static_cast<Capture*>(arg);
  if (c.samples.size() + c.pins.size() > c.capacity) return;
  for (double* p : c.pins)
    c.samples.push_back(*p);
}

inline int capture_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  Capture& c = *capture_slot();
  const int id = api->component_new(hal, "capture");
  for (std::size_t i = 0; i < c.pins.size(); ++i)
    if (api->pin_new(hal, id, ("capture.c" + std::to_string(i)).c_str(), TC_HAL_FLOAT, TC_HAL_IN,
                     reinterpret_cast<void**>(&c.pins[i])) != 0)
      return -22;
  api->funct_new(hal, id, "capture.sample", capture_sample, &c, 1);
  return api->component_ready(hal, id);
}

// Loads `capture` with `n` pins into `hal`; `c` must outlive the HAL.
inline void load_capture(rt::hal::Hal& hal, Capture& c, std::size_t n) {
  c.pins.assign(n, nullptr);
  capture_slot() = &c;
  hal.load("capture", capture_init, nullptr);
}

}  // namespace truecut::test::comp

namespace truecut::test::comp {

// A test component `source` with float out pins v0..v(n-1) that the test
// writes directly through `pins` (setp refuses NaN and Inf; a signal does not).
struct Source {
  std::vector<double*> pins;
};

inline Source*& source_slot() {
  static Source* slot = nullptr;
  return slot;
}

inline int source_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  Source& s = *source_slot();
  const int id = api->component_new(hal, "source");
  for (std::size_t i = 0; i < s.pins.size(); ++i)
    if (api->pin_new(hal, id, ("source.v" + std::to_string(i)).c_str(), TC_HAL_FLOAT, TC_HAL_OUT,
                     reinterpret_cast<void**>(&s.pins[i])) != 0)
      return -22;
  return api->component_ready(hal, id);
}

inline void load_source(rt::hal::Hal& hal, Source& s, std::size_t n) {
  s.pins.assign(n, nullptr);
  source_slot() = &s;
  hal.load("source", source_init, nullptr);
}

}  // namespace truecut::test::comp
