#include "truecut/offline/field_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/ray_scene.hpp"
#include "truecut/offline/rigid_transform.hpp"
#include "truecut/offline/surfaces.hpp"

namespace truecut::offline {

namespace {

using Clock = std::chrono::steady_clock;

class StageTimer {
 public:
  StageTimer(FieldPipelineResult& r, const PipelineProgress& p) : result_(r), progress_(p) {}
  void done(const std::string& name, const std::string& detail = {}) {
    const auto now = Clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    result_.stages.push_back({name, s});
    if (progress_) progress_(name, s, detail);
  }
  double total() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  FieldPipelineResult& result_;
  const PipelineProgress& progress_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point last_ = start_;
};

std::string text(const char* fmt, auto... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}

bool selected(const std::vector<std::int32_t>& surfaces, std::int32_t id) {
  return surfaces.empty() || std::find(surfaces.begin(), surfaces.end(), id) != surfaces.end();
}

ErrorVectors error_vectors(const FieldPipelineInputs& in, const FieldPipelineOptions& opt,
                           const CompensationPoints& points, const RayScene* scene,
                           const std::vector<Eigen::Vector3d>& cloud) {
  if (opt.method == ErrorMethod::ray)
    return error_vectors_by_rays(*in.nominal, points, *scene, opt.ray);
  return error_vectors_by_spheres(*in.nominal, points, cloud, opt.sphere);
}

// The truss separately on every compensated surface: bars across a sharp
// edge would mix the normal components of two faces (on a square shaft they
// pulled the valid vertices' compensation 18 % short). A vertex on an edge
// gets the mean of its surfaces' results.
TrussResult smooth_per_surface(const TriangleMesh& nominal, const std::vector<std::int32_t>& ids,
                               const std::vector<std::int32_t>& surfaces,
                               const std::vector<Eigen::Vector3d>& vectors,
                               const std::vector<std::uint8_t>& valid, const TrussOptions& o) {
  std::map<std::int32_t, std::vector<Triangle>> by_surface;
  for (std::size_t t = 0; t < nominal.triangles.size(); ++t)
    if (selected(surfaces, ids[t])) by_surface[ids[t]].push_back(nominal.triangles[t]);
  const std::size_t nv = nominal.vertices_mm.size();
  TrussResult out;
  out.displacement_mm.assign(nv, Eigen::Vector3d::Zero());
  std::vector<int> count(nv, 0);
  std::vector<std::uint8_t> used(nv, 0);
  for (const auto& [id, triangles] : by_surface) {
    const TrussResult r = smooth_truss(nominal.vertices_mm, triangles, vectors, valid, o);
    out.edge_count += r.edge_count;
    for (const Triangle& t : triangles)
      for (std::uint32_t v : t)
        used[v] = 1;
    for (std::size_t v = 0; v < nv; ++v) {
      if (!r.supported[v]) continue;
      out.displacement_mm[v] += r.displacement_mm[v];
      ++count[v];
    }
  }
  out.supported.assign(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    if (count[v] > 0) {
      out.displacement_mm[v] /= count[v];
      out.supported[v] = 1;
    } else if (used[v]) {
      ++out.unsupported_count;
    }
  }
  return out;
}

}  // namespace

VectorStatistics vector_statistics(std::span<const Eigen::Vector3d> vectors_mm,
                                   std::span<const std::uint8_t> valid,
                                   std::span<const Eigen::Vector3d> normals) {
  VectorStatistics s;
  s.points = vectors_mm.size();
  double sum_len = 0, sum_len2 = 0, sum_n = 0, sum_n2 = 0;
  for (std::size_t i = 0; i < vectors_mm.size(); ++i) {
    if (!valid[i]) continue;
    ++s.valid;
    const double len = vectors_mm[i].norm(), nc = vectors_mm[i].dot(normals[i]);
    s.mean_mm += vectors_mm[i];
    sum_len += len;
    sum_len2 += len * len;
    sum_n += nc;
    sum_n2 += nc * nc;
    s.max_length_mm = std::max(s.max_length_mm, len);
  }
  if (s.points > 0) s.percent_invalid = 100.0 * double(s.points - s.valid) / double(s.points);
  if (s.valid > 0) {
    const double n = double(s.valid);
    s.mean_mm /= n;
    s.mean_length_mm = sum_len / n;
    s.rms_length_mm = std::sqrt(sum_len2 / n);
    s.mean_normal_mm = sum_n / n;
    s.rms_normal_mm = std::sqrt(sum_n2 / n);
  }
  return s;
}

FieldPipelineResult run_field_pipeline(const FieldPipelineInputs& in,
                                       const FieldPipelineOptions& opt,
                                       const PipelineProgress& progress) {
  if (!in.nominal || !in.scan || !in.program)
    throw std::invalid_argument("field pipeline: nominal, scan and program are required");
  const TriangleMesh& nominal = *in.nominal;
  if (nominal.triangles.empty()) throw std::invalid_argument("the nominal model has no triangles");
  if (opt.method == ErrorMethod::ray && in.scan->triangles.empty())
    throw std::invalid_argument(
        "the ray method needs a scanned mesh with faces; use the sphere method for a point cloud");
  if (in.scan->vertices_mm.empty()) throw std::invalid_argument("the scan has no points");
  if (!(opt.spacing_mm >= 0.0)) throw std::invalid_argument("spacing must not be negative");

  FieldPipelineResult r;
  StageTimer timer(r, progress);

  // Surfaces.
  r.triangle_surface_ids =
      in.triangle_surface_ids.empty() ? segment_surfaces(nominal) : in.triangle_surface_ids;
  if (r.triangle_surface_ids.size() != nominal.triangles.size())
    throw std::invalid_argument(text("%zu surface ids for %zu nominal triangles",
                                     r.triangle_surface_ids.size(), nominal.triangles.size()));
  for (std::int32_t id : opt.surfaces) {
    if (std::find(r.triangle_surface_ids.begin(), r.triangle_surface_ids.end(), id) ==
        r.triangle_surface_ids.end())
      throw std::invalid_argument(text("surface %d does not exist in the nominal model", id));
  }

  // Registration: scan → workpiece frame.
  TriangleMesh scan = *in.scan;
  if (opt.register_scan) {
    IcpOptions icp = opt.icp;
    if (!opt.datum_surfaces.empty()) {
      icp.datum_triangles = triangles_of_surfaces(r.triangle_surface_ids, opt.datum_surfaces);
      if (icp.datum_triangles.empty())
        throw std::invalid_argument("the datum surfaces have no triangles in the nominal model");
    }
    r.registration = register_scan(nominal, scan.vertices_mm, icp);
    transform_points(r.registration->scan_to_nominal, scan.vertices_mm);
    timer.done("registration",
               text("%d iterations, RMS %.4f -> %.4f mm", r.registration->iterations,
                    r.registration->rms_before_mm, r.registration->rms_after_mm));
  }

  // Compensation points (and, for the truss, the vertices of the compensated surfaces).
  const bool at_vertices = opt.spacing_mm == 0.0;
  r.points = at_vertices
                 ? compensation_points_at_vertices(nominal, r.triangle_surface_ids, opt.surfaces)
                 : sample_compensation_points(nominal, r.triangle_surface_ids, opt.spacing_mm,
                                              opt.surfaces);
  if (r.points.size() == 0) throw std::invalid_argument("no compensation points");
  timer.done("compensation points", text("%zu points", r.points.size()));

  std::optional<RayScene> scene;
  if (opt.method == ErrorMethod::ray) {
    scene.emplace(scan);
    timer.done("scan ray scene", text("%zu faces", scan.triangles.size()));
  }
  r.errors = error_vectors(in, opt, r.points, scene ? &*scene : nullptr, scan.vertices_mm);
  const RigidBodyFit rbm_fit =
      opt.method == ErrorMethod::ray ? RigidBodyFit::normal_components : RigidBodyFit::full_vectors;
  if (opt.remove_rigid_body_motion) {
    const std::vector<std::uint8_t> use = r.errors.valid_mask();
    r.rigid_body_motion = fit_rigid_body_motion(r.points.positions_mm, r.errors.vectors_mm, rbm_fit,
                                                use, r.points.normals);
    remove_rigid_body_motion(*r.rigid_body_motion, rbm_fit, r.points.positions_mm,
                             r.errors.vectors_mm, r.points.normals);
    for (std::size_t i = 0; i < r.errors.size(); ++i) {
      if (!r.errors.valid(i)) r.errors.vectors_mm[i].setZero();
      r.errors.normal_mm[i] = r.errors.vectors_mm[i].dot(r.points.normals[i]);
    }
  }
  r.error_summary = summarize(r.errors, opt.sphere.radius_mm);
  r.matrix = mirror(r.points, r.errors);
  timer.done(opt.method == ErrorMethod::ray ? "error vectors (rays)" : "error vectors (spheres)",
             text("%zu of %zu valid", r.error_summary.valid, r.error_summary.points));

  // Vertex compensation for the truss: the same points in vertex mode, a
  // second pass at the vertices of the compensated surfaces otherwise.
  CompensationMatrix vertex_matrix;
  if (at_vertices) {
    vertex_matrix = r.matrix;
  } else {
    const CompensationPoints vp =
        compensation_points_at_vertices(nominal, r.triangle_surface_ids, opt.surfaces);
    ErrorVectors ve = error_vectors(in, opt, vp, scene ? &*scene : nullptr, scan.vertices_mm);
    if (r.rigid_body_motion) {
      remove_rigid_body_motion(*r.rigid_body_motion, rbm_fit, vp.positions_mm, ve.vectors_mm,
                               vp.normals);
      for (std::size_t i = 0; i < ve.size(); ++i)
        if (!ve.valid(i)) ve.vectors_mm[i].setZero();
    }
    vertex_matrix = mirror(vp, ve);
    timer.done("vertex error vectors", text("%zu vertices", vp.size()));
  }
  // Vertex indices of vertex_matrix (compensation_points_at_vertices lists
  // the vertices of the selected triangles in vertex order).
  const std::size_t nv = nominal.vertices_mm.size();
  std::vector<std::uint8_t> on_selected(nv, 0);
  for (std::size_t t = 0; t < nominal.triangles.size(); ++t) {
    if (!selected(opt.surfaces, r.triangle_surface_ids[t])) continue;
    for (std::uint32_t v : nominal.triangles[t])
      on_selected[v] = 1;
  }
  std::vector<Eigen::Vector3d> vertex_vectors(nv, Eigen::Vector3d::Zero());
  std::vector<std::uint8_t> vertex_valid(nv, 0);
  std::vector<std::uint32_t> vertex_of_point;
  for (std::size_t v = 0, k = 0; v < nv; ++v) {
    if (!on_selected[v]) continue;
    vertex_vectors[v] = vertex_matrix.vectors_mm[k];
    vertex_valid[v] = vertex_matrix.valid[k];
    vertex_of_point.push_back(static_cast<std::uint32_t>(v));
    ++k;
  }
  r.truss = smooth_per_surface(nominal, r.triangle_surface_ids, opt.surfaces, vertex_vectors,
                               vertex_valid, opt.truss);
  r.adapted = nominal;
  r.adapted.normals.clear();
  r.vertex_compensated.assign(nv, 0);
  double max_vertex_move = 0.0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!on_selected[v] || !r.truss.supported[v]) continue;
    r.adapted.vertices_mm[v] += r.truss.displacement_mm[v];
    r.vertex_compensated[v] = 1;
    max_vertex_move = std::max(max_vertex_move, r.truss.displacement_mm[v].norm());
  }
  timer.done("truss smoothing and adapted mesh", text("kb/kc %.3g, %lld bars", opt.truss.kb_over_kc,
                                                      static_cast<long long>(r.truss.edge_count)));

  // Vectors for the field.
  r.field_vectors_mm.resize(r.points.size());
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    r.field_vectors_mm[i] =
        at_vertices ? r.truss.displacement_mm[vertex_of_point[i]] : r.matrix.vectors_mm[i];
    if (!r.matrix.valid[i]) r.field_vectors_mm[i].setZero();
  }

  // Tool path and tool-centre placement.
  r.path = sample_tool_path(*in.program, opt.path);
  timer.done("tool path", text("%zu samples", r.path.samples.size()));
  r.placement = place_at_tool_centre(r.points.positions_mm, r.points.normals, r.path, in.tools,
                                     opt.placement);
  timer.done("tool-centre placement",
             text("%lld of %zu points cut by no tool",
                  static_cast<long long>(r.placement.uncut_points), r.points.size()));

  // Field fit.
  double max_field = 0.0;
  std::size_t fit_samples = 0;
  for (const ToolPlacement& tp : r.placement.tools) {
    ToolSamples ts;
    ts.tool = tp.tool;
    for (const PointPlacement& pp : tp.points) {
      if (!r.matrix.valid[pp.point]) continue;
      FitSample s;
      s.position_mm = pp.tcp_mm;
      s.normal = r.points.normals[pp.point];
      s.vector_mm = r.field_vectors_mm[pp.point];
      if (in.base_field) {
        const rt::FieldSample b = in.base_field->evaluate(tp.tool, pp.tcp_mm);
        if (b.status == rt::FieldStatus::ok) s.vector_mm += b.correction_mm;
      }
      s.surface_id = r.points.surface_ids[pp.point];
      max_field = std::max(max_field, s.vector_mm.norm());
      ts.samples.push_back(s);
    }
    fit_samples += ts.samples.size();
    r.tool_samples.push_back(std::move(ts));
  }
  if (fit_samples == 0)
    throw std::invalid_argument(
        "no valid compensation point is cut by any tool of the program: nothing to fit");
  r.fit = fit_correction_field(r.tool_samples, opt.fit);
  timer.done("field fit", text("%zu samples, %zu layers, %d x %d x %d nodes", fit_samples,
                               r.fit->layers.size(), r.fit->field.grid().dims[0],
                               r.fit->field.grid().dims[1], r.fit->field.grid().dims[2]));

  const std::vector<std::uint8_t> valid = r.errors.valid_mask();
  r.error_statistics = vector_statistics(r.errors.vectors_mm, valid, r.points.normals);
  r.compensation_statistics = vector_statistics(r.field_vectors_mm, valid, r.points.normals);
  r.max_correction_mm = std::max(max_field, max_vertex_move);
  r.total_wall_s = timer.total();
  return r;
}

}  // namespace truecut::offline
