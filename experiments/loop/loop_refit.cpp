// The refit by simulation of an accepted candidate (loop.hpp's design note): the linear estimate
// simulated on the whole grid, secant refinement when the response misses the traced strength,
// and the confirmation the simulations must give.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {

namespace {

// The next value to simulate: c interpolated between the known responses `pts` (value,
// response fraction; sorted), preferring the bracket next to the last trial's value. NaN when no
// bracket holds c.
double secant_value(const std::vector<std::pair<double, double>>& pts, double coef, double last_p) {
  double next = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t q = 0; q + 1 < pts.size(); ++q) {
    const auto [pa, fa] = pts[q];
    const auto [pb, fb] = pts[q + 1];
    if (fa == fb || (coef - fa) * (coef - fb) > 0.0) continue;
    next = pa + (coef - fa) / (fb - fa) * (pb - pa);
    if (pa == last_p || pb == last_p) break;
  }
  return next;
}

}  // namespace

double Loop::calibration_rmse(const Model& model, double mu) const {
  std::vector<double> r;
  for (std::size_t i : fit_) r.push_back(data_.tests[i].angle_deg - model.angle(i, mu));
  return rmse(r);
}

// One trial at p, appended to refit.trials. The value may overshoot into piles the measurement
// cannot see (a smooth plate spreads a small sample into a monolayer) or into pours a
// calibration test's outlet jams: then it steps back halfway towards off, twice at most. A
// held-out test that jams at p does not stop the trial: the model predicts no pile for it.
// Returns false when no attempt could be simulated.
bool Loop::run_trial(const CandidateEffect& e, double off, double p, const FingerprintRecord& fp,
                     double mu_node, const LoopState& state, const std::vector<Channel>& channels,
                     Refit& refit) {
  std::unique_ptr<Surface> surf;
  for (int attempt = 0; attempt < 3 && !surf; ++attempt) {
    std::vector<EffectSetting> with = state.effects;
    with.push_back({&e, p});
    try {
      surf = std::make_unique<Surface>(simulate_surface(with));
    } catch (const std::exception& ex) {
      refit.notes +=
          "at " + std::to_string(p) + ": " + std::string(ex.what()).substr(0, 300) + "; ";
      say("refit at " + std::to_string(p) + " failed; stepping back halfway");
      p = off + 0.5 * (p - off);
    }
  }
  if (!surf) return false;
  surfaces_.push_back(std::move(surf));
  Trial tr;
  tr.p = p;
  tr.surf = surfaces_.back().get();
  for (std::size_t i = 0; i < data_.tests.size(); ++i)
    if (!tr.surf->curve[i].no_pile.empty()) tr.no_pile.push_back(data_.tests[i].id);
  // The response in units of the fingerprint, over the refit's channels, each over its noise.
  const Model alone{{{1.0, tr.surf}}};
  double num = 0.0, den = 0.0;
  for (std::size_t i : fit_)
    for (Channel c : channels) {
      const double f = fp.change[c][i];
      const double w =
          c == Channel::kAngle ? 1.0 : std::pow(noise(i, Channel::kAngle) / noise(i, c), 2);
      num += w * (alone.value(i, mu_node, c) - state.model.value(i, mu_node, c)) * f;
      den += w * f * f;
    }
  tr.fraction = den > 0.0 ? num / den : 0.0;
  // t may extrapolate beyond the simulated value, but never past the effect's range.
  const double bound = (p < off ? e.lo : e.hi) - off;
  const double t_max = p != off ? std::min(s_.t_max, std::max(1.0, bound / (p - off))) : s_.t_max;
  tr.joint = fit_mu(state.model, tr.surf, t_max, fit_, channels);
  for (const auto& [w, sf] : state.model.terms)
    tr.model.terms.push_back({(1.0 - tr.joint.t) * w, sf});
  tr.model.terms.push_back({tr.joint.t, tr.surf});
  tr.rmse = calibration_rmse(tr.model, tr.joint.mu);
  refit.trials.push_back(tr);
  return true;
}

// Secant refinement (on the refit's channels: the angle, or every traced observable for a
// candidate admitted on the joint evidence). The linear estimate p1 assumes the response grows linearly from off to the
// probe; a threshold effect (a plate that starts to slide below some friction) breaks that. When
// the simulated response fraction misses the traced strength `coef` by more than half, the next
// value interpolates coef between the known responses (off: 0, probe: 1, and the trials), at
// most twice more.
Refit Loop::refit_by_simulation(const CandidateEffect& e, double off, double p1, double coef,
                                const FingerprintRecord& fp, double mu_node,
                                const LoopState& state, const std::vector<Channel>& channels) {
  Refit refit;
  const int kMaxRefinements = 2;
  if (!run_trial(e, off, p1, fp, mu_node, state, channels, refit)) return refit;
  for (int k = 0; k < kMaxRefinements; ++k) {
    const Trial& last = refit.trials.back();
    if (std::abs(last.fraction - coef) <= 0.5 * std::abs(coef)) break;
    std::vector<std::pair<double, double>> pts = {{off, 0.0}, {fp.probe, 1.0}};
    for (const Trial& tr : refit.trials) pts.push_back({tr.p, tr.fraction});
    std::sort(pts.begin(), pts.end());
    double next = secant_value(pts, coef, last.p);
    if (!std::isfinite(next)) break;
    next = std::clamp(next, e.lo, e.hi);
    bool known = false;
    for (const auto& [pp, ff] : pts)
      known = known || std::abs(pp - next) <= 1e-3 * std::max(1.0, std::abs(pp));
    if (known) break;
    say(e.name + ": simulated response " + std::to_string(last.fraction) + " of the probe's at " +
        std::to_string(last.p) + " (traced " + std::to_string(coef) + "); refining at " +
        std::to_string(next));
    if (!run_trial(e, off, next, fp, mu_node, state, channels, refit)) break;
  }
  return refit;
}

// The simulated refit is the test of the linear tracing: when the joint fit puts the effect back
// at its off value (t = 0), or the simulated model does not lower the calibration error by more
// than the seed noise of a prediction, the simulations do not confirm it and it is not chosen.
// Returns the reason, or an empty string when confirmed.
std::string Loop::unconfirmed_reason(const Trial& best, const LoopState& state) const {
  const double rmse_now = calibration_rmse(state.model, state.fit.mu);
  const double margin = s_.rule.loo_margin_factor * seed_se_;
  if (best.joint.t <= 0.0)
    return "the joint refit of mu_r and the effect on simulated piles puts the effect at its "
           "off value (t = 0)";
  if (best.rmse > rmse_now - margin)
    return "the simulated refit lowers the calibration RMSE from " + std::to_string(rmse_now) +
           " to " + std::to_string(best.rmse) + " deg, not by more than the seed noise " +
           std::to_string(margin) + " deg";
  return "";
}

}  // namespace reposetwin::experiments::loop_detail
