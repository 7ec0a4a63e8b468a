// Surface-mode diagnosis: re-machine, register, locate, explain by
// linearised re-machined signatures, fit, verify, prove on a held-out region.
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "effect_params.hpp"
#include "surface_params.hpp"
#include "truecut/analysis/diagnosis/surface.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/measure/part_surfaces.hpp"
#include "truecut/sim/part_file.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace truecut::analysis::diagnosis {

namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

struct Run {
  std::vector<double> deviation_mm;  // per measured point, NaN where not probed
  double a_range_deg = 0, c_range_deg = 0;
};

// The rotary travel the program used, from a run's trace.
void rotary_ranges(const fs::path& trace, Run& run) {
  std::ifstream in(trace);
  std::string line;
  if (!std::getline(in, line)) return;
  std::vector<std::string> head;
  {
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ','))
      head.push_back(f);
  }
  const auto ia = std::find(head.begin(), head.end(), "a_cmd") - head.begin();
  const auto ic = std::find(head.begin(), head.end(), "c_cmd") - head.begin();
  double amin = 1e300, amax = -1e300, cmin = 1e300, cmax = -1e300;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string f;
    for (long i = 0; std::getline(ss, f, ','); ++i) {
      if (i != ia && i != ic) continue;
      const double v = std::strtod(f.c_str(), nullptr);
      if (i == ia) amin = std::min(amin, v), amax = std::max(amax, v);
      if (i == ic) cmin = std::min(cmin, v), cmax = std::max(cmax, v);
    }
  }
  run.a_range_deg = amax >= amin ? amax - amin : 0.0;
  run.c_range_deg = cmax >= cmin ? cmax - cmin : 0.0;
}

class Machinist {
 public:
  Machinist(const SurfaceJob& job, const std::vector<sim::measure::CmmPoint>& points,
            const SurfaceOptions& options)
      : job_(job), points_(points), options_(options) {}

  Run machine(const sim::MachineDescription& m, const std::string& why) {
    // The key: the description and the job's files (program, part, tools,
    // nominal), so a changed job never reuses an old run.
    std::string text = sim::format_machine_description(m);
    for (const fs::path& f : {job_.program, job_.part, job_.tools, job_.nominal}) {
      std::ifstream in(f, std::ios::binary);
      std::ostringstream ss;
      ss << in.rdbuf();
      text += "\n" + f.string() + "\n" + ss.str();
    }
    const fs::path dir = job_.work_dir / "runs" / rt::format_hex64(fnv1a(text));
    const fs::path done = dir / "done";
    if (!fs::exists(done)) {
      if (options_.progress) options_.progress("re-machining (" + why + ") in " + dir.string());
      fs::create_directories(dir);
      sim::write_machine_description(dir / "machine.json", m);
      sim::SoftCncJob j;
      j.machine = dir / "machine.json";
      j.program = job_.program;
      j.nominal = job_.nominal;
      j.part = job_.part;
      j.tools = job_.tools;
      j.out_dir = dir;
      j.component_path = job_.component_path;
      j.record_every = 100;
      const auto r = sim::run_soft_cnc(j);
      if (!r.finished || r.limit_fault)
        throw std::runtime_error(
            "re-machining " + job_.program.string() + " on " + (dir / "machine.json").string() +
            (r.limit_fault ? " left the machine's travel" : " did not finish"));
      std::ofstream(done) << "ok\n";
      ++runs_;
    } else if (options_.progress) {
      options_.progress("re-machining (" + why + "): reused " + dir.string());
    }
    Run run;
    const auto mesh = offline::read_stl(dir / "machined.stl");
    sim::measure::CmmOptions o;
    o.sigma_mm = 0.0;
    const auto probed = sim::measure::probe(mesh, points_, o);
    run.deviation_mm.reserve(probed.size());
    for (const auto& p : probed)
      run.deviation_mm.push_back(p.valid ? p.deviation_mm : kNaN);
    rotary_ranges(dir / "trace.csv", run);
    return run;
  }
  int runs() const { return runs_; }

 private:
  const SurfaceJob& job_;
  const std::vector<sim::measure::CmmPoint>& points_;
  const SurfaceOptions& options_;
  int runs_ = 0;
};

struct Ls {
  Eigen::VectorXd beta;
  Eigen::MatrixXd cov_unscaled;  // (XᵀX)⁻¹
  double rss = 0;
  bool ok = false;
};

Ls least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  Ls r;
  const Eigen::MatrixXd xtx = x.transpose() * x;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(xtx);
  if (ldlt.info() != Eigen::Success) return r;
  r.beta = xtx.completeOrthogonalDecomposition().solve(x.transpose() * y);
  r.cov_unscaled = xtx.completeOrthogonalDecomposition().pseudoInverse();
  r.rss = (y - x * r.beta).squaredNorm();
  r.ok = std::isfinite(r.rss);
  return r;
}

double rms(const std::vector<double>& v, const std::vector<std::size_t>& idx) {
  double s = 0;
  for (auto i : idx)
    s += v[i] * v[i];
  return idx.empty() ? 0.0 : std::sqrt(s / double(idx.size()));
}
double max_abs(const std::vector<double>& v, const std::vector<std::size_t>& idx) {
  double m = 0;
  for (auto i : idx)
    m = std::max(m, std::abs(v[i]));
  return m;
}

std::string separation(const std::string& a, const std::string& b) {
  auto has = [&](const char* x, const char* y) {
    return (a.rfind(x, 0) == 0 && b.rfind(y, 0) == 0) || (a.rfind(y, 0) == 0 && b.rfind(x, 0) == 0);
  };
  if (has("tool_length_error", "rotary_location"))
    return "surfaces cut at two or more A angles: a tool-length error moves along the tool axis, "
           "which turns with A; an axis-line offset moves with the table";
  if (has("tool_length_error", "registration"))
    return "a datum measured independently of the tool tip (the part's bottom or the fixture), so "
           "the registration cannot absorb a shift along the tool axis";
  if (has("tool_radius_error", "registration") || has("tool_radius_error", "tool_deflection"))
    return "opposite walls and walls cut at different engagements: a radius error moves every "
           "side-cut wall inwards by the same amount, deflection follows the cutting force";
  if (has("tool_deflection", "workpiece_deflection"))
    return "cuts of the same force at different heights above the clamp: workpiece deflection "
           "grows with the height cubed, tool deflection does not";
  if (has("squareness", "registration") || has("rotary_location", "registration"))
    return "features far apart along the moving axes (a longer part or a test artefact)";
  return "a part whose surfaces move the two signatures independently (other orientations, "
         "heights or tools)";
}

// The surface → operations / tool map of part.json (empty when unreadable).
struct OperationMap {
  std::map<int, std::string> surface_name;
  std::vector<std::pair<std::string, std::set<int>>> operations;  // name → surfaces
  std::map<int, std::set<int>> tool_surfaces;
};

OperationMap read_operations(const fs::path& part_json) {
  OperationMap m;
  try {
    const sim::PartFile p =
        sim::read_part_file(part_json, sim::kPartSurfaces | sim::kPartOperations);
    for (const sim::PartSurface& s : p.metadata.surfaces)
      m.surface_name[s.id] = s.name;
    for (const sim::PartOperation& o : p.metadata.operations) {
      const std::set<int> ids(o.surface_ids.begin(), o.surface_ids.end());
      m.operations.emplace_back(o.name, ids);
      m.tool_surfaces[o.tool].insert(ids.begin(), ids.end());
    }
  } catch (const std::exception&) {
    return {};
  }
  return m;
}

}  // namespace

SurfaceDiagnosisResult diagnose_surface(const SurfaceMeasurement& measurement,
                                        const SurfaceJob& job,
                                        const sim::MachineDescription& believed,
                                        const SurfaceOptions& options) {
  auto progress = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  SurfaceDiagnosisResult res;
  res.measurement = measurement.source;
  res.kind = measurement.kind;
  res.program = job.program.string();
  res.believed = believed;
  res.fitted = believed;
  res.scan_to_nominal = measurement.scan_to_nominal;
  res.icp_rms_before_mm = measurement.icp_rms_before_mm;
  res.icp_rms_after_mm = measurement.icp_rms_after_mm;
  res.points = measurement.points.size();

  std::vector<sim::measure::CmmPoint> nominal;
  for (const auto& p : measurement.points)
    nominal.push_back(p.nominal);
  Machinist machinist(job, nominal, options);
  const Run base = machinist.machine(believed, "believed model");
  const bool five_axis = base.a_range_deg > 1.0 || base.c_range_deg > 1.0;

  // Points both measured and simulated.
  std::vector<std::size_t> use;
  for (std::size_t i = 0; i < measurement.points.size(); ++i)
    if (measurement.points[i].valid && std::isfinite(base.deviation_mm[i])) use.push_back(i);
  if (use.size() < 20)
    throw DiagnosisError(measurement.source + ": only " + std::to_string(use.size()) +
                         " points are both measured and on the re-machined surface (need 20)");
  res.valid_points = use.size();
  const std::size_t n_all = use.size();

  // Hold-out: the last fraction along the longest extent.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo,
                  centroid = Eigen::Vector3d::Zero();
  for (auto i : use) {
    const auto& p = measurement.points[i].nominal.position_mm;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    centroid += p;
  }
  centroid /= double(n_all);
  res.centroid_mm = centroid;
  int long_axis = 0;
  (hi - lo).maxCoeff(&long_axis);
  const double cut = hi[long_axis] - options.holdout_fraction * (hi[long_axis] - lo[long_axis]);
  std::vector<char> held(n_all, 0);
  std::vector<std::size_t> tr, ho;  // indices into `use`
  for (std::size_t k = 0; k < n_all; ++k) {
    held[k] = options.holdout_fraction > 0 &&
              measurement.points[use[k]].nominal.position_mm[long_axis] > cut;
    (held[k] ? ho : tr).push_back(k);
  }
  if (tr.size() < 20) {
    std::fill(held.begin(), held.end(), 0);
    tr.resize(n_all);
    std::iota(tr.begin(), tr.end(), 0);
    ho.clear();
  }
  res.has_heldout = !ho.empty();
  if (res.has_heldout) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "region: %c > %.3f mm", "xyz"[long_axis], cut);
    res.heldout_kind = buf;
  }

  // Residual and the registration nuisance (rigid motion, linearised).
  Eigen::VectorXd r(n_all);
  Eigen::MatrixXd nuis(n_all, 6);
  for (std::size_t k = 0; k < n_all; ++k) {
    const auto& m = measurement.points[use[k]];
    r[k] = m.deviation_mm - base.deviation_mm[use[k]];
    const Eigen::Vector3d& n = m.nominal.normal;
    nuis.row(k).head<3>() = n.transpose();
    nuis.row(k).tail<3>() = (m.nominal.position_mm - centroid).cross(n).transpose();
  }
  auto rows = [](const Eigen::MatrixXd& x, const std::vector<std::size_t>& idx) {
    Eigen::MatrixXd out(idx.size(), x.cols());
    for (std::size_t k = 0; k < idx.size(); ++k)
      out.row(k) = x.row(idx[k]);
    return out;
  };
  auto rows_v = [](const Eigen::VectorXd& x, const std::vector<std::size_t>& idx) {
    Eigen::VectorXd out(idx.size());
    for (std::size_t k = 0; k < idx.size(); ++k)
      out[k] = x[idx[k]];
    return out;
  };

  // Noise floor and neighbour correlation: each training point paired with
  // its nearest training neighbour on the same surface.
  const Ls reg0 = least_squares(rows(nuis, tr), rows_v(r, tr));
  const Eigen::VectorXd r0 = r - nuis * reg0.beta;  // registered residual, all points
  std::vector<double> diffs;
  double sxy = 0, sxx = 0;
  for (std::size_t a = 0; a < tr.size(); ++a) {
    const auto& pa = measurement.points[use[tr[a]]].nominal;
    double best = 1e300;
    std::size_t bi = a;
    for (std::size_t b = 0; b < tr.size(); ++b) {
      if (b == a) continue;
      const auto& pb = measurement.points[use[tr[b]]].nominal;
      if (pb.surface != pa.surface) continue;
      const double d = (pb.position_mm - pa.position_mm).squaredNorm();
      if (d < best) best = d, bi = b;
    }
    if (bi == a) continue;
    diffs.push_back(std::abs(r0[tr[a]] - r0[tr[bi]]));
    sxy += r0[tr[a]] * r0[tr[bi]];
    sxx += r0[tr[a]] * r0[tr[a]];
  }
  if (!diffs.empty()) {
    std::nth_element(diffs.begin(), diffs.begin() + long(diffs.size() / 2), diffs.end());
    res.noise_floor_mm = 1.4826 * diffs[diffs.size() / 2] / std::sqrt(2.0);
  }
  if (!(res.noise_floor_mm > 0))
    res.noise_floor_mm = std::max(1e-6, r0.norm() / std::sqrt(double(n_all)));

  // Locate: per surface, operation, tool (registered residual, all points).
  const OperationMap ops = read_operations(job.part);
  auto region = [&](const std::string& where, const std::string& what, const std::set<int>& ids) {
    SurfaceRegion g;
    g.where = where;
    g.what = what;
    double s2 = 0, s1 = 0;
    for (std::size_t k = 0; k < n_all; ++k) {
      if (!ids.count(measurement.points[use[k]].nominal.surface)) continue;
      ++g.points;
      s2 += r0[k] * r0[k];
      s1 += r0[k];
      g.max_mm = std::max(g.max_mm, std::abs(r0[k]));
    }
    if (g.points < 10) return;
    g.rms_mm = std::sqrt(s2 / double(g.points));
    g.mean_mm = s1 / double(g.points);
    g.ratio_to_floor = g.rms_mm / res.noise_floor_mm;
    if (g.ratio_to_floor > 1.5) res.mismatch.push_back(g);
  };
  std::set<int> surfaces;
  for (auto i : use)
    surfaces.insert(measurement.points[i].nominal.surface);
  for (int s : surfaces) {
    const auto it = ops.surface_name.find(s);
    region("surface",
           "surface " + std::to_string(s) +
               (it != ops.surface_name.end() ? " (" + it->second + ")" : ""),
           {s});
  }
  for (const auto& [name, ids] : ops.operations)
    region("operation", name, ids);
  for (const auto& [tool, ids] : ops.tool_surfaces)
    region("tool", "T" + std::to_string(tool), ids);
  std::stable_sort(res.mismatch.begin(), res.mismatch.end(), [](const auto& a, const auto& b) {
    return a.ratio_to_floor > b.ratio_to_floor;
  });

  // Signatures: one re-machining per parameter, nudged.
  WorkpieceGeometry geometry;
  geometry.clamp_point_mm = {centroid.x(), centroid.y(), lo.z()};
  geometry.reference_length_mm = std::max(1.0, hi.z() - lo.z());
  std::vector<SurfaceParam> params;
  for (const auto& p : surface_params(believed.machine, five_axis)) {
    if (!options.candidates.empty() &&
        std::find(options.candidates.begin(), options.candidates.end(), p.effect) ==
            options.candidates.end())
      continue;
    params.push_back(p);
  }
  std::vector<Eigen::VectorXd> sig;
  std::vector<SurfaceParam> kept;
  for (const auto& p : params) {
    sim::MachineDescription m = believed;
    set_surface_param(m.machine, p, p.base + p.step, geometry);
    const Run run = machinist.machine(m, surface_group(p) + " " + p.key);
    Eigen::VectorXd s(n_all);
    bool ok = true;
    for (std::size_t k = 0; k < n_all; ++k) {
      s[k] = (run.deviation_mm[use[k]] - base.deviation_mm[use[k]]) / p.step;
      ok = ok && std::isfinite(s[k]);
    }
    if (!ok) {
      for (std::size_t k = 0; k < n_all; ++k)
        if (!std::isfinite(s[k])) s[k] = 0;
    }
    // A parameter that moves no measured point cannot be seen.
    if (s.norm() * p.step < 1e-4 * std::sqrt(double(n_all))) continue;
    sig.push_back(s);
    kept.push_back(p);
  }
  params = kept;
  std::vector<std::string> groups;
  std::map<std::string, std::vector<std::size_t>> group_params;
  for (std::size_t i = 0; i < params.size(); ++i) {
    const std::string g = surface_group(params[i]);
    if (!group_params.count(g)) groups.push_back(g);
    group_params[g].push_back(i);
  }
  res.candidates_tested = groups;

  // Selection: BIC over the training points, registration always in.
  const Eigen::VectorXd ytr = rows_v(r, tr);
  const double n = double(tr.size());
  const double rho = sxx > 0 ? std::clamp(sxy / sxx, 0.0, 0.95) : 0.0;
  const double n_eff = std::max(n * (1 - rho) / (1 + rho), std::min(n, 20.0));
  auto design = [&](const std::vector<std::string>& sel, std::vector<std::size_t>* cols) {
    std::vector<std::size_t> pidx;
    for (const auto& g : sel)
      for (auto i : group_params[g])
        pidx.push_back(i);
    Eigen::MatrixXd x(tr.size(), 6 + pidx.size());
    x.leftCols(6) = rows(nuis, tr);
    for (std::size_t c = 0; c < pidx.size(); ++c)
      x.col(6 + c) = rows_v(sig[pidx[c]], tr);
    if (cols) *cols = pidx;
    return x;
  };
  auto bic = [&](const std::vector<std::string>& sel) {
    std::vector<std::size_t> pidx;
    const auto fit = least_squares(design(sel, &pidx), ytr);
    if (!fit.ok) return 1e300;
    const double k = double(6 + pidx.size());
    return n_eff * std::log(std::max(fit.rss, 1e-30) / n) + k * std::log(n_eff);
  };
  auto physical = [&](const std::vector<std::string>& sel) {
    std::vector<std::size_t> pidx;
    const auto fit = least_squares(design(sel, &pidx), ytr);
    for (std::size_t c = 0; c < pidx.size(); ++c)
      if (params[pidx[c]].compliance && params[pidx[c]].base + fit.beta[6 + long(c)] <= 0)
        return false;
    return true;
  };
  std::vector<std::string> selected;
  double current = bic({});
  std::map<std::string, double> gain;
  for (;;) {
    std::string best;
    double best_bic = current;
    for (const auto& g : groups) {
      if (std::find(selected.begin(), selected.end(), g) != selected.end()) continue;
      auto sel = selected;
      sel.push_back(g);
      const double b = bic(sel);
      if (b < best_bic && physical(sel)) best_bic = b, best = g;
    }
    if (best.empty() || current - best_bic <= options.bic_threshold) break;
    gain[best] = best_bic - current;
    progress("selected " + best + " (ΔBIC " + std::to_string(best_bic - current) + ")");
    selected.push_back(best);
    current = best_bic;
  }

  // Fit: Gauss–Newton on the re-machined residual. Step 0 is the linear fit
  // around the believed model (the selection's signatures); each iteration
  // re-machines the model at the estimate and its nudges, re-linearises
  // there and steps, until every step is below a fifth of its standard
  // error (the deflections change the engagement and so the force: one
  // linearisation around the believed model is biased).
  std::vector<std::size_t> pidx;
  Eigen::MatrixXd xs = design(selected, &pidx);
  Ls fit = least_squares(xs, ytr);
  const long np = long(pidx.size());
  auto covariance = [&](const Ls& f, const Eigen::MatrixXd& x) {
    const double dof = std::max(1.0, n - double(x.cols()));
    return Eigen::MatrixXd(f.cov_unscaled * (f.rss / dof * n / n_eff));
  };
  Eigen::MatrixXd cov = covariance(fit, xs);
  Eigen::VectorXd theta(np);
  for (long c = 0; c < np; ++c)
    theta[c] = params[pidx[std::size_t(c)]].base + fit.beta[6 + c];
  auto model_at = [&](const Eigen::VectorXd& th) {
    sim::MachineDescription m = believed;
    for (long c = 0; c < np; ++c)
      set_surface_param(m.machine, params[pidx[std::size_t(c)]], th[c], geometry);
    return m;
  };
  for (int it = 1; np > 0 && it <= options.gauss_newton_iterations; ++it) {
    const std::string tag = "Gauss-Newton " + std::to_string(it);
    const Run at = machinist.machine(model_at(theta), tag + ": estimate");
    auto deviation = [&](const Run& run, std::size_t k) {
      const double d = run.deviation_mm[use[k]];
      return std::isfinite(d) ? d : base.deviation_mm[use[k]];
    };
    Eigen::VectorXd y(long(tr.size()));
    for (std::size_t k = 0; k < tr.size(); ++k)
      y[long(k)] = measurement.points[use[tr[k]]].deviation_mm - deviation(at, tr[k]);
    Eigen::MatrixXd x(long(tr.size()), 6 + np);
    x.leftCols(6) = rows(nuis, tr);
    for (long c = 0; c < np; ++c) {
      const SurfaceParam& p = params[pidx[std::size_t(c)]];
      // Compliances are nudged in proportion (the deviation is far from
      // linear in them near zero); the others by their fixed step.
      const double step = p.compliance ? std::max(0.2 * std::abs(theta[c]), 0.05 * p.step) : p.step;
      Eigen::VectorXd nudged = theta;
      nudged[c] += step;
      const Run run = machinist.machine(model_at(nudged), tag + ": " + p.key);
      for (std::size_t k = 0; k < tr.size(); ++k)
        x(long(k), 6 + c) = (deviation(run, tr[k]) - deviation(at, tr[k])) / step;
    }
    const Ls f = least_squares(x, y);
    if (!f.ok) break;
    xs = x;
    fit = f;
    cov = covariance(f, x);
    res.gauss_newton_iterations = it;
    res.gauss_newton_converged = true;
    std::string line = tag + ":";
    for (long c = 0; c < np; ++c) {
      const SurfaceParam& p = params[pidx[std::size_t(c)]];
      const double delta = f.beta[6 + c];
      const double se = std::sqrt(std::max(0.0, cov(6 + c, 6 + c)));
      if (!(std::abs(delta) <= 0.2 * se)) res.gauss_newton_converged = false;
      // A compliance stays positive: at most halve it per step.
      theta[c] =
          p.compliance && theta[c] + delta < 0.5 * theta[c] ? 0.5 * theta[c] : theta[c] + delta;
      line += " " + p.key + " " + std::to_string(theta[c]) + " (step " + std::to_string(delta) +
              ", se " + std::to_string(se) + ")";
    }
    progress(line);
    if (res.gauss_newton_converged) break;
  }

  // Intervals, identifiability.
  res.registration_translation_mm = fit.beta.head<3>();
  res.registration_rotation_urad = fit.beta.segment<3>(3) * 1e6;
  sim::MachineDescription fitted = believed;
  for (const auto& g : selected) {
    Explanation e;
    const auto& first = params[group_params[g].front()];
    e.effect = first.effect;
    e.axis = first.axis;
    e.delta_bic = gain[g];
    Eigen::VectorXd contrib = Eigen::VectorXd::Zero(long(tr.size()));
    for (std::size_t c = 0; c < pidx.size(); ++c) {
      const auto& p = params[pidx[c]];
      if (surface_group(p) != g) continue;
      const double v = theta[long(c)];
      const double se = std::sqrt(std::max(0.0, cov(6 + long(c), 6 + long(c))));
      set_surface_param(fitted.machine, p, v, geometry);
      contrib += (v - p.base) * xs.col(6 + long(c));
      Parameter out;
      out.name = p.key;
      if (p.compliance) {
        out.value = 1.0 / v;
        const double clo = v - 1.96 * se, chi = v + 1.96 * se;
        out.ci95_lo = 1.0 / chi;
        out.ci95_hi = clo > 0 ? 1.0 / clo : std::numeric_limits<double>::infinity();
        char buf[96];
        std::snprintf(buf, sizeof buf, "compliance %.4g µm/N [%.4g, %.4g]", v, clo, chi);
        e.note = buf;
      } else {
        out.value = v;
        out.ci95_lo = v - 1.96 * se;
        out.ci95_hi = v + 1.96 * se;
      }
      e.parameters.push_back(out);
    }
    e.rms_effect_mm = contrib.norm() / std::sqrt(n);
    res.explanations.push_back(e);
  }
  // (a) a selected group another one replaces within the threshold.
  for (const auto& g : selected) {
    for (const auto& h : groups) {
      if (std::find(selected.begin(), selected.end(), h) != selected.end()) continue;
      auto sel = selected;
      std::replace(sel.begin(), sel.end(), g, h);
      if (bic(sel) - current < options.bic_threshold) {
        const Eigen::VectorXd& a = sig[group_params[g].front()];
        const Eigen::VectorXd& b = sig[group_params[h].front()];
        NotIdentifiable ni{g, h, a.dot(b) / std::max(1e-30, a.norm() * b.norm()), separation(g, h)};
        res.not_identifiable.push_back(ni);
      }
    }
  }
  // (b) fitted parameters that are nearly one combination.
  for (std::size_t c1 = 0; c1 < pidx.size(); ++c1)
    for (std::size_t c2 = c1 + 1; c2 < pidx.size(); ++c2) {
      const double cc =
          cov(6 + long(c1), 6 + long(c2)) /
          std::sqrt(cov(6 + long(c1), 6 + long(c1)) * cov(6 + long(c2), 6 + long(c2)));
      if (std::abs(cc) >= 0.99) {
        const auto& p1 = params[pidx[c1]];
        const auto& p2 = params[pidx[c2]];
        res.not_identifiable.push_back({surface_group(p1) + "." + p1.key,
                                        surface_group(p2) + "." + p2.key, cc,
                                        separation(p1.effect, p2.effect)});
      }
    }
  // (c) a candidate the registration absorbs: nearly in the span of the
  // rigid-motion columns, so no measurement of this part can show it.
  {
    const Eigen::MatrixXd nt = rows(nuis, tr);
    for (const auto& g : groups) {
      const auto& p0 = params[group_params[g].front()];
      const Eigen::VectorXd s = rows_v(sig[group_params[g].front()], tr);
      if (s.norm() * p0.step < 1e-4 * std::sqrt(n)) {
        res.not_identifiable.push_back(
            {g, "fitted region", 0.0,
             "the effect moves no point of the fitted region (only held-out ones): measure the "
             "surfaces it moves inside the fitted region, or fit without a split (--split 0)"});
        continue;
      }
      const Ls f = least_squares(nt, s);
      const double r2 = 1 - f.rss / std::max(1e-30, s.squaredNorm());
      if (f.ok && r2 >= 0.98)
        res.not_identifiable.push_back(
            {g, "registration", std::sqrt(std::max(0.0, r2)), separation(g, "registration")});
    }
  }

  // Verify: re-machine the fitted model; residuals before / after with the
  // registration refitted on the training points.
  std::vector<double> before(n_all), after(n_all);
  for (std::size_t k = 0; k < n_all; ++k)
    before[k] = r0[k];
  if (selected.empty()) {
    after = before;
  } else {
    const Run fr = machinist.machine(fitted, "fitted model");
    Eigen::VectorXd ra(n_all);
    for (std::size_t k = 0; k < n_all; ++k) {
      const double d = fr.deviation_mm[use[k]];
      ra[k] = measurement.points[use[k]].deviation_mm -
              (std::isfinite(d) ? d : base.deviation_mm[use[k]]);
    }
    const Ls rg = least_squares(rows(nuis, tr), rows_v(ra, tr));
    const Eigen::VectorXd rr = ra - nuis * rg.beta;
    for (std::size_t k = 0; k < n_all; ++k)
      after[k] = rr[k];
  }
  auto figures = [&](const std::vector<std::size_t>& idx) {
    SurfaceFit f;
    f.points = idx.size();
    f.rms_before_mm = rms(before, idx);
    f.rms_after_mm = rms(after, idx);
    f.max_before_mm = max_abs(before, idx);
    f.max_after_mm = max_abs(after, idx);
    return f;
  };
  res.train = figures(tr);
  if (res.has_heldout) res.heldout = figures(ho);
  res.resimulations = machinist.runs();
  res.fitted = fitted;
  for (std::size_t k = 0; k < n_all; ++k) {
    res.position_mm.push_back(measurement.points[use[k]].nominal.position_mm);
    res.surface.push_back(measurement.points[use[k]].nominal.surface);
    res.is_heldout.push_back(held[k]);
  }
  res.before_mm = before;
  res.after_mm = after;
  if (selected.empty()) {
    res.verdict = res.mismatch.empty()
                      ? "nothing missing: the residual is at the noise floor"
                      : "mismatch above the noise floor that no candidate effect explains";
  } else {
    res.verdict = "missing in the believed model:";
    for (std::size_t i = 0; i < selected.size(); ++i)
      res.verdict += (i ? ", " : " ") + selected[i];
  }
  return res;
}

}  // namespace truecut::analysis::diagnosis
