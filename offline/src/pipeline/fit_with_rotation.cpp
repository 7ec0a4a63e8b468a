#include "fit_with_rotation.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace truecut::offline {

FieldFitResult fit_with_tool_rotation(FieldPipelineResult& r, const FieldPipelineInputs& in,
                                      const FieldPipelineOptions& opt) {
  const auto base_rotation = [&](std::int32_t tool, const Eigen::Vector3d& at_mm) {
    if (in.base_field == nullptr || !in.base_field->has_rotation()) return Eigen::Vector3d(0, 0, 0);
    const rt::FieldSample b = in.base_field->evaluate(tool, at_mm);
    return b.status == rt::FieldStatus::kOk ? Eigen::Vector3d(b.rotation_rad)
                                            : Eigen::Vector3d(0, 0, 0);
  };
  // The rotation per tool-path sample (zero where its slope is within the
  // noise), then its field, then each point's translation at the tip under
  // the rotation that field gives at its sample: the two fields agree on
  // what the flank does where the fit has blended neighbouring rotations.
  std::vector<ToolSamples> rotation_samples;
  std::vector<std::vector<PlacedVector>> placed_per_tool;
  for (std::size_t t = 0; t < r.placement.tools.size(); ++t) {
    const ToolPlacement& tp = r.placement.tools[t];
    ToolSamples& ts = r.tool_samples[t];
    // ts.samples holds the valid points of tp.points, in order.
    std::vector<PlacedVector> placed;
    placed.reserve(ts.samples.size());
    std::size_t k = 0;
    for (const PointPlacement& pp : tp.points) {
      if (!r.matrix.valid[pp.point]) continue;
      PlacedVector p;
      p.sample = pp.sample;
      p.tcp_mm = pp.tcp_mm;
      p.axis = pp.axis;
      p.c_deg = r.path.samples[pp.sample].c_deg;
      p.point_mm = r.points.positions_mm[pp.point];
      p.normal = r.points.normals[pp.point];
      p.vector_mm = ts.samples[k++].vector_mm;
      placed.push_back(p);
    }
    const ToolRotationEstimate e = estimate_tool_rotation(placed, opt.rotation);
    r.rotation_tilted_samples += e.tilted_samples;
    r.rotation_insignificant_samples += e.insignificant_samples;
    r.rotation_cut_samples += e.cut_samples;
    r.rotation_max_left_out_rad = std::max(r.rotation_max_left_out_rad, e.max_left_out_rad);
    ToolSamples rs;
    rs.tool = ts.tool;
    rs.samples = e.rotations;
    // A base field's rotation is kept: the scan measures what is left of
    // the slope on top of it.
    if (in.base_field != nullptr && in.base_field->has_rotation())
      for (FitSample& rot : rs.samples)
        rot.vector_mm += base_rotation(ts.tool, rot.position_mm);
    rotation_samples.push_back(std::move(rs));
    placed_per_tool.push_back(std::move(placed));
  }
  const FieldFitResult rotation = fit_correction_field(rotation_samples, opt.fit);
  for (std::size_t t = 0; t < placed_per_tool.size(); ++t) {
    ToolSamples& ts = r.tool_samples[t];
    std::unordered_map<std::uint32_t, Eigen::Vector3d> at_sample;
    const std::vector<Eigen::Vector3d> tip = translations_at_tip(
        std::span<const PlacedVector>(placed_per_tool[t]), [&](const PlacedVector& p) {
          auto [it, fresh] = at_sample.try_emplace(p.sample);
          if (fresh) {
            const rt::FieldSample f = rotation.field.evaluate(ts.tool, p.tcp_mm);
            // The translations carry the base's translation, and the flank
            // the base's rotation already: only the new part of the
            // rotation comes off them.
            it->second =
                (f.status == rt::FieldStatus::kOk
                     ? realisable_rotation(f.vector_mm, p.axis, p.c_deg, opt.rotation.kinematics)
                     : Eigen::Vector3d::Zero()) -
                base_rotation(ts.tool, p.tcp_mm);
          }
          return it->second;
        });
    for (std::size_t i = 0; i < tip.size(); ++i)
      ts.samples[i].vector_mm = tip[i];
  }
  FieldFitResult translation = fit_correction_field(r.tool_samples, opt.fit);
  const rt::FieldGrid& g = translation.field.grid();
  const rt::FieldGrid& gr = rotation.field.grid();
  if (g.dims != gr.dims || g.origin_mm != gr.origin_mm || g.spacing_mm != gr.spacing_mm)
    throw std::logic_error("tool rotation: the rotation's grid differs from the translation's");
  std::vector<rt::FieldLayer> layers;
  for (const int32_t tool : translation.field.tools()) {
    rt::FieldLayer l;
    l.tool = tool;
    const auto nodes = translation.field.nodes(tool);
    l.nodes.assign(nodes.begin(), nodes.end());
    const auto rot = rotation.field.nodes(tool);
    l.rotation_rad.reserve(rot.size());
    for (const rt::FieldNode& n : rot)
      l.rotation_rad.emplace_back(n.dx_mm, n.dy_mm, n.dz_mm);
    layers.push_back(std::move(l));
  }
  return FieldFitResult{
      rt::CorrectionField(g, std::move(layers), translation.field.interpolation()),
      std::move(translation.layers)};
}

}  // namespace truecut::offline
