#include "truecut/offline/field_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <variant>

#include <sys/resource.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "fit_with_rotation.hpp"
#include "spatial/shared_scan_tree.hpp"
#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/compensation_significance.hpp"
#include "truecut/offline/ray_scene.hpp"
#include "truecut/offline/rigid_transform.hpp"
#include "truecut/offline/surfaces.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::offline {

namespace {

using Clock = std::chrono::steady_clock;

// Stage times and progress. Stages of the two chains run concurrently (see
// run_field_pipeline), so each stage is timed from its own start, reports
// are serialised, and the stages are listed in the fixed order of the
// pipeline whatever order they finish in.
class StageTimer {
 public:
  StageTimer(FieldPipelineResult& r, const PipelineProgress& p) : result_(r), progress_(p) {}
  Clock::time_point now() const { return Clock::now(); }
  void done(int order, Clock::time_point started, const std::string& name,
            const std::string& detail = {}) {
    const double s = std::chrono::duration<double>(Clock::now() - started).count();
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const double rss_mb = double(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
    std::lock_guard lock(mutex_);
    timed_.push_back({order, {name, s, rss_mb}});
    if (progress_) progress_(name, s, detail + rt::format_printf("  [peak %.0f MB]", rss_mb));
  }
  void finish() {
    std::stable_sort(timed_.begin(), timed_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [order, stage] : timed_)
      result_.stages.push_back(std::move(stage));
    result_.total_wall_s = std::chrono::duration<double>(Clock::now() - start_).count();
  }

 private:
  FieldPipelineResult& result_;
  const PipelineProgress& progress_;
  std::mutex mutex_;
  std::vector<std::pair<int, StageTime>> timed_;
  Clock::time_point start_ = Clock::now();
};

// The order stages are listed in.
enum StageOrder : int {
  kRegistrationStage,
  kPointsStage,
  kSceneStage,
  kScanCheckStage,
  kErrorStage,
  kSignificanceStage,
  kVertexErrorStage,
  kTrussStage,
  kPathStage,
  kPlacementStage,
  kFitStage,
};

bool selected(const std::vector<std::int32_t>& surfaces, std::int32_t id) {
  return surfaces.empty() || std::find(surfaces.begin(), surfaces.end(), id) != surfaces.end();
}

// The truss separately on every compensated surface, on that surface's
// vertices only: bars across a sharp edge would mix the normal components of
// two faces (on a square shaft they pulled the valid vertices' compensation
// 18 % short). A vertex on an edge gets the mean of its surfaces' results;
// every other vertex its own surface's. Surfaces are solved in parallel and
// merged in the order of their ids.
struct SurfaceTruss {
  std::vector<std::uint32_t> vertices;  // ascending; local index = position
  TrussResult result;
};
using SurfaceTrusses = std::map<std::int32_t, SurfaceTruss>;

// A vertex's displacement in its surface's own truss; false when the
// surface's truss does not support it.
bool surface_displacement(const SurfaceTrusses& trusses, std::int32_t surface, std::uint32_t v,
                          Eigen::Vector3d& d) {
  const auto it = trusses.find(surface);
  if (it == trusses.end()) return false;
  const auto& list = it->second.vertices;
  const auto at = std::lower_bound(list.begin(), list.end(), v);
  if (at == list.end() || *at != v) return false;
  const std::size_t local = static_cast<std::size_t>(at - list.begin());
  if (!it->second.result.supported[local]) return false;
  d = it->second.result.displacement_mm[local];
  return true;
}

TrussResult smooth_per_surface(const TriangleMesh& nominal, const std::vector<std::int32_t>& ids,
                               const std::vector<std::int32_t>& surfaces,
                               const std::vector<Eigen::Vector3d>& vectors,
                               const std::vector<std::uint8_t>& valid, const TrussOptions& o,
                               SurfaceTrusses& per_surface) {
  std::map<std::int32_t, std::vector<std::uint32_t>> triangles_of;
  for (std::size_t t = 0; t < nominal.triangles.size(); ++t)
    if (selected(surfaces, ids[t])) triangles_of[ids[t]].push_back(static_cast<std::uint32_t>(t));
  using Surface = SurfaceTruss;
  std::vector<Surface> parts(triangles_of.size());
  std::vector<const std::vector<std::uint32_t>*> tris;
  for (const auto& [id, list] : triangles_of)
    tris.push_back(&list);
  const std::size_t nv = nominal.vertices_mm.size();
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t k) {
    Surface& part = parts[k];
    for (std::uint32_t t : *tris[k])
      for (std::uint32_t v : nominal.triangles[t])
        part.vertices.push_back(v);
    std::sort(part.vertices.begin(), part.vertices.end());
    part.vertices.erase(std::unique(part.vertices.begin(), part.vertices.end()),
                        part.vertices.end());
    std::vector<std::uint32_t> local(nv, 0);
    const std::size_t n = part.vertices.size();
    std::vector<Eigen::Vector3d> positions(n), v(n);
    std::vector<std::uint8_t> ok(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t g = part.vertices[i];
      local[g] = static_cast<std::uint32_t>(i);
      positions[i] = nominal.vertices_mm[g];
      v[i] = vectors[g];
      ok[i] = valid[g];
    }
    std::vector<Triangle> triangles;
    triangles.reserve(tris[k]->size());
    for (std::uint32_t t : *tris[k]) {
      const Triangle& g = nominal.triangles[t];
      triangles.push_back({local[g[0]], local[g[1]], local[g[2]]});
    }
    part.result = smooth_truss(positions, triangles, v, ok, o);
  });
  TrussResult out;
  out.displacement_mm.assign(nv, Eigen::Vector3d::Zero());
  std::vector<int> count(nv, 0);
  std::vector<std::uint8_t> used(nv, 0);
  for (const Surface& part : parts) {
    out.edge_count += part.result.edge_count;
    for (std::size_t i = 0; i < part.vertices.size(); ++i) {
      const std::uint32_t g = part.vertices[i];
      used[g] = 1;
      if (!part.result.supported[i]) continue;
      out.displacement_mm[g] += part.result.displacement_mm[i];
      ++count[g];
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
  std::size_t k = 0;
  for (const auto& entry : triangles_of)
    per_surface[entry.first] = std::move(parts[k++]);
  return out;
}

// Truss smoothing of the vertex compensation, the adapted mesh and the
// vectors the field is fitted to.
// The machine's error alone: the measured error minus the expected cut's
// (FieldPipelineInputs::expected), point by point along the same normal. A
// point the expected cut gives no vector for becomes invalid with its
// status and loses its scan support (which only valid points carry).
void subtract_expected(ErrorVectors& e, const ErrorVectors& expected) {
  std::vector<std::uint32_t> begin{0}, point;
  std::vector<float> weight;
  begin.reserve(e.size() + 1);
  point.reserve(e.support_point.size());
  weight.reserve(e.support_weight.size());
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (e.valid(i) && !expected.valid(i)) {
      e.status[i] = expected.status[i];
      e.vectors_mm[i].setZero();
      e.normal_mm[i] = 0.0;
    } else if (e.valid(i)) {
      e.vectors_mm[i] -= expected.vectors_mm[i];
      e.normal_mm[i] -= expected.normal_mm[i];
      for (std::uint32_t k = e.support_begin[i]; k < e.support_begin[i + 1]; ++k) {
        point.push_back(e.support_point[k]);
        weight.push_back(e.support_weight[k]);
      }
    }
    begin.push_back(static_cast<std::uint32_t>(point.size()));
  }
  e.support_begin = std::move(begin);
  e.support_point = std::move(point);
  e.support_weight = std::move(weight);
}

// On a σ 20 µm scan of a plate meshed at 1 mm (41 × 21 vertices) the truss
// at sampled points leaves 4.4 µm in the matrix where the raw mirror left
// 6.9 µm (FieldPipeline.MatrixTheRewriterReadsIsSmoothed). On the implant's
// 1.6 mm shaft top (9 measured vertices of 25, about 256 sampled points) the
// few vertices carry more noise than the fit's own average of the raw
// points: the demo's second field took the CMM's RMS there from 1.7 to
// 5.5 µm; on the shaft's faces (99 measured vertices of 175) it moved the
// RMS by 0.4 µm or less each way, and the part's reduction by 0.4 %. Any
// bound between 10 and 99 separates the two; the truss is used only where it
// averages over tens of measured vertices.
constexpr int kMinMeasuredVerticesForSampledTruss = 20;

void smooth_and_adapt(const TriangleMesh& nominal, const FieldPipelineOptions& opt,
                      bool at_vertices, const CompensationMatrix& vertex_matrix, StageTimer& timer,
                      FieldPipelineResult& r) {
  const auto started = timer.now();
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
  SurfaceTrusses per_surface;
  r.truss = smooth_per_surface(nominal, r.triangle_surface_ids, opt.surfaces, vertex_vectors,
                               vertex_valid, opt.truss, per_surface);
  r.adapted = nominal;
  r.adapted.normals.clear();
  r.vertex_compensated.assign(nv, 0);
  r.max_vertex_move_mm = 0.0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!on_selected[v] || !r.truss.supported[v]) continue;
    r.adapted.vertices_mm[v] += r.truss.displacement_mm[v];
    r.vertex_compensated[v] = 1;
    r.max_vertex_move_mm = std::max(r.max_vertex_move_mm, r.truss.displacement_mm[v].norm());
  }
  // The matrix's smoothed vectors: the truss result at the point,
  // interpolated in its triangle over the vertices the truss supports.
  r.smoothed_matrix_mm.assign(r.points.size(), Eigen::Vector3d::Zero());
  std::vector<std::uint8_t> truss_at_sample(r.points.size(), 0);
  std::map<std::int32_t, int> measured_on;  // measured vertices of each surface's truss
  for (const auto& [id, truss] : per_surface)
    for (std::uint32_t v : truss.vertices)
      measured_on[id] += vertex_valid[v] != 0;
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    if (!r.matrix.valid[i] || !r.significance.compensated(r.points.surface_ids[i])) continue;
    if (at_vertices) {
      r.smoothed_matrix_mm[i] = r.truss.displacement_mm[vertex_of_point[i]];
      continue;
    }
    const Triangle& t = nominal.triangles[r.points.triangles[i]];
    const Eigen::Vector3d &a = nominal.vertices_mm[t[0]], &b = nominal.vertices_mm[t[1]],
                          &c = nominal.vertices_mm[t[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a), p = r.points.positions_mm[i];
    const double w[3] = {(c - b).cross(p - b).dot(n), (a - c).cross(p - c).dot(n),
                         (b - a).cross(p - a).dot(n)};
    // In the point's own surface's truss: at an edge the merged result mixes
    // in the neighbouring face's compensation.
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), d;
    double weight = 0.0;
    bool supported = true, measured = true;
    for (int k = 0; k < 3 && supported; ++k) {
      supported = surface_displacement(per_surface, r.points.surface_ids[i], t[k], d);
      measured = measured && vertex_valid[t[k]] != 0;
      const double wk = std::max(w[k], 0.0);
      sum += wk * d;
      weight += wk;
    }
    // A triangle the truss does not hold at every corner keeps the raw mirror.
    r.smoothed_matrix_mm[i] =
        supported && weight > 0.0 ? Eigen::Vector3d(sum / weight) : r.matrix.vectors_mm[i];
    if (supported && measured && weight > 0.0 &&
        measured_on[r.points.surface_ids[i]] >= kMinMeasuredVerticesForSampledTruss)
      truss_at_sample[i] = 1;
  }
  // Vectors for the field: at vertex points the truss-smoothed compensation;
  // at a sampled point the truss interpolated in its triangle where all three
  // corners are measured vertices of a surface whose truss holds at least
  // kMinMeasuredVerticesForSampledTruss of them, else the raw mirror (the
  // fit's regularisation alone smooths it). See the constant for why.
  r.field_vectors_mm.resize(r.points.size());
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    r.field_vectors_mm[i] = at_vertices          ? r.truss.displacement_mm[vertex_of_point[i]]
                            : truss_at_sample[i] ? r.smoothed_matrix_mm[i]
                                                 : r.matrix.vectors_mm[i];
    if (!r.matrix.valid[i] || !r.significance.compensated(r.points.surface_ids[i]))
      r.field_vectors_mm[i].setZero();
  }
  timer.done(kTrussStage, started, "truss smoothing and adapted mesh",
             rt::format_printf(opt.truss.stiffness == TrussStiffness::kAxialBars
                                   ? "kb/kc %.3g, %lld axial bars"
                                   : "kb/kc %.3g, %lld bars",
                               opt.truss.kb_over_kc, static_cast<long long>(r.truss.edge_count)));
}

// Memory per compensation point, measured on the implant (sphere method,
// `--spacing` 0.05 and 0.025: 44,544 and 178,176 points, 229 and 771 MB peak,
// 4.25 KB a point between them): its tool-centre placements and fit samples
// (about eleven passes cut each point there), its vectors and statuses,
// about 2.6 KB; and 12 bytes for each scan point of its sphere's support
// list (about 141 there). A scan point costs about 150 bytes (its copy in
// the registration, the k-d tree, the normals), a field grid node 135 bytes
// per layer while fitting.
constexpr double kBytesPerPoint = 2600.0;
constexpr double kBytesPerSupportEntry = 12.0;
constexpr double kBytesPerScanPoint = 150.0;
constexpr double kBytesPerGridNode = 135.0;

// The tools the program cuts with (feed moves), each with the line and
// operation of its first cut.
struct CuttingTool {
  int line = 0;
  std::string operation;
};
std::map<std::int32_t, CuttingTool> cutting_tools(const interp::CanonProgram& program,
                                                  const std::vector<ToolShape>& shapes) {
  std::map<std::int32_t, CuttingTool> out;
  for (const interp::CanonCall& call : program.calls) {
    if (!interp::is_motion(call.op) || std::holds_alternative<interp::StraightTraverse>(call.op))
      continue;
    const auto t = std::find_if(shapes.begin(), shapes.end(),
                                [&](const ToolShape& s) { return s.tool == call.context.tool; });
    if (t != shapes.end() && !out.count(t->tool))
      out[t->tool] = {call.context.line, call.context.operation};
  }
  return out;
}

// The base field's layers, "T1, T2" (or "none").
std::string layer_list(const rt::CorrectionField& field) {
  std::string layers;
  for (std::int32_t t : field.tools())
    layers += (layers.empty() ? "T" : ", T") + std::to_string(t);
  return layers.empty() ? "none" : layers;
}

bool has_layer(const rt::CorrectionField& field, std::int32_t tool) {
  const auto tools = field.tools();
  return std::find(tools.begin(), tools.end(), tool) != tools.end();
}

// Before any work: a base field with a layer for none of the tools the
// program cuts with (a field of another part or tool set) cannot be the one
// the scanned part was cut with. A layer missing for one tool is found at
// the fit (check_base_layer): a tool that cut no compensated surface has no
// layer in the field of the last iteration, rightly.
void check_base_layers(const FieldPipelineInputs& in) {
  if (!in.base_field) return;
  const auto tools = cutting_tools(*in.program, in.tools);
  if (tools.empty()) return;
  std::string cut;
  for (const auto& [tool, first] : tools) {
    if (has_layer(*in.base_field, tool)) return;
    cut += (cut.empty() ? "T" : ", T") + std::to_string(tool);
  }
  const auto& [tool, first] = *tools.begin();
  throw std::invalid_argument(rt::format_printf(
      "%s has no layer for any tool the program cuts with (%s; T%d first at line %d%s); its "
      "layers: %s. A base field is the field the scanned part was cut with",
      in.base_field_name.c_str(), cut.c_str(), tool, first.line,
      first.operation.empty() ? "" : (", operation '" + first.operation + "'").c_str(),
      layer_list(*in.base_field).c_str()));
}

// At the fit: a tool whose cuts carry compensation has a layer in the base
// (rewrite refuses a field without one likewise).
void check_base_layer(const FieldPipelineInputs& in, std::int32_t tool, std::size_t samples) {
  if (!in.base_field || samples == 0 || has_layer(*in.base_field, tool)) return;
  throw std::invalid_argument(rt::format_printf(
      "%s has no layer for tool %d, which cuts %zu compensated points' passes; its layers: %s. "
      "Without one the next part would get only the new increment there",
      in.base_field_name.c_str(), tool, samples, layer_list(*in.base_field).c_str()));
}

// The memory estimate (kBytesPerPoint ...) against opt.max_memory_mb.
void check_memory(const FieldPipelineInputs& in, const FieldPipelineOptions& opt, double points,
                  double nominal_area_mm2, double grid_nodes, FieldPipelineResult& r) {
  double support = 3.0;  // ray method: the corners of the hit facet
  if (opt.method == ErrorMethod::kSphere) {
    // The scan's density over the nominal's whole area, in a sphere of Rs.
    const double density = double(in.scan->vertices_mm.size()) / std::max(nominal_area_mm2, 1e-9);
    support = density * M_PI * opt.sphere.radius_mm * opt.sphere.radius_mm;
    if (opt.sphere.max_points_per_sphere > 0)
      support = std::min(support, double(opt.sphere.max_points_per_sphere));
  }
  const double layers = std::max<double>(1.0, double(cutting_tools(*in.program, in.tools).size()));
  const double bytes = points * (kBytesPerPoint + support * kBytesPerSupportEntry) +
                       double(in.scan->vertices_mm.size()) * kBytesPerScanPoint +
                       grid_nodes * layers * kBytesPerGridNode;
  r.estimated_memory_mb = bytes / double(1 << 20);
  if (r.estimated_memory_mb <= opt.max_memory_mb) return;
  throw std::invalid_argument(rt::format_printf(
      "this run would need about %.0f MB (%.3g compensation points at about %.1f KB each with "
      "%.0f scan points in each one's %s, %zu scan points, a field grid of %.3g nodes x %.0f "
      "layers), more than --max-memory-mb %.0f; choose a larger --spacing or --resolution, or "
      "raise --max-memory-mb",
      r.estimated_memory_mb, points, (kBytesPerPoint + support * kBytesPerSupportEntry) / 1024.0,
      support, opt.method == ErrorMethod::kSphere ? "sphere" : "support",
      in.scan->vertices_mm.size(), grid_nodes, layers, opt.max_memory_mb));
}

// What spacing and resolution would cost, from the nominal alone.
void check_budgets(const FieldPipelineInputs& in, const FieldPipelineOptions& opt,
                   const std::vector<std::int32_t>& ids, FieldPipelineResult& r) {
  const TriangleMesh& nominal = *in.nominal;
  double area_mm2 = 0.0, nominal_area_mm2 = 0.0;
  Eigen::AlignedBox3d box;
  std::vector<std::uint8_t> vertex_selected(nominal.vertices_mm.size(), 0);
  for (std::size_t t = 0; t < nominal.triangles.size(); ++t) {
    const auto& [a, b, c] = nominal.triangles[t];
    const Eigen::Vector3d &pa = nominal.vertices_mm[a], &pb = nominal.vertices_mm[b],
                          &pc = nominal.vertices_mm[c];
    const double facet_mm2 = 0.5 * (pb - pa).cross(pc - pa).norm();
    nominal_area_mm2 += facet_mm2;
    if (!selected(opt.surfaces, ids[t])) continue;
    area_mm2 += facet_mm2;
    box.extend(pa);
    box.extend(pb);
    box.extend(pc);
    vertex_selected[a] = vertex_selected[b] = vertex_selected[c] = 1;
  }
  double points = 0.0;
  for (std::uint8_t v : vertex_selected)
    points += v;
  if (opt.spacing_mm > 0.0) {
    points = area_mm2 / (opt.spacing_mm * opt.spacing_mm);
    if (points > opt.max_compensation_points)
      throw std::invalid_argument(rt::format_printf(
          "--spacing %g mm would place about %.3g compensation points on the %.4g mm² of the "
          "compensated surfaces, more than --max-points %.0f; choose a larger --spacing or raise "
          "--max-points",
          opt.spacing_mm, points, area_mm2, opt.max_compensation_points));
  }
  if (box.isEmpty()) return check_memory(in, opt, points, nominal_area_mm2, 0.0, r);
  // The tool centres lie about a tool radius off the surfaces they cut (a
  // flank cut holds the tip lower, which this estimate leaves out; the
  // fit's own limit of 2^26 nodes per layer stays the backstop).
  double reach_mm = 0.0;
  for (const ToolShape& t : in.tools)
    reach_mm = std::max(reach_mm, t.radius_mm);
  const double h = opt.fit.spacing_mm;
  const double margin_mm = (opt.fit.support_radius_nodes + opt.fit.fade_nodes + 2.0) * h;
  const Eigen::Vector3d extent = box.sizes();
  double nodes = 1.0;
  for (int a = 0; a < 3; ++a)
    nodes *= std::ceil((extent[a] + 2.0 * (reach_mm + margin_mm)) / h) + 1.0;
  if (nodes > opt.max_grid_nodes)
    throw std::invalid_argument(rt::format_printf(
        "--resolution %g mm gives a field grid of about %.3g nodes per layer over the compensated "
        "surfaces (%.4g x %.4g x %.4g mm plus a tool radius of %.4g mm), more than "
        "--max-grid-nodes "
        "%.0f (about 135 bytes each while fitting); choose a coarser --resolution or raise "
        "--max-grid-nodes (a field file holds at most 2^26 nodes per layer)",
        h, nodes, extent.x(), extent.y(), extent.z(), reach_mm, opt.max_grid_nodes));
  check_memory(in, opt, points, nominal_area_mm2, nodes, r);
}

// A base field that adds nothing where the part is cut (its grid elsewhere,
// or zero there) would be dropped without a word: refused.
void check_base_coverage(const FieldPipelineInputs& in, const FieldPipelineResult& r) {
  if (!in.base_field || r.base_samples == 0 || r.base_samples_corrected > 0) return;
  const rt::FieldGrid& g = in.base_field->grid();
  Eigen::Vector3d end = g.origin_mm;
  for (int k = 0; k < 3; ++k)
    end[k] += g.spacing_mm[k] * (g.dims[k] - 1);
  throw std::invalid_argument(rt::format_printf(
      "%s adds nothing at any of the %zu tool centres that cut the compensated surfaces: its "
      "grid (%g, %g, %g) .. (%g, %g, %g) mm does not reach them, or it is zero there. A base "
      "field is the field the scanned part was cut with; without one, omit --base",
      in.base_field_name.c_str(), r.base_samples, g.origin_mm.x(), g.origin_mm.y(), g.origin_mm.z(),
      end.x(), end.y(), end.z()));
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
  if (opt.method == ErrorMethod::kRay && in.scan->triangles.empty())
    throw std::invalid_argument(
        "the ray method needs a scanned mesh with faces; use the sphere method for a point cloud");
  if (in.scan->vertices_mm.empty()) throw std::invalid_argument("the scan has no points");
  if (!(opt.spacing_mm >= 0.0)) throw std::invalid_argument("spacing must not be negative");
  if (in.expected && in.expected->triangles.empty())
    throw std::invalid_argument("the expected cut has no triangles");

  FieldPipelineResult r;
  StageTimer timer(r, progress);

  // Surfaces.
  r.triangle_surface_ids =
      in.triangle_surface_ids.empty() ? segment_surfaces(nominal) : in.triangle_surface_ids;
  if (r.triangle_surface_ids.size() != nominal.triangles.size())
    throw std::invalid_argument(rt::format_printf("%zu surface ids for %zu nominal triangles",
                                                  r.triangle_surface_ids.size(),
                                                  nominal.triangles.size()));
  for (std::int32_t id : opt.surfaces) {
    if (std::find(r.triangle_surface_ids.begin(), r.triangle_surface_ids.end(), id) ==
        r.triangle_surface_ids.end())
      throw std::invalid_argument(
          rt::format_printf("surface %d does not exist in the nominal model", id));
  }
  for (std::int32_t id : opt.datum_surfaces) {
    if (std::find(r.triangle_surface_ids.begin(), r.triangle_surface_ids.end(), id) ==
        r.triangle_surface_ids.end())
      throw std::invalid_argument(
          rt::format_printf("datum surface %d does not exist in the nominal model", id));
  }
  IcpOptions icp = opt.icp;
  if (opt.register_scan && !opt.datum_surfaces.empty()) {
    icp.datum_triangles = triangles_of_surfaces(r.triangle_surface_ids, opt.datum_surfaces);
    if (icp.datum_triangles.empty())
      throw std::invalid_argument("the datum surfaces have no triangles in the nominal model");
  }

  check_budgets(in, opt, r.triangle_surface_ids, r);
  check_base_layers(in);

  // Compensation points (and, for the truss, the vertices of the compensated surfaces).
  auto started = timer.now();
  const bool at_vertices = opt.spacing_mm == 0.0;
  r.points = at_vertices
                 ? compensation_points_at_vertices(nominal, r.triangle_surface_ids, opt.surfaces)
                 : sample_compensation_points(nominal, r.triangle_surface_ids, opt.spacing_mm,
                                              opt.surfaces);
  if (r.points.size() == 0) throw std::invalid_argument("no compensation points");
  timer.done(kPointsStage, started, "compensation points",
             rt::format_printf("%zu points", r.points.size()));

  // Two chains that share nothing until the field fit run concurrently (their
  // parallel loops share the threads): the scan chain (registration and the
  // scan's ray scene, error vectors, truss, adapted mesh) and the program
  // chain (tool path, tool-centre placement). Each chain's result is the
  // same as run alone.
  std::optional<RayScene> scene;
  std::optional<RayScene> expected_scene;  // the expected cut, workpiece frame
  std::vector<Eigen::Vector3d> cloud;      // sphere method: the registered scan points
  // One k-d tree of the scan's points for the registration(s), the sphere
  // method (on the scan left in place) and the significance test's noise
  // (on a point cloud), built by the registration or when first needed.
  std::optional<spatial::KdTree> scan_tree;
  auto shared_scan_tree = [&]() -> const spatial::KdTree& {
    if (!scan_tree) scan_tree.emplace(in.scan->vertices_mm);
    return *scan_tree;
  };
  auto registration = [&] {
    if (!opt.register_scan) return;
    const auto t0 = timer.now();
    r.registration = register_scan(nominal, in.scan->vertices_mm, icp, shared_scan_tree());
    const IcpResult& g = *r.registration;
    timer.done(kRegistrationStage, t0, "registration",
               g.applied ? rt::format_printf("%d iterations, RMS %.4f -> %.4f mm", g.iterations,
                                             g.rms_before_mm, g.rms_after_mm)
                         : rt::format_printf(
                               "%d iterations; the motion found is within the scan's noise "
                               "(chi2 %.1f <= %.1f): scan left in place, RMS %.4f mm",
                               g.iterations, g.motion_chi2, g.motion_threshold, g.rms_after_mm));
  };
  // The scene is built on the scan as it is and placed by the registration
  // (RayScene::set_world_from_mesh): the scan is neither copied nor moved.
  auto build_scene = [&] {
    const auto t0 = timer.now();
    if (in.expected) expected_scene.emplace(*in.expected);
    if (opt.method == ErrorMethod::kRay) scene.emplace(*in.scan);
    if (!scene && !expected_scene) return;
    timer.done(kSceneStage, t0, "scan ray scene",
               in.expected ? rt::format_printf(
                                 "%zu + %zu faces (scan + expected cut)",
                                 opt.method == ErrorMethod::kRay ? in.scan->triangles.size() : 0,
                                 in.expected->triangles.size())
                           : rt::format_printf("%zu faces", in.scan->triangles.size()));
  };
  // Refuses (ScanMismatchError) a scan that does not belong to the nominal. A
  // scan declared in the workpiece frame is registered here only to measure
  // how far off it sits; the motion is not applied.
  auto check_scan_fits = [&] {
    if (!opt.scan_check.enabled) return;
    const auto t0 = timer.now();
    Eigen::Isometry3d scan_to_nominal = Eigen::Isometry3d::Identity(), motion = scan_to_nominal;
    if (r.registration) {
      scan_to_nominal = r.registration->scan_to_nominal;
      motion = scan_to_nominal;
    } else {
      const IcpResult found = register_scan(nominal, in.scan->vertices_mm, icp, shared_scan_tree());
      if (found.applied) motion = found.scan_to_nominal;
    }
    r.scan_check = check_scan(nominal, in.scan->vertices_mm, scan_to_nominal, motion,
                              !opt.register_scan, opt.scan_check);
    timer.done(kScanCheckStage, t0, "scan check",
               rt::format_printf("motion up to %.4f mm; %.1f %% of %zu points off the nominal",
                                 r.scan_check->motion_max_displacement_mm,
                                 r.scan_check->off_percent, r.scan_check->points_checked));
  };
  auto scan_chain = [&] {
    if (opt.concurrent_stages) {
      tbb::task_group g;
      g.run(build_scene);
      registration();
      g.wait();
    } else {
      registration();
      build_scene();
    }
    check_scan_fits();
    const auto t0 = timer.now();
    if (scene && r.registration) scene->set_world_from_mesh(r.registration->scan_to_nominal);
    if (opt.method == ErrorMethod::kSphere) {
      cloud = in.scan->vertices_mm;
      if (r.registration) transform_points(r.registration->scan_to_nominal, cloud);
    }
    auto measured_error_vectors = [&](const CompensationPoints& points) {
      if (opt.method == ErrorMethod::kRay)
        return error_vectors_by_rays(nominal, points, *scene, opt.ray);
      // The scan's own tree, queried through the registration's inverse.
      return error_vectors_by_spheres(
          nominal, points, cloud, opt.sphere, shared_scan_tree(),
          r.registration ? r.registration->scan_to_nominal : Eigen::Isometry3d::Identity());
    };
    auto error_vectors = [&](const CompensationPoints& points) {
      ErrorVectors e = measured_error_vectors(points);
      if (expected_scene)
        subtract_expected(e, error_vectors_by_rays(nominal, points, *expected_scene, opt.ray));
      return e;
    };
    r.errors = error_vectors(r.points);
    const RigidBodyFit rbm_fit = opt.method == ErrorMethod::kRay ? RigidBodyFit::kNormalComponents
                                                                 : RigidBodyFit::kFullVectors;
    if (opt.remove_rigid_body_motion) {
      const std::vector<std::uint8_t> use = r.errors.valid_mask();
      r.rigid_body_motion = fit_rigid_body_motion(r.points.positions_mm, r.errors.vectors_mm,
                                                  rbm_fit, use, r.points.normals);
      remove_rigid_body_motion(*r.rigid_body_motion, rbm_fit, r.points.positions_mm,
                               r.errors.vectors_mm, r.points.normals);
      for (std::size_t i = 0; i < r.errors.size(); ++i) {
        if (!r.errors.valid(i)) r.errors.vectors_mm[i].setZero();
        r.errors.normal_mm[i] = r.errors.vectors_mm[i].dot(r.points.normals[i]);
      }
    }
    r.error_summary = summarize(r.errors, opt.sphere.radius_mm);
    r.matrix = mirror(r.points, r.errors);
    timer.done(
        kErrorStage, t0,
        opt.method == ErrorMethod::kRay ? "error vectors (rays)" : "error vectors (spheres)",
        rt::format_printf("%zu of %zu valid", r.error_summary.valid, r.error_summary.points) +
            (r.errors.scan_fraction < 1.0
                 ? rt::format_printf("; fitted on %.1f %% of the scan (median %.0f points per "
                                     "sphere, more than --sphere-max-points %zu)",
                                     100.0 * r.errors.scan_fraction,
                                     r.error_summary.median_density_per_mm2 * M_PI *
                                         opt.sphere.radius_mm * opt.sphere.radius_mm,
                                     opt.sphere.max_points_per_sphere)
                 : std::string()) +
            (r.errors.nominal_fraction < 1.0
                 ? rt::format_printf("; planes beside the point from %.1f %% of the facets "
                                     "(median %zu per sphere, more than --sphere-max-facets %zu)",
                                     100.0 * r.errors.nominal_fraction,
                                     r.errors.median_facets_per_sphere,
                                     opt.sphere.max_facets_per_sphere)
                 : std::string()));
    const auto t_test = timer.now();
    const Eigen::Isometry3d world_from_scan =
        r.registration ? r.registration->scan_to_nominal : Eigen::Isometry3d::Identity();
    r.significance =
        in.scan->triangles.empty()
            ? test_compensation_significance(r.points, r.errors, *in.scan, world_from_scan,
                                             opt.significance, shared_scan_tree())
            : test_compensation_significance(r.points, r.errors, *in.scan, world_from_scan,
                                             opt.significance);
    std::size_t kept = 0;
    for (const SurfaceSignificance& s : r.significance.surfaces)
      kept += s.compensated ? 1 : 0;
    timer.done(
        kSignificanceStage, t_test, "significance test",
        rt::format_printf("noise %.4f mm; %zu of %zu surfaces compensated",
                          r.significance.pooled_noise_mm, kept, r.significance.surfaces.size()));

    // Vertex compensation for the truss: the same points in vertex mode, a
    // second pass at the vertices of the compensated surfaces otherwise.
    CompensationMatrix vertex_matrix;
    if (at_vertices) {
      vertex_matrix = r.matrix;
    } else {
      const auto t1 = timer.now();
      const CompensationPoints vp =
          compensation_points_at_vertices(nominal, r.triangle_surface_ids, opt.surfaces);
      ErrorVectors ve = error_vectors(vp);
      if (r.rigid_body_motion) {
        remove_rigid_body_motion(*r.rigid_body_motion, rbm_fit, vp.positions_mm, ve.vectors_mm,
                                 vp.normals);
        for (std::size_t i = 0; i < ve.size(); ++i)
          if (!ve.valid(i)) ve.vectors_mm[i].setZero();
      }
      vertex_matrix = mirror(vp, ve);
      vertex_matrix.surface_ids = vp.surface_ids;
      timer.done(kVertexErrorStage, t1, "vertex error vectors",
                 rt::format_printf("%zu vertices", vp.size()));
    }
    // A surface whose measured error the scan's noise explains gets no
    // compensation: its vectors become zero, and stay in the truss and the
    // fit as measured points (so a neighbouring surface's correction does
    // not spread onto it).
    for (std::size_t i = 0; i < vertex_matrix.size(); ++i)
      if (!r.significance.compensated(vertex_matrix.surface_ids[i]))
        vertex_matrix.vectors_mm[i].setZero();
    FieldPipelineOptions smoothing = opt;
    const double noise_mm = r.significance.pooled_noise_mm;
    if (opt.truss_reference_noise_mm > 0.0 && noise_mm > opt.truss_reference_noise_mm) {
      const double ratio = noise_mm / opt.truss_reference_noise_mm;
      smoothing.truss.kb_over_kc = opt.truss.kb_over_kc * ratio * ratio;
    }
    r.truss_kb_over_kc = smoothing.truss.kb_over_kc;
    smooth_and_adapt(nominal, smoothing, at_vertices, vertex_matrix, timer, r);
  };
  auto program_chain = [&] {
    auto t0 = timer.now();
    r.path = sample_tool_path(*in.program, opt.path);
    timer.done(kPathStage, t0, "tool path",
               rt::format_printf("%zu samples", r.path.samples.size()));
    t0 = timer.now();
    r.placement = place_at_tool_centre(r.points.positions_mm, r.points.normals, r.path, in.tools,
                                       opt.placement);
    timer.done(
        kPlacementStage, t0, "tool-centre placement",
        rt::format_printf("%lld of %zu points cut by no tool",
                          static_cast<long long>(r.placement.uncut_points), r.points.size()));
  };
  if (opt.concurrent_stages) {
    tbb::task_group chains;
    chains.run(program_chain);
    try {
      scan_chain();
    } catch (...) {
      // The program chain is left to finish (it holds references to this
      // frame); cancelling the group here crashed oneTBB 2021.8.
      chains.wait();
      throw;
    }
    chains.wait();
  } else {
    scan_chain();
    program_chain();
  }

  // Field fit.
  started = timer.now();
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
        if (b.status == rt::FieldStatus::kOk) s.vector_mm += b.correction_mm;
        ++r.base_samples;
        if (b.status != rt::FieldStatus::kOk) ++r.base_samples_outside;
        if (b.status == rt::FieldStatus::kOk && b.correction_mm.squaredNorm() > 0.0)
          ++r.base_samples_corrected;
      }
      s.surface_id = r.points.surface_ids[pp.point];
      // What the scan measured: along the normal (rays; spheres on one
      // plane), or the whole vector (spheres at an edge or corner).
      s.along_normal_only =
          r.errors.sphere_case.empty() || r.errors.sphere_case[pp.point] == SphereCase::kSurface;
      max_field = std::max(max_field, s.vector_mm.norm());
      ts.samples.push_back(s);
    }
    check_base_layer(in, ts.tool, ts.samples.size());
    fit_samples += ts.samples.size();
    r.tool_samples.push_back(std::move(ts));
  }
  if (fit_samples == 0)
    throw std::invalid_argument(
        "no valid compensation point is cut by any tool of the program: nothing to fit");
  check_base_coverage(in, r);
  // A base field that turns the tool keeps doing so in the next iteration.
  if (opt.tool_rotation || (in.base_field != nullptr && in.base_field->has_rotation())) {
    r.fit = fit_with_tool_rotation(r, in, opt);
  } else {
    r.fit = fit_correction_field(r.tool_samples, opt.fit);
  }
  timer.done(kFitStage, started, "field fit",
             rt::format_printf("%zu samples, %zu layers, %d x %d x %d nodes", fit_samples,
                               r.fit->layers.size(), r.fit->field.grid().dims[0],
                               r.fit->field.grid().dims[1], r.fit->field.grid().dims[2]));

  // Where a tool cuts the point, the matrix holds what the field applies
  // there: the mean of its correction (less the base field's) over the
  // passes that cut it, the scan's noise smoothed as in the field.
  // The field is evaluated once per path sample (a sample cuts several
  // points: its placements share the tool centre), in parallel; the sums
  // are taken in the placements' order.
  {
    const std::size_t n = r.points.size();
    std::vector<Eigen::Vector3d> sum(n, Eigen::Vector3d::Zero());
    std::vector<int> count(n, 0);
    constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> slot_of_sample(r.path.samples.size(), kUnused);
    std::vector<const PointPlacement*> first;  // per slot: a placement at that sample
    std::vector<std::uint8_t> ok;
    std::vector<Eigen::Vector3d> value;
    for (const ToolPlacement& tp : r.placement.tools) {
      auto counted = [&](const PointPlacement& pp) {
        return r.matrix.valid[pp.point] &&
               r.significance.compensated(r.points.surface_ids[pp.point]);
      };
      first.clear();
      for (const PointPlacement& pp : tp.points) {
        if (!counted(pp) || slot_of_sample[pp.sample] != kUnused) continue;
        slot_of_sample[pp.sample] = static_cast<std::uint32_t>(first.size());
        first.push_back(&pp);
      }
      ok.assign(first.size(), 0);
      value.assign(first.size(), Eigen::Vector3d::Zero());
      tbb::parallel_for(std::size_t{0}, first.size(), [&](std::size_t k) {
        const Eigen::Vector3d& tcp = first[k]->tcp_mm;
        const rt::FieldSample f = r.fit->field.evaluate(tp.tool, tcp);
        if (f.status != rt::FieldStatus::kOk) return;
        Eigen::Vector3d v = f.correction_mm;
        if (in.base_field) {
          const rt::FieldSample b = in.base_field->evaluate(tp.tool, tcp);
          if (b.status == rt::FieldStatus::kOk) v -= b.correction_mm;
        }
        value[k] = v;
        ok[k] = 1;
      });
      for (const PointPlacement& pp : tp.points) {
        if (!counted(pp)) continue;
        const std::uint32_t k = slot_of_sample[pp.sample];
        if (!ok[k]) continue;
        sum[pp.point] += value[k];
        ++count[pp.point];
      }
      for (const PointPlacement* pp : first)
        slot_of_sample[pp->sample] = kUnused;
    }
    for (std::size_t i = 0; i < n; ++i)
      if (count[i] > 0) r.smoothed_matrix_mm[i] = sum[i] / count[i];
  }

  const std::vector<std::uint8_t> valid = r.errors.valid_mask();
  r.error_statistics = vector_statistics(r.errors.vectors_mm, valid, r.points.normals);
  r.compensation_statistics = vector_statistics(r.field_vectors_mm, valid, r.points.normals);
  r.max_correction_mm = std::max(max_field, r.max_vertex_move_mm);
  if (r.registration && r.registration->applied) {
    r.registration_max_displacement_mm =
        max_displacement_on_mesh_mm(nominal, r.registration->scan_to_nominal);
    r.registration_absorbed_beyond_noise =
        opt.datum_surfaces.empty() &&
        r.registration_max_displacement_mm > r.significance.pooled_noise_mm;
  }
  timer.finish();
  return r;
}

}  // namespace truecut::offline
