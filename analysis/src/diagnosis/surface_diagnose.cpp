// Surface-mode diagnosis as a sequence of steps: re-machine the believed
// model → usable points and held-out region → residual and registration
// nuisance → noise floor → locate → signatures → selection by BIC →
// Gauss–Newton → intervals and identifiability → verify → verdict.
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "effect_params.hpp"
#include "surface_params.hpp"
#include "surface_steps.hpp"
#include "truecut/analysis/diagnosis/surface.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/measure/part_surfaces.hpp"
#include "truecut/sim/part_file.hpp"
#include "truecut/sim/soft_cnc.hpp"
#include "truecut/sim/soft_cnc_outputs.hpp"

namespace truecut::analysis::diagnosis {

namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMinSurfacePoints = 20;  // points both measured and re-machined

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names)
    s += (s.empty() ? "" : ", ") + n;
  return s;
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  if (from.empty()) return text;
  for (std::size_t at = text.find(from); at != std::string::npos;
       at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
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
      create_directories_tracked(dir);
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
      sim::SoftCncResult r;
      try {
        r = sim::run_soft_cnc(j);
      } catch (const sim::SoftCncInputError& e) {
        // Bad input (a program that leaves the travel, a tool table that does
        // not read): named with the --machine file, not the internal copy.
        throw DiagnosisError(replace_all(e.what(), j.machine.string(), machine_name(why)));
      }
      if (!r.finished || r.limit_fault)
        throw std::runtime_error(
            "re-machining " + job_.program.string() + " on " + machine_name(why) +
            (r.limit_fault ? " left the machine's travel" : " did not finish"));
      std::ofstream(done) << "ok\n";
      ++runs_;
    } else if (options_.progress) {
      options_.progress("re-machining (" + why + "): reused " + dir.string());
    }
    Run run;
    const auto mesh = offline::read_stl(dir / sim::kMachinedStl);
    sim::measure::CmmOptions o;
    o.sigma_mm = 0.0;
    const auto probed = sim::measure::probe(mesh, points_, o);
    run.deviation_mm.reserve(probed.size());
    for (const auto& p : probed)
      run.deviation_mm.push_back(p.valid ? p.deviation_mm : kNaN);
    rotary_ranges(dir / sim::kTraceCsv, run);
    return run;
  }
  int runs() const { return runs_; }

  // Removes the folders this diagnosis created (after a failure: bad input
  // leaves nothing behind); runs reused from an earlier diagnosis stay.
  void remove_created() {
    std::error_code ec;
    for (auto it = created_.rbegin(); it != created_.rend(); ++it)
      fs::remove_all(*it, ec);
    created_.clear();
  }

 private:
  // create_directories that remembers the outermost folder it made.
  void create_directories_tracked(const fs::path& dir) {
    fs::path outermost;
    for (fs::path p = dir; !p.empty() && !fs::exists(p); p = p.parent_path()) {
      outermost = p;
      if (p == p.parent_path()) break;
    }
    fs::create_directories(dir);
    if (!outermost.empty()) created_.push_back(outermost);
  }

  // The machine as the user named it: the --machine file, or the model
  // derived from it for this re-machining.
  std::string machine_name(const std::string& why) const {
    const std::string file = job_.machine_file.empty() ? std::string("the believed machine")
                                                       : job_.machine_file.string();
    return why == "believed model" ? file : file + " (" + why + ")";
  }

  std::vector<fs::path> created_;
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

// The points both measured and re-machined, their split into a fitted and a
// held-out region, the residual against the believed model and the
// registration nuisance (rigid motion, linearised).
struct SurfacePoints {
  std::vector<std::size_t> use;      // measurement points used
  std::vector<char> held;            // per used point
  std::vector<std::size_t> tr, ho;   // indices into `use`
  Eigen::Vector3d lo, hi, centroid;  // of the used points' nominal positions
  Eigen::VectorXd r;                 // measured − believed deviation
  Eigen::MatrixXd nuis;              // n × 6: translation, rotation about the centroid
};

Eigen::MatrixXd rows(const Eigen::MatrixXd& x, const std::vector<std::size_t>& idx) {
  Eigen::MatrixXd out(idx.size(), x.cols());
  for (std::size_t k = 0; k < idx.size(); ++k)
    out.row(k) = x.row(idx[k]);
  return out;
}
Eigen::VectorXd rows_v(const Eigen::VectorXd& x, const std::vector<std::size_t>& idx) {
  Eigen::VectorXd out(idx.size());
  for (std::size_t k = 0; k < idx.size(); ++k)
    out[k] = x[idx[k]];
  return out;
}

// Points both measured and simulated (at least 20).
std::vector<std::size_t> usable_points(const SurfaceMeasurement& measurement, const Run& base) {
  std::vector<std::size_t> use;
  for (std::size_t i = 0; i < measurement.points.size(); ++i)
    if (measurement.points[i].valid && std::isfinite(base.deviation_mm[i])) use.push_back(i);
  if (use.size() < kMinSurfacePoints)
    throw DiagnosisError(measurement.source + ": only " + std::to_string(use.size()) +
                         " points are both measured and on the re-machined surface (need " +
                         std::to_string(kMinSurfacePoints) + ")");
  return use;
}

// Hold-out: the last fraction along the longest extent (none when fewer
// than 20 points would remain to fit); returns the region's description.
std::string split_heldout(const SurfaceMeasurement& measurement, double holdout_fraction,
                          SurfacePoints& sp) {
  const std::size_t n_all = sp.use.size();
  sp.lo = Eigen::Vector3d::Constant(1e300), sp.hi = -sp.lo;
  sp.centroid = Eigen::Vector3d::Zero();
  for (auto i : sp.use) {
    const auto& p = measurement.points[i].nominal.position_mm;
    sp.lo = sp.lo.cwiseMin(p);
    sp.hi = sp.hi.cwiseMax(p);
    sp.centroid += p;
  }
  sp.centroid /= double(n_all);
  int long_axis = 0;
  (sp.hi - sp.lo).maxCoeff(&long_axis);
  const double cut = sp.hi[long_axis] - holdout_fraction * (sp.hi[long_axis] - sp.lo[long_axis]);
  sp.held.assign(n_all, 0);
  for (std::size_t k = 0; k < n_all; ++k) {
    sp.held[k] =
        holdout_fraction > 0 && measurement.points[sp.use[k]].nominal.position_mm[long_axis] > cut;
    (sp.held[k] ? sp.ho : sp.tr).push_back(k);
  }
  if (sp.tr.size() < 20) {
    std::fill(sp.held.begin(), sp.held.end(), 0);
    sp.tr.resize(n_all);
    std::iota(sp.tr.begin(), sp.tr.end(), 0);
    sp.ho.clear();
  }
  if (sp.ho.empty()) return {};
  char buf[64];
  std::snprintf(buf, sizeof buf, "region: %c > %.3f mm", "xyz"[long_axis], cut);
  return buf;
}

void residual_and_nuisance(const SurfaceMeasurement& measurement, const Run& base,
                           SurfacePoints& sp) {
  const std::size_t n_all = sp.use.size();
  sp.r.resize(n_all);
  sp.nuis.resize(n_all, 6);
  for (std::size_t k = 0; k < n_all; ++k) {
    const auto& m = measurement.points[sp.use[k]];
    sp.r[k] = m.deviation_mm - base.deviation_mm[sp.use[k]];
    const Eigen::Vector3d& n = m.nominal.normal;
    sp.nuis.row(k).head<3>() = n.transpose();
    sp.nuis.row(k).tail<3>() = (m.nominal.position_mm - sp.centroid).cross(n).transpose();
  }
}

}  // namespace

SurfaceNoise surface_noise_floor(const std::vector<sim::measure::CmmPoint>& nominal,
                                 const Eigen::VectorXd& r0, const std::vector<std::size_t>& tr) {
  SurfaceNoise out;
  std::vector<double> diffs;
  for (std::size_t a = 0; a < tr.size(); ++a) {
    const auto& pa = nominal[tr[a]];
    double best = 1e300;
    std::size_t bi = a;
    for (std::size_t b = 0; b < tr.size(); ++b) {
      if (b == a) continue;
      const auto& pb = nominal[tr[b]];
      if (pb.surface != pa.surface) continue;
      const double d = (pb.position_mm - pa.position_mm).squaredNorm();
      if (d < best) best = d, bi = b;
    }
    if (bi == a) continue;
    diffs.push_back(std::abs(r0[tr[a]] - r0[tr[bi]]));
    out.sxy += r0[tr[a]] * r0[tr[bi]];
    out.sxx += r0[tr[a]] * r0[tr[a]];
  }
  if (!diffs.empty()) {
    std::nth_element(diffs.begin(), diffs.begin() + long(diffs.size() / 2), diffs.end());
    out.floor_mm = 1.4826 * diffs[diffs.size() / 2] / std::sqrt(2.0);
  }
  if (!(out.floor_mm > 0)) out.floor_mm = std::max(1e-6, r0.norm() / std::sqrt(double(r0.size())));
  return out;
}

namespace {

// Locate: per surface, operation, tool (registered residual r0, all points),
// the regions above 1.5 × the floor, largest ratio first.
std::vector<SurfaceRegion> locate_regions(const SurfaceMeasurement& measurement,
                                          const SurfacePoints& sp, const Eigen::VectorXd& r0,
                                          const OperationMap& ops, double floor_mm) {
  std::vector<SurfaceRegion> out;
  auto region = [&](const std::string& where, const std::string& what, const std::set<int>& ids) {
    SurfaceRegion g;
    g.where = where;
    g.what = what;
    double s2 = 0, s1 = 0;
    for (std::size_t k = 0; k < sp.use.size(); ++k) {
      if (!ids.count(measurement.points[sp.use[k]].nominal.surface)) continue;
      ++g.points;
      s2 += r0[k] * r0[k];
      s1 += r0[k];
      g.max_mm = std::max(g.max_mm, std::abs(r0[k]));
    }
    if (g.points < 10) return;
    g.rms_mm = std::sqrt(s2 / double(g.points));
    g.mean_mm = s1 / double(g.points);
    g.ratio_to_floor = g.rms_mm / floor_mm;
    if (g.ratio_to_floor > 1.5) out.push_back(g);
  };
  std::set<int> surfaces;
  for (auto i : sp.use)
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
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.ratio_to_floor > b.ratio_to_floor;
  });
  return out;
}

// The candidates, their signatures (one re-machining per parameter,
// nudged) and their groups, the units of selection.
struct Signatures {
  std::vector<SurfaceParam> params;  // those that move a measured point
  std::vector<Eigen::VectorXd> sig;  // per parameter, per used point
  std::vector<std::string> groups;   // in order of first appearance
  std::map<std::string, std::vector<std::size_t>> group_params;
};

Signatures signatures(Machinist& machinist, const sim::MachineDescription& believed,
                      const SurfaceOptions& options, bool five_axis,
                      const WorkpieceGeometry& geometry, const Run& base,
                      const std::vector<std::size_t>& use) {
  const std::size_t n_all = use.size();
  Signatures S;
  for (const auto& p : surface_params(believed.machine, five_axis)) {
    if (!options.candidates.empty() &&
        std::find(options.candidates.begin(), options.candidates.end(), p.effect) ==
            options.candidates.end())
      continue;
    sim::MachineDescription m = believed;
    set_surface_param(m.machine, p, p.base + p.step, geometry);
    const Run run = machinist.machine(m, surface_group(p) + " " + p.key);
    Eigen::VectorXd s(n_all);
    for (std::size_t k = 0; k < n_all; ++k) {
      s[k] = (run.deviation_mm[use[k]] - base.deviation_mm[use[k]]) / p.step;
      if (!std::isfinite(s[k])) s[k] = 0;
    }
    // A parameter that moves no measured point cannot be seen.
    if (s.norm() * p.step < 1e-4 * std::sqrt(double(n_all))) continue;
    S.sig.push_back(s);
    S.params.push_back(p);
  }
  for (std::size_t i = 0; i < S.params.size(); ++i) {
    const std::string g = surface_group(S.params[i]);
    if (!S.group_params.count(g)) S.groups.push_back(g);
    S.group_params[g].push_back(i);
  }
  return S;
}

// The linear model on the training points: registration always in, the
// signatures of the selected groups beside it.
struct LinearModel {
  const SurfacePoints& sp;
  Signatures& S;
  Eigen::VectorXd ytr;
  double n = 0, n_eff = 0;

  Eigen::MatrixXd design(const std::vector<std::string>& sel,
                         std::vector<std::size_t>* cols) const {
    std::vector<std::size_t> pidx;
    for (const auto& g : sel)
      for (auto i : S.group_params.at(g))
        pidx.push_back(i);
    Eigen::MatrixXd x(sp.tr.size(), 6 + pidx.size());
    x.leftCols(6) = rows(sp.nuis, sp.tr);
    for (std::size_t c = 0; c < pidx.size(); ++c)
      x.col(6 + c) = rows_v(S.sig[pidx[c]], sp.tr);
    if (cols) *cols = pidx;
    return x;
  }
  double bic(const std::vector<std::string>& sel) const {
    std::vector<std::size_t> pidx;
    const auto fit = least_squares(design(sel, &pidx), ytr);
    if (!fit.ok) return 1e300;
    const double k = double(6 + pidx.size());
    return n_eff * std::log(std::max(fit.rss, 1e-30) / n) + k * std::log(n_eff);
  }
  // Every compliance stays positive.
  bool physical(const std::vector<std::string>& sel) const {
    std::vector<std::size_t> pidx;
    const auto fit = least_squares(design(sel, &pidx), ytr);
    for (std::size_t c = 0; c < pidx.size(); ++c)
      if (S.params[pidx[c]].compliance && S.params[pidx[c]].base + fit.beta[6 + long(c)] <= 0)
        return false;
    return true;
  }
  Eigen::MatrixXd covariance(const Ls& f, const Eigen::MatrixXd& x) const {
    const double dof = std::max(1.0, n - double(x.cols()));
    return Eigen::MatrixXd(f.cov_unscaled * (f.rss / dof * n / n_eff));
  }
};

struct GroupSelection {
  std::vector<std::string> selected;
  std::map<std::string, double> gain;  // ΔBIC of each
  double bic = 0;                      // of the selected model
};

// Selection: forward, by BIC over the training points.
GroupSelection select_groups(const LinearModel& lm, double threshold,
                             const std::function<void(const std::string&)>& progress) {
  GroupSelection G;
  G.bic = lm.bic({});
  for (;;) {
    std::string best;
    double best_bic = G.bic;
    for (const auto& g : lm.S.groups) {
      if (std::find(G.selected.begin(), G.selected.end(), g) != G.selected.end()) continue;
      auto sel = G.selected;
      sel.push_back(g);
      const double b = lm.bic(sel);
      if (b < best_bic && lm.physical(sel)) best_bic = b, best = g;
    }
    if (best.empty() || G.bic - best_bic <= threshold) break;
    G.gain[best] = best_bic - G.bic;
    progress("selected " + best + " (ΔBIC " + std::to_string(best_bic - G.bic) + ")");
    G.selected.push_back(best);
    G.bic = best_bic;
  }
  return G;
}

// The fitted parameters of the selected groups, their covariance (in the
// columns of xs, the last design) and the design.
struct SurfaceFitState {
  std::vector<std::size_t> pidx;  // parameters fitted, into Signatures::params
  Eigen::MatrixXd xs, cov;
  Ls fit;
  Eigen::VectorXd theta;
};

// Step 0: the linear fit around the believed model (the selection's signatures).
SurfaceFitState linear_fit(const LinearModel& lm, const std::vector<std::string>& selected) {
  SurfaceFitState st;
  st.xs = lm.design(selected, &st.pidx);
  st.fit = least_squares(st.xs, lm.ytr);
  st.cov = lm.covariance(st.fit, st.xs);
  const long np = long(st.pidx.size());
  st.theta.resize(np);
  for (long c = 0; c < np; ++c)
    st.theta[c] = lm.S.params[st.pidx[std::size_t(c)]].base + st.fit.beta[6 + c];
  return st;
}

// Gauss–Newton on the re-machined residual: each iteration re-machines the
// model at the estimate and its nudges, re-linearises there and steps,
// until every step is below a fifth of its standard error (the deflections
// change the engagement and so the force: one linearisation around the
// believed model is biased).
class GaussNewton {
 public:
  GaussNewton(Machinist& machinist, const SurfaceMeasurement& measurement,
              const sim::MachineDescription& believed, const WorkpieceGeometry& geometry,
              const Run& base, const LinearModel& lm)
      : machinist_(machinist),
        measurement_(measurement),
        believed_(believed),
        geometry_(geometry),
        base_(base),
        lm_(lm) {}

  sim::MachineDescription model_at(const SurfaceFitState& st, const Eigen::VectorXd& th) const {
    sim::MachineDescription m = believed_;
    for (long c = 0; c < th.size(); ++c)
      set_surface_param(m.machine, lm_.S.params[st.pidx[std::size_t(c)]], th[c], geometry_);
    return m;
  }

  // Iterates from st; the iteration count and convergence into res.
  void run(int iterations, const std::function<void(const std::string&)>& progress,
           SurfaceFitState& st, SurfaceDiagnosisResult& res) {
    const long np = long(st.pidx.size());
    for (int it = 1; np > 0 && it <= iterations; ++it) {
      const std::string tag = "Gauss-Newton " + std::to_string(it);
      Eigen::VectorXd y;
      const Eigen::MatrixXd x = linearise(st, tag, y);
      const Ls f = least_squares(x, y);
      if (!f.ok) break;
      st.xs = x;
      st.fit = f;
      st.cov = lm_.covariance(f, x);
      res.gauss_newton_iterations = it;
      res.gauss_newton_converged = true;
      std::string line = tag + ":";
      for (long c = 0; c < np; ++c) {
        const SurfaceParam& p = lm_.S.params[st.pidx[std::size_t(c)]];
        const double delta = f.beta[6 + c];
        const double se = std::sqrt(std::max(0.0, st.cov(6 + c, 6 + c)));
        if (!(std::abs(delta) <= 0.2 * se)) res.gauss_newton_converged = false;
        // A compliance stays positive: at most halve it per step.
        st.theta[c] = p.compliance && st.theta[c] + delta < 0.5 * st.theta[c] ? 0.5 * st.theta[c]
                                                                              : st.theta[c] + delta;
        line += " " + p.key + " " + std::to_string(st.theta[c]) + " (step " +
                std::to_string(delta) + ", se " + std::to_string(se) + ")";
      }
      progress(line);
      if (res.gauss_newton_converged) break;
    }
  }

 private:
  double deviation(const Run& run, std::size_t k) const {
    const auto& use = lm_.sp.use;
    const double d = run.deviation_mm[use[k]];
    return std::isfinite(d) ? d : base_.deviation_mm[use[k]];
  }

  // The design at the estimate (re-machined there and at each nudge) and
  // the residual y there, on the training points.
  Eigen::MatrixXd linearise(const SurfaceFitState& st, const std::string& tag, Eigen::VectorXd& y) {
    const auto& tr = lm_.sp.tr;
    const auto& use = lm_.sp.use;
    const long np = long(st.pidx.size());
    const Run at = machinist_.machine(model_at(st, st.theta), tag + ": estimate");
    y.resize(long(tr.size()));
    for (std::size_t k = 0; k < tr.size(); ++k)
      y[long(k)] = measurement_.points[use[tr[k]]].deviation_mm - deviation(at, tr[k]);
    Eigen::MatrixXd x(long(tr.size()), 6 + np);
    x.leftCols(6) = rows(lm_.sp.nuis, tr);
    for (long c = 0; c < np; ++c) {
      const SurfaceParam& p = lm_.S.params[st.pidx[std::size_t(c)]];
      // Compliances are nudged in proportion (the deviation is far from
      // linear in them near zero); the others by their fixed step.
      const double step =
          p.compliance ? std::max(0.2 * std::abs(st.theta[c]), 0.05 * p.step) : p.step;
      Eigen::VectorXd nudged = st.theta;
      nudged[c] += step;
      const Run run = machinist_.machine(model_at(st, nudged), tag + ": " + p.key);
      for (std::size_t k = 0; k < tr.size(); ++k)
        x(long(k), 6 + c) = (deviation(run, tr[k]) - deviation(at, tr[k])) / step;
    }
    return x;
  }

  Machinist& machinist_;
  const SurfaceMeasurement& measurement_;
  const sim::MachineDescription& believed_;
  const WorkpieceGeometry& geometry_;
  const Run& base_;
  const LinearModel& lm_;
};

// One fitted parameter as reported (a compliance as a stiffness 1/v).
Parameter reported_parameter(const SurfaceParam& p, double v, double se, Explanation& e) {
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
  return out;
}

// Intervals: each selected group as an explanation; the fitted model.
sim::MachineDescription explain_groups(const LinearModel& lm, const GroupSelection& G,
                                       const SurfaceFitState& st,
                                       const sim::MachineDescription& believed,
                                       const WorkpieceGeometry& geometry,
                                       SurfaceDiagnosisResult& res) {
  const auto& params = lm.S.params;
  sim::MachineDescription fitted = believed;
  for (const auto& g : G.selected) {
    Explanation e;
    const auto& first = params[lm.S.group_params.at(g).front()];
    e.effect = first.effect;
    e.axis = first.axis;
    e.delta_bic = G.gain.at(g);
    Eigen::VectorXd contrib = Eigen::VectorXd::Zero(long(lm.sp.tr.size()));
    for (std::size_t c = 0; c < st.pidx.size(); ++c) {
      const auto& p = params[st.pidx[c]];
      if (surface_group(p) != g) continue;
      const double v = st.theta[long(c)];
      const double se = std::sqrt(std::max(0.0, st.cov(6 + long(c), 6 + long(c))));
      set_surface_param(fitted.machine, p, v, geometry);
      contrib += (v - p.base) * st.xs.col(6 + long(c));
      e.parameters.push_back(reported_parameter(p, v, se, e));
    }
    e.rms_effect_mm = contrib.norm() / std::sqrt(lm.n);
    res.explanations.push_back(e);
  }
  return fitted;
}

// (a) a selected group another one replaces within the threshold.
void replaceable_groups(const LinearModel& lm, const GroupSelection& G, double threshold,
                        SurfaceDiagnosisResult& res) {
  for (const auto& g : G.selected) {
    for (const auto& h : lm.S.groups) {
      if (std::find(G.selected.begin(), G.selected.end(), h) != G.selected.end()) continue;
      auto sel = G.selected;
      std::replace(sel.begin(), sel.end(), g, h);
      if (lm.bic(sel) - G.bic < threshold) {
        const Eigen::VectorXd& a = lm.S.sig[lm.S.group_params.at(g).front()];
        const Eigen::VectorXd& b = lm.S.sig[lm.S.group_params.at(h).front()];
        NotIdentifiable ni{g, h, a.dot(b) / std::max(1e-30, a.norm() * b.norm()), separation(g, h)};
        res.not_identifiable.push_back(ni);
      }
    }
  }
}

// (b) fitted parameters that are nearly one combination.
void correlated_parameters(const LinearModel& lm, const SurfaceFitState& st,
                           SurfaceDiagnosisResult& res) {
  const auto& cov = st.cov;
  for (std::size_t c1 = 0; c1 < st.pidx.size(); ++c1)
    for (std::size_t c2 = c1 + 1; c2 < st.pidx.size(); ++c2) {
      const double cc =
          cov(6 + long(c1), 6 + long(c2)) /
          std::sqrt(cov(6 + long(c1), 6 + long(c1)) * cov(6 + long(c2), 6 + long(c2)));
      if (std::abs(cc) >= 0.99) {
        const auto& p1 = lm.S.params[st.pidx[c1]];
        const auto& p2 = lm.S.params[st.pidx[c2]];
        res.not_identifiable.push_back({surface_group(p1) + "." + p1.key,
                                        surface_group(p2) + "." + p2.key, cc,
                                        separation(p1.effect, p2.effect)});
      }
    }
}

// (c) a candidate the registration absorbs: nearly in the span of the
// rigid-motion columns, so no measurement of this part can show it.
void absorbed_by_registration(const LinearModel& lm, SurfaceDiagnosisResult& res) {
  const Eigen::MatrixXd nt = rows(lm.sp.nuis, lm.sp.tr);
  for (const auto& g : lm.S.groups) {
    const auto& p0 = lm.S.params[lm.S.group_params.at(g).front()];
    const Eigen::VectorXd s = rows_v(lm.S.sig[lm.S.group_params.at(g).front()], lm.sp.tr);
    if (s.norm() * p0.step < 1e-4 * std::sqrt(lm.n)) {
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

// Verify: the fitted model re-machined; its residual with the registration
// refitted on the training points.
std::vector<double> residual_after(Machinist& machinist, const SurfaceMeasurement& measurement,
                                   const SurfacePoints& sp, const Run& base,
                                   const sim::MachineDescription& fitted) {
  const std::size_t n_all = sp.use.size();
  const Run fr = machinist.machine(fitted, "fitted model");
  Eigen::VectorXd ra(n_all);
  for (std::size_t k = 0; k < n_all; ++k) {
    const double d = fr.deviation_mm[sp.use[k]];
    ra[k] = measurement.points[sp.use[k]].deviation_mm -
            (std::isfinite(d) ? d : base.deviation_mm[sp.use[k]]);
  }
  const Ls rg = least_squares(rows(sp.nuis, sp.tr), rows_v(ra, sp.tr));
  const Eigen::VectorXd rr = ra - sp.nuis * rg.beta;
  return std::vector<double>(rr.data(), rr.data() + n_all);
}

SurfaceFit surface_figures(const std::vector<double>& before, const std::vector<double>& after,
                           const std::vector<std::size_t>& idx) {
  SurfaceFit f;
  f.points = idx.size();
  f.rms_before_mm = rms(before, idx);
  f.rms_after_mm = rms(after, idx);
  f.max_before_mm = max_abs(before, idx);
  f.max_after_mm = max_abs(after, idx);
  return f;
}

std::string surface_verdict(const std::vector<std::string>& selected, bool mismatch) {
  if (selected.empty())
    return !mismatch ? "nothing missing: the residual is at the noise floor"
                     : "mismatch above the noise floor that no candidate effect explains";
  std::string v = "missing in the believed model:";
  for (std::size_t i = 0; i < selected.size(); ++i)
    v += (i ? ", " : " ") + selected[i];
  return v;
}

// What the result says before any step: the inputs.
SurfaceDiagnosisResult result_header(const SurfaceMeasurement& measurement, const SurfaceJob& job,
                                     const sim::MachineDescription& believed) {
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
  return res;
}

void diagnose_with(Machinist& machinist, const SurfaceMeasurement& measurement,
                   const SurfaceJob& job, const sim::MachineDescription& believed,
                   const SurfaceOptions& options, SurfaceDiagnosisResult& res);

// Refused before any re-machining: a name that is no surface-mode effect
// (a typo, or a trace-mode effect such as backlash) would test nothing.
void check_candidates(const std::vector<std::string>& candidates) {
  const auto& known = surface_candidate_effects();
  for (const auto& c : candidates)
    if (std::find(known.begin(), known.end(), c) == known.end())
      throw DiagnosisError("candidate '" + c +
                           "' is not a surface-mode effect; known: " + join(known));
}

// A measurement with fewer usable points than a fit needs is refused before
// any re-machining.
void check_measured_points(const SurfaceMeasurement& measurement) {
  std::size_t valid = 0;
  for (const auto& p : measurement.points)
    valid += p.valid ? 1 : 0;
  if (valid < kMinSurfacePoints)
    throw DiagnosisError(measurement.source + ": only " + std::to_string(valid) + " of " +
                         std::to_string(measurement.points.size()) +
                         " points are measured (valid, with a deviation); need " +
                         std::to_string(kMinSurfacePoints));
}

// "surface 6 (base_bottom)" for each surface with nominal points of which
// none was measured (a face the scanner never saw).
std::vector<std::string> unmeasured_surfaces(const SurfaceMeasurement& measurement,
                                             const OperationMap& ops) {
  std::map<int, std::size_t> valid;
  for (const auto& p : measurement.points)
    valid[p.nominal.surface] += p.valid ? 1 : 0;
  std::vector<std::string> out;
  for (const auto& [surface, count] : valid) {
    if (count > 0) continue;
    const auto it = ops.surface_name.find(surface);
    out.push_back("surface " + std::to_string(surface) +
                  (it != ops.surface_name.end() ? " (" + it->second + ")" : ""));
  }
  return out;
}

}  // namespace

const std::vector<std::string>& surface_candidate_effects() {
  static const std::vector<std::string> names{"tool_radius_error",    "tool_length_error",
                                              "rotary_location",      "tool_deflection",
                                              "workpiece_deflection", "squareness"};
  return names;
}

SurfaceDiagnosisResult diagnose_surface(const SurfaceMeasurement& measurement,
                                        const SurfaceJob& job,
                                        const sim::MachineDescription& believed,
                                        const SurfaceOptions& options) {
  check_candidates(options.candidates);
  check_measured_points(measurement);
  SurfaceDiagnosisResult res = result_header(measurement, job, believed);

  std::vector<sim::measure::CmmPoint> nominal;
  for (const auto& p : measurement.points)
    nominal.push_back(p.nominal);
  Machinist machinist(job, nominal, options);
  try {
    diagnose_with(machinist, measurement, job, believed, options, res);
  } catch (...) {
    machinist.remove_created();
    throw;
  }
  return res;
}

namespace {

void diagnose_with(Machinist& machinist, const SurfaceMeasurement& measurement,
                   const SurfaceJob& job, const sim::MachineDescription& believed,
                   const SurfaceOptions& options, SurfaceDiagnosisResult& res) {
  auto progress = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  const Run base = machinist.machine(believed, "believed model");
  const bool five_axis = base.a_range_deg > 1.0 || base.c_range_deg > 1.0;

  SurfacePoints sp;
  sp.use = usable_points(measurement, base);
  res.valid_points = sp.use.size();
  const std::size_t n_all = sp.use.size();
  res.heldout_kind = split_heldout(measurement, options.holdout_fraction, sp);
  res.has_heldout = !sp.ho.empty();
  res.centroid_mm = sp.centroid;
  residual_and_nuisance(measurement, base, sp);

  // Noise floor and neighbour correlation on the registered residual.
  const Ls reg0 = least_squares(rows(sp.nuis, sp.tr), rows_v(sp.r, sp.tr));
  const Eigen::VectorXd r0 = sp.r - sp.nuis * reg0.beta;  // registered residual, all points
  std::vector<sim::measure::CmmPoint> used_nominal;
  for (auto i : sp.use)
    used_nominal.push_back(measurement.points[i].nominal);
  const SurfaceNoise noise = surface_noise_floor(used_nominal, r0, sp.tr);
  res.noise_floor_mm = noise.floor_mm;
  const OperationMap ops = read_operations(job.part);
  res.mismatch = locate_regions(measurement, sp, r0, ops, res.noise_floor_mm);
  res.unmeasured_surfaces = unmeasured_surfaces(measurement, ops);

  WorkpieceGeometry geometry;
  geometry.clamp_point_mm = {sp.centroid.x(), sp.centroid.y(), sp.lo.z()};
  geometry.reference_length_mm = std::max(1.0, sp.hi.z() - sp.lo.z());
  Signatures S = signatures(machinist, believed, options, five_axis, geometry, base, sp.use);
  res.candidates_tested = S.groups;

  LinearModel lm{sp, S, rows_v(sp.r, sp.tr), double(sp.tr.size())};
  const double rho = noise.sxx > 0 ? std::clamp(noise.sxy / noise.sxx, 0.0, 0.95) : 0.0;
  lm.n_eff = std::max(lm.n * (1 - rho) / (1 + rho), std::min(lm.n, 20.0));
  const GroupSelection G = select_groups(lm, options.bic_threshold, progress);
  SurfaceFitState st = linear_fit(lm, G.selected);
  GaussNewton(machinist, measurement, believed, geometry, base, lm)
      .run(options.gauss_newton_iterations, progress, st, res);

  res.registration_translation_mm = st.fit.beta.head<3>();
  res.registration_rotation_urad = st.fit.beta.segment<3>(3) * 1e6;
  const sim::MachineDescription fitted = explain_groups(lm, G, st, believed, geometry, res);
  replaceable_groups(lm, G, options.bic_threshold, res);
  correlated_parameters(lm, st, res);
  absorbed_by_registration(lm, res);

  const std::vector<double> before(r0.data(), r0.data() + n_all);
  const std::vector<double> after =
      G.selected.empty() ? before : residual_after(machinist, measurement, sp, base, fitted);
  res.train = surface_figures(before, after, sp.tr);
  if (res.has_heldout) res.heldout = surface_figures(before, after, sp.ho);
  res.resimulations = machinist.runs();
  res.fitted = fitted;
  for (std::size_t k = 0; k < n_all; ++k) {
    res.position_mm.push_back(measurement.points[sp.use[k]].nominal.position_mm);
    res.surface.push_back(measurement.points[sp.use[k]].nominal.surface);
    res.is_heldout.push_back(sp.held[k]);
  }
  res.before_mm = before;
  res.after_mm = after;
  res.verdict = S.groups.empty() ? "nothing tested: no candidate effect moves a measured point"
                                 : surface_verdict(G.selected, !res.mismatch.empty());
}

}  // namespace

}  // namespace truecut::analysis::diagnosis
