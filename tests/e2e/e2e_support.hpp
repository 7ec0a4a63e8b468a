// Shared by the end-to-end suites: a coarse implant written to disk,
// synthetic correction fields as .tcf files, and soft-CNC jobs on the part's
// ideal machine.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "test_paths.hpp"
#include "truecut/rt/core/correction_field.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace truecut::test::e2e {

// Coarse options: a small, fast part (the cutting component's own tests use
// the same resolution).
inline sim::PartOptions coarse_options(double step_down_mm = 2.0) {
  sim::PartOptions o;
  o.mesh_edge_mm = 0.25;
  o.stepover_mm = 0.8;
  o.point_spacing_mm = 1.0;
  o.step_down_mm = step_down_mm;
  return o;
}

// The correction (mm, workpiece frame) as a function of position.
using CorrectionFn = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;

// A field with a layer for every tool of the part, validity 1 on every node,
// on a grid that covers the whole machine envelope (so the tool never leaves
// it); node vectors sampled from `fn`. A constant or linear `fn` is
// reproduced exactly between the nodes (the interpolating cubic B-spline
// reproduces linear functions).
inline void write_synthetic_field(const std::filesystem::path& file, const sim::BenchmarkPart& part,
                                  const CorrectionFn& fn) {
  rt::FieldGrid g;
  g.origin_mm = Eigen::Vector3d::Constant(-500.0);
  g.spacing_mm = Eigen::Vector3d::Constant(50.0);
  g.dims = {21, 21, 21};
  std::vector<rt::FieldLayer> layers;
  for (const auto& tool : part.metadata.tools) {
    rt::FieldLayer l;
    l.tool = tool.number;
    l.nodes.resize(static_cast<std::size_t>(g.node_count()));
    for (int32_t k = 0; k < g.dims[2]; ++k)
      for (int32_t j = 0; j < g.dims[1]; ++j)
        for (int32_t i = 0; i < g.dims[0]; ++i) {
          const Eigen::Vector3d v = fn(g.node_position_mm(i, j, k));
          l.nodes[static_cast<std::size_t>(g.index(i, j, k))] = {v.x(), v.y(), v.z(), 1.0};
        }
    layers.push_back(std::move(l));
  }
  rt::write_field_file(file, rt::CorrectionField(g, std::move(layers)),
                       {"2026-11-22T00:00:00Z", "truecut e2e test: synthetic field"});
}

// A job machining `part_dir`'s program on its ideal machine (every physics
// effect off), so the only deviation the field adds is the field's.
inline sim::SoftCncJob ideal_job(const std::filesystem::path& part_dir,
                                 const std::filesystem::path& out_dir) {
  sim::SoftCncJob job = sim::part_folder_job(part_dir, out_dir, "machine_ideal.json");
  job.component_path = {component_dir()};
  return job;
}

}  // namespace truecut::test::e2e
