// The closed-loop demo's HTML report.
#include "truecut/analysis/report/closed_loop_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include <tbb/parallel_for.h>
#include <Eigen/Geometry>

#include "truecut/analysis/report/deviation_image.hpp"
#include "truecut/analysis/report/svg_plots.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::report {
namespace {

const char* kStageColours[] = {"#c0392b", "#2471a3", "#7d3c98", "#1e8449", "#b9770e"};

std::string png_img(const RgbImage& image, const std::string& alt) {
  return "<img class='view' alt='" + html_escape(alt) + "' src='data:image/png;base64," +
         base64(encode_png(image)) + "'>";
}

// Area-weighted vertex normals and, per vertex, whether every triangle
// around it lies on a judged surface.
struct VertexProbe {
  std::vector<sim::measure::CmmPoint> points;
  std::vector<std::uint32_t> vertex;  // the vertex of each point
};

VertexProbe judged_vertices(const offline::TriangleMesh& mesh, const std::vector<int>& tri_surface,
                            const std::vector<ReportSurface>& surfaces) {
  std::map<int, bool> judged;
  for (const auto& s : surfaces)
    judged[s.id] = s.compensate;
  std::vector<Eigen::Vector3d> normal(mesh.vertices_mm.size(), Eigen::Vector3d::Zero());
  std::vector<char> ok(mesh.vertices_mm.size(), 1);
  std::vector<int> surface(mesh.vertices_mm.size(), -1);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3d n = (mesh.vertices_mm[tri[1]] - mesh.vertices_mm[tri[0]])
                                  .cross(mesh.vertices_mm[tri[2]] - mesh.vertices_mm[tri[0]]);
    const int sid = t < tri_surface.size() ? tri_surface[t] : -1;
    const bool j = judged.count(sid) && judged[sid];
    for (auto v : tri) {
      normal[v] += n;
      if (!j) ok[v] = 0;
      surface[v] = sid;
    }
  }
  VertexProbe p;
  for (std::uint32_t v = 0; v < mesh.vertices_mm.size(); ++v) {
    if (!ok[v] || normal[v].norm() == 0) continue;
    p.points.push_back({mesh.vertices_mm[v], normal[v].normalized(), surface[v]});
    p.vertex.push_back(v);
  }
  return p;
}

std::string stats_cell(const sim::measure::SurfaceDeviationStats& s, double tolerance_um) {
  const bool pass = s.max_abs_um <= tolerance_um;
  return "<td>" + rt::format_printf("%.1f", s.rms_um) + "</td><td class='" + (pass ? "ok" : "bad") +
         "'>" + rt::format_printf("%.1f", s.max_abs_um) + "</td><td>" +
         rt::format_printf("%.1f", s.p95_abs_um) + "</td><td>" +
         rt::format_printf("%.1f", s.std_um) + "</td>";
}

std::string field_picture(const std::filesystem::path& tcf) {
  const rt::LoadedField loaded = rt::read_field_file(tcf);
  const rt::CorrectionField& f = loaded.field;
  const rt::FieldGrid& g = f.grid();
  std::string html;
  for (int32_t tool : f.tools()) {
    // Top view: the largest correction along each vertical line of the grid.
    const int sx = 6, W = g.dims[0], H = g.dims[1];
    std::vector<double> mag(static_cast<size_t>(W) * H, 0.0);
    double limit = 1e-6;
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i)
        for (int k = 0; k < g.dims[2]; ++k) {
          const rt::FieldSample s = f.evaluate(tool, g.node_position_mm(i, j, k));
          const double m = s.correction_mm.norm() * 1000.0;
          mag[j * W + i] = std::max(mag[j * W + i], m);
          limit = std::max(limit, m);
        }
    RgbImage img;
    img.width = W * sx;
    img.height = H * sx;
    img.rgb.resize(static_cast<size_t>(img.width) * img.height * 3);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const int i = x / sx, j = (H - 1) - y / sx;  // +Y up
        const auto c = deviation_colour(mag[j * W + i], limit);
        for (int k = 0; k < 3; ++k)
          img.rgb[(static_cast<size_t>(y) * img.width + x) * 3 + k] = c[k];
      }
    html += "<figure>" + png_img(img, "field of tool " + std::to_string(tool)) +
            "<figcaption>tool " + std::to_string(tool) +
            ": largest |correction| over Z, top view (" +
            rt::format_printf("%.0f", g.spacing_mm.x()) + " mm grid), 0 … " +
            rt::format_printf("%.1f", limit) + " µm</figcaption></figure>";
  }
  return html;
}

// Mean CMM deviation per height band of the judged points whose nominal
// normal is within ~17° of horizontal (walls), one line per stage: how the
// error and what is left of it vary from the foot of a wall to its top.
std::string wall_profile(const ReportPart& part, double tolerance_um) {
  std::map<int, bool> judged;
  for (const auto& s : part.surfaces)
    judged[s.id] = s.compensate;
  auto is_wall_point = [&](const sim::measure::CmmMeasurement& m) {
    return m.valid && judged.count(m.nominal.surface) && judged[m.nominal.surface] &&
           std::abs(m.nominal.normal.z()) < 0.3;
  };
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (const auto& st : part.stages)
    for (const auto& m : st.cmm)
      if (is_wall_point(m)) {
        low = std::min(low, m.nominal.position_mm.z());
        high = std::max(high, m.nominal.position_mm.z());
      }
  if (!(high > low)) return "";
  const int bands = 17;
  const double width = (high - low) / bands;
  std::vector<ProfileSeries> series;
  double range = 5.0;
  for (std::size_t k = 0; k < part.stages.size(); ++k) {
    std::vector<double> sum(bands, 0.0);
    std::vector<int> n(bands, 0);
    for (const auto& m : part.stages[k].cmm) {
      if (!is_wall_point(m)) continue;
      const int b =
          std::clamp(static_cast<int>((m.nominal.position_mm.z() - low) / width), 0, bands - 1);
      sum[b] += m.deviation_mm * 1000.0;
      ++n[b];
    }
    ProfileSeries ps{part.stages[k].title, kStageColours[k % 5], {}};
    for (int b = 0; b < bands; ++b)
      if (n[b] > 0) {
        ps.points.emplace_back(low + (b + 0.5) * width, sum[b] / n[b]);
        range = std::max(range, 1.15 * std::abs(sum[b] / n[b]));
      }
    series.push_back(std::move(ps));
  }
  return profile_svg(series, low, high, 5.0 * std::ceil(range / 5.0), tolerance_um, "µm",
                     "height z (mm)");
}

}  // namespace

std::vector<sim::measure::SurfaceDeviationStats> judged_statistics(
    const std::vector<sim::measure::CmmMeasurement>& cmm,
    const std::vector<ReportSurface>& surfaces) {
  std::vector<sim::measure::CmmMeasurement> judged;
  for (const auto& m : cmm)
    for (const auto& s : surfaces)
      if (s.id == m.nominal.surface && s.compensate) judged.push_back(m);
  std::vector<sim::measure::SurfaceDeviationStats> out = sim::measure::surface_statistics(judged);
  out.push_back(sim::measure::overall_statistics(judged));
  return out;
}

std::string closed_loop_html(const std::vector<ReportPart>& parts, const ReportOptions& o) {
  std::string h =
      "<!DOCTYPE html><html><head><meta charset='utf-8'><title>" + html_escape(o.title) +
      "</title><style>body{font-family:sans-serif;margin:24px;max-width:1200px;color:#222}"
      "table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #bbb;padding:3px 7px;"
      "text-align:right}th{background:#eee}td.name{text-align:left}.ok{background:#d5f5e3}"
      ".bad{background:#fadbd8}figure{display:inline-block;margin:6px}img.view{border:1px solid "
      "#ccc}pre{background:#f6f6f6;padding:8px;overflow:auto;max-height:320px;font-size:12px}"
      "</style></head><body><h1>" +
      html_escape(o.title) + "</h1>";
  h += "<p>Every figure is measured by the virtual CMM (σ ≈ 2 µm) on the machined surface — "
       "never by the scan (σ = " +
       rt::format_printf("%.0f", o.scanner_sigma_um) +
       " µm) the correction was built from. Deviation is along the nominal normal: positive = "
       "material left (oversize). Tolerance drawn: ±" +
       rt::format_printf("%.0f", o.tolerance_um) + " µm.</p>";
  for (const ReportPart& part : parts) {
    h += "<h2>" + html_escape(part.name) + "</h2>";
    const offline::TriangleMesh nominal = offline::read_mesh(part.nominal_stl);
    const VertexProbe vp = judged_vertices(nominal, part.triangle_surface_ids, part.surfaces);

    // Summary table: all judged surfaces per stage, reduction vs the first.
    std::vector<std::vector<sim::measure::SurfaceDeviationStats>> stats;
    for (const auto& st : part.stages)
      stats.push_back(judged_statistics(st.cmm, part.surfaces));
    h += "<table><tr><th>stage</th><th>RMS µm</th><th>max µm</th><th>P95 µm</th><th>std "
         "µm</th><th>RMS reduction</th></tr>";
    for (std::size_t k = 0; k < part.stages.size(); ++k) {
      const auto& all = stats[k].back();
      const double ref = stats[0].back().rms_um;
      h += "<tr><td class='name'>" + html_escape(part.stages[k].title) + "</td>" +
           stats_cell(all, o.tolerance_um) + "<td>" +
           (part.stages[k].key == "ideal" ? std::string("floor")
            : k == 0 || ref <= 0          ? std::string("—")
                                 : rt::format_printf("%.0f %%", 100.0 * (1.0 - all.rms_um / ref))) +
           "</td></tr>";
    }
    h += "</table>";

    // Colour maps, one colour scale for all stages of the part.
    double limit_um = 2.0 * o.tolerance_um;
    for (const auto& m : part.stages.front().cmm)
      if (m.valid) limit_um = std::max(limit_um, std::abs(m.deviation_mm) * 1000.0);
    limit_um = 5.0 * std::ceil(limit_um / 5.0);  // axis labels people can read
    h += "<h3>Deviation maps (judged surfaces; grey: not judged)</h3><div>";
    // The stages' maps are independent (each reads its own machined mesh):
    // made at once, written in the stages' order.
    std::vector<std::string> figures(part.stages.size());
    tbb::parallel_for(std::size_t{0}, part.stages.size(), [&](std::size_t k) {
      const auto& st = part.stages[k];
      const offline::TriangleMesh machined = offline::read_mesh(st.machined_stl);
      sim::measure::CmmOptions exact;
      exact.sigma_mm = 0.0;
      const auto probes = sim::measure::probe(machined, vp.points, exact);
      std::vector<double> values(nominal.vertices_mm.size(),
                                 std::numeric_limits<double>::quiet_NaN());
      for (std::size_t i = 0; i < probes.size(); ++i)
        if (probes[i].valid) values[vp.vertex[i]] = probes[i].deviation_mm * 1000.0;
      figures[k] = "<figure>" + png_img(render_mesh(nominal, values, limit_um), st.title) +
                   "<figcaption>" + html_escape(st.title) + "</figcaption></figure>";
    });
    for (const std::string& figure : figures)
      h += figure;
    h += "</div>" + colour_bar_svg(limit_um, o.tolerance_um, "deviation µm");

    // Histograms.
    std::vector<HistogramSeries> series;
    for (std::size_t k = 0; k < part.stages.size(); ++k) {
      HistogramSeries s{part.stages[k].title, kStageColours[k % 5], {}};
      for (const auto& m : part.stages[k].cmm)
        for (const auto& sf : part.surfaces)
          if (m.valid && sf.compensate && sf.id == m.nominal.surface)
            s.values.push_back(m.deviation_mm * 1000.0);
      series.push_back(std::move(s));
    }
    h += "<h3>Relative frequency of the CMM deviations (judged surfaces)</h3>" +
         histogram_svg(series, limit_um, 40, o.tolerance_um, "µm");

    const std::string profile = wall_profile(part, o.tolerance_um);
    if (!profile.empty())
      h += "<h3>Deviation along the height of the judged walls (mean per height band)</h3>" +
           profile;

    // Per-surface tables.
    h += "<h3>Per surface (RMS / max / P95 / std, µm; max within tolerance in green)</h3><table>"
         "<tr><th>surface</th>";
    for (const auto& st : part.stages)
      h += "<th colspan='4'>" + html_escape(st.title) + "</th>";
    h += "</tr>";
    for (std::size_t row = 0; row + 1 < stats[0].size() + 1; ++row) {
      const bool all = row + 1 == stats[0].size();
      const int sid = stats[0][row].surface;
      std::string name = all ? "all judged" : std::to_string(sid);
      for (const auto& sf : part.surfaces)
        if (!all && sf.id == sid) name = sf.name;
      h += "<tr><td class='name'>" + html_escape(name) + "</td>";
      for (std::size_t k = 0; k < part.stages.size(); ++k)
        h += row < stats[k].size() ? stats_cell(stats[k][row], o.tolerance_um)
                                   : "<td colspan='4'></td>";
      h += "</tr>";
    }
    h += "</table>";

    if (!part.field_tcf.empty())
      h += "<h3>Correction field (1st iteration)</h3>" + field_picture(part.field_tcf);
    if (!part.audit_json.empty())
      h += "<details><summary>Audit record of the field</summary><pre>" +
           html_escape(part.audit_json) + "</pre></details>";
    if (!part.commands.empty())
      h += "<details><summary>The steps, as commands</summary><pre>" + html_escape(part.commands) +
           "</pre></details>";
  }
  // Lets a headless browser confirm every picture decoded.
  h += "<script>window.addEventListener('load',function(){var im=document.images,ok=0;"
       "for(var i=0;i<im.length;i++)if(im[i].complete&&im[i].naturalWidth>0)ok++;"
       "document.body.setAttribute('data-images',ok+'/'+im.length);});</script>";
  return h + "</body></html>\n";
}

}  // namespace truecut::analysis::report
