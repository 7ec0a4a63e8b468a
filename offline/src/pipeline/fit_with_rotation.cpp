#include "fit_with_rotation.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace truecut::offline {

FieldFitResult fit_with_tool_rotation(FieldPipelineResult& r, const FieldPipelineInputs& in,
                                      const FieldPipelineOptions& opt) {
  std::vector<ToolSamples> rotation_samples;
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
    r.rotation_cut_samples += e.cut_samples;
    r.rotation_max_left_out_rad = std::max(r.rotation_max_left_out_rad, e.max_left_out_rad);
    for (std::size_t i = 0; i < placed.size(); ++i)
      ts.samples[i].vector_mm = e.translations_mm[i];
    ToolSamples rs;
    rs.tool = ts.tool;
    rs.samples = e.rotations;
    if (in.base_field != nullptr && in.base_field->has_rotation())
      for (FitSample& s : rs.samples) {
        const rt::FieldSample b = in.base_field->evaluate(ts.tool, s.position_mm);
        if (b.status == rt::FieldStatus::kOk) s.vector_mm += b.rotation_rad;
      }
    rotation_samples.push_back(std::move(rs));
  }
  FieldFitResult translation = fit_correction_field(r.tool_samples, opt.fit);
  const FieldFitResult rotation = fit_correction_field(rotation_samples, opt.fit);
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
