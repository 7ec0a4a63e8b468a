#include "truecut/offline/field_outputs.hpp"

#include <tbb/parallel_invoke.h>
#include <nlohmann/json.hpp>

#include <stdexcept>

#include "truecut/interp/sha256.hpp"
#include "truecut/offline/compensation_matrix.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::offline {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

json vec(const Eigen::Vector3d& v) {
  return json::array({v.x(), v.y(), v.z()});
}

json stats_json(const VectorStatistics& s) {
  return {{"points", s.points},
          {"valid", s.valid},
          {"percent_invalid", s.percent_invalid},
          {"mean_vector_mm", vec(s.mean_mm)},
          {"mean_length_mm", s.mean_length_mm},
          {"rms_length_mm", s.rms_length_mm},
          {"max_length_mm", s.max_length_mm},
          {"mean_normal_mm", s.mean_normal_mm},
          {"rms_normal_mm", s.rms_normal_mm}};
}

json digest_json(const FileDigest& d) {
  return {{"role", d.role}, {"path", d.path.string()}, {"bytes", d.bytes}, {"sha256", d.sha256}};
}

json transform_json(const RigidTransformReport& t) {
  json m = json::array();
  for (int i = 0; i < 4; ++i)
    m.push_back({t.matrix(i, 0), t.matrix(i, 1), t.matrix(i, 2), t.matrix(i, 3)});
  return {{"matrix", m},
          {"translation_mm", vec(t.translation_mm)},
          {"rotation_xyz_deg", vec(t.rotation_xyz_deg)},
          {"rotation_angle_deg", t.rotation_angle_deg},
          {"rotation_axis", vec(t.rotation_axis)}};
}

json parameters_json(const FieldPipelineOptions& o, const AuditContext& c, double kb_used) {
  json tools = json::array();
  for (const ToolShape& t : c.tools)
    tools.push_back({{"tool", t.tool},
                     {"radius_mm", t.radius_mm},
                     {"corner_radius_mm", t.corner_radius_mm},
                     {"cutting_length_mm", t.cutting_length_mm}});
  const char* kernel[] = {"none", "huber", "tukey"};
  return {
      {"method", o.method == ErrorMethod::kRay ? "ray" : "sphere"},
      {"compensation_points", o.spacing_mm > 0 ? "sampled" : "vertices"},
      {"spacing_mm", o.spacing_mm},
      {"surfaces", o.surfaces},
      {"datum_surfaces", o.datum_surfaces},
      {"register_scan", o.register_scan},
      {"remove_rigid_body_motion", o.remove_rigid_body_motion},
      {"tool_rotation",
       {{"enabled", o.tool_rotation},
        {"kinematics",
         o.rotation.kinematics == RotaryKinematics::kAcTableTable ? "ac-table" : "any"},
        {"min_height_spread_mm", o.rotation.min_height_spread_mm},
        {"min_points", o.rotation.min_points},
        {"max_normal_spread_deg", o.rotation.max_normal_spread_deg},
        {"min_slope_significance", o.rotation.min_slope_significance}}},
      {"icp",
       {{"max_iterations", o.icp.max_iterations},
        {"samples", o.icp.samples},
        {"edge_margin_mm", o.icp.edge_margin_mm},
        {"sharp_edge_deg", o.icp.sharp_edge_deg},
        {"max_correspondence_mm", o.icp.max_correspondence_mm},
        {"kernel", kernel[static_cast<int>(o.icp.kernel)]},
        {"min_robust_scale_mm", o.icp.min_robust_scale_mm},
        {"significance_level", o.icp.significance_level}}},
      {"ray",
       {{"max_distance_mm", o.ray.max_distance_mm},
        {"grazing_angle_deg", o.ray.grazing_angle_deg},
        {"sharp_edge_deg", o.ray.sharp_edge_deg},
        {"edge_exclusion_mm", o.ray.edge_exclusion_mm},
        {"reject_back_faces", o.ray.reject_back_faces}}},
      {"sphere",
       {{"radius_mm", o.sphere.radius_mm},
        {"min_points", o.sphere.min_points},
        {"plane_angle_deg", o.sphere.plane_angle_deg},
        {"max_displacement_ratio", o.sphere.max_displacement_ratio},
        {"max_points_per_sphere", o.sphere.max_points_per_sphere},
        {"max_facets_per_sphere", o.sphere.max_facets_per_sphere},
        {"plane_fit", o.sphere.tilted_planes ? "tilted" : "parallel"}}},
      {"significance",
       {{"level", o.significance.significance_level},
        {"patch_mm", o.significance.patch_mm},
        {"noise_mm", o.significance.noise_mm},
        {"min_noise_points", o.significance.min_noise_points}}},
      {"truss",
       {{"kb_over_kc", o.truss.kb_over_kc},
        {"reference_noise_mm", o.truss_reference_noise_mm},
        {"kb_over_kc_used", kb_used},
        {"edge_weight",
         o.truss.edge_weight == TrussEdgeWeight::kUniform ? "uniform" : "inverse_length"},
        {"stiffness",
         o.truss.stiffness == TrussStiffness::kAxialBars ? "axial_bars" : "zero_length_springs"}}},
      {"field",
       {{"resolution_mm", o.fit.spacing_mm},
        {"smoothness", o.fit.smoothness},
        {"membrane_weight", o.fit.membrane_weight},
        {"support_radius_nodes", o.fit.support_radius_nodes},
        {"fade_nodes", o.fit.fade_nodes},
        {"refinement_iterations", o.fit.refinement_iterations}}},
      {"tool_path",
       {{"step_mm", o.path.step_mm},
        {"max_axis_step_deg", o.path.max_axis_step_deg},
        {"spline_tolerance_mm", o.path.spline_tolerance_mm}}},
      {"placement",
       {{"contact_tolerance_mm", o.placement.contact_tolerance_mm},
        {"max_normal_angle_deg", o.placement.max_normal_angle_deg},
        {"tie_mm", o.placement.tie_mm},
        {"every_generating_pass", o.placement.every_generating_pass}}},
      {"tools", tools},
      {"max_correction_mm", c.max_correction_limit_mm},
      {"force", c.forced}};
}

}  // namespace

std::string audit_json(const FieldPipelineResult& r, const FieldPipelineOptions& o,
                       const AuditContext& c, std::span<const FileDigest> outputs) {
  json j;
  j["truecut_audit"] = 1;
  j["created_utc"] = c.created_utc.empty() ? rt::utc_timestamp_now() : c.created_utc;
  j["command_line"] = c.command_line;
  j["frame"] = "workpiece";
  j["units"] = "mm";
  json in = json::array(), out = json::array();
  for (const FileDigest& d : c.inputs)
    in.push_back(digest_json(d));
  for (const FileDigest& d : outputs)
    out.push_back(digest_json(d));
  j["inputs"] = in;
  j["outputs"] = out;
  json meshes = json::array();
  for (const MeshInputAudit& m : c.meshes) {
    json dropped = json::array();
    for (const DroppedTriangle& d : m.dropped)
      dropped.push_back(
          {{"facet", d.face}, {"area_mm2", d.area_mm2}, {"longest_edge_mm", d.longest_edge_mm}});
    json topology = nullptr;
    if (m.topology) {
      const MeshTopology& t = *m.topology;
      topology = {{"edges", t.edges},
                  {"boundary_edges", t.boundary_edges},
                  {"nonmanifold_edges", t.nonmanifold_edges},
                  {"inconsistent_edges", t.inconsistent_edges},
                  {"shells", t.shells},
                  {"open_shells", t.open_shells},
                  {"nonorientable_shells", t.nonorientable_shells},
                  {"inverted_shells", t.inverted_shells},
                  {"facets_turned_round", t.flipped_triangles}};
    }
    meshes.push_back({{"role", m.role},
                      {"path", m.file.string()},
                      {"facets_in_file", m.facets_in_file},
                      {"degenerate_facets_dropped", dropped},
                      {"topology", topology}});
  }
  j["meshes"] = meshes;
  j["parameters"] = parameters_json(o, c, r.truss_kb_over_kc);
  if (r.scan_check) {
    const ScanCheck& c = *r.scan_check;
    j["scan_check"] = {{"declared_in_frame", c.declared_in_frame},
                       {"motion", transform_json(c.motion)},
                       {"motion_max_displacement_mm", c.motion_max_displacement_mm},
                       {"points_checked", c.points_checked},
                       {"points_off", c.points_off},
                       {"off_percent", c.off_percent},
                       {"off_median_distance_mm", c.off_median_distance_mm},
                       {"max_offset_mm", o.scan_check.max_offset_mm},
                       {"max_off_percent", o.scan_check.max_off_percent}};
  }
  if (r.registration) {
    const IcpResult& g = *r.registration;
    json reg = transform_json(g.transform);
    reg["iterations"] = g.iterations;
    reg["converged"] = g.converged;
    reg["samples"] = g.samples;
    reg["correspondences"] = g.correspondences;
    reg["rms_before_mm"] = g.rms_before_mm;
    reg["rms_residual_mm"] = g.rms_after_mm;
    reg["robust_scale_mm"] = g.robust_scale_mm;
    reg["determined_directions"] = g.determined_directions;
    reg["applied"] = g.applied;
    reg["motion_chi2"] = g.motion_chi2;
    reg["motion_threshold"] = g.motion_threshold;
    reg["max_displacement_mm"] = r.registration_max_displacement_mm;
    reg["absorbed_beyond_noise"] = r.registration_absorbed_beyond_noise;
    reg["datum"] = o.datum_surfaces.empty() ? "all faces" : "datum surfaces";
    j["registration"] = reg;
  } else {
    j["registration"] = nullptr;
  }
  if (r.rigid_body_motion) {
    const RigidBodyMotion& m = *r.rigid_body_motion;
    json rbm = transform_json(m.transform);
    rbm["barycentre_mm"] = vec(m.barycentre_mm);
    rbm["points_used"] = m.points_used;
    rbm["rms_before_mm"] = m.rms_before_mm;
    rbm["rms_after_mm"] = m.rms_after_mm;
    j["rigid_body_motion"] = rbm;
  } else {
    j["rigid_body_motion"] = nullptr;
  }
  json errors = stats_json(r.error_statistics);
  json by_status = json::object();
  for (int s = 0; s < 9; ++s)
    if (r.error_summary.by_status[s] > 0)
      by_status[std::string(to_string(static_cast<ErrorStatus>(s)))] = r.error_summary.by_status[s];
  errors["by_status"] = by_status;
  if (!r.errors.points_in_sphere.empty()) {
    errors["median_density_per_mm2"] = r.error_summary.median_density_per_mm2;
    errors["below_recommended_density"] = r.error_summary.below_recommended_density;
    errors["scan_fraction_used"] = r.errors.scan_fraction;
    errors["nominal_fraction_used"] = r.errors.nominal_fraction;
  }
  j["error_vectors"] = errors;
  json surfaces = json::array();
  for (const SurfaceSignificance& s : r.significance.surfaces)
    surfaces.push_back({{"surface", s.surface},
                        {"valid_points", s.valid_points},
                        {"scan_points", s.scan_points},
                        {"noise_mm", s.noise_mm},
                        {"pooled_noise", s.pooled_noise},
                        {"mean_normal_mm", s.mean_normal_mm},
                        {"mean_uncertainty_mm", s.mean_uncertainty_mm},
                        {"patches", s.patches},
                        {"chi2", s.chi2},
                        {"threshold", s.threshold},
                        {"compensated", s.compensated}});
  j["significance"] = {{"tested", r.significance.tested},
                       {"pooled_noise_mm", r.significance.pooled_noise_mm},
                       {"noise_points", r.significance.noise_points},
                       {"surfaces", surfaces}};
  j["compensation_vectors"] = stats_json(r.compensation_statistics);
  json layers = json::array();
  for (std::size_t i = 0; i < r.fit->layers.size(); ++i) {
    const FieldFitLayerStats& l = r.fit->layers[i];
    std::size_t placed = 0, points = 0;
    for (const ToolPlacement& tp : r.placement.tools) {
      if (tp.tool != l.tool) continue;
      placed = tp.points.size();
      // Ascending point index: a point placed in several passes counts once.
      for (std::size_t k = 0; k < tp.points.size(); ++k)
        if (k == 0 || tp.points[k].point != tp.points[k - 1].point) ++points;
    }
    layers.push_back({{"tool", l.tool},
                      {"points_cut", points},
                      {"placements", placed},
                      {"valid_samples", l.valid_samples},
                      {"unknown_nodes", l.unknown_nodes},
                      {"residual_rms_mm", l.residual_rms_mm},
                      {"residual_max_mm", l.residual_max_mm}});
  }
  const rt::FieldGrid& g = r.fit->field.grid();
  j["tool_path"] = {{"samples", r.path.samples.size()},
                    {"feed_moves", r.path.feed_moves},
                    {"rapid_moves", r.path.rapid_moves},
                    {"skipped_rotated_moves", r.path.skipped_rotated_moves}};
  j["placement"] = {{"points", r.points.size()}, {"uncut_points", r.placement.uncut_points}};
  if (o.tool_rotation)
    j["tool_rotation"] = {{"tilted_samples", r.rotation_tilted_samples},
                          {"samples_within_noise", r.rotation_insignificant_samples},
                          {"samples_cut_to_the_machine", r.rotation_cut_samples},
                          {"max_left_out_rad", r.rotation_max_left_out_rad}};
  j["field"] = {{"origin_mm", vec(g.origin_mm)},
                {"spacing_mm", vec(g.spacing_mm)},
                {"dims", {g.dims[0], g.dims[1], g.dims[2]}},
                {"layers", layers}};
  std::size_t moved = 0;
  double max_move = 0.0;
  for (std::size_t v = 0; v < r.vertex_compensated.size(); ++v) {
    if (!r.vertex_compensated[v]) continue;
    ++moved;
    max_move = std::max(max_move, r.truss.displacement_mm[v].norm());
  }
  j["adapted_mesh"] = {{"vertices", r.adapted.vertices_mm.size()},
                       {"vertices_moved", moved},
                       {"max_move_mm", max_move},
                       {"unsupported_vertices", r.truss.unsupported_count}};
  const bool exceeded = r.max_correction_mm > c.max_correction_limit_mm;
  j["max_correction"] = {{"limit_mm", c.max_correction_limit_mm},
                         {"max_mm", r.max_correction_mm},
                         {"exceeded", exceeded},
                         {"forced", exceeded && c.forced}};
  json stages = json::array();
  for (const StageTime& s : r.stages)
    stages.push_back({{"name", s.name}, {"wall_s", s.wall_s}, {"peak_rss_mb", s.peak_rss_mb}});
  j["stages"] = stages;
  j["total_wall_s"] = r.total_wall_s;
  // Invalid UTF-8 in a string (a Latin-1 file name or operation name) becomes
  // U+FFFD: nlohmann's default threw type_error.316 after all the work.
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::vector<FileDigest> write_field_outputs(const fs::path& dir, const FieldPipelineResult& r,
                                            const FieldPipelineOptions& o, const AuditContext& c) {
  const auto& names = kFieldOutputFiles;
  rt::StagedFiles files({dir / names[0], dir / names[1], dir / names[2], dir / names[3]}, ".new");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create the folder: " + ec.message());

  // The three files are independent: written and hashed side by side.
  const char* roles[] = {"field", "compensation_matrix", "adapted_model"};
  std::vector<FileDigest> out(3);
  auto digest = [&](int i) {
    out[i] = digest_file(roles[i], files.staged(i));
    out[i].path = files.target(i);
  };
  tbb::parallel_invoke(
      [&] {
        rt::FieldFileInfo info;
        info.source = "truecut field";
        rt::write_field_file(files.staged(0), r.fit->field, info);
        digest(0);
      },
      [&] {
        CompensationMatrix matrix = r.matrix;
        matrix.raw_vectors_mm = r.matrix.vectors_mm;
        matrix.vectors_mm = r.smoothed_matrix_mm;
        write_compensation_matrix(
            files.staged(1), matrix,
            rt::format_printf("dx,dy,dz: the mirror smoothed by the truss (kb/kc %.4g) at the "
                              "point, 0 on surfaces whose error is within the scan's noise\n"
                              "raw_dx,raw_dy,raw_dz: mirror method, -(measured - nominal)",
                              r.truss_kb_over_kc));
        digest(1);
      },
      [&] {
        write_stl(files.staged(2), r.adapted, StlEncoding::kBinary, "truecut adapted model");
        digest(2);
      });
  const std::string audit = audit_json(r, o, c, out);
  files.write(3, audit);
  files.commit();
  out.push_back({"audit", files.target(3), audit.size(), interp::sha256_hex(audit)});
  return out;
}

}  // namespace truecut::offline
