// Sparse selection on the linearisation: forward selection of candidate
// groups by BIC, and the chosen groups another one replaces almost as well.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "effect_params.hpp"
#include "fit_steps.hpp"

namespace truecut::analysis::diagnosis {

using Eigen::MatrixXd;
using Eigen::VectorXd;

double rms_on_support(const VectorXd& v, const Layout& layout) {
  std::vector<double> ms;
  Eigen::Index r = 0;
  for (const auto& ix : layout.index) {
    const Eigen::Index m = Eigen::Index(ix.size());
    ms.push_back(m ? v.segment(r, m).squaredNorm() / double(m) : 0.0);
    r += m;
  }
  const double top = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  double ss = 0, n = 0;
  for (std::size_t a = 0; a < ms.size(); ++a)
    if (ms[a] > 0 && ms[a] >= 1e-4 * top) {
      const double m = double(layout.index[a].size());
      ss += ms[a] * m, n += m;
    }
  return n > 0 ? std::sqrt(ss / n) : 0.0;
}

namespace {

using Groups = std::map<std::string, std::vector<const Candidate*>>;
// Each candidate's rss_after(X, r) alone: the first step of the forward
// selection and the confusions of a single chosen group fit the same
// columns again (the same numbers, not computed twice).
using AloneRss = std::map<const Candidate*, double>;

// Each group's variant that alone fits r best.
std::vector<const Candidate*> best_variants(const Groups& groups, const VectorXd& r,
                                            AloneRss& alone) {
  std::vector<const Candidate*> best_of;
  for (const auto& [g, vs] : groups) {
    const Candidate* best = nullptr;
    double best_rss = INFINITY;
    for (const auto* v : vs) {
      const double rss = rss_after(v->X, r);
      alone[v] = rss;
      if (rss < best_rss) best_rss = rss, best = v;
    }
    best_of.push_back(best);
  }
  return best_of;
}

// Effective sample count from the noise correlation left after the fit
// with every group's best single variant.
double selection_n_eff(const std::vector<const Candidate*>& best_of, const VectorXd& r) {
  const Eigen::Index n = r.size();
  std::vector<const MatrixXd*> all;
  for (const auto* c : best_of)
    all.push_back(&c->X);
  VectorXd coef_all;
  const MatrixXd X_all = hcat(all, n);
  rss_after(X_all, r, &coef_all);
  const VectorXd res_all = X_all.cols() ? VectorXd(r - X_all * coef_all) : r;
  double rho = 0, den = res_all.squaredNorm();
  for (Eigen::Index i = 1; i < n; ++i)
    rho += res_all[i] * res_all[i - 1];
  rho = den > 0 ? rho / den : 0;
  return n_eff_of(double(n), rho);
}

std::vector<const MatrixXd*> columns_of(const std::vector<const Candidate*>& chosen) {
  std::vector<const MatrixXd*> cur;
  for (const auto* c : chosen)
    cur.push_back(&c->X);
  return cur;
}

// The variant, among the groups neither used nor rejected, whose addition
// lowers the BIC most (below −threshold); null when none does.
const Candidate* best_addition(const Groups& groups, const std::set<std::string>& skip,
                               const std::vector<const Candidate*>& chosen, const VectorXd& r,
                               double rss, double threshold, double n_eff, const AloneRss& alone,
                               double& best_dbic, double& best_rss) {
  const Eigen::Index n = r.size();
  const Candidate* best = nullptr;
  best_dbic = -threshold, best_rss = rss;
  const std::vector<const MatrixXd*> cur = columns_of(chosen);
  for (const auto& [g, vs] : groups) {
    if (skip.count(g)) continue;
    for (const auto* v : vs) {
      double rss_new;
      if (cur.empty()) {
        rss_new = alone.at(v);
      } else {
        auto parts = cur;
        parts.push_back(&v->X);
        rss_new = rss_after(hcat(parts, n), r);
      }
      const double dbic =
          n_eff * std::log(std::max(rss_new, 1e-300) / rss) + double(v->X.cols()) * std::log(n_eff);
      if (dbic < best_dbic) best_dbic = dbic, best = v, best_rss = rss_new;
    }
  }
  return best;
}

// Every effect of `next` keeps a physical meaning with the joint coefficients.
bool all_physical(const std::vector<const Candidate*>& next, const VectorXd& coef,
                  const sim::MachineParams& base) {
  sim::MachineParams trial = base;
  bool ok = true;
  Eigen::Index c0 = 0;
  for (const auto* c : next) {
    ok = ok && c->apply(trial, coef.segment(c0, c->X.cols()));
    c0 += c->X.cols();
  }
  return ok;
}

// Not identifiable: a chosen group that another group replaces almost as well.
void find_confusions(const Groups& groups, const std::vector<const Candidate*>& best_of,
                     const std::set<std::string>& used, const VectorXd& r, double rss,
                     double threshold, double n_eff, const AloneRss& alone, Selection& sel) {
  const Eigen::Index n = r.size();
  const std::vector<const MatrixXd*> cur = columns_of(sel.chosen);
  Eigen::Index c0 = 0;
  for (std::size_t i = 0; i < sel.chosen.size(); ++i) {
    const Candidate* s = sel.chosen[i];
    const VectorXd contrib = s->X * sel.coef.segment(c0, s->X.cols());
    c0 += s->X.cols();
    for (const auto* o : best_of) {
      if (o->group == s->group || used.count(o->group)) continue;
      // The other group's best variant for this contribution.
      const Candidate* ob = nullptr;
      double ob_rss = INFINITY;
      for (const auto* v : groups.at(o->group)) {
        double rr;
        if (cur.size() == 1) {
          rr = alone.at(v);
        } else {
          auto parts = cur;
          parts[i] = &v->X;
          rr = rss_after(hcat(parts, n), r);
        }
        if (rr < ob_rss) ob_rss = rr, ob = v;
      }
      const double d = n_eff * std::log(std::max(ob_rss, 1e-300) / std::max(rss, 1e-300)) +
                       double(ob->X.cols() - s->X.cols()) * std::log(n_eff);
      if (d >= threshold) continue;
      const double resid = rss_after(ob->X, contrib);
      const double corr = contrib.squaredNorm() > 0
                              ? std::sqrt(std::max(0.0, 1 - resid / contrib.squaredNorm()))
                              : 0;
      NotIdentifiable ni;
      ni.first = s->group;
      ni.second = ob->group;
      ni.correlation = corr;
      ni.separate_by = separation_hint(s->effect, ob->effect);
      sel.confusions.push_back(ni);
    }
  }
}

}  // namespace

Selection forward_select(const std::vector<Candidate>& cands, const VectorXd& r, double threshold,
                         double min_effect, const Layout& layout, const sim::MachineParams& base,
                         double& n_eff_out) {
  const Eigen::Index n = r.size();
  Groups groups;
  for (const auto& c : cands)
    groups[c.group].push_back(&c);
  AloneRss alone;
  const std::vector<const Candidate*> best_of = best_variants(groups, r, alone);
  const double n_eff = selection_n_eff(best_of, r);
  n_eff_out = n_eff;

  Selection sel;
  std::set<std::string> used, rejected;
  double rss = r.squaredNorm();
  for (;;) {
    std::set<std::string> skip = used;
    skip.insert(rejected.begin(), rejected.end());
    double best_dbic = 0, best_rss = 0;
    const Candidate* best = best_addition(groups, skip, sel.chosen, r, rss, threshold, n_eff, alone,
                                          best_dbic, best_rss);
    if (!best) break;
    auto parts = columns_of(sel.chosen);
    parts.push_back(&best->X);
    VectorXd coef;
    rss_after(hcat(parts, n), r, &coef);
    std::vector<const Candidate*> next = sel.chosen;
    next.push_back(best);
    const bool ok = all_physical(next, coef, base);
    // Too small to be physics rather than a departure of the noise from the
    // white Gaussian noise the BIC assumes (weighted units: the floor is 1).
    const VectorXd contrib = best->X * coef.tail(best->X.cols());
    const double least = best->min_effect_ratio > 0 ? best->min_effect_ratio : min_effect;
    if (!ok || rms_on_support(contrib, layout) < least) {
      rejected.insert(best->group);
      continue;
    }
    sel.chosen = next;
    sel.delta_bic.push_back(best_dbic);
    sel.coef = coef;
    used.insert(best->group);
    rss = best_rss;
  }
  find_confusions(groups, best_of, used, r, rss, threshold, n_eff, alone, sel);
  return sel;
}

}  // namespace truecut::analysis::diagnosis
